"""Identification of the pressure-dependent friction model from steady-state points (ch. 4).

:func:`identify` runs the thesis method and more on a points table (from
:func:`cylfric.steady_state.extract_campaign`): per-pressure Stribeck fits (Table 4.1), the
pressure laws two ways (regression of the per-pressure parameters, and one global surface
fit), information criteria across laws, the alpha / v_r sensitivity study (Tables 4.2-4.4),
and per-direction fits on request.

The package :mod:`cylfric.identify` re-exports every public name of this module.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from ..friction._checks import roundoff_tolerance
from ..friction.laws import viscous
from ..friction.pressure import PRESSURE_LAW_COEFFICIENTS
from ..levels import pressure_levels
from ..model import PARAMETER_BOUNDS, FrictionModel
from .confounding import Confounding, pressure_confounding
from .linear_fit import fit_linear_surface
from .pressure_fit import (
    FITTED_LAWS,
    PRESSURE_DEPENDENT,
    PressureLawFit,
    SurfaceFit,
    fit_surface,
    information_criteria,
    regress_parameters,
)
from .sensitivity import sensitivity_grid, sensitivity_refits, thesis_tables
from .stribeck_fit import (
    MIN_POINTS,
    PARAMETERS,
    IdentificationWarning,
    StribeckFit,
    fit_stribeck,
)

if TYPE_CHECKING:
    from collections.abc import Mapping

    from matplotlib.figure import Figure

__all__ = [
    "identify",
    "add_sensitivity",
    "Identification",
    "sensitivity_refits",
    "fit_stribeck",
    "StribeckFit",
    "fit_surface",
    "SurfaceFit",
    "regress_parameters",
    "PressureLawFit",
    "sensitivity_grid",
    "thesis_tables",
    "pressure_levels",
    "UnphysicalFrictionError",
    "validity_of",
    "point_errors",
    "unphysical",
    "fit_linear_surface",
    "IdentificationWarning",
    "PARAMETERS",
]

LAWS_COMPARED = FITTED_LAWS
LEVEL_ONLY_FIXABLE = {"F_c", "sigma_2"}
"""Parameters that may be held fixed when only the friction level is identifiable (at most
three speeds per pressure): a fixed F_c is the level itself (constant over pressure), a
fixed sigma_2 adds a known viscous term ``sigma_2 |v|``. F_s, v_r and alpha shape the
Stribeck dip, which such data cannot show: holding them is refused."""


def _distinct_speeds(speed, relative: float = 0.1):
    s = np.sort(np.abs(speed))
    return 1 + int(np.sum(np.diff(s) > relative * s[1:])) if s.size else 0


def validity_of(points: pd.DataFrame) -> dict[str, float]:
    """The ranges a points table covers: ``pressure_min/max`` [Pa], ``velocity_min/max`` [m/s].

    The pressure range starts at 0 Pa at the lowest: the mean of a noisy pressure channel at
    0 bar can fall slightly below 0, which is measurement noise, not a range to promise.
    """
    speed = points["velocity [m/s]"].abs()
    return {
        "pressure_min": max(float(points["pressure [Pa]"].min()), 0.0),
        "pressure_max": float(points["pressure [Pa]"].max()),
        "velocity_min": float(speed.min()),
        "velocity_max": float(speed.max()),
    }


class UnphysicalFrictionError(ValueError):
    """The data push the friction level to 0 N: a force-balance sign or a unit is wrong."""


@dataclass
class Identification:
    """Everything :func:`identify` found (SI units); the report draws from it, fitting nothing.

    Attributes
    ----------
    model : FrictionModel
        The datasheet's model: the global surface fit with the chosen pressure law, its
        covariance, statistics and validity ranges.
    models : dict
        Pressure law -> FrictionModel for every compared law.
    residuals : ndarray
        Data minus ``model`` [N], in the order of ``points``.
    points : pandas.DataFrame
        The points used (flag ``"ok"``), with their pressure ``level`` (index into ``levels``).
    levels : ndarray
        Mean pressure of each level [Pa] (computed once, here).
    per_pressure : pandas.DataFrame
        Table 4.1 layout: one row per pressure level with ``pressure [Pa]``, ``F_c [N]``,
        ``F_s [N]``, ``sigma_2 [N*s/m]``, ``v_r [m/s]``, ``alpha [-]``,
        ``stribeck_velocity [m/s]``, ``rmse [N]``, ``n_points [-]`` and ``*_stderr`` columns
        (NaN where a parameter is not identified).
    per_pressure_fits : list of StribeckFit
        The per-pressure fits.
    regressions : dict
        Parameter -> pressure law -> :class:`PressureLawFit` (route a).
    comparison : pandas.DataFrame
        ``law``, ``coefficients [-]``, ``rmse [N]``, ``aic``, ``bic`` of the surface fits.
    pressure_law : str
        Pressure law of ``model``.
    fixed : dict
        Parameters held fixed in every fit (SI).
    stribeck_identifiable : bool
        False when the data has too few speeds per pressure (e.g. one speed per direction).
    sensitivity, grid, recommended, sensitivity_refits
        The alpha / v_r study (:func:`add_sensitivity`): Tables 4.2-4.4, the RMSE grid, its
        minimum, and the refits of Figs. 4.4-4.12 (dicts with a ``model``).
    directions : dict
        ``"extension"``/``"retraction"`` -> Identification.
    notes : list of str
        Warnings raised on the way, in words, for the report.
    confounding : dict or None
        The datasheet's ``fit.confounding`` record when the pressure is tied to the direction
        or the speed (:mod:`cylfric.identify.confounding`); its pressure slopes are then in
        ``model.not_identified`` with the reason. None otherwise.
    """

    model: FrictionModel
    models: dict
    residuals: np.ndarray
    points: pd.DataFrame
    levels: np.ndarray
    per_pressure: pd.DataFrame
    per_pressure_fits: list
    regressions: dict
    comparison: pd.DataFrame
    pressure_law: str
    fixed: dict
    stribeck_identifiable: bool = True
    sensitivity: pd.DataFrame | None = None
    grid: pd.DataFrame | None = None
    recommended: dict = field(default_factory=dict)
    sensitivity_refits: list | None = None
    directions: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    confounding: dict | None = None

    def summary(self) -> pd.DataFrame:
        """Pressure laws in engineering units: parameter, coefficient, value, stderr, unit."""
        rows = []
        for p in self.model.parameters.values():
            value, stderr, unit = p.engineering()
            rows.append(
                {
                    "parameter": p.name,
                    "value": value,
                    "stderr": stderr,
                    "unit": unit,
                    "vary": p.vary,
                }
            )
        return pd.DataFrame(rows)

    def to_pandas(self) -> pd.DataFrame:
        """The model's coefficients with units and standard errors (SI and engineering);
        :meth:`FrictionModel.to_pandas`. The data are in :attr:`points`, the
        per-pressure fits in :attr:`per_pressure`."""
        return self.model.to_pandas()

    def _repr_html_(self) -> str:
        from ..model.text import html_summary

        rmse = self.model.statistics.get("rmse")
        fit = (
            f"<div>{len(self.points)} points at {len(self.levels)} pressure level(s)"
            + ("" if rmse is None else f", RMSE {rmse:.3g} N")
            + f"; {self.pressure_law} pressure laws</div>"
        )
        return html_summary(self.model, title="Identification") + fit

    def plot(self) -> Figure:
        """Thesis Fig. 4.1: the points per pressure, the model and its 95 % band of the mean
        (:func:`cylfric.report.figures.figure_fit`). Returns the matplotlib Figure."""
        from ..report.figures import figure_fit  # the plotting module; it imports no identify

        return figure_fit(self)


_TABLE_UNITS = {"F_c": "N", "F_s": "N", "sigma_2": "N*s/m", "v_r": "m/s", "alpha": "-"}


def _per_pressure(points, levels, fixed):
    rows, fits = [], []
    for k in range(len(levels)):
        sel = points[points["level"] == k]
        if len(sel) < MIN_POINTS:
            continue
        fit = fit_stribeck(sel["velocity [m/s]"], sel["friction [N]"], fixed=fixed)
        fits.append(fit)
        row = {"pressure [Pa]": float(sel["pressure [Pa]"].mean())}
        for p in PARAMETERS:
            row[f"{p} [{_TABLE_UNITS[p]}]"] = fit.params[p]
        row["stribeck_velocity [m/s]"] = fit.stribeck_velocity
        row["rmse [N]"] = fit.rmse
        row["n_points [-]"] = fit.n_points
        for p in PARAMETERS:
            row[f"{p}_stderr [{_TABLE_UNITS[p]}]"] = fit.stderr[p]
        rows.append(row)
    return pd.DataFrame(rows), fits


def _check_per_pressure(per_pressure, fits) -> None:
    """Warn about failed fits and parameters that fall significantly as pressure rises."""
    for fit, (_, row) in zip(fits, per_pressure.iterrows(), strict=True):
        if not fit.success:
            warnings.warn(
                f"the Stribeck fit at {row['pressure [Pa]'] / 1e5:.3g} bar did not "
                f"converge ({fit.message}); its row of the table is unreliable",
                IdentificationWarning,
                stacklevel=3,
            )
    if per_pressure.empty:  # no pressure level with enough points (pressures set by a valve)
        return
    table = per_pressure.sort_values("pressure [Pa]")
    for par in ("F_c", "F_s"):
        values = table[f"{par} [N]"].to_numpy()
        errors = table[f"{par}_stderr [N]"].to_numpy()
        drops = np.diff(values) < -2 * np.hypot(errors[1:], errors[:-1])
        for i in np.flatnonzero(drops):
            p0, p1 = table["pressure [Pa]"].to_numpy()[[i, i + 1]] / 1e5
            warnings.warn(
                f"{par} is not monotonic in pressure: it falls from "
                f"{values[i]:.1f} N at {p0:.3g} bar to {values[i + 1]:.1f} N at "
                f"{p1:.3g} bar; the pressure law may not describe this level "
                "(temperature, seal run-in?)",
                IdentificationWarning,
                stacklevel=3,
            )


def point_errors(points: pd.DataFrame) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(sigma [N], groups) of a points table for the weighted, run-clustered surface fit.

    ``sigma`` is each window's standard error ``friction_std / sqrt(n)`` (floored at a tenth
    of the median, so that no window weighs without bound), or None when the table lacks
    those columns; ``groups`` is the ``run`` column (the points of one run share its
    offset) or None.
    """
    sigma = None
    if {"friction_std [N]", "n [-]"} <= set(points.columns):
        sem = points["friction_std [N]"].to_numpy(float) / np.sqrt(points["n [-]"].to_numpy(float))
        valid = np.isfinite(sem) & (sem > 0)
        if valid.any():
            typical = float(np.median(sem[valid]))
            sigma = np.where(valid, np.maximum(sem, 0.1 * typical), typical)
    groups = points["run"].to_numpy() if "run" in points.columns else None
    return sigma, groups


STRONG_EVIDENCE_BIC = 10.0
"""BIC gain [-] the Stribeck law must show over Coulomb + viscous to be kept ("very strong"
evidence on the scale of Kass & Raftery 1995)."""

SHAPE_RELATIVE_SE = 1.0
"""Largest standard error of the Stribeck shape (v_r, alpha) relative to its value [-] for the
shape to count as identified: beyond it (|t| < 1) the data do not tell the dip's width or
form, and the level's standard errors, which share the shape's covariance, explode with it
(a rough virtual campaign of 3 pressures x 4 speeds gave F_c = 22 N +- 1.8e5 N)."""


def _shape_unidentified(model: FrictionModel, fixed: Mapping[str, Any]) -> list[str]:
    """``"v_r = x +- y"`` for each free Stribeck shape parameter whose standard error exceeds
    :data:`SHAPE_RELATIVE_SE` times its value (or is not finite)."""
    values, errors = model.coefficients(), model.stderr()
    found = []
    for name in ("v_r", "alpha"):
        value, error = values.get(name), errors.get(name)
        if name in fixed or not isinstance(value, float) or not isinstance(error, float):
            continue
        if not math.isfinite(error) or error > SHAPE_RELATIVE_SE * abs(value):
            found.append(f"{name} = {value:.3g} +- {error:.3g}")
    return found


def unphysical(
    model: FrictionModel, validity: Mapping[str, float], *, points: int = 41
) -> str | None:
    """Why a model is unphysical within the validity pressures, or None.

    Checks F_c >= 0, F_s >= F_c and sigma_2 >= 0 at ``points`` pressures over the range.
    """
    p = np.linspace(validity["pressure_min"], validity["pressure_max"], points)
    k = model.params_at(p)  # rounding onto a bound is clamped there (ROUNDOFF)
    tol, tol_2 = roundoff_tolerance(k["F_c"], k["F_s"], k["sigma_2"])
    checks = (
        (k["F_c"] < -tol, "F_c < 0"),
        (k["F_s"] < k["F_c"] - tol, "F_s < F_c"),
        (np.asarray(k["sigma_2"]) < -tol_2, "sigma_2 < 0"),
    )
    for bad, what in checks:
        bad = np.broadcast_to(bad, p.shape)
        if bad.any():
            return f"it gives {what} at {p[bad][0] / 1e5:.4g} bar"
    return None


def _linear_model(args, fixed, weights, notes):
    """The linear-law model the data support: Stribeck, else Coulomb + viscous, else Coulomb.

    Returns (chosen SurfaceFit, the Coulomb + viscous alternative or None). Raises
    ValueError when even the friction level is pushed to 0 N (a sign or unit error).
    """
    stribeck = fit_linear_surface(*args, friction_law="stribeck", fixed=fixed, **weights)
    reduced_fixed = {k: v for k, v in fixed.items() if k in ("F_c", "sigma_2")}
    gain = None
    shape_bounds = [b for b in stribeck.at_bounds if b.split()[0] in ("amplitude", "v_r", "alpha")]
    shape_loose = [] if shape_bounds else _shape_unidentified(stribeck.model, fixed)
    if shape_loose and "alpha" not in fixed:
        # the exponent is the first to go: the exponential Stribeck law (alpha = 1, as the
        # thesis held it; Armstrong-Helouvry et al. 1994) often leaves v_r identified
        held = {**fixed, "alpha": 1.0}
        exponential = fit_linear_surface(*args, friction_law="stribeck", fixed=held, **weights)
        if not any(
            b.split()[0] in ("amplitude", "v_r") or b.startswith("F_c")
            for b in exponential.at_bounds
        ) and not _shape_unidentified(exponential.model, held):
            notes.append(
                f"the data leave the Stribeck exponent open ({', '.join(shape_loose)}: standard "
                f"error above {SHAPE_RELATIVE_SE:g}x the value); the exponential Stribeck law "
                "is fitted (alpha = 1 held, as in the thesis): alpha is a choice of law, not "
                "a measured value"
            )
            stribeck, fixed, shape_loose = exponential, held, []
    alternative = None
    if not {"F_s", "v_r", "alpha"} & set(fixed) or shape_bounds or shape_loose:
        alternative = fit_linear_surface(
            *args, friction_law="coulomb_viscous", fixed=reduced_fixed, **weights
        )
        gain = alternative.model.statistics["bic"] - stribeck.model.statistics["bic"]
    if shape_bounds or shape_loose or (gain is not None and gain <= STRONG_EVIDENCE_BIC):
        why = (
            "the fit pushes " + ", ".join(shape_bounds) + " to its physical bound"
            if shape_bounds
            else "the data leave the dip's shape open ("
            + ", ".join(shape_loose)
            + f": standard error above {SHAPE_RELATIVE_SE:g}x the value)"
            if shape_loose
            else f"the Stribeck law improves BIC by only {gain:.3g} (<= "
            f"{STRONG_EVIDENCE_BIC:g}) over Coulomb + viscous friction"
        )
        reason = f"no identifiable Stribeck dip: {why}"
        notes.append(
            f"{reason}; the datasheet gives the Coulomb + viscous model F_c(p) + "
            "sigma_2(p) |v| and marks F_s, v_r and alpha not identified"
        )
        chosen = fit_linear_surface(
            *args,
            friction_law="coulomb_viscous",
            fixed=reduced_fixed,
            not_identified={n: reason for n in ("F_s", "v_r", "alpha")},
            **weights,
        )
        alternative = stribeck
        if sum(b.startswith("sigma_2") for b in chosen.at_bounds) == 2 and "sigma_2" not in fixed:
            reason = "the data ask for a negative viscous coefficient at every pressure"
            notes.append(f"{reason}: the datasheet gives the Coulomb level F_c(p) only")
            chosen = fit_linear_surface(
                *args,
                friction_law="coulomb",
                fixed={k: v for k, v in fixed.items() if k == "F_c"},
                not_identified={"F_s": reason, "sigma_2": reason, "v_r": reason, "alpha": reason},
                **weights,
            )
    else:
        chosen = stribeck
    level = [b for b in chosen.at_bounds if b.startswith("F_c")]
    if level and chosen is stribeck and not {"F_s", "v_r", "alpha"} & set(fixed):
        # the dip's shape took the level: Coulomb + viscous friction keeps it positive when
        # the data do (a rough rig's scatter between pressures); else the signs are wrong
        reason = (
            f"no identifiable Stribeck dip: the Stribeck fit pushes {', '.join(level)} to 0 N "
            "while Coulomb + viscous friction keeps the level positive"
        )
        fallback = fit_linear_surface(
            *args,
            friction_law="coulomb_viscous",
            fixed=reduced_fixed,
            not_identified={n: reason for n in ("F_s", "v_r", "alpha")},
            **weights,
        )
        if not any(b.startswith("F_c") for b in fallback.at_bounds):
            notes.append(
                f"{reason}; the datasheet gives the Coulomb + viscous model F_c(p) + "
                "sigma_2(p) |v| and marks F_s, v_r and alpha not identified"
            )
            chosen, alternative, level = fallback, stribeck, []
    if level:
        raise UnphysicalFrictionError(
            f"the friction level is pushed to 0 N ({', '.join(level)}): the data contradict a "
            "positive friction force; check the force-balance signs (load_cell_sign, "
            "position_sign), the offset and the force and position units"
        )
    for bound in chosen.at_bounds:
        if bound.startswith("sigma_2"):
            notes.append(
                f"sigma_2 is held at its bound 0 N*s/m ({bound}): the data ask for a negative "
                "viscous coefficient there"
            )
    return chosen, alternative


def _core(points, levels, *, pressure_law, fixed, notes, validity):
    per_pressure, fits = _per_pressure(points, levels, fixed)
    _check_per_pressure(per_pressure, fits)
    regressions = {}
    if len(per_pressure) >= 2:
        for par in PRESSURE_DEPENDENT:
            unit = _TABLE_UNITS[par]
            regressions[par] = regress_parameters(
                per_pressure["pressure [Pa]"],
                per_pressure[f"{par} [{unit}]"],
                per_pressure[f"{par}_stderr [{unit}]"],
                parameter=par,
                laws=LAWS_COMPARED,
            )
    else:
        notes.append(
            "fewer than two pressure levels with enough points: the pressure "
            "dependence rests on the surface fit alone"
        )
    sigma, groups = point_errors(points)
    args = (points["velocity [m/s]"], points["pressure [Pa]"], points["friction [N]"])
    weights: dict[str, Any] = {"sigma": sigma, "groups": groups}
    linear, alternative = _linear_model(args, fixed, weights, notes)
    fits_by_law = {"linear": linear}
    shape_only = set(fixed) <= {"v_r", "alpha"}
    for name in LAWS_COMPARED[1:]:
        if linear.model.friction_law != "stribeck" or not shape_only:
            notes.append(
                f"the {name} pressure law was not fitted: cylfric fits it only for the "
                "Stribeck law with at most v_r and alpha held"
            )
            continue
        if len(PRESSURE_LAW_COEFFICIENTS[name]) > len(levels):
            continue
        try:
            fit = fit_surface(*args, pressure_law=name, fixed=fixed, start=linear.model, **weights)
        except (ValueError, np.linalg.LinAlgError) as exc:
            notes.append(f"surface fit with the {name} pressure law failed: {exc}")
            continue
        problem = unphysical(fit.model, validity)
        if problem:
            notes.append(f"the {name} pressure law was left out: {problem}")
            continue
        fits_by_law[name] = fit
    if pressure_law not in fits_by_law:
        raise ValueError(
            f"the {pressure_law} pressure law cannot be used on these data ({len(levels)} "
            "pressure level(s); see the notes above); use --pressure-law linear"
            + ("" if len(levels) > 2 else " or measure more pressures")
        )
    models = {n: f.model.replace(validity=validity) for n, f in fits_by_law.items()}
    rows = [(n, m) for n, m in models.items()]
    if alternative is not None:
        rows.insert(1, ("linear", alternative.model))
    comparison = pd.DataFrame(
        [
            {
                "law": n,
                "friction_law": m.friction_law,
                "coefficients [-]": m.statistics["n_variables"],
                "rmse [N]": m.statistics["rmse"],
                "aic": m.statistics["aic"],
                "bic": m.statistics["bic"],
            }
            for n, m in rows
        ]
    )
    for name, f in fits_by_law.items():
        if not f.success:
            notes.append(f"surface fit with the {name} pressure law: {f.message}")
    return per_pressure, fits, regressions, models, fits_by_law, comparison


def identify(
    points: pd.DataFrame,
    *,
    fixed: Mapping[str, Any] | None = None,
    pressure_law: str = "linear",
    per_direction: bool = False,
    sensitivity: bool = True,
    workers: int | None = None,
    pressure_reference: str | Mapping[str, Any] | None = None,
) -> Identification:
    """Identify the pressure-dependent friction model from a points table.

    This is the step of :func:`cylfric.fit` that sees only the points: it cannot know the
    campaign (its cylinder, its pressure reference, its data-quality gate, its viscosity
    correction, its presliding tests). ``cylfric.fit(folder)`` is the route that gives
    what ``cylfric fit`` gives; use this one for points of your own, and say which chamber
    pressure their ``pressure [Pa]`` is (``pressure_reference``).

    Parameters
    ----------
    points : pandas.DataFrame
        Points with ``velocity [m/s]``, ``pressure [Pa]``, ``friction [N]`` and, when present,
        ``flag`` (only ``"ok"`` rows are used) and ``direction [-]``.
    fixed : dict, optional
        Parameters held fixed in every fit (SI), e.g. ``{"alpha": 1, "v_r": 0.010}`` as the
        thesis chose.
    pressure_law : {"linear", "quadratic", "exponential"}
        Pressure law of the datasheet model; all three are fitted and compared.
    per_direction : bool
        Also identify extension and retraction separately.
    sensitivity : bool
        Run the alpha / v_r sensitivity study (see :func:`add_sensitivity`).
    workers : int or None
        Processes: with 2 or more (None: the cores this process may use,
        :func:`cylfric._parallel.cores`) and from :data:`STUDY_FORK_MIN_POINTS` points, the
        sensitivity study is computed by a forked process while the models are fitted here
        (Linux; the same results); 1: everything here.
    pressure_reference : str or mapping, optional
        Which chamber pressure the points' ``pressure [Pa]`` is, recorded in the model
        (``model.reference`` and ``model.pressure_reference_basis``) so that it is evaluated
        in the same pressure: a rule (``"a"``, ``"b"``, ``"sum"``, ``"mean"``, ``"max"``) or
        a campaign's basis (``Campaign.config.pressure_basis``). None: ``"mean"`` is assumed,
        and a note says so.

    Returns
    -------
    Identification

    The fits run with BLAS limited to one thread (threadpoolctl): their matrices are tall
    and narrow (points x about 8 coefficients), where a second BLAS thread costs more than
    it gives (the scale benchmark's 20,000 runs: 1.3 s against 2.1-2.3 s with two threads,
    5,000 runs 0.6 s against 0.7-3.3 s, on a shared 2-core machine); the caller's limits are
    restored after.

    Raises
    ------
    ValueError
        Missing columns, NaN values, too few points, unknown law or fixed names.
    """
    from threadpoolctl import threadpool_limits

    basis = _reference_basis(pressure_reference)  # a bad rule refused before the fit
    with threadpool_limits(limits=1, user_api="blas"):
        ident = _identify(
            points,
            fixed=fixed,
            pressure_law=pressure_law,
            per_direction=per_direction,
            sensitivity=sensitivity,
            workers=workers,
        )
    return with_pressure_reference(ident, basis)


def _reference_basis(reference: str | Mapping[str, Any] | None) -> dict[str, Any]:
    """The pressure-reference basis of :func:`identify`'s ``pressure_reference``."""
    from ..friction.pressure import pressure_reference_basis

    if reference is None:
        basis = pressure_reference_basis(None, None, where="identify()")
        return {
            **basis,
            "stated_by": (
                "default: identify() was not told which chamber pressure the points' "
                "'pressure [Pa]' is (pressure_reference=None)"
            ),
        }
    if isinstance(reference, str):
        return pressure_reference_basis(None, reference, where="identify(pressure_reference=)")
    missing = {"kind", "rule", "chamber", "stated_by"} - set(reference)
    if missing:
        raise ValueError(
            f"pressure_reference: a basis needs {sorted(missing)} too "
            "(cylfric.friction.pressure.pressure_reference_basis makes one)"
        )
    return dict(reference)


def with_pressure_reference(ident: Identification, basis: Mapping[str, Any]) -> Identification:
    """The identification with the pressure reference ``basis`` recorded in its model (the
    points were formed in it, steady_state.operating_pressure_signal), and a note when the
    reference is a default rather than stated."""
    model = ident.model.replace(reference=basis["rule"], pressure_reference_basis=basis)
    notes = list(ident.notes)
    if basis["stated_by"].startswith("default"):
        reason = basis["stated_by"].removeprefix("default: ")
        notes.append(
            f'pressure reference "{basis["rule"]}" is a default: {reason}; state [cylinder] '
            "pressure_reference in campaign.toml if the laws should see another pressure "
            '("a", "b", "sum", "mean" or "max")'
        )
    return replace(ident, model=model, notes=notes)


def _identify(
    points: pd.DataFrame,
    *,
    fixed: Mapping[str, Any] | None,
    pressure_law: str,
    per_direction: bool,
    sensitivity: bool,
    workers: int | None = None,
) -> Identification:
    """The body of :func:`identify` (run under its one-thread BLAS limit)."""
    fixed = dict(fixed or {})
    unknown = set(fixed) - set(PARAMETERS)
    if unknown:
        raise ValueError(f"unknown fixed parameters {sorted(unknown)}; valid: {list(PARAMETERS)}")
    for name, value in fixed.items():  # a held value the model cannot have: refused here
        low, high = PARAMETER_BOUNDS[name]
        if not (math.isfinite(value) and low <= value <= high and (value > 0 or name != "v_r")):
            unit = _TABLE_UNITS[name]
            span = f"{low:g} to {high:g}" if math.isfinite(high) else f">= {low:g}"
            raise ValueError(
                f"fixed {name} = {value!r} {unit} is out of range; expected {span} {unit}"
            )
    if pressure_law not in LAWS_COMPARED:
        raise ValueError(f"unknown pressure law {pressure_law!r}; valid: {list(LAWS_COMPARED)}")
    needed = {"velocity [m/s]", "pressure [Pa]", "friction [N]"}
    missing = needed - set(points.columns)
    if missing:
        raise ValueError(f"points table lacks columns {sorted(missing)}")
    used = points[points["flag"].eq("ok")] if "flag" in points else points
    data = used[list(needed)].to_numpy(dtype=float)
    if np.isnan(data).any():
        raise ValueError("points contain NaN in velocity, pressure or friction; drop or flag them")
    if len(used) < MIN_POINTS:
        raise ValueError(
            f"{len(used)} usable points are too few; expected at least "
            f"{MIN_POINTS} (check the flags of the points table)"
        )
    notes: list[str] = []
    labels, levels = pressure_levels(used["pressure [Pa]"])
    used = used.assign(level=labels)
    validity = validity_of(used)
    speeds_per_level = [
        _distinct_speeds(used["velocity [m/s]"].to_numpy()[labels == k]) for k in range(len(levels))
    ]
    if max(speeds_per_level) < 4:
        if pressure_law != "linear":
            raise ValueError(
                f"at most {max(speeds_per_level)} distinct speed(s) per pressure: only the "
                "friction level against pressure can be identified, and cylfric fits it with "
                f"the linear law; the {pressure_law} pressure law is not available for it"
            )
        message = (
            f"at most {max(speeds_per_level)} distinct speed(s) per pressure: the "
            "Stribeck shape (F_s, v_r, alpha, sigma_2) cannot be identified; the datasheet "
            "gives the Coulomb friction level against pressure, F_c(p), and marks the rest "
            "not identified"
        )
        shape_fixed = sorted(set(fixed) - LEVEL_ONLY_FIXABLE)
        if shape_fixed:
            options = ", ".join(f"--fix {name}" for name in shape_fixed)
            raise ValueError(
                f"fixed {', '.join(shape_fixed)} ({options}): at most "
                f"{max(speeds_per_level)} distinct speed(s) per pressure, so only the "
                "friction level against pressure, F_c(p), is fitted and the Stribeck shape "
                f"that {', '.join(shape_fixed)} belong(s) to is not identified; fix only "
                "F_c or sigma_2 here, or measure at least 4 speeds per pressure"
            )
        warnings.warn(message, IdentificationWarning, stacklevel=3)
        result = _level_only(used, levels, fixed, notes + [message], validity)
    else:
        study = _start_study(used, workers) if sensitivity else None
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                core = _core(
                    used,
                    levels,
                    pressure_law=pressure_law,
                    fixed=fixed,
                    notes=notes,
                    validity=validity,
                )
            notes += [str(w.message) for w in caught]
            notes[:] = dict.fromkeys(notes)  # each warning once (several fits repeat some)
            for w in caught:  # recorded for the report, and still shown to the caller
                warnings.warn(w.message, w.category, stacklevel=3)
            per_pressure, fits, regressions, models, fits_by_law, comparison = core
            model = models[pressure_law]
            shape = model.friction_law == "stribeck"
            for par in PRESSURE_DEPENDENT:
                spec = model.coefficients()[par]
                slope = spec.get("slope") if isinstance(spec, dict) else None
                if slope is not None and slope < 0:
                    notes.append(
                        f"{par} falls with pressure (slope {slope * 1e5:.3g} per bar): check "
                        "the pressure column and the force-balance signs"
                    )
            result = Identification(
                model=model,
                models=models,
                residuals=fits_by_law[pressure_law].residuals,
                points=used,
                levels=levels,
                per_pressure=per_pressure,
                per_pressure_fits=fits,
                regressions=regressions,
                comparison=comparison,
                pressure_law=pressure_law,
                fixed=fixed,
                stribeck_identifiable=shape,
                notes=notes,
            )
            if study is not None:
                computed = study.results()[0] if shape and model.reference == "mean" else None
                if shape:
                    result = _with_study(result, computed)
            elif sensitivity and shape:
                result = add_sensitivity(result)
        finally:
            if study is not None:
                study.close()  # an error here too: its process is not left running
    tie = pressure_confounding(used)
    if tie is not None and tie.confounded:
        result = _mark_confounded(result, tie)
    result = with_uncertainty(result)
    if per_direction and "direction [-]" in used:
        if "offset [N]" in used:  # points of steady_state.extract_campaign
            result.notes.append(
                "per direction: each run's own load-cell offset, the mean of its extension "
                "and retraction force levels, is removed, so the two directions have the "
                "same mean friction in every run and their fits differ only by stroke "
                "scatter and missing windows; an asymmetry between the directions cannot "
                "be told from the offset without a load-cell reading at rest"
            )
        for name, sign in (("extension", 1), ("retraction", -1)):
            subset = used[used["direction [-]"] == sign].drop(columns="level")
            if len(subset) >= MIN_POINTS:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", IdentificationWarning)
                    result.directions[name] = identify(
                        subset, fixed=fixed, pressure_law=pressure_law, sensitivity=False
                    )
    return result


def with_uncertainty(ident: Identification) -> Identification:
    """``ident`` with its model's scatter components and lack-of-fit test (issue 22).

    The model's record gains ``fit.scatter`` (:func:`cylfric.identify.scatter.scatter_components`:
    repeatability, run-to-run, session-to-session, by REML on the relative residuals) and
    ``quality.lack_of_fit`` (:func:`cylfric.identify.lack_of_fit.lack_of_fit`); the notes say
    both, and the assumption when the session scatter is a prior. Data the mixed model cannot
    take leave a note instead (no bands beyond scope "point" then).
    """
    from .lack_of_fit import lack_of_fit
    from .scatter import residual_function, scatter_components, scatter_note

    model, points = ident.model, ident.points
    residuals = np.asarray(ident.residuals, dtype=float)
    if residuals.shape != (len(points),):
        return ident
    fitted = points["friction [N]"].to_numpy(dtype=float) - residuals
    n_parameters = int(model.statistics.get("n_variables") or 1)
    notes = list(ident.notes)
    record = dict(model.record)
    try:
        scatter = scatter_components(points, fitted, n_parameters=n_parameters)
    except (ValueError, np.linalg.LinAlgError) as exc:
        notes.append(f"scatter components not computed ({exc}); bands: scope 'point' only")
    else:
        strata = _residual_strata(model, points, residuals)
        if strata is not None:
            scatter["residual_variance"] = strata
        shape = residual_function(fitted, residuals, n_parameters)
        if shape is not None:
            scatter["residual_function"] = shape
        record["fit"] = {**record.get("fit", {}), "scatter": scatter}
        notes.append(scatter_note(scatter))
    test = lack_of_fit(points, residuals, n_parameters)
    if test is not None:
        record["quality"] = {**record.get("quality", {}), "lack_of_fit": test}
        if test["significant"]:
            notes.append(
                f"lack of fit: {test['test']} p = {test['p_value']:.3g} (alpha 0.05); "
                + test["action"]
            )
    return replace(ident, model=model.replace(record=record), notes=notes)


def _residual_strata(model: FrictionModel, points: pd.DataFrame, residuals: np.ndarray):
    """The residual variance's strata and degrees of freedom
    (:func:`cylfric.identify.scatter.residual_strata`), or None for a model without a
    covariance (nothing fitted) or a design the strata cannot be formed on."""
    from .scatter import residual_strata

    if model.covariance is None or not len(model.covariance[0]):
        return None
    speed = points["velocity [m/s]"].abs().to_numpy(dtype=float)
    pressure = points["pressure [Pa]"].to_numpy(dtype=float)
    try:
        jacobian = model._jacobian(speed, pressure)  # d friction / d fitted coefficient
        sigma, _ = point_errors(points)
        return residual_strata(points, residuals, jacobian, sigma)
    except np.linalg.LinAlgError:  # a singular information matrix: no strata to state
        return None


def _mark_confounded(result: Identification, tie: Confounding) -> Identification:
    """Mark the pressure slopes of ``result``'s models not identified, with the reason.

    The fitted law stays: it reproduces each direction's friction at its own pressures and
    speeds (the identifiable combination), and the datasheet says its slopes are not
    identified instead of giving them as numbers with small standard errors.
    """
    reason = tie.reason()

    def slopes(model):
        names = []
        for par in PRESSURE_DEPENDENT:
            spec = model.coefficients()[par]
            if isinstance(spec, dict) and spec.get("law", model.pressure_law) != "constant":
                names += [f"{par}.{k}" for k in spec if k not in ("intercept", "law")]
        return names

    def marked(model):
        names = slopes(model)
        if not names:
            return model
        return model.replace(
            not_identified={**model.not_identified, **dict.fromkeys(names, reason)}
        )

    names = slopes(result.model)
    if not names:
        return result
    message = (
        f"{reason}; the datasheet marks {', '.join(names)} not identified: the fitted law "
        "gives each direction's friction at its own pressures, not how friction changes with "
        "pressure (vary the pressure within each direction, e.g. with a counter-pressure or "
        "several supply pressures, to identify it)"
    )
    warnings.warn(message, IdentificationWarning, stacklevel=3)
    return replace(
        result,
        model=marked(result.model),
        models={law: marked(m) for law, m in result.models.items()},
        directions=dict(result.directions),
        notes=[*result.notes, message],
        confounding=tie.record(names),
    )


def add_sensitivity(ident: Identification) -> Identification:
    """A copy of ``ident`` with the alpha / v_r sensitivity study (thesis 4.1.1-4.1.2).

    Fills ``sensitivity`` (Tables 4.2-4.4), ``grid``, ``recommended`` and
    ``sensitivity_refits`` (the refits of Figs. 4.4-4.12); warnings raised on the way are
    added to ``notes``. :func:`identify` calls it unless ``sensitivity=False``. An
    identification without a Stribeck shape is returned unchanged.
    """
    return _with_study(ident, None)


def _with_study(ident: Identification, study: tuple | None) -> Identification:
    """:func:`add_sensitivity` with the study already computed (``study``: what
    :func:`_sensitivity_study` returned for these points and reference; None: computed here)."""
    if not ident.stribeck_identifiable:
        return ident
    if study is None:
        study = _sensitivity_study(ident.points, ident.model.reference)
    table, grid, recommended, refits, caught = study
    for message, category in caught:
        warnings.warn(message, category, stacklevel=3)
    return replace(
        ident,
        sensitivity=table,
        grid=grid,
        recommended=recommended,
        sensitivity_refits=refits,
        directions=dict(ident.directions),
        notes=list(dict.fromkeys(ident.notes + [str(message) for message, _ in caught])),
    )


def _sensitivity_study(points: pd.DataFrame, reference: str) -> tuple:
    """(Tables 4.2-4.4, grid, recommended, refits, the warnings raised as (message, category))
    of the points used (picklable: a forked process may compute it, :func:`_start_study`)."""
    args = (points["velocity [m/s]"], points["pressure [Pa]"], points["friction [N]"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = thesis_tables(*args)
        grid, recommended = sensitivity_grid(*args)
        refits = sensitivity_refits(*args, reference=reference)
    return table, grid, recommended, refits, [(w.message, w.category) for w in caught]


STUDY_FORK_MIN_POINTS = 2000
"""Fewest points for which :func:`identify` computes the sensitivity study in a forked
process while it fits the models here (:func:`cylfric._parallel.start`, one background
task). The study does not need the fits (it refits the points on its own grid of alpha and
v_r); it costs about 0.04 s at 2,000 points, 0.18 s at 10,000 and 0.33 s at 40,000 (the
scale benchmark's 5,000 and 20,000 runs), against about 10 ms to fork and send back."""


def _start_study(used: pd.DataFrame, workers: int | None):
    """The sensitivity study of ``used`` started beside this process (None: too few points
    for the fork to pay, or ``workers`` 1). The fits here use the reference ``"mean"``;
    :func:`_identify` computes the study again here if the model's reference is another."""
    from .._parallel import start

    if len(used) < STUDY_FORK_MIN_POINTS or workers == 1:
        return None
    # start forks only where this process has a second core (else the study runs here)
    return start(lambda _: _sensitivity_study(used, "mean"), 1, min_items=1, background=True)


def _level_only(points, levels, fixed, notes, validity):
    """Coulomb friction level against pressure when the Stribeck shape is not identifiable.

    ``fixed`` may hold ``F_c`` (the level, constant over pressure: nothing of it fitted)
    and ``sigma_2`` (a known viscous term, subtracted before the level is fitted) [SI].
    """
    labels = points["level"].to_numpy()
    sigma_2 = fixed.get("sigma_2")
    known = (  # the viscous part a fixed sigma_2 gives [N], eq. 2.2
        viscous(points["velocity [m/s]"].abs().to_numpy(), sigma_2) if sigma_2 is not None else 0.0
    )
    points_f = points["friction [N]"].to_numpy() - known
    level_rows = []
    for k in range(len(levels)):
        sel = points[labels == k]
        f = points_f[labels == k]
        row = {
            "pressure [Pa]": float(sel["pressure [Pa]"].mean()),
            **{f"{p} [{_TABLE_UNITS[p]}]": math.nan for p in PARAMETERS},
            "stribeck_velocity [m/s]": math.nan,
            "rmse [N]": float(f.std()),
            "n_points [-]": int(f.size),
            **{f"{p}_stderr [{_TABLE_UNITS[p]}]": math.nan for p in PARAMETERS},
        }
        row["F_c [N]"] = float(f.mean())
        if f.size > 1:
            row["F_c_stderr [N]"] = float(f.std(ddof=1) / math.sqrt(f.size))
        if "F_c" in fixed:
            row["F_c [N]"], row["F_c_stderr [N]"] = float(fixed["F_c"]), 0.0
        if sigma_2 is not None:
            row["sigma_2 [N*s/m]"], row["sigma_2_stderr [N*s/m]"] = float(sigma_2), 0.0
        level_rows.append(row)
    per_pressure = pd.DataFrame(level_rows)
    p = points["pressure [Pa]"].to_numpy()
    f = points_f
    if "F_c" in fixed:
        design = np.zeros((p.size, 0))
        names = []
        coef = np.zeros(0)
        res = f - float(fixed["F_c"])
        note = (
            f"F_c held at {float(fixed['F_c']):.4g} N (--fix): RMSE "
            f"{float(np.sqrt(np.mean(res**2))):.3g} N"
        )
        try:  # what the data say without the fixed level, for comparison
            free = _level_only(
                points, levels, {k: v for k, v in fixed.items() if k != "F_c"}, [], validity
            )
            note += f", where the fitted level F_c(p) gives {free.model.statistics['rmse']:.3g} N"
        except UnphysicalFrictionError:
            note += "; the data alone push the level to 0 N"
        notes = notes + [note]
    else:
        if len(levels) >= 2:
            design = np.column_stack([np.ones_like(p), p])
            names = ["F_c.intercept", "F_c.slope"]
        else:
            design = np.ones((p.size, 1))
            names = ["F_c"]
        coef, *_ = np.linalg.lstsq(design, f, rcond=None)
        res = f - design @ coef
        ends = np.array([validity["pressure_min"], validity["pressure_max"]])
        level = coef[0] + (coef[1] * ends if len(coef) == 2 else 0.0)
        if np.any(level <= 0):  # as the surface fits: never a negative friction level
            raise UnphysicalFrictionError(
                f"the friction level is pushed to 0 N (F_c = {np.min(level):.4g} N within "
                f"{ends[0] / 1e5:.3g}-{ends[1] / 1e5:.3g} bar): the data contradict a positive "
                "friction force; check the force-balance signs (load_cell_sign, "
                "position_sign), the offset, the force and position units"
                + (" and the fixed sigma_2" if sigma_2 is not None else "")
            )
    dof = max(f.size - len(coef), 1)
    cov = np.linalg.pinv(design.T @ design) * float(res @ res) / dof
    se = np.sqrt(np.diag(cov))
    if "F_c" in fixed:
        F_c = {"law": "constant", "intercept": float(fixed["F_c"])}
        F_c_se = {"intercept": 0.0}
    elif len(coef) == 2:
        F_c = {"intercept": float(coef[0]), "slope": float(coef[1])}
        F_c_se = {"intercept": float(se[0]), "slope": float(se[1])}
    else:
        F_c = {"law": "constant", "intercept": float(coef[0])}
        F_c_se = {"intercept": float(se[0])}
    aic, bic = information_criteria(float(res @ res), f.size, len(coef))
    reason = "one speed per direction: the Stribeck shape cannot be identified"
    not_identified = ("F_s", "v_r", "alpha") + (() if sigma_2 is not None else ("sigma_2",))
    stderr = {"F_c": F_c_se}
    if sigma_2 is not None:
        stderr["sigma_2"] = {"intercept": 0.0}
    model = FrictionModel(
        {
            "F_c": F_c,
            "F_s": None,
            "sigma_2": None if sigma_2 is None else {"law": "constant", "intercept": sigma_2},
            "v_r": None,
            "alpha": None,
        },
        friction_law="coulomb" if sigma_2 is None else "coulomb_viscous",
        stderr=stderr,
        fixed=tuple(fixed),
        covariance=(names, cov) if names else None,
        covariance_nonrobust=(names, cov) if names else None,  # the same: no clusters here
        statistics={
            "n_points": int(f.size),
            "n_variables": len(coef),
            "rmse": float(np.sqrt(np.mean(res**2))),
            "residual_std": float(np.sqrt(float(res @ res) / dof)),
            "dof": int(dof),
            "aic": aic,
            "bic": bic,
        },
        validity=validity,
        provenance={
            "method": "friction level versus pressure (Stribeck shape not identifiable)"
            + (f"; held fixed: {', '.join(sorted(fixed))}" if fixed else "")
        },
        not_identified={n: reason for n in not_identified},
    )
    comparison = pd.DataFrame(
        [
            {
                "law": "linear" if len(coef) == 2 else "constant",  # (fixed: constant)
                "coefficients [-]": len(coef),
                "rmse [N]": model.statistics["rmse"],
                "aic": aic,
                "bic": bic,
            }
        ]
    )
    return Identification(
        model=model,
        models={"linear": model},
        residuals=res,
        points=points,
        levels=levels,
        per_pressure=per_pressure,
        per_pressure_fits=[],
        regressions={},
        comparison=comparison,
        pressure_law="linear",
        fixed=fixed,
        stribeck_identifiable=False,
        notes=notes,
    )
