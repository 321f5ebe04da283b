"""Friction phenomena of thesis section 2.1.3, reproduced with the dynamic model.

Each function runs one classic experiment and returns plain numbers and arrays (SI), so
tests can check them and ``docs/make_figures.py`` can draw them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .plant import AppliedForce, Cylinder, FrictionModel, PrescribedMotion, SpringPull, simulate

if TYPE_CHECKING:
    from .result import SimulationResult

__all__ = ["stick_slip", "friction_lag", "presliding", "breakaway_force"]

_MASS = 10.0  # [kg], the stick-slip benchmark's mass


def _model(sigma_0: float = 1e6, mass=_MASS):
    return FrictionModel(sigma_0=sigma_0, sigma_1=float(np.sqrt(sigma_0 * mass)))


def stick_slip(
    pressure: float,
    *,
    stiffness: float = 2e4,
    speed: float = 5e-3,
    duration: float = 10.0,
    mass: float = _MASS,
) -> tuple[SimulationResult, float]:
    """Spring pulled at constant ``speed`` [m/s] through ``stiffness`` [N/m] at ``pressure`` [Pa].

    Returns the result and the peak-to-peak spring force over the second half [N] (the
    stick-slip amplitude, which grows with F_s - F_c and so with pressure).
    """
    result = simulate(
        Cylinder(mass),
        _model(mass=mass),
        SpringPull(stiffness, speed),
        duration,
        pressure_a=pressure,
    )
    late = result.time >= duration / 2
    spring = result.outputs["drive_force"][late]
    return result, float(spring.max() - spring.min())


def friction_lag(
    pressure: float,
    *,
    mean_speed: float = 0.010,
    amplitude: float = 0.008,
    frequency: float = 5.0,
    periods: int = 6,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Friction against a sinusoidal velocity ``mean + amplitude sin(2 pi f t)`` [m/s].

    Returns (velocity, friction) over the last period and the mean friction difference
    [N] between accelerating and decelerating halves at matching speeds (> 0: friction is
    higher while accelerating, the friction lag of Fig. 2.1d).
    """
    duration = periods / frequency
    omega = 2 * np.pi * frequency
    result = simulate(
        Cylinder(2.5),
        _model(),
        PrescribedMotion(lambda t: mean_speed + amplitude * np.sin(omega * t)),
        duration,
        dt=1e-4,
        pressure_a=pressure,
    )
    last = result.time >= duration - 1 / frequency
    v = result.states["velocity"][last]
    f = result.outputs["friction_force"][last]
    phase = (omega * result.time[last]) % (2 * np.pi)
    rising = (phase < np.pi / 2) | (phase > 3 * np.pi / 2)
    grid = np.linspace(mean_speed - 0.8 * amplitude, mean_speed + 0.8 * amplitude, 50)
    order_up = np.argsort(v[rising])
    order_down = np.argsort(v[~rising])
    up = np.interp(grid, v[rising][order_up], f[rising][order_up])
    down = np.interp(grid, v[~rising][order_down], f[~rising][order_down])
    return v, f, float(np.mean(up - down))


def presliding(
    pressure: float,
    *,
    fraction: float = 0.5,
    ramp_time: float = 0.5,
    hold: float = 0.5,
    sigma_0: float = 1e6,
) -> tuple[SimulationResult, float, float]:
    """Ramp a force to ``fraction * F_c`` [-], hold, release: the spring-like presliding regime.

    Returns the result, the displacement at the peak force [m] and ``F_peak / sigma_0`` [m],
    the linear-spring estimate.
    """
    model = _model(sigma_0=sigma_0, mass=2.5)
    peak = fraction * model.params_at(pressure)["F_c"]
    total = 2 * ramp_time + hold

    def force(t):
        return peak * np.clip(np.minimum(t / ramp_time, (total - t) / ramp_time), 0, 1)

    result = simulate(
        Cylinder(2.5), model, AppliedForce(force), total + 0.2, dt=1e-4, pressure_a=pressure
    )
    at_peak = result.states["position"][np.searchsorted(result.time, ramp_time + hold / 2)]
    return result, float(at_peak), peak / sigma_0


def breakaway_force(pressure: float, rate: float, *, sigma_0: float = 1e6) -> float:
    """Breakaway force [N] under an applied force ramp of ``rate`` [N/s].

    The breakaway force is the first peak of the friction force: friction rises with the
    applied force through presliding, peaks, then falls as the rod slides into the
    Stribeck dip. (A velocity threshold would not do: presliding alone creeps at
    ``rate / sigma_0``.) As in Canudas de Wit et al. (1995, after Johannes et al. 1973),
    it falls as the force rate rises.
    """
    model = _model(sigma_0=sigma_0, mass=2.5)
    F_s = model.params_at(pressure)["F_s"]
    duration = 3.0 * F_s / rate
    dt = min(1e-3, duration / 4000)
    result = simulate(
        Cylinder(2.5), model, AppliedForce(lambda t: rate * t), duration, dt=dt, pressure_a=pressure
    )
    friction = result.outputs["friction_force"]
    falling = np.nonzero(np.diff(friction) < 0)[0]
    if falling.size == 0:
        raise RuntimeError(
            f"no friction peak under a {rate} N/s ramp: at this rate the rod accelerates "
            "without a distinct breakaway; use a slower rate"
        )
    return float(friction[falling[0]])  # first local maximum
