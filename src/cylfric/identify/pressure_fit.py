"""Pressure dependence of the friction parameters (thesis ch. 4, eq. 4.1-4.3), two ways.

(a) :func:`regress_parameters`: each per-pressure parameter regressed on pressure with the
    pressure laws of :mod:`cylfric.friction.pressure`, weighted by its uncertainty.
(b) :func:`fit_surface`: one fit of the whole surface F(v, p) with the pressure laws built in
    (F_c, F_s, sigma_2 pressure dependent; v_r and alpha shared). The starting point comes
    from a grid over (v_r, alpha) where the rest of the model is linear (variable projection).

Both report AIC and BIC so linear, quadratic and exponential laws can be compared.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import curve_fit

from ..friction import params_at_pressure, stribeck
from ..friction.pressure import PRESSURE_LAWS
from .stribeck_fit import design_columns, robust_least_squares, solve_linear

__all__ = [
    "LawFit",
    "regress_parameters",
    "SurfaceFit",
    "fit_surface",
    "information_criteria",
    "PRESSURE_DEPENDENT",
    "LAW_COEFFICIENTS",
]

PRESSURE_DEPENDENT = ("F_c", "F_s", "sigma_2")
"""Parameters that carry a pressure law; v_r and alpha are shared."""

LAW_COEFFICIENTS = {
    "linear": ("intercept", "slope"),
    "quadratic": ("intercept", "slope", "curvature"),
    "exponential": ("intercept", "amplitude", "rate"),
}
"""Coefficient names of each scalar pressure law (SI: unit, unit/Pa, unit/Pa^2, 1/Pa)."""

_BAR = 1e5
_TO_SI = {
    "intercept": 1.0,
    "slope": 1 / _BAR,
    "curvature": 1 / _BAR**2,
    "amplitude": 1.0,
    "rate": 1 / _BAR,
}
"""Factor from the fitted coefficient (pressure in bar) to SI (pressure in Pa)."""
_MIN_RATE = 1e-9  # [1/bar]: below it the exponential law is the linear law


def _exp_slope_form(p_bar, a, s, c):
    """a + s (exp(c p) - 1) / c: the exponential law by its initial slope s (well posed at c=0)."""
    c = np.where(np.abs(c) < _MIN_RATE, _MIN_RATE, c)
    return a + s * np.expm1(c * p_bar) / c


def _exp_to_law(a, s, c):
    """(intercept, amplitude, rate) of the exponential law, pressure in bar."""
    c = c if abs(c) >= _MIN_RATE else _MIN_RATE
    return a, s / c, c


def information_criteria(rss, n, k):
    """Gaussian AIC and BIC from the residual sum of squares ``rss`` [N^2]."""
    n = max(n, 1)
    rss = max(rss, 1e-300)
    return n * math.log(rss / n) + 2 * k, n * math.log(rss / n) + k * math.log(n)


@dataclass(frozen=True)
class LawFit:
    """One parameter regressed on pressure with one law.

    ``coefficients`` and ``stderr`` in SI (e.g. N and N/Pa), ``aic``/``bic`` from the
    weighted residuals, ``n`` levels.
    """

    parameter: str
    law: str
    coefficients: dict
    stderr: dict
    aic: float
    bic: float
    n: int

    def __call__(self, pressure):
        """Evaluate the law at ``pressure`` [Pa]."""
        return PRESSURE_LAWS[self.law](pressure, **self.coefficients)


def regress_parameters(pressure, values, stderr=None, *, parameter="", laws=("linear",)):
    """Weighted regression of one parameter on pressure with each law in ``laws``.

    Parameters
    ----------
    pressure : array_like
        Pressure levels [Pa].
    values, stderr : array_like
        Parameter values and their standard errors (weights 1/stderr^2; equal weights when
        absent or zero).
    laws : iterable of str
        Pressure laws to try; laws with more coefficients than levels are skipped.

    Returns
    -------
    dict of law -> LawFit
    """
    p_bar = np.asarray(pressure, dtype=float) / _BAR
    y = np.asarray(values, dtype=float)
    se = None if stderr is None else np.asarray(stderr, dtype=float)
    if se is not None and (np.any(~np.isfinite(se)) or np.any(se <= 0)):
        se = None
    out = {}
    for law in laws:
        names = LAW_COEFFICIENTS[law]
        if len(p_bar) <= len(names):
            continue
        if law == "linear":

            def f(p, a, b):
                return a + b * p

            p0 = np.polyfit(p_bar, y, 1)[::-1]
        elif law == "quadratic":

            def f(p, a, b, c):
                return a + b * p + c * p * p

            p0 = np.polyfit(p_bar, y, 2)[::-1]
        else:
            f = _exp_slope_form
            p0 = [*np.polyfit(p_bar, y, 1)[::-1], 1e-4]
        try:
            coef, cov = curve_fit(
                f, p_bar, y, p0=p0, sigma=se, absolute_sigma=se is not None, maxfev=20000
            )
        except RuntimeError:
            continue
        resid = (y - f(p_bar, *coef)) / (se if se is not None else 1.0)
        aic, bic = information_criteria(float(resid @ resid), len(y), len(names))
        if law == "exponential":  # back to (intercept, amplitude, rate); errors by the delta rule
            a, s, c = coef
            coef = np.array(_exp_to_law(a, s, c))
            cov = _exp_covariance(cov, s, coef[2])
        errs = np.sqrt(np.clip(np.diag(cov), 0, None))
        out[law] = LawFit(
            parameter,
            law,
            {n: float(c * _TO_SI[n]) for n, c in zip(names, coef, strict=True)},
            {n: float(e * _TO_SI[n]) for n, e in zip(names, errs, strict=True)},
            aic,
            bic,
            len(y),
        )
    return out


def _exp_covariance(cov, s, c):
    """Covariance of (a, s/c, c) from that of (a, s, c) (first-order delta rule)."""
    jac = np.array([[1, 0, 0], [0, 1 / c, -s / c**2], [0, 0, 1]])
    return jac @ cov @ jac.T


@dataclass(frozen=True)
class SurfaceFit:
    """Global fit of F(v, p) (SI).

    ``coefficients`` is a pressure coefficient set (plugs into
    :func:`cylfric.friction.params_at_pressure`); ``stderr`` mirrors it.
    """

    law: str
    coefficients: dict
    stderr: dict
    rmse: float
    aic: float
    bic: float
    n_points: int
    residuals: np.ndarray
    success: bool
    message: str

    def friction(self, velocity, pressure):
        """Model friction [N] at ``velocity`` [m/s] and ``pressure`` [Pa]."""
        return stribeck(velocity, **params_at_pressure(pressure, self.coefficients, law=self.law))


def _grid_start(speed, p_bar, force, v_r_grid, alpha_grid):
    best = (np.inf, None)
    for v_r in v_r_grid:
        for alpha in alpha_grid:
            a = design_columns(speed, p_bar, v_r, alpha)
            coef = solve_linear(a, force)
            rss = float(np.sum((a @ coef - force) ** 2))
            if rss < best[0]:
                best = (rss, (coef, v_r, alpha))
    return best[1]


def fit_surface(
    velocity, pressure, friction, *, law="linear", fixed=None, loss="soft_l1", start=None
):
    """One fit of the whole surface F(v, p) with pressure laws for F_c, F_s and sigma_2.

    Parameters
    ----------
    velocity, pressure, friction : array_like
        Points: [m/s], [Pa], [N] (friction magnitude).
    law : {"linear", "quadratic", "exponential"}
        Pressure law of F_c, F_s and sigma_2.
    fixed : dict, optional
        ``v_r`` [m/s] and/or ``alpha`` [-] held fixed.
    loss : str
        Loss of :func:`scipy.optimize.least_squares` (robust by default).
    start : SurfaceFit, optional
        A fit of the same points whose linear coefficients, v_r and alpha start this one
        (skips the grid search; used to compare laws).

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
    v_r_grid = (
        [fixed["v_r"]]
        if "v_r" in fixed
        else np.geomspace(max(speed.min(), 1e-4) * 0.5, max(speed.max(), 1e-3), 25)
    )
    alpha_grid = [fixed["alpha"]] if "alpha" in fixed else np.linspace(0.4, 3.0, 14)
    if start is not None and start.law == "linear":
        c = start.coefficients
        coef = [
            c[par][key] * (_BAR if key == "slope" else 1.0)
            for par in PRESSURE_DEPENDENT
            for key in ("intercept", "slope")
        ]
        v_r0, alpha0 = c["v_r"], c["alpha"]
    else:
        coef, v_r0, alpha0 = _grid_start(speed, p_bar, force, v_r_grid, alpha_grid)
    names = LAW_COEFFICIENTS[law]
    k = len(names)
    # start: linear coefficients (pressure in bar) then zeros for higher-order terms
    start = []
    for j in range(3):
        a, b = coef[2 * j], coef[2 * j + 1]
        start += [a, b] if law == "linear" else [a, b, 0.0 if law == "quadratic" else 1e-4]
    shared = [n for n in ("v_r", "alpha") if n not in fixed]
    start += [v_r0 if n == "v_r" else alpha0 for n in shared]
    lower = [-np.inf] * (3 * k) + [1e-5 if n == "v_r" else 0.2 for n in shared]
    upper = [np.inf] * (3 * k) + [10.0 if n == "v_r" else 5.0 for n in shared]
    fn = _exp_slope_form if law == "exponential" else PRESSURE_LAWS[law]

    def model(x):
        vals = [fn(p_bar, *x[j * k : (j + 1) * k]) for j in range(3)]
        sh = dict(zip(shared, x[3 * k :], strict=True))
        v_r = sh.get("v_r", fixed.get("v_r"))
        alpha = sh.get("alpha", fixed.get("alpha"))
        e = np.exp(-((speed / v_r) ** alpha))
        return vals[0] + (vals[1] - vals[0]) * e + vals[2] * speed

    def residuals(x):
        return model(x) - force

    x0 = np.clip(start, np.array(lower) + 1e-12, np.array(upper) - 1e-12)
    result = robust_least_squares(residuals, x0, (lower, upper), loss)
    res = -result.fun
    n_free = len(result.x)
    dof = max(force.size - n_free, 1)
    cov = np.linalg.pinv(result.jac.T @ result.jac) * float(res @ res) / dof
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    coefficients, stderr = {}, {}
    for j, par in enumerate(PRESSURE_DEPENDENT):
        block = result.x[j * k : (j + 1) * k]
        eblock = se[j * k : (j + 1) * k]
        if law == "exponential":
            sub = cov[j * k : (j + 1) * k, j * k : (j + 1) * k]
            block = np.array(_exp_to_law(*block))
            eblock = np.sqrt(
                np.clip(np.diag(_exp_covariance(sub, result.x[j * k + 1], block[2])), 0, None)
            )
        coefficients[par] = {n: float(c * _TO_SI[n]) for n, c in zip(names, block, strict=True)}
        stderr[par] = {n: float(e * _TO_SI[n]) for n, e in zip(names, eblock, strict=True)}
    for i, n in enumerate(shared):
        coefficients[n] = float(result.x[3 * k + i])
        stderr[n] = float(se[3 * k + i])
    for n, value in fixed.items():
        coefficients[n] = float(value)
        stderr[n] = 0.0
    aic, bic = information_criteria(float(res @ res), force.size, n_free)
    return SurfaceFit(
        law,
        coefficients,
        stderr,
        float(math.sqrt(np.mean(res**2))),
        aic,
        bic,
        int(force.size),
        res,
        bool(result.success),
        str(result.message),
    )
