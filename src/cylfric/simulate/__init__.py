"""Time-domain simulation of a cylinder with dynamic pressure-dependent friction."""

from .plant import (
    DEFAULT_FIXED_STEP,
    MAX_OUTPUT_BYTES,
    THESIS_CYLINDER,
    AppliedForce,
    BatchResult,
    Cylinder,
    FrictionModel,
    PositionServo,
    PrescribedMotion,
    SpringPull,
    simulate,
    simulate_batch,
)
from .result import SimulationResult

__all__ = [
    "Cylinder",
    "FrictionModel",
    "PrescribedMotion",
    "AppliedForce",
    "SpringPull",
    "PositionServo",
    "SimulationResult",
    "simulate",
    "simulate_batch",
    "BatchResult",
    "THESIS_CYLINDER",
    "DEFAULT_FIXED_STEP",
    "MAX_OUTPUT_BYTES",
]
