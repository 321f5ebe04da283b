"""Identification of the pressure-dependent friction model from steady-state points (ch. 4).

:func:`identify` runs the thesis method and more on a points table (from
:func:`cylfric.steady_state.extract_campaign`): per-pressure Stribeck fits (Table 4.1), the
pressure laws two ways (regression of the per-pressure parameters, and one global surface
fit), information criteria across laws, the alpha / v_r sensitivity study (Tables 4.2-4.4),
and per-direction fits on request.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from .pressure_fit import (
    LAW_COEFFICIENTS,
    PRESSURE_DEPENDENT,
    LawFit,
    SurfaceFit,
    fit_surface,
    information_criteria,
    regress_parameters,
)
from .sensitivity import sensitivity_grid, thesis_tables
from .stribeck_fit import (
    MIN_POINTS,
    PARAMETERS,
    IdentificationWarning,
    StribeckFit,
    fit_stribeck,
)

__all__ = [
    "identify",
    "add_sensitivity",
    "Identification",
    "fit_stribeck",
    "StribeckFit",
    "fit_surface",
    "SurfaceFit",
    "regress_parameters",
    "LawFit",
    "sensitivity_grid",
    "thesis_tables",
    "pressure_levels",
    "IdentificationWarning",
    "PARAMETERS",
]

LAWS_COMPARED = ("linear", "quadratic", "exponential")


def pressure_levels(pressure, *, gap=1e5, relative=0.05):
    """Group measured pressures [Pa] into levels; returns (level index per point, level means).

    A new level starts where sorted pressures jump by more than max(gap [Pa],
    relative * pressure).
    """
    p = np.asarray(pressure, dtype=float)
    order = np.argsort(p)
    sorted_p = p[order]
    jumps = np.diff(sorted_p) > np.maximum(gap, relative * np.abs(sorted_p[1:]))
    labels_sorted = np.concatenate(([0], np.cumsum(jumps)))
    labels = np.empty_like(labels_sorted)
    labels[order] = labels_sorted
    means = np.array([p[labels == k].mean() for k in range(labels_sorted[-1] + 1)])
    return labels, means


def _distinct_speeds(speed, relative=0.1):
    s = np.sort(np.abs(speed))
    return 1 + int(np.sum(np.diff(s) > relative * s[1:])) if s.size else 0


@dataclass
class Identification:
    """Everything :func:`identify` found (SI units).

    Attributes
    ----------
    per_pressure : pandas.DataFrame
        Table 4.1 layout: one row per pressure level with ``pressure [Pa]``, ``F_c [N]``,
        ``F_s [N]``, ``sigma_2 [N*s/m]``, ``v_r [m/s]``, ``alpha [-]``,
        ``stribeck_velocity [m/s]``, ``rmse [N]``, ``n_points [-]`` and ``*_stderr`` columns.
    fits : list of StribeckFit
        The per-pressure fits.
    regressions : dict
        Parameter -> law -> :class:`LawFit` (route a).
    surface : SurfaceFit
        The global fit with the chosen law (route b); the datasheet's model.
    surfaces : dict
        Law -> SurfaceFit for every compared law.
    comparison : pandas.DataFrame
        Law, number of coefficients, RMSE, AIC, BIC of the surface fits.
    sensitivity : pandas.DataFrame
        Tables 4.2-4.4 (``table``, ``alpha [-]``, ``v_r [m/s]``, ``rmse [N]``).
    grid : pandas.DataFrame
        RMSE over a finer alpha x v_r grid.
    recommended : dict
        Grid minimum: ``alpha``, ``v_r``, ``rmse``.
    directions : dict
        ``"extension"``/``"retraction"`` -> Identification, with ``per_direction``.
    stribeck_identifiable : bool
        False when the data has too few speeds per pressure (e.g. one speed per direction).
    notes : list of str
        Warnings raised on the way, in words, for the report.
    """

    per_pressure: pd.DataFrame
    fits: list
    regressions: dict
    surface: SurfaceFit
    surfaces: dict
    comparison: pd.DataFrame
    sensitivity: pd.DataFrame | None
    grid: pd.DataFrame | None
    recommended: dict
    law: str
    fixed: dict
    points: pd.DataFrame
    stribeck_identifiable: bool = True
    directions: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    @property
    def parameters(self) -> dict:
        """The pressure coefficient set of the surface fit (plugs into params_at_pressure)."""
        return self.surface.coefficients

    def summary(self) -> pd.DataFrame:
        """Pressure laws in engineering units: parameter, intercept, slope per bar, unit."""
        rows = []
        units = {"F_c": ("N", 1.0), "F_s": ("N", 1.0), "sigma_2": ("N*s/mm", 1e-3)}
        for par in PRESSURE_DEPENDENT:
            unit, k = units[par]
            c = self.surface.coefficients[par]
            e = self.surface.stderr[par]
            row = {
                "parameter": par,
                "unit": unit,
                "intercept": c["intercept"] * k,
                "intercept_stderr": e["intercept"] * k,
            }
            if "slope" in c:
                row.update(slope_per_bar=c["slope"] * k * 1e5, slope_stderr=e["slope"] * k * 1e5)
            rows.append(row)
        return pd.DataFrame(rows)


def _per_pressure(points, levels, fixed):
    rows, fits = [], []
    for k in range(len(levels)):
        sel = points[points["level"] == k]
        if len(sel) < MIN_POINTS:
            continue
        fit = fit_stribeck(sel["velocity [m/s]"], sel["friction [N]"], fixed=fixed)
        fits.append(fit)
        units = {"F_c": "N", "F_s": "N", "sigma_2": "N*s/m", "v_r": "m/s", "alpha": "-"}
        row = {"pressure [Pa]": float(sel["pressure [Pa]"].mean())}
        for p in PARAMETERS:
            row[f"{p} [{units[p]}]"] = fit.params[p]
        row["stribeck_velocity [m/s]"] = fit.stribeck_velocity
        row["rmse [N]"] = fit.rmse
        row["n_points [-]"] = fit.n_points
        for p in PARAMETERS:
            row[f"{p}_stderr [{units[p]}]"] = fit.stderr[p]
        rows.append(row)
    return pd.DataFrame(rows), fits


def _check_per_pressure(per_pressure, fits):
    """Warn about failed fits and parameters that fall significantly as pressure rises."""
    for fit, (_, row) in zip(fits, per_pressure.iterrows(), strict=True):
        if not fit.success:
            warnings.warn(
                f"the Stribeck fit at {row['pressure [Pa]'] / 1e5:.3g} bar did not "
                f"converge ({fit.message}); its row of the table is unreliable",
                IdentificationWarning,
                stacklevel=3,
            )
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


def _core(points, *, law, fixed, notes):
    labels, levels = pressure_levels(points["pressure [Pa]"])
    points = points.assign(level=labels)
    per_pressure, fits = _per_pressure(points, levels, fixed)
    _check_per_pressure(per_pressure, fits)
    regressions = {}
    if len(per_pressure) >= 2:
        for par, unit in (("F_c", "N"), ("F_s", "N"), ("sigma_2", "N*s/m")):
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
    surface_fixed = {k: v for k, v in fixed.items() if k in ("v_r", "alpha")}
    surfaces = {}
    for name in LAWS_COMPARED:
        n_levels = len(levels)
        if len(LAW_COEFFICIENTS[name]) > n_levels:
            continue
        try:
            surfaces[name] = fit_surface(
                points["velocity [m/s]"],
                points["pressure [Pa]"],
                points["friction [N]"],
                law=name,
                fixed=surface_fixed,
                start=surfaces.get("linear"),  # LAWS_COMPARED starts with linear
            )
        except (ValueError, np.linalg.LinAlgError) as exc:
            notes.append(f"surface fit with the {name} law failed: {exc}")
    if law not in surfaces:
        raise ValueError(
            f"the {law} pressure law cannot be fitted to {len(levels)} pressure "
            "level(s); use --law linear or measure more pressures"
        )
    comparison = pd.DataFrame(
        [
            {
                "law": n,
                "coefficients [-]": 3 * len(LAW_COEFFICIENTS[n]) + 2 - len(surface_fixed),
                "rmse [N]": s.rmse,
                "aic": s.aic,
                "bic": s.bic,
            }
            for n, s in surfaces.items()
        ]
    )
    return points, per_pressure, fits, regressions, surfaces, comparison


def identify(
    points: pd.DataFrame, *, fixed=None, law="linear", per_direction=False, sensitivity=True
) -> Identification:
    """Identify the pressure-dependent friction model from a points table.

    Parameters
    ----------
    points : pandas.DataFrame
        Points with ``velocity [m/s]``, ``pressure [Pa]``, ``friction [N]`` and, when present,
        ``flag`` (only ``"ok"`` rows are used) and ``direction [-]``.
    fixed : dict, optional
        Parameters held fixed in every fit (SI), e.g. ``{"alpha": 1, "v_r": 0.010}`` as the
        thesis chose.
    law : {"linear", "quadratic", "exponential"}
        Pressure law of the datasheet model; all three are fitted and compared.
    per_direction : bool
        Also identify extension and retraction separately.
    sensitivity : bool
        Run the alpha / v_r sensitivity study (see :func:`add_sensitivity`).

    Returns
    -------
    Identification

    Raises
    ------
    ValueError
        Missing columns, NaN values, too few points, unknown law or fixed names.
    """
    fixed = dict(fixed or {})
    unknown = set(fixed) - set(PARAMETERS)
    if unknown:
        raise ValueError(f"unknown fixed parameters {sorted(unknown)}; valid: {list(PARAMETERS)}")
    if law not in LAW_COEFFICIENTS:
        raise ValueError(f"unknown pressure law {law!r}; valid: {sorted(LAW_COEFFICIENTS)}")
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
    notes = []
    labels, levels = pressure_levels(used["pressure [Pa]"])
    speeds_per_level = [
        _distinct_speeds(used["velocity [m/s]"].to_numpy()[labels == k]) for k in range(len(levels))
    ]
    if max(speeds_per_level) < 4:
        message = (
            f"at most {max(speeds_per_level)} distinct speed(s) per pressure: the "
            "Stribeck shape (F_s, v_r, alpha, sigma_2) cannot be identified; the datasheet "
            "gives the friction level versus pressure (F_c(p), with F_s = F_c, sigma_2 = 0)"
        )
        warnings.warn(message, IdentificationWarning, stacklevel=2)
        return _level_only(used, labels, levels, law, fixed, notes + [message])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        core = _core(used, law=law, fixed=fixed, notes=notes)
    notes += [str(w.message) for w in caught]
    for w in caught:  # recorded for the report, and still shown to the caller
        warnings.warn(w.message, w.category, stacklevel=2)
    pts, per_pressure, fits, regressions, surfaces, comparison = core
    surface = surfaces[law]
    for par in PRESSURE_DEPENDENT:
        slope = surface.coefficients[par].get("slope")
        if slope is not None and slope < 0:
            notes.append(
                f"{par} falls with pressure (slope {slope * 1e5:.3g} per bar): check "
                "the pressure column and the force-balance signs"
            )
    result = Identification(
        per_pressure,
        fits,
        regressions,
        surface,
        surfaces,
        comparison,
        sensitivity=None,  # filled by add_sensitivity
        grid=None,
        recommended={},
        law=law,
        fixed=fixed,
        points=pts,
        stribeck_identifiable=True,
        directions={},
        notes=notes,
    )
    if sensitivity:
        result = add_sensitivity(result)
    if per_direction and "direction [-]" in used:
        for name, sign in (("extension", 1), ("retraction", -1)):
            subset = used[used["direction [-]"] == sign]
            if len(subset) >= MIN_POINTS:
                result.directions[name] = identify(subset, fixed=fixed, law=law, sensitivity=False)
    return result


def add_sensitivity(ident: Identification) -> Identification:
    """A copy of ``ident`` with the alpha / v_r sensitivity study (thesis 4.1.1-4.1.2).

    Fills ``sensitivity`` (Tables 4.2-4.4), ``grid`` and ``recommended``; warnings raised on
    the way are added to ``notes``. :func:`identify` calls it unless ``sensitivity=False``;
    calling it separately lets a caller use the model (e.g. start drawing figures) while the
    study runs. An identification without a Stribeck shape is returned unchanged.
    """
    if not ident.stribeck_identifiable:
        return ident
    points = ident.points
    args = (points["velocity [m/s]"], points["pressure [Pa]"], points["friction [N]"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = thesis_tables(*args)
        grid, recommended = sensitivity_grid(*args)
    for w in caught:
        warnings.warn(w.message, w.category, stacklevel=2)
    return replace(
        ident,
        sensitivity=table,
        grid=grid,
        recommended=recommended,
        notes=ident.notes + [str(w.message) for w in caught],
    )


def _level_only(points, labels, levels, law, fixed, notes):
    """Friction level versus pressure when the Stribeck shape is not identifiable."""
    level_rows = []
    for k in range(len(levels)):
        sel = points[labels == k]
        f = sel["friction [N]"].to_numpy()
        level_rows.append(
            {
                "pressure [Pa]": float(sel["pressure [Pa]"].mean()),
                "F_c [N]": float(f.mean()),
                "F_s [N]": float(f.mean()),
                "sigma_2 [N*s/m]": 0.0,
                "v_r [m/s]": math.nan,
                "alpha [-]": math.nan,
                "stribeck_velocity [m/s]": math.nan,
                "rmse [N]": float(f.std()),
                "n_points [-]": int(f.size),
                "F_c_stderr [N]": float(f.std(ddof=1) / math.sqrt(f.size))
                if f.size > 1
                else math.nan,
            }
        )
    per_pressure = pd.DataFrame(level_rows)
    p = points["pressure [Pa]"].to_numpy()
    f = points["friction [N]"].to_numpy()
    if len(levels) >= 2:
        design = np.column_stack([np.ones_like(p), p])
        coef, *_ = np.linalg.lstsq(design, f, rcond=None)
        res = f - design @ coef
        cov = np.linalg.pinv(design.T @ design) * float(res @ res) / max(f.size - 2, 1)
        se = np.sqrt(np.diag(cov))
    else:
        coef, se, res = np.array([f.mean(), 0.0]), np.array([f.std(), 0.0]), f - f.mean()
    v_r = float(fixed.get("v_r", 0.010))
    alpha = float(fixed.get("alpha", 1.0))
    line = {"intercept": float(coef[0]), "slope": float(coef[1])}
    line_se = {"intercept": float(se[0]), "slope": float(se[1])}
    coefficients = {
        "F_c": line,
        "F_s": dict(line),
        "sigma_2": {"intercept": 0.0, "slope": 0.0},
        "v_r": v_r,
        "alpha": alpha,
    }
    stderr = {
        "F_c": line_se,
        "F_s": dict(line_se),
        "sigma_2": {"intercept": 0.0, "slope": 0.0},
        "v_r": 0.0,
        "alpha": 0.0,
    }
    aic, bic = information_criteria(float(res @ res), f.size, 2)
    surface = SurfaceFit(
        "linear",
        coefficients,
        stderr,
        float(np.sqrt(np.mean(res**2))),
        aic,
        bic,
        int(f.size),
        res,
        True,
        "friction level versus pressure only",
    )
    comparison = pd.DataFrame(
        [{"law": "linear", "coefficients [-]": 2, "rmse [N]": surface.rmse, "aic": aic, "bic": bic}]
    )
    return Identification(
        per_pressure,
        [],
        {},
        surface,
        {"linear": surface},
        comparison,
        None,
        None,
        {},
        "linear",
        fixed,
        points.assign(level=labels),
        False,
        {},
        notes,
    )
