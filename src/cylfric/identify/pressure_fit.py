"""Pressure dependence of the friction parameters (thesis ch. 4, eq. 4.1-4.3), two ways.

(a) :func:`regress_parameters`: each per-pressure parameter regressed on pressure with the
    pressure laws of :mod:`cylfric.friction.pressure`, weighted by its uncertainty.
(b) :func:`fit_surface`: one fit of the whole surface F(v, p) with the pressure laws built in
    (F_c, F_s, sigma_2 pressure dependent; v_r and alpha shared). The starting point comes
    from a grid over (v_r, alpha) where the rest of the model is linear (variable projection).
    It returns a :class:`~cylfric.model.FrictionModel` with the covariance of its coefficients.

Both report AIC and BIC so linear, quadratic and exponential laws can be compared. Every
model evaluation goes through :mod:`cylfric.friction` (eq. 2.7 and the pressure laws).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from scipy.optimize import curve_fit

from ..friction import stribeck_unchecked
from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS, PRESSURE_LAWS, exponential_by_slope
from ..model import PARAMETER_BOUNDS, FrictionModel
from .stribeck_fit import (
    design_columns,
    grid_rss,
    near_minimum,
    robust_least_squares,
    solve_linear,
)

if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping

    from numpy.typing import ArrayLike

__all__ = [
    "PressureLawFit",
    "regress_parameters",
    "SurfaceFit",
    "fit_surface",
    "information_criteria",
    "PRESSURE_DEPENDENT",
    "FITTED_LAWS",
]

PRESSURE_DEPENDENT = ("F_c", "F_s", "sigma_2")
"""Parameters that carry a pressure law; v_r and alpha are shared."""

FITTED_LAWS = ("linear", "quadratic", "exponential")
"""Pressure laws the identification fits and compares."""

_BAR = 1e5
_TO_SI = {
    "intercept": 1.0,
    "slope": 1 / _BAR,
    "curvature": 1 / _BAR**2,
    "amplitude": 1.0,
    "rate": 1 / _BAR,
}
"""Factor from a coefficient fitted with the pressure in bar to SI (pressure in Pa)."""


_MIN_RATE = 1e-9  # [1/bar]: below it the exponential law is the linear law


def _rate(c):
    """The exponential rate [1/bar] kept away from 0 (where amplitude = slope / rate)."""
    return c if abs(c) >= _MIN_RATE else math.copysign(_MIN_RATE, c)


def information_criteria(rss: float, n: int, k: int) -> tuple[float, float]:
    """Gaussian AIC and BIC from the residual sum of squares ``rss`` [N^2]."""
    n = max(n, 1)
    rss = max(rss, 1e-300)
    return n * math.log(rss / n) + 2 * k, n * math.log(rss / n) + k * math.log(n)


def _law_in_bar(law):
    """The pressure law as fitted (pressure in bar; exponential by its initial slope)."""
    return exponential_by_slope if law == "exponential" else PRESSURE_LAWS[law]


def _to_si(law, coef, cov):
    """Coefficients and covariance fitted in bar (exponential: slope form) -> the law in SI.

    Returns ({name: value [SI]}, covariance [SI]) by the first-order delta rule.
    """
    coef = np.asarray(coef, dtype=float)
    jac = _block_jacobian(law, coef)
    if law == "exponential":  # (a, s, c) -> (a, s / c, c)
        a, s, c = coef
        c = _rate(c)
        coef = np.array([a, s / c, c])
    names = PRESSURE_LAW_COEFFICIENTS[law]
    values = {n: float(v * _TO_SI[n]) for n, v in zip(names, coef, strict=True)}
    return values, jac @ cov @ jac.T if cov is not None else None


@dataclass(frozen=True)
class PressureLawFit:
    """One parameter regressed on pressure with one law (route a).

    ``coefficients`` and ``stderr`` in SI (e.g. N and N/Pa), ``aic``/``bic`` from the
    weighted residuals, ``n`` levels. ``spec`` is the entry for a coefficient set.
    """

    parameter: str
    law: str
    coefficients: dict
    stderr: dict
    aic: float
    bic: float
    n: int

    @property
    def spec(self) -> dict:
        """``{"law": ..., coefficients}`` for :func:`cylfric.friction.params_at_pressure`."""
        return {"law": self.law, **self.coefficients}


def regress_parameters(
    pressure: ArrayLike,
    values: ArrayLike,
    stderr: ArrayLike | None = None,
    *,
    parameter: str = "",
    laws: Iterable[str] = ("linear",),
) -> dict[str, PressureLawFit]:
    """Weighted regression of one parameter on pressure with each law in ``laws``.

    Parameters
    ----------
    pressure : array_like
        Pressure levels [Pa].
    values, stderr : array_like
        Parameter values and their standard errors (weights 1/stderr^2; equal weights when
        absent or zero).
    laws : iterable of str
        Pressure laws to try; laws with at least as many coefficients as levels are skipped.

    Returns
    -------
    dict of law -> PressureLawFit
    """
    p_bar = np.asarray(pressure, dtype=float) / _BAR
    y = np.asarray(values, dtype=float)
    se = None if stderr is None else np.asarray(stderr, dtype=float)
    if se is not None and (np.any(~np.isfinite(se)) or np.any(se <= 0)):
        se = None
    out = {}
    for law in laws:
        names = PRESSURE_LAW_COEFFICIENTS[law]
        if len(p_bar) <= len(names):
            continue
        line = np.polyfit(p_bar, y, 1)[::-1]
        p0 = {
            "linear": line,
            "quadratic": np.polyfit(p_bar, y, 2)[::-1],
            "exponential": [*line, 1e-4],
        }[law]
        function = _law_in_bar(law)
        try:
            coef, cov = curve_fit(
                lambda p, *c, f=function: f(p, *c),
                p_bar,
                y,
                p0=p0,
                sigma=se,
                absolute_sigma=se is not None,
                maxfev=20000,
            )
        except RuntimeError:
            continue
        resid = (y - function(p_bar, *coef)) / (se if se is not None else 1.0)
        aic, bic = information_criteria(float(resid @ resid), len(y), len(names))
        values_si, cov_si = _to_si(law, coef, cov)
        errs = np.sqrt(np.clip(np.diag(cov_si), 0, None))
        out[law] = PressureLawFit(
            parameter,
            law,
            values_si,
            {n: float(e) for n, e in zip(names, errs, strict=True)},
            aic,
            bic,
            len(y),
        )
    return out


@dataclass(frozen=True)
class SurfaceFit:
    """Result of :func:`fit_surface`: the model and how the fit went.

    ``model`` is the fitted :class:`~cylfric.model.FrictionModel` (covariance, statistics);
    ``residuals`` are data minus model [N], in the order of the points; ``at_bounds`` names
    what the fit pressed against a physical bound (:func:`fit_linear_surface`).
    """

    model: FrictionModel
    residuals: np.ndarray
    success: bool
    message: str
    at_bounds: tuple = ()


def _grid_start(speed, p_bar, force, v_r_grid, alpha_grid):
    """Coefficients, v_r and alpha of the grid node of least RSS (variable projection).

    All nodes are screened at once (:func:`grid_rss`); the few near the minimum are solved
    again one by one with :func:`solve_linear`, which decides (in grid order, the first of
    equal values), so the start is the same as solving every node that way.
    """
    nodes = [(v_r, alpha) for v_r in v_r_grid for alpha in alpha_grid]
    screened, trusted = grid_rss(speed, p_bar, force, [n[0] for n in nodes], [n[1] for n in nodes])
    best: tuple[float, Any] = (np.inf, None)
    for (v_r, alpha), candidate in zip(nodes, near_minimum(screened, trusted, force), strict=True):
        if not candidate:
            continue
        a = design_columns(speed, p_bar, v_r, alpha)
        coef = solve_linear(a, force)
        rss = float(np.sum((a @ coef - force) ** 2))
        if rss < best[0]:
            best = (rss, (coef, v_r, alpha))
    return best[1]


def fit_surface(
    velocity: ArrayLike,
    pressure: ArrayLike,
    friction: ArrayLike,
    *,
    pressure_law: str = "linear",
    fixed: Mapping[str, Any] | None = None,
    loss: str = "soft_l1",
    start: FrictionModel | None = None,
    reference: str = "mean",
    sigma: ArrayLike | None = None,
    groups: ArrayLike | None = None,
) -> SurfaceFit:
    """One fit of the whole surface F(v, p) with pressure laws for F_c, F_s and sigma_2.

    Parameters
    ----------
    velocity, pressure, friction : array_like
        Points: [m/s], [Pa] (operating pressure), [N] (friction magnitude).
    pressure_law : {"linear", "quadratic", "exponential"}
        Pressure law of F_c, F_s and sigma_2.
    fixed : dict, optional
        ``v_r`` [m/s] and/or ``alpha`` [-] held fixed.
    loss : str
        Loss of :func:`scipy.optimize.least_squares` (robust by default).
    start : FrictionModel, optional
        A linear-law model of the same points whose coefficients, v_r and alpha start this
        fit (skips the grid search; used to compare laws).
    reference : str
        Operating-pressure rule recorded in the model.
    sigma : array_like, optional
        Standard error of each point [N]: weighted least squares (weights 1/sigma^2).
    groups : array_like, optional
        Label of the run each point comes from. Points of one run share its errors (both
        directions of a run share its offset), so the covariance is cluster-robust by run
        (a sandwich estimator, also robust to unequal scatter); without groups it is the
        classical one, scaled by the residual variance.

    Returns
    -------
    SurfaceFit
    """
    speed = np.abs(np.asarray(velocity, dtype=float))
    p_bar = np.asarray(pressure, dtype=float) / _BAR
    force = np.asarray(friction, dtype=float)
    fixed = dict(fixed or {})
    unknown = set(fixed) - {"v_r", "alpha"}
    if unknown:
        raise ValueError(
            f"only v_r and alpha can be fixed in the surface fit; got {sorted(unknown)}"
        )
    if pressure_law not in FITTED_LAWS:
        raise ValueError(f"unknown pressure law {pressure_law!r}; valid: {list(FITTED_LAWS)}")
    v_r_grid = (
        [fixed["v_r"]]
        if "v_r" in fixed
        else np.geomspace(max(speed.min(), 1e-4) * 0.5, max(speed.max(), 1e-3), 25)
    )
    alpha_grid = [fixed["alpha"]] if "alpha" in fixed else np.linspace(0.4, 3.0, 14)
    if start is not None and start.laws["F_c"] == "linear":
        coef = [
            cast("float", start.parameters[f"{par}.{key}"].value)  # set: F_c is linear
            * (_BAR if key == "slope" else 1.0)
            for par in PRESSURE_DEPENDENT
            for key in ("intercept", "slope")
        ]
        v_r0, alpha0 = start.parameters["v_r"].value, start.parameters["alpha"].value
    else:
        coef, v_r0, alpha0 = _grid_start(speed, p_bar, force, v_r_grid, alpha_grid)
    names = PRESSURE_LAW_COEFFICIENTS[pressure_law]
    k = len(names)
    x0: list[Any] = []  # floats (a start model's v_r, alpha: float | None)
    for j in range(3):  # the linear coefficients (pressure in bar), then higher-order terms
        a, b = coef[2 * j], coef[2 * j + 1]
        extra = {"linear": [], "quadratic": [0.0], "exponential": [1e-4]}[pressure_law]
        x0 += [a, b, *extra]
    shared = [n for n in ("v_r", "alpha") if n not in fixed]
    x0 += [v_r0 if n == "v_r" else alpha0 for n in shared]
    lower = [-np.inf] * (3 * k) + [PARAMETER_BOUNDS[n][0] for n in shared]
    upper = [np.inf] * (3 * k) + [PARAMETER_BOUNDS[n][1] for n in shared]
    function = _law_in_bar(pressure_law)

    weight = np.ones_like(force) if sigma is None else 1.0 / np.asarray(sigma, dtype=float)
    if not (np.all(np.isfinite(weight)) and np.all(weight > 0)):
        raise ValueError("sigma must be finite and > 0 N for every point")

    def model_force(x):
        values = [function(p_bar, *x[j * k : (j + 1) * k]) for j in range(3)]
        sh = {**fixed, **dict(zip(shared, x[3 * k :], strict=True))}
        return stribeck_unchecked(  # type: ignore[call-arg, misc]  # values[:2]: F_c, F_s
            speed, *values[:2], sh["v_r"], values[2], alpha=sh["alpha"]
        )

    def residuals(x):
        return (model_force(x) - force) * weight

    start_x = np.clip(x0, np.array(lower) + 1e-12, np.array(upper) - 1e-12)
    result = robust_least_squares(residuals, start_x, (lower, upper), loss)
    res = force - model_force(result.x)  # data minus model [N]
    n_free = len(result.x)
    dof = max(force.size - n_free, 1)
    rss = float(res @ res)
    cov_x, dof, influence, nonrobust = _covariance(residuals, result.x, groups, dof)
    # to SI and the model's coefficient names, block by block (delta rule)
    transform = np.eye(n_free)
    coefficients, cov_names = {}, []
    for j, par in enumerate(PRESSURE_DEPENDENT):
        block = slice(j * k, (j + 1) * k)
        coefficients[par], _ = _to_si(pressure_law, result.x[block], None)
        transform[block, block] = _block_jacobian(pressure_law, result.x[block])
        cov_names += [f"{par}.{n}" for n in names]
    for i, n in enumerate(shared):
        coefficients[n] = float(result.x[3 * k + i])
        cov_names.append(n)
    for n, value in fixed.items():
        coefficients[n] = float(value)
    covariance = transform @ cov_x @ transform.T
    aic, bic = information_criteria(rss, force.size, n_free)
    stderr = _stderr_of(coefficients, cov_names, covariance, fixed)
    model = FrictionModel(
        coefficients,
        pressure_law=pressure_law,
        reference=reference,
        stderr=stderr,
        fixed=tuple(fixed),
        covariance=(cov_names, covariance),
        influence=None if influence is None else (cov_names, influence @ transform.T),
        covariance_nonrobust=(cov_names, transform @ nonrobust @ transform.T),
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
            "method": "global surface fit, bounded soft-L1 least squares "
            f"({pressure_law} pressure laws)"
        },
    )
    return SurfaceFit(model, res, bool(result.success), str(result.message))


def _covariance(residuals, x, groups, dof):
    """Covariance of the fitted coefficients, its degrees of freedom and the runs' influence.

    ``residuals`` are the weighted residuals; their Jacobian is taken by central
    differences (the robust loss's own Jacobian is reweighted). Without ``groups``:
    ``s^2 (J^T J)^-1``. With groups (runs): the cluster-robust CR2 sandwich
    ``(J^T J)^-1 (sum_g J_g^T A_g r_g r_g^T A_g J_g) (J^T J)^-1`` with
    ``A_g = (I - H_gg)^(-1/2)`` (Bell & McCaffrey 2002; Cameron & Miller 2015) and G - K
    degrees of freedom. The third value is the influence of each run, ``D`` (runs x
    coefficients, None without groups) with ``covariance = D.T @ D``: it gives the model's
    bands each point's effective degrees of freedom, as Imbens & Kolesar (2016) recommend
    with CR2 when few runs carry a coefficient. The fourth is the model-based
    ``s^2 (J^T J)^-1`` (the first, where there are no groups): the bands of new data of the
    same mount use it (FrictionModel.prediction_band).
    """
    r = residuals(x)
    steps = 1e-6 * np.maximum(np.abs(x), 1e-3)
    jac = np.column_stack(
        [
            (residuals(x + h * e) - residuals(x - h * e)) / (2 * h)
            for h, e in zip(steps, np.eye(x.size), strict=True)
        ]
    )
    return _cluster_robust(jac, r, groups, dof)


_STACK = 2**20
"""Matrix elements per stacked array of :func:`_cluster_robust` (8 MB of float64)."""


def _cluster_robust(jac, r, groups, dof):
    """:func:`_covariance` from the Jacobian ``jac`` (points x coefficients) of the weighted
    residuals ``r`` (points): the same four values.

    The runs' CR2 adjustments are computed for all runs of one size at once (stacked
    ``(runs, m, m)`` arrays through :func:`numpy.linalg.eigh`), so the cost grows with the
    number of points, not with points x runs.
    """
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    scaled = jac / scale
    bread = np.linalg.pinv(scaled.T @ scaled) / np.outer(scale, scale)
    k = jac.shape[1]
    nonrobust = bread * float(r @ r) / dof
    if groups is None:
        return nonrobust, dof, None, nonrobust
    labels, index = np.unique(np.asarray(groups), return_inverse=True)
    g = labels.size
    if g <= k:
        return nonrobust, dof, None, nonrobust
    # cluster-robust CR2 (Bell & McCaffrey 2002): each run's residuals scaled by
    # (I - H_gg)^(-1/2), robust to unequal scatter and to the high leverage of the few
    # fastest runs; with each point's effective degrees of freedom (FrictionModel.band)
    # this is the combination Imbens & Kolesar (2016) recommend for few dominant clusters
    information = scaled.T @ scaled
    inverse = np.linalg.pinv(information)
    influence = np.empty((g, k))
    index = index.reshape(-1)
    sizes = np.bincount(index, minlength=g)
    order = np.argsort(index, kind="stable")  # each run's points together, in their order
    starts = np.cumsum(sizes) - sizes
    for m in np.unique(sizes):  # the runs with m points each, as stacked arrays
        same = np.flatnonzero(sizes == m)
        step = max(1, _STACK // (m * max(m, k)))  # runs per stack: memory bounded
        for first in range(0, same.size, step):
            runs = same[first : first + step]
            rows = order[starts[runs, None] + np.arange(m)]  # (runs, m)
            js = scaled[rows]  # (runs, m, k)
            js_t = js.transpose(0, 2, 1)
            leverage, vectors = np.linalg.eigh(js @ inverse @ js_t)  # of H_gg
            root = np.sqrt(np.clip(1.0 - leverage, 1e-12, None))
            adjust = (vectors / root[:, None, :]) @ vectors.transpose(0, 2, 1)
            score = js_t @ (adjust @ r[rows][..., None])  # J_g^T A_g r_g: (runs, k, 1)
            influence[runs] = (inverse @ score)[..., 0] / scale
    return influence.T @ influence, g - k, influence, nonrobust


def _block_jacobian(law, coef):
    """d(SI coefficients)/d(fitted coefficients) of one parameter's pressure law.

    Fitted: pressure in bar, the exponential law by its initial slope (a, s, c); SI: the
    law's own coefficients with the pressure in Pa.
    """
    jac = np.eye(len(coef))
    if law == "exponential":
        _, s, c = coef
        c = _rate(c)
        jac = np.array([[1, 0, 0], [0, 1 / c, -s / c**2], [0, 0, 1]])
    scale = np.diag([_TO_SI[n] for n in PRESSURE_LAW_COEFFICIENTS[law]])
    return scale @ jac


def _stderr_of(coefficients, names, covariance, fixed):
    """Standard errors mirroring ``coefficients`` from the covariance (0 for held values)."""
    se = dict(zip(names, np.sqrt(np.clip(np.diag(covariance), 0, None)), strict=True))
    out: dict[str, Any] = {}
    for par, spec in coefficients.items():
        if isinstance(spec, dict):
            out[par] = {c: float(se[f"{par}.{c}"]) for c in spec}
        else:
            out[par] = 0.0 if par in fixed else float(se[par])
    return out
