"""Parameter validation shared by the friction and pressure laws (numpy only)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

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


ROUNDOFF = 1e-9
"""Relative tolerance [-] of the physical constraints F_c >= 0, F_s >= F_c, sigma_2 >= 0:
a value below its bound by at most ``ROUNDOFF * max(|value|, |F_c|, |F_s|, 1)`` (in the
parameter's SI unit) is rounding of a value fitted onto the bound, and counts as the bound.
The datasheet validation, the identification's check and the model all use
:func:`roundoff_tolerance`, so what one accepts the others evaluate."""


def roundoff_tolerance(
    F_c: ArrayLike, F_s: ArrayLike | None = None, sigma_2: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Per-point tolerances (force [N], sigma_2 [N*s/m]) of the physical constraints.

    ``ROUNDOFF`` times the larger of 1 and the magnitudes of F_c and F_s [N] (for F_c >= 0
    and F_s >= F_c), and of 1 and |sigma_2| [N*s/m] (for sigma_2 >= 0); broadcast arrays.
    """
    F_c = np.abs(np.asarray(F_c, dtype=float))
    F_s = F_c if F_s is None else np.abs(np.asarray(F_s, dtype=float))
    force = ROUNDOFF * np.maximum(np.maximum(F_c, F_s), 1.0)
    s2 = 0.0 if sigma_2 is None else np.abs(np.asarray(sigma_2, dtype=float))
    return force, ROUNDOFF * np.maximum(s2, 1.0)


def clamp_roundoff(params: dict) -> dict:
    """``params`` with F_c, F_s and sigma_2 that miss their physical bound by rounding only
    (:func:`roundoff_tolerance`) set exactly onto it (F_c, sigma_2 to 0; F_s to F_c).

    Larger violations are left as they are (the parameter checks then refuse them).
    """
    out = dict(params)
    F_c, F_s, sigma_2 = out.get("F_c"), out.get("F_s"), out.get("sigma_2")
    if F_c is None:
        return out
    if all(isinstance(x, float | int) for x in (F_c, F_s, sigma_2) if x is not None):
        return _clamp_scalars(out, F_c, F_s, sigma_2)  # one set: no numpy (batch set-up)
    tol, tol_2 = roundoff_tolerance(F_c, F_s, sigma_2)

    def onto(value, bound, tolerance):
        value = np.asarray(value, dtype=float)
        bound = np.broadcast_to(np.asarray(bound, dtype=float), value.shape)
        near = (value < bound) & (value >= bound - tolerance)
        if not near.any():
            return None
        fixed = np.where(near, bound, value)
        return float(fixed) if fixed.ndim == 0 else fixed

    if (new := onto(F_c, 0.0, tol)) is not None:
        out["F_c"] = F_c = new
    if F_s is not None and (new := onto(F_s, F_c, tol)) is not None:
        out["F_s"] = new
    if sigma_2 is not None and (new := onto(sigma_2, 0.0, tol_2)) is not None:
        out["sigma_2"] = new
    return out


def _clamp_scalars(out: dict, F_c, F_s, sigma_2) -> dict:
    """:func:`clamp_roundoff` of plain numbers, as floats, with the same tolerances."""
    tol = ROUNDOFF * max(abs(F_c), abs(F_c if F_s is None else F_s), 1.0)
    if -tol <= F_c < 0.0:
        out["F_c"] = F_c = 0.0
    if F_s is not None and F_c - tol <= F_s < F_c:
        out["F_s"] = float(F_c)
    if sigma_2 is not None and -ROUNDOFF * max(abs(sigma_2), 1.0) <= sigma_2 < 0.0:
        out["sigma_2"] = 0.0
    return out


def check_parameters(**values: ArrayLike) -> None:
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
                first = float(arr[bad].flat[0] if arr.ndim else arr)
                raise ValueError(f"parameter {name} = {first!r} is out of range; expected {rule}")


def check_signal(name: str, value: ArrayLike) -> np.ndarray:
    """Return ``value`` as a float array, raising ValueError if it holds NaN."""
    arr = np.asarray(value, dtype=float)
    if np.isnan(arr).any():
        raise ValueError(f"{name} contains NaN; expected finite values")
    return arr


def as_output(result: np.ndarray | float, *inputs: ArrayLike) -> np.ndarray | float:
    """Return a Python float when every input was a scalar, else the array."""
    if all(np.ndim(x) == 0 for x in inputs):
        return float(result)
    return result
