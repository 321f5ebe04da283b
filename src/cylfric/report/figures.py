"""Figures of an identification (matplotlib, Agg). Engineering units on every axis.

Each ``figure_*`` function returns a matplotlib Figure; :func:`save_figure` writes PNG and
SVG atomically. Numbering follows the thesis (Figs. 4.1-4.12).
"""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..friction import params_at_pressure  # noqa: E402
from ..identify.sensitivity import THESIS_ALPHAS  # noqa: E402
from ..identify.stribeck_fit import design_columns, solve_linear  # noqa: E402
from ..io.writers import atomic_write_bytes  # noqa: E402

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
    "FigureRenderer",
]

plt.rcParams.update(
    {
        "figure.dpi": 100,
        "axes.grid": True,
        "grid.alpha": 0.3,
        "svg.fonttype": "none",
        "font.size": 9,
    }
)


def _log_speed_axis(ax):
    """Log speed axis with 1-2-5 ticks labelled in plain numbers and no minor ticks.

    Engineers read 1, 2, 5, 10, 20, 50 mm/s at a glance; it also draws several times faster
    than the default scientific-notation labels with minor ticks and their gridlines.
    """
    from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

    ax.set_xscale("log")
    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    ax.xaxis.set_minor_locator(NullLocator())


def _levels(ident):
    pts = ident.points
    levels = sorted(pts["level"].unique())
    colors = plt.cm.viridis(np.linspace(0, 0.9, max(len(levels), 1)))
    return pts, levels, colors


def figure_fit(ident):
    """Fig. 4.1: friction against speed (log axis) per pressure, with the fitted surface."""
    pts, levels, colors = _levels(ident)
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.11, top=0.93)
    speed = pts["velocity [m/s]"].abs()
    grid = np.geomspace(max(speed.min(), 1e-4), speed.max(), 200)
    for level, color in zip(levels, colors, strict=True):
        sel = pts[pts["level"] == level]
        p = sel["pressure [Pa]"].mean()
        ax.plot(
            sel["velocity [m/s]"].abs() * 1e3,
            sel["friction [N]"],
            "o",
            ms=3.5,
            color=color,
            alpha=0.8,
            label=f"{p / 1e5:.3g} bar",
        )
        ax.plot(
            grid * 1e3,
            ident.surface.friction(grid, np.full_like(grid, p)),
            "-",
            color=color,
            lw=1.2,
        )
    _log_speed_axis(ax)
    ax.set_xlabel("speed |v| [mm/s]")
    ax.set_ylabel("friction force F_f [N]")
    ax.set_title(
        "Steady-state friction and the fitted pressure-dependent model (cf. thesis Fig. 4.1)"
    )
    ax.legend(title="pressure", fontsize=7, ncol=2, loc="upper left")
    return fig


def figure_parameters(ident):
    """Fig. 4.2: per-pressure parameters with the fitted pressure laws and 95 % intervals."""
    table = ident.per_pressure
    fig, axes = plt.subplots(2, 3, figsize=(10, 5.6))
    fig.subplots_adjust(left=0.07, right=0.99, bottom=0.09, top=0.92, wspace=0.32, hspace=0.3)
    specs = [
        ("F_c", "N", 1, "F_c [N]"),
        ("F_s", "N", 1, "F_s [N]"),
        ("sigma_2", "N*s/m", 1e-3, "sigma_2 [N*s/mm]"),
        ("v_r", "m/s", 1e3, "v_r [mm/s]"),
        ("alpha", "-", 1, "alpha [-]"),
        ("stribeck_velocity", "m/s", 1e3, "v_Stribeck [mm/s]"),
    ]
    p_bar = table["pressure [Pa]"] / 1e5 if len(table) else []
    p_line = np.linspace(0, max(float(np.max(p_bar)) if len(table) else 1, 1), 100)
    for ax, (name, unit, k, label) in zip(axes.flat, specs, strict=True):
        col = f"{name} [{unit}]"
        if col not in table or table[col].isna().all():
            ax.text(0.5, 0.5, "not identified", ha="center", transform=ax.transAxes)
            ax.set_ylabel(label)
            continue
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
            law = ident.regressions[name]["linear"]
            ax.plot(p_line, law(p_line * 1e5) * k, "-", lw=1, label="weighted regression")
        coef = ident.surface.coefficients.get(name)
        if isinstance(coef, dict):
            values = params_at_pressure(p_line * 1e5, {name: coef}, law=ident.surface.law)[name]
            ax.plot(p_line, values * k, "--", lw=1, label="global surface fit")
        elif coef is not None:
            ax.axhline(coef * k, ls="--", lw=1, label="global surface fit")
        ax.set_xlabel("pressure p [bar]")
        ax.set_ylabel(label)
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("Parameters against pressure (cf. thesis Fig. 4.2)")
    return fig


def figure_directions(ident, offset=None):
    """Fig. 4.3: ascending against descending force-balance levels and the weight offset."""
    pts, levels, colors = _levels(ident)
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.11, top=0.9)
    if "force [N]" in pts and "direction [-]" in pts:
        for level, color in zip(levels, colors, strict=True):
            sel = pts[pts["level"] == level]
            for sign, marker in ((1, "^"), (-1, "v")):
                part = sel[sel["direction [-]"] == sign]
                ax.plot(
                    part["velocity [m/s]"].abs() * 1e3,
                    part["force [N]"] * sign,
                    marker,
                    ms=3.5,
                    color=color,
                    alpha=0.8,
                )
        if offset is not None and np.isfinite(offset):
            ax.set_title(
                "Ascending (^) and descending (v, sign flipped) levels (cf. thesis Fig. 4.3):\n"
                f"they differ by 2 x the weight offset = {2 * offset:.2f} N",
                fontsize=9,
            )
    _log_speed_axis(ax)
    ax.set_xlabel("speed |v| [mm/s]")
    ax.set_ylabel("force-balance level x direction [N]")
    return fig


def figure_sensitivity(ident):
    """Tables 4.2-4.4 as curves: RMSE against alpha (two v_r) and against v_r (alpha = 1)."""
    table = ident.sensitivity
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    fig.subplots_adjust(left=0.08, right=0.99, bottom=0.14, top=0.88, wspace=0.25)
    for name, label in (
        ("4.2", "v_r = 7.43 mm/s (Table 4.2)"),
        ("4.3", "v_r = 10 mm/s (Table 4.3)"),
    ):
        part = table[table["table"] == name]
        axes[0].plot(part["alpha [-]"], part["rmse [N]"], "o-", label=label)
    axes[0].set_xlabel("alpha [-]")
    axes[0].set_ylabel("RMSE ('SME', eq. 4.4) [N]")
    axes[0].legend(fontsize=7)
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
    axes[1].legend(fontsize=7)
    fig.suptitle("Sensitivity of the whole model to alpha and v_r (thesis 4.1.1-4.1.2)")
    return fig


def figure_sensitivity_curves(ident):
    """Figs. 4.4-4.12 in two panels: the model refit at each fixed alpha and v_r, with data.

    Left: alpha = 0.5 ... 2 at v_r = 10 mm/s (thesis Figs. 4.4-4.9); right: v_r = 5 ... 15
    mm/s at alpha = 1 (Figs. 4.10-4.12 and 4.7). Each refit is the whole pressure-dependent
    model with alpha and v_r held; drawn at the lowest and highest pressure, RMSE in the legend.
    """
    pts, levels, _ = _levels(ident)
    speed = pts["velocity [m/s]"].abs().to_numpy()
    p_bar = pts["pressure [Pa]"].to_numpy() / 1e5
    force = pts["friction [N]"].to_numpy()
    grid = np.geomspace(max(speed.min(), 1e-4), speed.max(), 120)
    shown = [levels[0], levels[-1]] if len(levels) > 1 else levels
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), sharey=True)
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.12, top=0.86, wspace=0.05)
    panels = (
        (axes[0], [(a, 0.010) for a in THESIS_ALPHAS], "v_r = 10 mm/s"),
        (axes[1], [(1.0, v) for v in (0.005, 0.00743, 0.010, 0.015)], "alpha = 1"),
    )
    for ax, cases, title in panels:
        colors = plt.cm.plasma(np.linspace(0, 0.85, len(cases)))
        for level in shown:
            sel = pts["level"].to_numpy() == level
            ax.plot(speed[sel] * 1e3, force[sel], "o", ms=3, color="0.35", zorder=3)
        for (alpha, v_r), color in zip(cases, colors, strict=True):
            design = design_columns(speed, p_bar, v_r, alpha)
            coef = solve_linear(design, force)
            rmse = float(np.sqrt(np.mean((design @ coef - force) ** 2)))
            label = (
                f"alpha = {alpha:g}" if title.startswith("v_r") else f"v_r = {v_r * 1e3:g} mm/s"
            ) + f": RMSE {rmse:.2f} N"
            for j, level in enumerate(shown):
                pb = p_bar[pts["level"].to_numpy() == level].mean()
                model = design_columns(grid, np.full_like(grid, pb), v_r, alpha) @ coef
                ax.plot(
                    grid * 1e3, model, "-", color=color, lw=1.2, label=label if j == 0 else None
                )
        _log_speed_axis(ax)
        ax.set_xlabel("speed |v| [mm/s]")
        ax.set_title(f"refit at fixed values, {title}", fontsize=9)
        ax.legend(fontsize=7, loc="upper center", ncol=2)
    axes[0].set_ylabel("friction [N]")
    p_low, p_high = (p_bar[pts["level"].to_numpy() == lv].mean() for lv in (shown[0], shown[-1]))
    fig.suptitle(
        f"Model refit at fixed alpha and v_r against the data at {p_low:.3g} and "
        f"{p_high:.3g} bar (cf. thesis Figs. 4.4-4.12)"
    )
    return fig


def figure_residuals(ident):
    """Residuals of the surface fit against speed and pressure."""
    pts = ident.points
    res = ident.surface.residuals
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4), sharey=True)
    fig.subplots_adjust(left=0.08, right=0.99, bottom=0.15, top=0.88, wspace=0.05)
    axes[0].plot(pts["velocity [m/s]"].abs() * 1e3, res, ".", ms=3)
    _log_speed_axis(axes[0])
    axes[0].set_xlabel("speed |v| [mm/s]")
    axes[0].set_ylabel("residual (data - model) [N]")
    axes[1].plot(pts["pressure [Pa]"] / 1e5, res, ".", ms=3)
    axes[1].set_xlabel("pressure p [bar]")
    for ax in axes:
        ax.axhline(0, color="k", lw=0.6)
    fig.suptitle(f"Residuals of the global fit (RMSE {ident.surface.rmse:.3f} N)")
    return fig


def render(fig) -> tuple[bytes, bytes]:
    """PNG and SVG bytes of a figure (fixed layouts: no layout pass at save time)."""
    png = io.BytesIO()
    fig.savefig(png, format="png")
    svg = io.BytesIO()
    fig.savefig(svg, format="svg")
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


def _warm_up():
    """Load fonts and the Agg/SVG machinery in a worker (the first draw is the slowest)."""
    fig, ax = plt.subplots(figsize=(2, 1.5))
    ax.plot([1, 10], [1, 2], "o-")
    _log_speed_axis(ax)
    ax.set_title("warm-up")
    render(fig)
    return True


def _render_job(ident, offset, index):
    _, _, build = all_figures(ident, offset)[index]
    return render(build())


# the heaviest figures first, so the two workers finish together
_ORDER = ("parameters", "sensitivity_curves", "fit", "sensitivity", "residuals", "directions")


class FigureRenderer:
    """Draw the report figures, in worker processes when that is safe.

    Create it early (e.g. before reading a campaign): the workers fork and warm up on the
    otherwise idle second core while the single-threaded core pipeline runs, so that the
    report later costs only the drawing. Workers are used when the platform has ``fork``
    and this process has a single thread (not inside a notebook kernel, whose helper
    threads make forking unsafe); otherwise figures are drawn one after another.
    Use as a context manager, or call :meth:`close`.
    """

    def __init__(self, workers: int = 2):
        import multiprocessing
        import threading
        from concurrent.futures import ProcessPoolExecutor

        self.pool = None
        can_fork = (
            "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1
        )
        if workers > 1 and can_fork:
            self.pool = ProcessPoolExecutor(
                max_workers=workers, mp_context=multiprocessing.get_context("fork")
            )
            self._warm = [self.pool.submit(_warm_up) for _ in range(workers)]

    def render(self, ident, offset=None):
        """[(stem, caption, png, svg)] for every report figure."""
        figures = all_figures(ident, offset)
        if self.pool is None:
            rendered = [render(build()) for _, _, build in figures]
        else:
            stems = [stem for stem, _, _ in figures]
            order = sorted(
                range(len(figures)),
                key=lambda i: _ORDER.index(stems[i]) if stems[i] in _ORDER else len(_ORDER),
            )
            futures = {i: self.pool.submit(_render_job, ident, offset, i) for i in order}
            rendered = [futures[i].result() for i in range(len(figures))]
        return [
            (stem, caption, png, svg)
            for (stem, caption, _), (png, svg) in zip(figures, rendered, strict=True)
        ]

    def close(self):
        if self.pool is not None:
            self.pool.shutdown(wait=True)
            self.pool = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def render_all(ident, offset=None, *, workers=2):
    """Render every report figure; returns [(stem, caption, png, svg)] (see FigureRenderer)."""
    with FigureRenderer(workers) as renderer:
        return renderer.render(ident, offset)


def all_figures(ident, offset=None):
    """(stem, caption, builder) for every figure of the report, in order."""
    figures = [
        (
            "fit",
            "Steady-state points and the fitted pressure-dependent model (cf. thesis Fig. 4.1).",
            lambda: figure_fit(ident),
        ),
        (
            "parameters",
            "Per-pressure parameters with 95 % intervals, the weighted "
            "regressions and the global fit (cf. Fig. 4.2).",
            lambda: figure_parameters(ident),
        ),
        (
            "directions",
            "Ascending against descending levels and the weight offset (cf. Fig. 4.3).",
            lambda: figure_directions(ident, offset),
        ),
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
