"""Time-domain simulation of a cylinder with dynamic pressure-dependent friction."""

from .plant import (
    BATCH_PEAK_FACTOR,
    DEFAULT_FIXED_STEP,
    MAX_OUTPUT_BYTES,
    PEAK_BYTES_PER_SAMPLE,
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
    "PEAK_BYTES_PER_SAMPLE",
    "BATCH_PEAK_FACTOR",
]
