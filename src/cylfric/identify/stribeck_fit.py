"""Fit of the steady-state Stribeck law (thesis eq. 2.7) to friction points at one pressure.

``fit_stribeck(velocity, friction)`` returns a frozen :class:`StribeckFit` whose ``params``
plug straight back into :func:`cylfric.friction.stribeck`. Bounded, robust (soft-L1) least
squares from data-driven starting values; any subset of parameters can be held fixed.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from scipy.optimize import least_squares
from scipy.special import stdtrit

from ..friction import (
    NoStribeckMinimumWarning,
    stribeck_jacobian,
    stribeck_shape,
    stribeck_unchecked,
    stribeck_velocity,
)
from ..model import PARAMETER_BOUNDS, STEADY_PARAMETERS

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping

    from numpy.typing import ArrayLike

__all__ = [
    "StribeckFit",
    "fit_stribeck",
    "PARAMETERS",
    "BOUNDS",
    "IdentificationWarning",
    "design_columns",
    "grid_rss",
    "near_minimum",
]

PARAMETERS = STEADY_PARAMETERS
"""Order of the Stribeck parameters in vectors and tables."""

BOUNDS = {name: PARAMETER_BOUNDS[name] for name in PARAMETERS}
"""Bounds of the fit (SI), the model's physical bounds."""

MIN_POINTS = 6
"""Fewest points for a Stribeck fit."""


class IdentificationWarning(UserWarning):
    """The data cannot support part of the model; the result says what was done instead."""


def design_columns(speed: np.ndarray, pressure: np.ndarray, v_r: float, alpha: float) -> np.ndarray:
    """Columns of the model linear in the other coefficients at fixed ``v_r``, ``alpha``.

    Eq. 2.7 with linear pressure laws is linear in (a_c, b_c, a_s, b_s, a_2, b_2):
    F = a_c (1 - e) + b_c p (1 - e) + a_s e + b_s p e + a_2 v + b_2 p v, with
    e = :func:`~cylfric.friction.stribeck_shape`; returns the (n, 6) matrix. ``speed`` [m/s],
    ``pressure`` in any unit (the b coefficients come out per that unit).
    """
    e = stribeck_shape(speed, v_r, alpha)
    return np.column_stack([1 - e, pressure * (1 - e), e, pressure * e, speed, pressure * speed])


def robust_least_squares(
    residuals: Callable[[np.ndarray], np.ndarray],
    x0: ArrayLike,
    bounds: tuple[ArrayLike, ArrayLike],
    loss: str = "soft_l1",
    jac: str | Callable[[np.ndarray], np.ndarray] = "2-point",
) -> Any:
    """Bounded least squares; a robust ``loss`` refit scaled by the first fit's residual spread.

    A plain fit finds the residual spread (1.4826 MAD); the robust refit from there uses it
    as ``f_scale``, so outliers beyond a few sigma lose their pull. Returns the
    :func:`scipy.optimize.least_squares` result.
    """
    first = least_squares(residuals, x0, jac=jac, bounds=bounds, x_scale="jac")
    if loss == "linear":
        return first
    scale = 1.4826 * float(np.median(np.abs(first.fun - np.median(first.fun))))
    return least_squares(
        residuals,
        first.x,
        jac=jac,
        bounds=bounds,
        x_scale="jac",
        loss=loss,
        f_scale=max(scale, 1e-6),
    )


def solve_linear(a: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of ``a @ c ~ y`` by column-scaled normal equations.

    About five times faster than ``numpy.linalg.lstsq`` for the tall, narrow design matrices
    of the sensitivity grid; falls back to ``lstsq`` when the normal matrix is singular.
    """
    scale = np.sqrt(np.einsum("ij,ij->j", a, a))
    scale[scale == 0] = 1.0
    scaled = a / scale
    try:
        coef = np.linalg.solve(scaled.T @ scaled, scaled.T @ y)
    except np.linalg.LinAlgError:
        coef = np.linalg.lstsq(scaled, y, rcond=None)[0]
    return coef / scale


GRID_BLOCK = 2**18
"""Points x nodes :func:`grid_rss` evaluates at once: its work arrays (2 MB of float64
each) stay in the processor's cache."""


def grid_rss(
    speed: np.ndarray, pressure: np.ndarray, force: np.ndarray, v_r: ArrayLike, alpha: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Residual sum of squares [N^2] of the model linear in the six pressure-law coefficients
    (:func:`design_columns`) at many fixed (``v_r`` [m/s], ``alpha`` [-]) nodes at once.

    The design's columns span the same space as ``[1, p, v, p v]``, fixed at every node, and
    ``[e, p e]``, the node's own (``e`` the Stribeck decay): the fixed part is projected out
    once (SVD) and each node solves a 2 x 2 problem on its projected columns, the nodes of
    one ``alpha`` in blocks of stacked rows. The values equal :func:`solve_linear`'s to
    rounding (about 1e-13 relative), not to the bit: callers that need the bit (a start
    value, a minimum) solve the few nodes near the minimum again (:func:`near_minimum`).

    Returns
    -------
    rss : ndarray
        Residual sum of squares at each node [N^2] (NaN where not trusted).
    trusted : ndarray of bool
        False where a node's projected columns are too close to collinear (or zero) for the
        2 x 2 solve to agree with :func:`solve_linear` to rounding; all False when the fixed
        columns are collinear themselves (a single pressure or speed).
    """
    v_r = np.atleast_1d(np.asarray(v_r, dtype=float))
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), v_r.shape)
    rss = np.full(v_r.shape, np.nan)
    trusted = np.zeros(v_r.shape, dtype=bool)
    fixed = np.column_stack([np.ones_like(speed), pressure, speed, pressure * speed])
    fixed = fixed / np.linalg.norm(fixed, axis=0)
    basis, singular, _ = np.linalg.svd(fixed, full_matrices=False)
    if singular[-1] < 1e-8 * singular[0]:  # collinear fixed columns: no shortcut
        return rss, trusted
    y = force - basis @ (basis.T @ force)  # the force the fixed columns do not explain
    products = np.column_stack([y, pressure * y, basis, pressure[:, None] * basis])
    weights = np.column_stack([np.ones_like(pressure), pressure, pressure**2])
    columns = basis.T.copy()  # (4, points)
    block = max(1, GRID_BLOCK // max(speed.size, 1))
    for value in np.unique(alpha):
        powered = speed**value  # (v / v_r)^alpha = v^alpha * v_r^-alpha
        members = np.flatnonzero(alpha == value)
        for first in range(0, members.size, block):
            nodes = members[first : first + block]
            e = np.multiply(v_r[nodes, None] ** -value, powered)  # (nodes, points)
            np.exp(-e, out=e)
            dots = e @ products  # e.y, (p e).y, Q^T e, Q^T (p e)
            squares = (e * e) @ weights  # e.e, e.(p e), (p e).(p e)
            qe, qpe = dots[:, 2:6], dots[:, 6:10]
            # Gram of the projected columns [e, p e]; cancellation below 1e-8: not trusted
            g00 = squares[:, 0] - np.einsum("ij,ij->i", qe, qe)
            g01 = squares[:, 1] - np.einsum("ij,ij->i", qe, qpe)
            g11 = squares[:, 2] - np.einsum("ij,ij->i", qpe, qpe)
            ok = (g00 > 1e-8 * squares[:, 0]) & (g11 > 1e-8 * squares[:, 2])
            n0 = np.sqrt(np.where(ok, g00, 1.0))
            n1 = np.sqrt(np.where(ok, g11, 1.0))
            cos = g01 / (n0 * n1)  # the 2 x 2 problem scaled to unit columns
            det = 1.0 - cos**2
            ok &= det > 1e-8
            det = np.where(ok, det, 1.0)
            p0, p1 = dots[:, 0] / n0, dots[:, 1] / n1
            c0 = (p0 - cos * p1) / det / n0
            c1 = (p1 - cos * p0) / det / n1
            # residual y_perp - (w - Q Q^T w), w = c0 e + c1 p e, formed in place
            e *= c0[:, None] + c1[:, None] * pressure
            np.subtract(y, e, out=e)
            shift = c0[:, None] * qe + c1[:, None] * qpe  # Q^T w
            e += shift @ columns
            rss[nodes] = np.where(ok, np.einsum("ij,ij->i", e, e), np.nan)
            trusted[nodes] = ok
    return rss, trusted


def near_minimum(rss: np.ndarray, trusted: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Nodes of :func:`grid_rss` to re-evaluate exactly: untrusted ones and those within
    rounding of the smallest trusted RSS (relative 1e-6, absolute 1e-9 ||force||^2 [N^2]),
    so that the exact minimum over all nodes is among them."""
    if not trusted.any():
        return np.ones(rss.shape, dtype=bool)
    least = float(np.min(rss[trusted]))
    margin = 1e-6 * least + 1e-9 * float(force @ force)
    return ~trusted | (rss <= least + margin)


@dataclass(frozen=True)
class StribeckFit:
    """Result of :func:`fit_stribeck` (SI units).

    Attributes
    ----------
    params : dict
        F_c [N], F_s [N], sigma_2 [N*s/m], v_r [m/s], alpha [-].
    stderr : dict
        Standard errors (0 for fixed parameters).
    ci95 : dict
        95 % confidence intervals (low, high).
    covariance : ndarray
        Covariance of the free parameters, in the order of ``free``.
    free : tuple
        Names of the fitted parameters.
    residuals : ndarray
        Data minus model [N].
    rmse : float
        Root-mean-square error, the thesis' "SME" (eq. 4.4) [N].
    stribeck_velocity : float
        Velocity of minimum friction [m/s] (NaN if none).
    n_points : int
    success : bool
    message : str
    """

    params: dict
    stderr: dict
    ci95: dict
    covariance: np.ndarray
    free: tuple
    residuals: np.ndarray
    rmse: float
    stribeck_velocity: float
    n_points: int
    success: bool
    message: str
    extra: dict = field(default_factory=dict)

    def report(self) -> str:
        """A plain-text table of the parameters with standard errors, in engineering units."""
        units = {
            "F_c": ("N", 1),
            "F_s": ("N", 1),
            "sigma_2": ("N*s/mm", 1e-3),
            "v_r": ("mm/s", 1e3),
            "alpha": ("-", 1),
        }
        lines = [f"Stribeck fit ({self.n_points} points, RMSE {self.rmse:.3f} N): {self.message}"]
        for name in PARAMETERS:
            unit, k = units[name]
            fixed = "" if name in self.free else "  (fixed)"
            lines.append(
                f"  {name:8s} = {self.params[name] * k:10.4g} ± "
                f"{self.stderr[name] * k:.2g} {unit}{fixed}"
            )
        lines.append(f"  v_Stribeck = {self.stribeck_velocity * 1e3:.3g} mm/s")
        return "\n".join(lines)


def _start_values(speed, friction, fixed):
    order = np.argsort(speed)
    v, f = speed[order], friction[order]
    fast = v >= np.quantile(v, 0.7)
    if fast.sum() >= 2 and np.ptp(v[fast]) > 0:
        slope, intercept = np.polyfit(v[fast], f[fast], 1)
    else:
        slope, intercept = 0.0, float(np.median(f))
    slope = max(slope, 0.0)
    low = f[: max(2, len(f) // 10)]
    start = {
        "F_c": max(float(intercept), 1e-3),
        "F_s": max(float(np.max(low)), 1e-3),
        "sigma_2": float(slope),
        "v_r": float(np.clip(np.quantile(v, 0.25), 1e-4, 1.0)),
        "alpha": 1.0,
    }
    if start["F_s"] < start["F_c"]:
        start["F_s"] = start["F_c"]
    start.update(fixed)
    return start


def fit_stribeck(
    velocity: ArrayLike,
    friction: ArrayLike,
    *,
    fixed: Mapping[str, Any] | None = None,
    loss: Literal["linear", "soft_l1", "huber"] = "soft_l1",
    start: Mapping[str, Any] | None = None,
) -> StribeckFit:
    """Fit eq. 2.7 to steady-state points.

    Parameters
    ----------
    velocity : array_like
        Velocities [m/s]; the symmetric model uses |v|.
    friction : array_like
        Friction magnitudes [N] (after the weight offset is removed).
    fixed : dict, optional
        Parameters held at given values (SI), e.g. ``{"alpha": 1.0, "v_r": 0.010}``.
    loss : {"linear", "soft_l1", "huber"}
        Loss of :func:`scipy.optimize.least_squares`; robust losses are scaled by the
        residual spread of a first linear fit.
    start : dict, optional
        Starting values (default: from the data).

    Returns
    -------
    StribeckFit

    Raises
    ------
    ValueError
        NaN input, fewer than 6 points, or unknown fixed names.
    """
    speed = np.abs(np.asarray(velocity, dtype=float))
    force = np.asarray(friction, dtype=float)
    if speed.shape != force.shape:
        raise ValueError("velocity and friction must have the same length")
    if np.isnan(speed).any() or np.isnan(force).any():
        raise ValueError("velocity or friction contains NaN; drop flagged points first")
    if speed.size < MIN_POINTS:
        raise ValueError(
            f"{speed.size} points are too few for a Stribeck fit; expected at least {MIN_POINTS}"
        )
    fixed = dict(fixed or {})
    unknown = set(fixed) - set(PARAMETERS)
    if unknown:
        raise ValueError(f"unknown fixed parameters {sorted(unknown)}; valid: {list(PARAMETERS)}")
    free = tuple(p for p in PARAMETERS if p not in fixed)
    s = {**_start_values(speed, force, fixed), **(start or {})}
    bounds = {p: BOUNDS[p] for p in free}
    # F_s >= F_c: fitted as F_c plus a non-negative Stribeck amplitude when both are free
    amplitude = "F_c" in free and "F_s" in free
    if amplitude:
        bounds["F_s"] = (0.0, np.inf)
        s["F_s"] = max(s["F_s"] - s["F_c"], 1e-6 * max(abs(s["F_c"]), 1.0))
    elif "F_c" in free and "F_s" in fixed:
        bounds["F_c"] = (BOUNDS["F_c"][0], fixed["F_s"])
    elif "F_s" in free and "F_c" in fixed:
        bounds["F_s"] = (fixed["F_c"], BOUNDS["F_s"][1])
    lower = np.array([bounds[p][0] for p in free])
    upper = np.array([bounds[p][1] for p in free])
    x0 = np.clip([s[p] for p in free], lower + 1e-12, upper - 1e-12)

    def unpack(x):
        params = {**fixed, **dict(zip(free, x, strict=True))}
        if amplitude:
            params["F_s"] = params["F_c"] + params["F_s"]
        return params

    def residuals(x):
        return stribeck_unchecked(speed, **unpack(x)) - force

    def jacobian(x):  # analytic: 4x fewer model evaluations than finite differences
        partial = stribeck_jacobian(speed, **unpack(x))
        if amplitude:  # F_s = F_c + amplitude
            partial["F_c"] = partial["F_c"] + partial["F_s"]
        return np.column_stack([partial[p] for p in free])

    result = robust_least_squares(residuals, x0, (lower, upper), loss, jac=jacobian)
    params = unpack(result.x)
    res = -result.fun  # data minus model
    dof = max(speed.size - len(free), 1)
    sigma2 = float(res @ res) / dof
    jac = result.jac
    try:
        covariance = np.linalg.pinv(jac.T @ jac) * sigma2
    except np.linalg.LinAlgError:  # pragma: no cover - pinv is robust
        covariance = np.full((len(free), len(free)), np.nan)
    if amplitude:  # (F_c, amplitude) -> (F_c, F_s = F_c + amplitude)
        transform = np.eye(len(free))
        transform[free.index("F_s"), free.index("F_c")] = 1.0
        covariance = transform @ covariance @ transform.T
    se = np.sqrt(np.clip(np.diag(covariance), 0, None))
    tq = float(stdtrit(dof, 0.975))
    stderr = {p: 0.0 for p in PARAMETERS}
    stderr.update(dict(zip(free, se, strict=True)))
    ci95 = {p: (params[p] - tq * stderr[p], params[p] + tq * stderr[p]) for p in PARAMETERS}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NoStribeckMinimumWarning)
        vs = stribeck_velocity(
            params["F_c"], params["F_s"], params["v_r"], params["sigma_2"], alpha=params["alpha"]
        )
    return StribeckFit(
        params={p: float(params[p]) for p in PARAMETERS},
        stderr={p: float(v) for p, v in stderr.items()},
        ci95=ci95,
        covariance=covariance,
        free=free,
        residuals=res,
        rmse=float(math.sqrt(np.mean(res**2))),
        stribeck_velocity=float(vs),
        n_points=int(speed.size),
        success=bool(result.success),
        message=str(result.message),
    )
