"""Parameter validation shared by the friction and pressure laws (numpy only)."""

from __future__ import annotations

import numpy as np

# parameter name -> (lower bound, strict?, description of the valid range)
RANGES: dict[str, tuple[float, bool, str]] = {
    "F_c": (0.0, False, ">= 0 N"),
    "F_s": (0.0, False, ">= 0 N"),
    "sigma_0": (0.0, True, "> 0 N/m"),
    "sigma_1": (0.0, False, ">= 0 N*s/m"),
    "sigma_2": (0.0, False, ">= 0 N*s/m"),
    "v_r": (0.0, True, "> 0 m/s"),
    "alpha": (0.0, True, "> 0"),
    "sigma": (0.0, True, "> 0 N/m"),
    "exponent": (0.0, False, ">= 0"),
    "velocity_tolerance": (0.0, True, "> 0 m/s"),
    "step": (0.0, False, ">= 0 s"),
    "viscosity_0": (0.0, True, "> 0 Pa*s"),
    "load_per_length": (0.0, True, "> 0 N/m"),
}


def check_parameters(**values) -> None:
    """Raise ValueError if any named parameter is NaN or outside its valid range.

    Parameters are scalars or arrays; every element is checked. Names not in
    :data:`RANGES` are only checked for NaN.
    """
    for name, value in values.items():
        arr = np.asarray(value, dtype=float)
        if np.isnan(arr).any():
            rule = RANGES.get(name, (None, None, "a finite number"))[2]
            raise ValueError(f"parameter {name} is NaN; expected {rule}")
        if name in RANGES:
            low, strict, rule = RANGES[name]
            bad = arr <= low if strict else arr < low
            if bad.any():
                first = arr[bad].flat[0] if arr.ndim else float(arr)
                raise ValueError(f"parameter {name} = {first!r} is out of range; expected {rule}")


def check_signal(name: str, value) -> np.ndarray:
    """Return ``value`` as a float array, raising ValueError if it holds NaN."""
    arr = np.asarray(value, dtype=float)
    if np.isnan(arr).any():
        raise ValueError(f"{name} contains NaN; expected finite values")
    return arr


def as_output(result, *inputs):
    """Return a Python float when every input was a scalar, else the array."""
    if all(np.ndim(x) == 0 for x in inputs):
        return float(result)
    return result
