"""The surface fit with linear pressure laws inside the physical range (thesis eq. 4.1-4.3).

Each pressure-dependent quantity is parametrised by its values at the lowest and highest
measured pressure, ``P(p) = P_lo + (P_hi - P_lo) (p - p_lo) / (p_hi - p_lo)``; a linear law
is non-negative over the whole measured range exactly when both values are. So bounds of
zero on F_c, on the Stribeck amplitude F_s - F_c and on sigma_2 at both ends keep the model
physical (F_c >= 0, F_s >= F_c, sigma_2 >= 0) over its validity range, and a bound the fit
runs into says which part of the model the data contradict (:attr:`SurfaceFit.at_bounds`).

Three friction laws: ``stribeck`` (eq. 2.7), ``coulomb_viscous`` (F_s = F_c: no Stribeck
dip) and ``coulomb`` (F_c only). Model evaluation goes through
:func:`cylfric.friction.stribeck_unchecked` (trial steps of the optimiser may leave the
physical range); the result is a :class:`~cylfric.model.FrictionModel` in SI.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal, cast

import numpy as np

from ..friction import params_at_pressure, stribeck_unchecked
from ..friction._checks import roundoff_tolerance
from ..model import PARAMETER_BOUNDS, FrictionModel
from .pressure_fit import (
    SurfaceFit,
    _covariance,
    _grid_start,
    information_criteria,
)
from .stribeck_fit import robust_least_squares

if TYPE_CHECKING:
    from collections.abc import Mapping

    from numpy.typing import ArrayLike

__all__ = ["fit_linear_surface", "COMPONENTS"]

_BAR = 1e5

COMPONENTS = {
    "stribeck": ("F_c", "amplitude", "sigma_2"),
    "coulomb_viscous": ("F_c", "sigma_2"),
    "coulomb": ("F_c",),
}
"""Quantities each friction law fits: F_c [N], the Stribeck amplitude F_s - F_c [N],
sigma_2 [N*s/m]; each >= 0 at the lowest and highest pressure."""

_NOT_IN_LAW = {
    "coulomb_viscous": ("F_s", "v_r", "alpha"),
    "coulomb": ("F_s", "sigma_2", "v_r", "alpha"),
}


def fit_linear_surface(
    velocity: ArrayLike,
    pressure: ArrayLike,
    friction: ArrayLike,
    *,
    friction_law: Literal["stribeck", "coulomb_viscous", "coulomb"] = "stribeck",
    fixed: Mapping[str, Any] | None = None,
    sigma: ArrayLike | None = None,
    groups: ArrayLike | None = None,
    loss: str = "soft_l1",
    reference: str = "mean",
    not_identified: Mapping[str, Any] | None = None,
) -> SurfaceFit:
    """Fit F(v, p) with linear pressure laws, bounded to the physical range.

    Parameters
    ----------
    velocity, pressure, friction : array_like
        Points: [m/s], [Pa] (operating pressure), [N] (friction magnitude).
    friction_law : {"stribeck", "coulomb_viscous", "coulomb"}
        Steady-state law to fit.
    fixed : dict, optional
        Values held (SI): ``v_r`` [m/s], ``alpha`` [-], and ``F_c``, ``F_s`` [N] or
        ``sigma_2`` [N*s/m], which are then held constant at every pressure.
    sigma, groups : array_like, optional
        Standard error of each point [N] (weights) and the run of each point (a
        cluster-robust covariance); see :func:`~cylfric.identify.fit_surface`.
    loss : str
        Loss of :func:`scipy.optimize.least_squares` (robust by default).
    reference : str
        Operating-pressure rule recorded in the model.
    not_identified : dict, optional
        Reasons recorded for the parameters a reduced law leaves out.

    Returns
    -------
    SurfaceFit
        ``at_bounds`` lists the quantities the fit pressed against a physical bound, as
        ``"amplitude at 0.1 bar"`` (the data ask for F_s < F_c there).
    """
    if friction_law not in COMPONENTS:
        raise ValueError(f"unknown friction law {friction_law!r}; valid: {sorted(COMPONENTS)}")
    speed = np.abs(np.asarray(velocity, dtype=float))
    p_bar = np.asarray(pressure, dtype=float) / _BAR
    force = np.asarray(friction, dtype=float)
    fixed = dict(fixed or {})
    unknown = set(fixed) - set(PARAMETER_BOUNDS)
    if unknown:
        raise ValueError(f"unknown fixed parameters {sorted(unknown)}")
    p_lo, p_hi = float(p_bar.min()), float(p_bar.max())
    span = p_hi - p_lo
    frac = (p_bar - p_lo) / span if span > 0 else np.zeros_like(p_bar)
    held = {"F_c": "F_c", "amplitude": "F_s", "sigma_2": "sigma_2"}
    blocks = []  # (quantity, number of fitted values: 0 held, 1 constant, 2 two-point)
    for quantity in COMPONENTS[friction_law]:
        blocks.append((quantity, 0 if held[quantity] in fixed else (2 if span > 0 else 1)))
    shape = [n for n in ("v_r", "alpha") if friction_law == "stribeck" and n not in fixed]
    upper_fc = fixed.get("F_s", math.inf) if friction_law == "stribeck" else math.inf

    def unpack(x):
        out, i = {}, 0
        for quantity, count in blocks:
            if count == 2:
                out[quantity] = x[i] + (x[i + 1] - x[i]) * frac
            elif count == 1:
                out[quantity] = x[i]
            i += count
        out.update(zip(shape, x[i:], strict=True))
        return out

    def model_force(x):
        q = unpack(x)
        F_c = q.get("F_c", fixed.get("F_c"))
        if friction_law != "stribeck":
            F_s, v_r, alpha = F_c, 1.0, 1.0
        else:
            F_s = fixed["F_s"] if "F_s" in fixed else F_c + q["amplitude"]
            v_r, alpha = q.get("v_r", fixed.get("v_r")), q.get("alpha", fixed.get("alpha"))
        sigma_2 = 0.0 if friction_law == "coulomb" else q.get("sigma_2", fixed.get("sigma_2"))
        return stribeck_unchecked(speed, F_c, F_s, v_r, sigma_2, alpha=alpha)

    weight = np.ones_like(force) if sigma is None else 1.0 / np.asarray(sigma, dtype=float)

    def residuals(x):
        return (model_force(x) - force) * weight

    x0, lower, upper = _start(
        speed, p_bar, force, friction_law, fixed, blocks, shape, p_lo, p_hi, upper_fc
    )
    result = robust_least_squares(residuals, x0, (lower, upper), loss)
    res = force - model_force(result.x)
    n_free = result.x.size
    rss = float(res @ res)
    dof = max(force.size - n_free, 1)
    cov_x, dof, influence, nonrobust = _covariance(residuals, result.x, groups, dof)
    names, transform, coefficients = _to_model(
        result.x, blocks, shape, fixed, friction_law, p_lo, span
    )
    pa = np.asarray(pressure, dtype=float)
    _onto_bounds(coefficients, (float(pa.min()), float(pa.max())))
    covariance = transform @ cov_x @ transform.T
    stderr = _stderr(coefficients, names, covariance)
    aic, bic = information_criteria(rss, force.size, n_free)
    model = FrictionModel(
        coefficients,
        pressure_law="linear",
        friction_law=friction_law,
        reference=reference,
        stderr=stderr,
        fixed=tuple(fixed),
        covariance=(names, covariance),
        influence=None if influence is None else (names, influence @ transform.T),
        covariance_nonrobust=(names, transform @ nonrobust @ transform.T),
        statistics={
            "n_points": int(force.size),
            "n_variables": int(n_free),
            "rmse": float(math.sqrt(rss / force.size)),
            "residual_std": float(math.sqrt(rss / max(force.size - n_free, 1))),
            "dof": int(dof),
            "aic": aic,
            "bic": bic,
        },
        provenance={
            "method": f"global surface fit of the {friction_law} law, bounded soft-L1 least "
            "squares, linear pressure laws kept physical (F_c >= 0, F_s >= F_c, sigma_2 >= 0) "
            "over the measured pressures"
        },
        not_identified=not_identified,
    )
    return SurfaceFit(
        model,
        res,
        bool(result.success),
        str(result.message),
        _at_bounds(result, blocks, shape, p_lo, p_hi),
    )


def _start(speed, p_bar, force, friction_law, fixed, blocks, shape, p_lo, p_hi, upper_fc):
    """Starting values (inside the bounds) and the bounds of the fitted values."""
    if friction_law == "stribeck":
        v_r_grid = (
            [fixed["v_r"]]
            if "v_r" in fixed
            else np.geomspace(max(speed.min(), 1e-4) * 0.5, max(speed.max(), 1e-3), 25)
        )
        alpha_grid = [fixed["alpha"]] if "alpha" in fixed else np.linspace(0.4, 3.0, 14)
        coef, v_r0, alpha0 = _grid_start(speed, p_bar, force, v_r_grid, alpha_grid)
        lines = {
            "F_c": (coef[0], coef[1]),
            "amplitude": (coef[2] - coef[0], coef[3] - coef[1]),
            "sigma_2": (coef[4], coef[5]),
        }
    else:
        columns = [np.ones_like(p_bar), p_bar]
        if friction_law == "coulomb_viscous":
            columns += [speed, p_bar * speed]
        coef = np.linalg.lstsq(np.column_stack(columns), force, rcond=None)[0]
        lines = {"F_c": coef[:2], "sigma_2": coef[2:4] if coef.size > 2 else (0.0, 0.0)}
        v_r0 = alpha0 = None
    scale = max(float(np.median(np.abs(force))), 1e-9)
    x0, lower, upper = [], [], []
    for quantity, count in blocks:
        a, b = lines[quantity]
        ends = [a + b * p_lo, a + b * p_hi][:count] if count == 2 else [a + b * np.mean(p_bar)]
        top = upper_fc if quantity == "F_c" else math.inf
        for value in ends[:count]:
            floor = 1e-6 * scale if quantity != "sigma_2" else 1e-9
            value = max(value, floor)
            x0.append(min(value, top * (1 - 1e-9)) if math.isfinite(top) else value)
            lower.append(0.0)
            upper.append(top)
    for name in shape:
        x0.append(v_r0 if name == "v_r" else alpha0)
        lower.append(PARAMETER_BOUNDS[name][0])
        upper.append(PARAMETER_BOUNDS[name][1])
    lower_x, upper_x = np.array(lower), np.array(upper)
    top = np.where(np.isfinite(upper_x), upper_x - 1e-12, np.inf)
    start = np.clip(np.array(x0, dtype=float), lower_x + 1e-12, top)
    return start, lower_x, upper_x


def _to_model(x, blocks, shape, fixed, friction_law, p_lo, span):
    """Model coefficients (SI), their covariance names and d(coefficients)/d(x)."""
    rows: list[np.ndarray] = []
    names: list[str] = []
    coefficients: dict[str, Any] = {}
    # quantity -> (intercept row, slope row) over x, pressure in bar
    lines: dict[str, tuple[np.ndarray, np.ndarray | None]] = {}
    i = 0
    for quantity, count in blocks:
        if count == 2:
            slope = np.zeros(x.size)
            slope[i], slope[i + 1] = -1.0 / span, 1.0 / span
            intercept = np.zeros(x.size)
            intercept[i], intercept[i + 1] = 1.0 + p_lo / span, -p_lo / span
            lines[quantity] = (intercept, slope)
        elif count == 1:
            intercept = np.zeros(x.size)
            intercept[i] = 1.0
            lines[quantity] = (intercept, None)
        i += count
    parts = {"F_c": ["F_c"], "F_s": ["F_c", "amplitude"], "sigma_2": ["sigma_2"]}
    laws = {"stribeck": ("F_c", "F_s", "sigma_2"), "coulomb_viscous": ("F_c", "sigma_2")}
    for par in laws.get(friction_law, ("F_c",)):
        if par in fixed:
            coefficients[par] = {"law": "constant", "intercept": float(fixed[par])}
            continue
        members = [lines[m] for m in parts[par] if m in lines]
        # (members is never empty: a fitted quantity has its lines, so no sum() of nothing)
        intercept = cast("np.ndarray", sum(m[0] for m in members))
        slopes = [m[1] for m in members if m[1] is not None]
        if par == "F_s" and "F_c" in fixed:  # F_s = fixed F_c + amplitude
            shift = float(fixed["F_c"])
        else:
            shift = 0.0
        if slopes:
            slope = cast("np.ndarray", sum(slopes))
            coefficients[par] = {
                "intercept": float(intercept @ x + shift),
                "slope": float(slope @ x) / _BAR,
            }
            names += [f"{par}.intercept", f"{par}.slope"]
            rows += [intercept, slope / _BAR]
        else:
            coefficients[par] = {"law": "constant", "intercept": float(intercept @ x + shift)}
            names.append(par)
            rows.append(intercept)
    for j, name in enumerate(shape):
        coefficients[name] = float(x[i + j])
        row = np.zeros(x.size)
        row[i + j] = 1.0
        names.append(name)
        rows.append(row)
    for name in ("v_r", "alpha"):
        if friction_law == "stribeck" and name in fixed:
            coefficients[name] = float(fixed[name])
    for name in _NOT_IN_LAW.get(friction_law, ()):
        coefficients[name] = None
    return names, np.array(rows), coefficients


def _onto_bounds(coefficients, ends):
    """Put values the bounded fit left on a bound exactly onto it in the written law.

    The fit holds F_c, F_s - F_c and sigma_2 >= 0 at both ends of the measured pressures
    ``ends`` [Pa]; converting the two end values to intercept and slope can leave one of
    them a rounding error below its bound there (sigma_2 = -2.2e-16 N*s/m at 10 bar). Such
    an intercept is raised by that error, in place, so the datasheet holds F_c >= 0,
    F_s >= F_c and sigma_2 >= 0 exactly over the measured range. Anything larger than
    rounding (:func:`~cylfric.friction._checks.roundoff_tolerance`) is left for the
    physical check to refuse.
    """
    ends = np.asarray(ends, dtype=float)

    def at(name):
        spec = coefficients.get(name)
        if spec is None:
            return None
        return np.asarray(params_at_pressure(ends, {name: spec}, law="linear")[name], float)

    for name, bound in (("F_c", None), ("F_s", "F_c"), ("sigma_2", None)):
        spec = coefficients.get(name)
        if not isinstance(spec, dict):
            continue
        for _ in range(4):  # one raise is almost always enough; rounding may need another
            floor = 0.0 if bound is None else at(bound)
            short = float(np.max(floor - at(name)))
            force_tol, sigma_tol = roundoff_tolerance(at("F_c"), at("F_s"), at("sigma_2"))
            tol = float(np.min(sigma_tol if name == "sigma_2" else force_tol))
            if short <= 0 or short > tol:
                break
            raised = spec["intercept"] + short
            if raised == spec["intercept"]:
                raised = float(np.nextafter(raised, math.inf))
            spec["intercept"] = raised


def _stderr(coefficients, names, covariance):
    se = dict(zip(names, np.sqrt(np.clip(np.diag(covariance), 0, None)), strict=True))
    out: dict[str, Any] = {}
    for par, spec in coefficients.items():
        if isinstance(spec, dict):
            if spec.get("law") == "constant":
                out[par] = {"intercept": float(se.get(par, 0.0))}
            else:
                out[par] = {c: float(se[f"{par}.{c}"]) for c in spec if c != "law"}
        elif spec is not None:
            out[par] = float(se.get(par, 0.0))
    return out


def _at_bounds(result, blocks, shape, p_lo, p_hi):
    """Which fitted quantities ended on a bound (``"amplitude at 0.1 bar"``, ``"v_r"``)."""
    active = np.asarray(result.active_mask)
    out, i = [], 0
    for quantity, count in blocks:
        where = [p_lo, p_hi] if count == 2 else [None]
        for k in range(count):
            if active[i + k] != 0:
                at = where[k]
                out.append(quantity if at is None else f"{quantity} at {at:.4g} bar")
        i += count
    out += [name for j, name in enumerate(shape) if active[i + j] != 0]
    return tuple(out)
