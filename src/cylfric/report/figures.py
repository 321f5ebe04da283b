"""Figures of an identification (matplotlib). Engineering units on every axis.

Each ``figure_*`` function returns a matplotlib Figure; :func:`save_figure` writes PNG and
SVG atomically. Numbering follows the thesis (Figs. 4.1-4.12).

The figures are plain :class:`matplotlib.figure.Figure` objects, made without pyplot and
drawn in the report's own style (:data:`STYLE`, applied with ``rc_context``): importing this
module changes neither the user's backend (e.g. a notebook's inline plots) nor their
``rcParams``.
"""

from __future__ import annotations

import functools
import io
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from ..friction import params_at_pressure
from ..io.writers import atomic_write_bytes

if TYPE_CHECKING:
    from matplotlib.typing import RcKeyType

__all__ = [
    "figure_fit",
    "figure_parameters",
    "figure_directions",
    "figure_sensitivity",
    "figure_sensitivity_curves",
    "figure_residuals",
    "save_figure",
    "all_figures",
    "render",
    "render_all",
    "save_rendered",
    "log_axis",
    "not_identified_line",
    "STYLE",
]

STYLE: dict[RcKeyType, Any] = {
    "figure.dpi": 100,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "svg.fonttype": "none",
    "font.size": 9,
    "axes.titley": 1.0,  # titles above the axes, not moved above top tick labels (costly)
}
"""matplotlib rcParams of the report figures (applied only while they are made and drawn)."""

PNG_COMPRESS_LEVEL = 3
"""zlib level of the PNG figures: files 4 % larger than at the default 6, saved 7 % faster."""


def _styled(function):
    """Run ``function`` with :data:`STYLE` in effect."""

    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return function(*args, **kwargs)

    return wrapper


def _log_speed_axis(ax):
    """Log speed axis with 1-2-5 ticks labelled in plain numbers and no minor ticks.

    Engineers read 1, 2, 5, 10, 20, 50 mm/s at a glance; it also draws several times faster
    than the default scientific-notation labels with minor ticks and their gridlines.
    """
    log_axis(ax)


def log_axis(ax, which="x", decades=None):
    """Make the ``which`` axis of ``ax`` logarithmic with several labelled ticks.

    1-2-5 ticks in plain numbers (``decades`` <= 3, or unknown), 1-3 ticks up to 5 decades,
    one per decade beyond; no minor ticks. The default log axis labels only the powers of
    ten, which leaves a range such as 20-200 N/s with one label or none.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    subs: tuple[float, ...] = (1.0, 2.0, 5.0) if decades is None or decades <= 3 else (1.0, 3.0)
    if decades is not None and decades > 5:
        subs = (1.0,)
    (ax.set_xscale if which == "x" else ax.set_yscale)("log")
    axis = ax.xaxis if which == "x" else ax.yaxis
    axis.set_major_locator(LogLocator(base=10, subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    axis.set_minor_locator(NullLocator())


def _legend_right(ax, **keywords):
    """Legend outside the axes, to their right (the canvas leaves room): never over data."""
    return ax.legend(
        loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=7, **keywords
    )


def _legend_below(ax, **keywords):
    """Legend outside the axes, under their x label (the canvas leaves room)."""
    from matplotlib.transforms import offset_copy

    below = offset_copy(ax.transAxes, fig=ax.figure, y=-36, units="points")
    return ax.legend(
        loc="upper center",
        bbox_to_anchor=(0.5, 0.0),
        bbox_transform=below,
        borderaxespad=0.0,
        fontsize=7,
        **keywords,
    )


def _figure_band(model, velocity, pressure, level=0.95):
    """The band the fit figure draws for judging the data: (lower, upper, label).

    The band of a new measured point (:meth:`FrictionModel.prediction_band`, of a new run
    where the model states a scope), not only the band of the mean, which real data miss
    as soon as runs scatter. The band of the mean where the model carries no scatter.
    ``velocity`` [m/s], ``pressure`` [Pa]; lower and upper [N].
    """
    import inspect

    predict = getattr(model, "prediction_band", None)
    if predict is not None and model.statistics.get("residual_std") is not None:
        if "scope" in inspect.signature(predict).parameters:
            lower, upper = predict(velocity, pressure, level, scope="run")
            return lower, upper, f"{level * 100:.0f} % band of a new run's point"
        lower, upper = predict(velocity, pressure, level)
        return lower, upper, f"{level * 100:.0f} % band of a new measured point"
    lower, upper = model.band(velocity, pressure, level)
    return lower, upper, f"{level * 100:.0f} % band of the mean"


def not_identified_line(names_reasons, width=110):
    """One short text: which parameters were not identified and why (grouped by reason).

    ``names_reasons`` maps a parameter name to its reason; '' when it is empty.
    """
    import textwrap

    by_reason: dict[str, list[str]] = {}
    for name, reason in names_reasons.items():
        by_reason.setdefault(str(reason) or "no reason given", []).append(str(name))
    text = "; ".join(
        f"{', '.join(names)} not identified ({reason})" for reason, names in by_reason.items()
    )
    return textwrap.fill(text, width) if text else ""


# The fixed layout of every report figure: size [in], subplot grid, margins (fractions of
# the figure), shared y axes and which panels have a log speed axis.
_CANVASES: dict[str, dict[str, Any]] = {
    "fit": {
        "figsize": (9.4, 4.8),
        "adjust": {"left": 0.075, "right": 0.75, "bottom": 0.11, "top": 0.93},
        "log_speed": (0,),
    },
    "directions": {
        "figsize": (9.4, 4.6),
        "adjust": {"left": 0.08, "right": 0.75, "bottom": 0.11, "top": 0.9},
        "log_speed": (0,),
    },
    "sensitivity": {
        "grid": (1, 2),
        "figsize": (9, 4.2),
        "adjust": {"left": 0.08, "right": 0.99, "bottom": 0.27, "top": 0.9, "wspace": 0.25},
    },
    "sensitivity_curves": {
        "grid": (1, 2),
        "figsize": (11, 5.4),
        "sharey": True,
        "adjust": {"left": 0.06, "right": 0.99, "bottom": 0.23, "top": 0.88, "wspace": 0.05},
        "log_speed": (0, 1),
    },
    "residuals": {
        "grid": (1, 2),
        "figsize": (9, 3.8),
        "sharey": True,
        "adjust": {"left": 0.08, "right": 0.99, "bottom": 0.22, "top": 0.89, "wspace": 0.05},
        "log_speed": (0,),
    },
}


def _canvas(stem, ticks=0):
    """(figure, axes) with the fixed layout of a report figure."""
    spec = _CANVASES[stem]
    fig = Figure(figsize=spec["figsize"])
    axes = fig.subplots(*spec.get("grid", (1, 1)), sharey=spec.get("sharey", False))
    fig.subplots_adjust(**spec["adjust"])
    flat = np.atleast_1d(axes).ravel()
    for i in spec.get("log_speed", ()):
        _log_speed_axis(flat[i])
    return fig, axes


def _levels(points):
    """Points with their pressure ``level`` (as identified), the levels and their colours.

    A points table without ``level`` (an extraction's) is drawn as one group.
    """
    pts = points
    if "flag" in pts:
        pts = pts[pts["flag"].eq("ok")]
    if "level" not in pts:
        pts = pts.assign(level=0)
    levels = sorted(pts["level"].unique())
    colors = matplotlib.colormaps["viridis"](np.linspace(0, 0.9, max(len(levels), 1)))
    return pts, levels, colors


POINTS_DRAWN = 3000
"""Most points a figure draws one marker each; a larger campaign's points are drawn as the
mean and standard deviation of each bin (:func:`_plot_points`), so that a report's cost and
size stay bounded at thousands of runs (issue 27) [-]."""

BINS_PER_DECADE = 24
"""Bins of a logarithmic axis per decade when the points are binned [-]."""

LINEAR_BINS = 200
"""Bins across a linear axis when the points are binned [-]."""


def _plot_points(ax, x, y, fmt, *, binned, log=True, **style):
    """Points (x, y) as markers ``fmt``; with ``binned``, one marker per bin of x (1/24
    decade on a ``log`` axis, else 1/200 of the range): the mean of x and y with error bars
    of the standard deviation of y (its points' spread)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if not binned or x.size == 0:
        ax.plot(x, y, fmt, **style)
        return
    if log:
        key = np.round(np.log10(np.maximum(x, 1e-300)) * BINS_PER_DECADE)
    else:
        span = float(np.ptp(x)) or 1.0
        key = np.round((x - x.min()) / span * LINEAR_BINS)
    _, bin_of, count = np.unique(key, return_inverse=True, return_counts=True)
    mean_x = np.bincount(bin_of, x) / count
    mean_y = np.bincount(bin_of, y) / count
    spread = np.sqrt(np.maximum(np.bincount(bin_of, y * y) / count - mean_y**2, 0.0))
    ax.errorbar(mean_x, mean_y, yerr=spread, fmt=fmt, elinewidth=0.7, capsize=0, **style)


def _binned_note(ax, points: int) -> None:
    """A legend entry saying the markers are bin means (``points`` points in all)."""
    ax.plot([], [], "o", color="0.4", ms=3, label=f"mean ± s.d. per bin ({points:,} points)")


@_styled
def figure_fit(ident):
    """Fig. 4.1: friction against speed (log axis) per pressure, the model and its 95 % bands.

    Two bands: the band a new measured point falls in (:func:`_figure_band`, light) and
    the band of the mean (dark). The legend stands outside the axes, over no point.
    """
    import warnings

    pts, levels, colors = _levels(ident.points)
    model = ident.model
    fig, ax = _canvas("fit")
    speed = pts["velocity [m/s]"].abs()
    grid = np.geomspace(max(speed.min(), 1e-4), speed.max(), 200)
    banded = model.covariance is not None
    widest, widest_mean, band_label = 0.0, 0.0, None
    binned = len(pts) > POINTS_DRAWN
    for level, color in zip(levels, colors, strict=True):
        sel = pts[pts["level"] == level]
        p = float(ident.levels[level])
        _plot_points(
            ax,
            sel["velocity [m/s]"].abs() * 1e3,
            sel["friction [N]"],
            "o",
            binned=binned,
            ms=3.5,
            color=color,
            alpha=0.8,
            label=f"{p / 1e5:.3g} bar",
            zorder=3,
        )
        pressure = np.full_like(grid, p)
        ax.plot(grid * 1e3, model.friction(grid, pressure), "-", color=color, lw=1.2)
        if banded:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the grid spans the data: no extrapolation
                lower, upper, band_label = _figure_band(model, grid, pressure)
                mean_lower, mean_upper = model.band(grid, pressure)
            if not band_label.endswith("of the mean"):
                ax.fill_between(grid * 1e3, lower, upper, color=color, alpha=0.13, lw=0)
                widest = max(widest, float(np.max(upper - lower)) / 2)
            ax.fill_between(grid * 1e3, mean_lower, mean_upper, color=color, alpha=0.35, lw=0)
            widest_mean = max(widest_mean, float(np.max(mean_upper - mean_lower)) / 2)
    ax.plot([], [], "-", color="0.3", lw=1.2, label="model")
    if binned:
        _binned_note(ax, len(pts))
    if banded and band_label is not None and not band_label.endswith("of the mean"):
        ax.fill_between(
            [],
            [],
            [],
            color="0.3",
            alpha=0.13,
            lw=0,
            label=f"{band_label}\n(± up to {widest:.2g} N)",
        )
    if banded:
        ax.fill_between(
            [],
            [],
            [],
            color="0.3",
            alpha=0.35,
            lw=0,
            label=f"95 % band of the mean\n(± up to {widest_mean:.2g} N)",
        )
    ax.set_xlabel("speed |v| [mm/s]")
    ax.set_ylabel("friction force F_f [N]")
    ax.set_title(
        "Steady-state friction and the fitted pressure-dependent model (cf. thesis Fig. 4.1)"
    )
    _legend_right(ax, title="pressure", ncol=1 if len(levels) <= 16 else 2)
    return fig


@_styled
def figure_model(model, pressures=None, *, velocities=None, level=0.95, ax=None):
    """A model alone: friction against speed (log axis) per pressure, with its band of the mean.

    What :meth:`cylfric.model.FrictionModel.plot` draws. Takes any object with the
    FrictionModel interface (``friction``, ``band``, ``validity``, ``covariance``); imports none.

    Parameters
    ----------
    model : FrictionModel
    pressures : sequence of float, optional
        Operating pressures [Pa]; default three over the validity range (else 0, 50, 100 bar).
    velocities : sequence of float, optional
        Speeds [m/s]; default 120 on a log grid over the validity range (else 1-100 mm/s).
    level : float
        Confidence level of the band of the mean [-] (drawn when the model has a covariance).
    ax : matplotlib Axes, optional
        Axes to draw into; default a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import warnings

    val = model.validity
    if pressures is None:
        low, high = (0.0, 100e5) if val is None else (val["pressure_min"], val["pressure_max"])
        pressures = np.linspace(low, high, 3)
    if velocities is None:
        low, high = (1e-3, 0.1) if val is None else (val["velocity_min"], val["velocity_max"])
        velocities = np.geomspace(max(low, 1e-5), max(high, 2 * max(low, 1e-5)), 120)
    speeds = np.abs(np.asarray(velocities, dtype=float))
    own = ax is None
    if ax is None:
        fig = Figure(figsize=(9.2, 4.6))
        ax = fig.subplots()
        fig.subplots_adjust(left=0.08, right=0.77, bottom=0.11, top=0.9)
    else:
        fig = ax.figure
    _log_speed_axis(ax)
    banded = model.covariance is not None
    colors = matplotlib.colormaps["viridis"](np.linspace(0.1, 0.85, max(len(pressures), 1)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # extrapolation warnings: the caller chose the grid
        for p, color in zip(pressures, colors, strict=False):
            pressure = np.full_like(speeds, float(p))
            ax.plot(
                speeds * 1e3,
                model.friction(speeds, pressure),
                "-",
                color=color,
                lw=1.4,
                label=f"{float(p) / 1e5:.3g} bar",
            )
            if banded:
                lower, upper = model.band(speeds, pressure, level)
                ax.fill_between(speeds * 1e3, lower, upper, color=color, alpha=0.25, lw=0)
    if banded:
        ax.fill_between(
            [], [], [], color="0.3", alpha=0.25, lw=0, label=f"{level:.0%} band of the mean"
        )
    ax.set_xlabel("speed |v| [mm/s]")
    ax.set_ylabel("friction force F_f [N]")
    ax.set_title(f"Steady-state friction ({model.friction_law} law, {model.reference} pressure)")
    if own:
        _legend_right(ax, title="operating pressure")
    else:  # the user's axes: matplotlib's emptiest corner
        ax.legend(title="operating pressure", fontsize=7, loc="best")
    return fig


_PARAMETER_PANELS = (
    ("F_c", "N", 1, "F_c [N]"),
    ("F_s", "N", 1, "F_s [N]"),
    ("sigma_2", "N*s/m", 1e-3, "sigma_2 [N*s/mm]"),
    ("v_r", "m/s", 1e3, "v_r [mm/s]"),
    ("alpha", "-", 1, "alpha [-]"),
    ("stribeck_velocity", "m/s", 1e3, "v_Stribeck [mm/s]"),
)
"""Panels of the parameters figure: (name, SI unit, factor to the shown unit, axis label)."""


def _shown_parameters(ident):
    """(panels with per-pressure values, {name: reason} of those without)."""
    table = ident.per_pressure
    shown, missing = [], {}
    reasons = dict(getattr(ident.model, "not_identified", {}) or {})
    for spec in _PARAMETER_PANELS:
        name, unit = spec[0], spec[1]
        col = f"{name} [{unit}]"
        if len(table) and col in table and not table[col].isna().all():
            shown.append(spec)
        elif name == "stribeck_velocity":
            if "v_r" not in reasons and "alpha" not in reasons:
                missing["v_Stribeck"] = "no per-pressure values"
        else:
            missing[name] = reasons.get(name, "no per-pressure values")
    return shown, missing


@_styled
def figure_parameters(ident):
    """Fig. 4.2: per-pressure parameters with the fitted pressure laws and 95 % intervals.

    Only the parameters with per-pressure values get a panel; a line under the title says
    which were not identified and why (the model's ``not_identified`` reasons). None when
    no parameter has per-pressure values.
    """
    table = ident.per_pressure
    shown, missing = _shown_parameters(ident)
    if not shown:
        return None
    ncols = min(len(shown), 3)
    nrows = -(-len(shown) // 3)
    note = not_identified_line(missing, width=40 * ncols + 20)
    note_lines = note.count("\n") + 1 if note else 0
    width, height = 3.4 * ncols + 0.4, 2.6 * nrows + 1.0 + 0.16 * note_lines
    fig = Figure(figsize=(width, height))
    axes = np.atleast_1d(fig.subplots(nrows, ncols, squeeze=False)).ravel()
    top = 1 - (0.42 + 0.16 * note_lines) / height
    fig.subplots_adjust(
        left=0.6 / width,
        right=1 - 0.1 / width,
        bottom=0.95 / height,
        top=top,
        wspace=0.38,
        hspace=0.35,
    )
    for ax in axes[len(shown) :]:
        fig.delaxes(ax)  # a short last row: no empty panel
    p_bar = table["pressure [Pa]"] / 1e5
    p_line = np.linspace(0, max(float(np.max(p_bar)), 1), 100)
    for ax, (name, unit, k, label) in zip(axes, shown, strict=False):
        col = f"{name} [{unit}]"
        err = table.get(f"{name}_stderr [{unit}]")
        yerr = 1.96 * err * k if err is not None else None
        ax.errorbar(
            p_bar,
            table[col] * k,
            yerr=yerr,
            fmt="o",
            ms=4,
            capsize=2,
            label="per-pressure fit (95 %)",
        )
        if name in ident.regressions and "linear" in ident.regressions[name]:
            spec = ident.regressions[name]["linear"].spec
            values = params_at_pressure(p_line * 1e5, {name: spec})[name]
            ax.plot(p_line, values * k, "-", lw=1, label="weighted regression")
        if ident.model.laws.get(name) is not None:
            values = ident.model.params_at(p_line * 1e5)[name]
            if np.ndim(values):
                ax.plot(p_line, values * k, "--", lw=1, label="global surface fit")
            else:
                ax.axhline(values * k, ls="--", lw=1, label="global surface fit")
        ax.set_xlabel("pressure p [bar]")
        ax.set_ylabel(label)
    handles: dict[str, Any] = {}
    for ax in axes[: len(shown)]:
        for handle, text in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(text, handle)
    fig.legend(
        list(handles.values()),
        list(handles),
        loc="lower center",
        bbox_to_anchor=(0.5, 0.02),
        ncol=len(handles),
        fontsize=7,
        frameon=False,
    )
    fig.suptitle("Parameters against pressure (cf. thesis Fig. 4.2)", y=1 - 0.08 / height, va="top")
    if note:
        fig.text(0.5, 1 - 0.36 / height, note, ha="center", va="top", fontsize=7.5, color="0.3")
    return fig


@_styled
def figure_directions(points, offset=None):
    """Fig. 4.3: ascending against descending force-balance levels and the load-cell offset.

    ``points`` is a points table (an extraction's, or an identification's ``points``); it
    needs no identified model.
    """
    pts, levels, colors = _levels(points)
    fig, ax = _canvas("directions")
    if "force [N]" in pts and "direction [-]" in pts:
        binned = len(pts) > POINTS_DRAWN
        for level, color in zip(levels, colors, strict=True):
            sel = pts[pts["level"] == level]
            pressure = sel["pressure [Pa]"].mean() / 1e5
            for sign, marker in ((1, "^"), (-1, "v")):
                part = sel[sel["direction [-]"] == sign]
                _plot_points(
                    ax,
                    part["velocity [m/s]"].abs() * 1e3,
                    part["force [N]"] * sign,
                    marker,
                    binned=binned,
                    ms=3.5,
                    color=color,
                    alpha=0.8,
                    label=f"{pressure:.3g} bar" if sign == 1 else None,
                )
        ax.plot([], [], "^", color="0.4", label="ascending (extension)")
        ax.plot([], [], "v", color="0.4", label="descending, sign flipped")
        if binned:
            _binned_note(ax, len(pts))
        _legend_right(ax, ncol=1 if len(levels) <= 16 else 2)
        if offset is not None and np.isfinite(offset):
            ax.set_title(
                "Ascending and descending levels (cf. thesis Fig. 4.3): they differ by\n"
                f"2 x the load-cell offset (weight, preload or pressure force) = "
                f"{2 * offset:.2f} N",
                fontsize=9,
            )
    ax.set_xlabel("speed |v| [mm/s]")
    ax.set_ylabel("force-balance level x direction [N]")
    return fig


@_styled
def figure_sensitivity(ident):
    """Tables 4.2-4.4 as curves: RMSE against alpha (two v_r) and against v_r (alpha = 1)."""
    table = ident.sensitivity
    fig, axes = _canvas("sensitivity")
    for name, label in (
        ("4.2", "v_r = 7.43 mm/s (Table 4.2)"),
        ("4.3", "v_r = 10 mm/s (Table 4.3)"),
    ):
        part = table[table["table"] == name]
        axes[0].plot(part["alpha [-]"], part["rmse [N]"], "o-", label=label)
    axes[0].set_xlabel("alpha [-]")
    axes[0].set_ylabel("RMSE ('SME', eq. 4.4) [N]")
    _legend_below(axes[0])
    part = table[table["table"] == "4.4"]
    axes[1].plot(part["v_r [m/s]"] * 1e3, part["rmse [N]"], "o-", label="alpha = 1 (Table 4.4)")
    if ident.recommended:
        axes[1].axvline(
            ident.recommended["v_r"] * 1e3,
            ls="--",
            color="gray",
            label=f"grid minimum: alpha = {ident.recommended['alpha']:.2f}, "
            f"v_r = {ident.recommended['v_r'] * 1e3:.2f} mm/s",
        )
    axes[1].set_xlabel("v_r [mm/s]")
    axes[1].set_ylabel("RMSE [N]")
    _legend_below(axes[1])
    fig.suptitle("Sensitivity of the whole model to alpha and v_r (thesis 4.1.1-4.1.2)")
    return fig


@_styled
def figure_sensitivity_curves(ident):
    """Figs. 4.4-4.12 in two panels: the model refit at each fixed alpha and v_r, with data.

    Left: alpha = 0.5 ... 2 at v_r = 10 mm/s (thesis Figs. 4.4-4.9); right: v_r = 5 ... 15
    mm/s at alpha = 1 (Figs. 4.10-4.12 and 4.7). Each refit is the whole pressure-dependent
    model with alpha and v_r held; drawn at the lowest and highest pressure, RMSE in the legend.
    """
    pts, levels, _ = _levels(ident.points)
    speed = pts["velocity [m/s]"].abs().to_numpy()
    force = pts["friction [N]"].to_numpy()
    grid = np.geomspace(max(speed.min(), 1e-4), speed.max(), 120)
    shown = [levels[0], levels[-1]] if len(levels) > 1 else levels
    fig, axes = _canvas("sensitivity_curves")
    panels = ((axes[0], "alpha", "v_r = 10 mm/s"), (axes[1], "v_r", "alpha = 1"))
    for ax, panel, title in panels:
        cases = [r for r in ident.sensitivity_refits if r["panel"] == panel]
        colors = matplotlib.colormaps["plasma"](np.linspace(0, 0.85, len(cases)))
        for level in shown:
            sel = pts["level"].to_numpy() == level
            _plot_points(
                ax,
                speed[sel] * 1e3,
                force[sel],
                "o",
                binned=len(pts) > POINTS_DRAWN,
                ms=3,
                color="0.35",
                zorder=3,
            )
        for refit, color in zip(cases, colors, strict=True):
            label = (
                f"alpha = {refit['alpha [-]']:g}"
                if panel == "alpha"
                else f"v_r = {refit['v_r [m/s]'] * 1e3:g} mm/s"
            ) + f": RMSE {refit['rmse [N]']:.2f} N"
            for j, level in enumerate(shown):
                pressure = np.full_like(grid, ident.levels[level])
                curve = refit["model"].params_at(pressure)
                model = refit["model"].friction(grid, pressure) if _physical(curve) else None
                if model is None:
                    label += " (unphysical)" if j == 0 else ""
                    continue
                ax.plot(
                    grid * 1e3, model, "-", color=color, lw=1.2, label=label if j == 0 else None
                )
        ax.set_xlabel("speed |v| [mm/s]")
        ax.set_title(f"refit at fixed values, {title}", fontsize=9)
        _legend_below(ax, ncol=2)
    axes[0].set_ylabel("friction [N]")
    p_low, p_high = (ident.levels[lv] / 1e5 for lv in (shown[0], shown[-1]))
    fig.suptitle(
        f"Model refit at fixed alpha and v_r against the data at {p_low:.3g} and "
        f"{p_high:.3g} bar (cf. thesis Figs. 4.4-4.12)"
    )
    return fig


def _physical(params):
    """True when a refit's parameters are drawable (F_c, F_s, sigma_2 >= 0)."""
    return all(np.min(params[n]) >= 0 for n in ("F_c", "F_s", "sigma_2"))


@_styled
def figure_residuals(ident):
    """Residuals of the surface fit against speed and pressure."""
    pts = ident.points
    res = ident.residuals
    fig, axes = _canvas("residuals")
    binned = len(pts) > POINTS_DRAWN
    label = f"mean ± s.d. per bin ({len(pts):,} points)" if binned else "point (window)"
    speed = pts["velocity [m/s]"].abs() * 1e3
    _plot_points(axes[0], speed, res, ".", binned=binned, ms=3, label=label)
    axes[0].set_xlabel("speed |v| [mm/s]")
    axes[0].set_ylabel("residual (data - model) [N]")
    pressure = pts["pressure [Pa]"] / 1e5
    _plot_points(axes[1], pressure, res, ".", binned=binned, log=False, ms=3, label=label)
    axes[1].set_xlabel("pressure p [bar]")
    scatter = ident.model.statistics.get("residual_std")
    for ax in axes:
        ax.axhline(0, color="k", lw=0.6)
        if scatter:
            ax.axhspan(
                -2 * scatter, 2 * scatter, color="0.5", alpha=0.12, lw=0, label="± 2 x residual std"
            )
    _legend_below(axes[0], ncol=2)
    fig.suptitle(f"Residuals of the global fit (RMSE {ident.model.statistics['rmse']:.3f} N)")
    return fig


@_styled
def render(fig) -> tuple[bytes, bytes]:
    """PNG and SVG bytes of a figure (fixed layouts: no layout pass at save time).

    A figure made with pyplot is closed afterwards.
    """
    png = io.BytesIO()
    fig.savefig(png, format="png", pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    svg = io.BytesIO()
    fig.savefig(svg, format="svg")
    if fig.canvas.manager is not None:
        import matplotlib.pyplot as plt

        plt.close(fig)
    return png.getvalue(), svg.getvalue()


def save_figure(fig, folder, stem) -> dict:
    """Write ``stem.png`` and ``stem.svg`` atomically; return their paths and the PNG bytes."""
    png, svg = render(fig)
    return save_rendered(folder, stem, png, svg)


def save_rendered(folder, stem, png: bytes, svg: bytes) -> dict:
    """Write already rendered PNG and SVG bytes atomically."""
    folder = Path(folder)
    return {
        "png": atomic_write_bytes(folder / f"{stem}.png", png),
        "svg": atomic_write_bytes(folder / f"{stem}.svg", svg),
        "png_bytes": png,
    }


def render_all(ident, offset=None, *, workers=None, progress=None):
    """Draw every report figure: ``[(stem, caption, png, svg)]`` in report order.

    With ``workers`` >= 2 (None: the cores this process may use,
    :func:`cylfric._parallel.cores`) the figures are drawn on a pool of forked processes
    (:func:`cylfric._parallel.run`: matplotlib is single-threaded, and the workers inherit
    it loaded); where no pool can be forked, here, one after another. The result is the
    same either way. ``progress`` is called with each figure's stem once it is drawn.
    """
    from .._parallel import cores, run

    figures = all_figures(ident, offset)
    done = None if progress is None else (lambda i, _: progress(figures[i][0]))
    if workers is None:
        workers = cores()
    drawn = run(lambda i: render(figures[i][2]()), len(figures), workers=workers, done=done)
    return [
        (stem, caption, *images) for (stem, caption, _), images in zip(figures, drawn, strict=True)
    ]


def all_figures(ident=None, offset=None, points=None):
    """(stem, caption, builder) for every report figure the given results allow, in order.

    ``points`` (a points table; default ``ident.points``) allows the directions figure, an
    identification ``ident`` the model figures, and its sensitivity study the last two.
    ``offset`` is the load-cell offset [N] (weight, preload or pressure force).
    """
    if points is None and ident is not None:
        points = ident.points
    directions = (
        "directions",
        "Ascending against descending levels and the load-cell offset (weight, preload or "
        "pressure force) between them (cf. Fig. 4.3).",
        lambda: figure_directions(points, offset),
    )
    if ident is None:
        return [directions] if points is not None else []
    figures = [
        (
            "fit",
            "Steady-state points and the fitted pressure-dependent model with the 95 % "
            "band of a new measured point (light) and of the mean (dark) (cf. thesis "
            "Fig. 4.1).",
            lambda: figure_fit(ident),
        ),
    ]
    if _shown_parameters(ident)[0]:
        figures.append(
            (
                "parameters",
                "Per-pressure parameters with 95 % intervals, the weighted "
                "regressions and the global fit (cf. Fig. 4.2); a parameter without "
                "per-pressure values has no panel.",
                lambda: figure_parameters(ident),
            )
        )
    figures += [
        directions,
        ("residuals", "Residuals against speed and pressure.", lambda: figure_residuals(ident)),
    ]
    if ident.sensitivity is not None:
        figures += [
            (
                "sensitivity",
                "RMSE against alpha and v_r (Tables 4.2-4.4).",
                lambda: figure_sensitivity(ident),
            ),
            (
                "sensitivity_curves",
                "Model refit at each fixed alpha (v_r = 10 mm/s) and v_r (alpha = 1) against the "
                "data, with the RMSE of each (cf. Figs. 4.4-4.12).",
                lambda: figure_sensitivity_curves(ident),
            ),
        ]
    return figures
