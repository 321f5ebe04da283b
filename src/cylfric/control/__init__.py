"""Friction compensation in the servo loop (issue 25): axis, controllers, loop, metrics."""
