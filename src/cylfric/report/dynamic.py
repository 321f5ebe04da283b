"""Report part of the dynamic parameters: force against displacement with the identified
presliding line, breakaway force against force rate (measured and simulated), a table.

Draws from a :class:`cylfric.identify.dynamic.DynamicIdentification` it is given (the report
never imports identify).
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING

import matplotlib
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from .figures import STYLE, _legend_below, log_axis

if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any as _Results  # identification results, duck-typed: never imported here


__all__ = ["figure_dynamic", "dynamic_tables", "dynamic_html"]


def figure_dynamic(dynamic: _Results) -> Figure:
    """Left: net force [N] against displacement [um] of each presliding record's first slow
    cycle, the fitted model's curve and the line of slope sigma_0 (presliding stiffness).
    Right: breakaway force [N] against force rate [N/s], measured and simulated; without
    breakaway tests no right panel, and a line under the left one says so. Legends stand
    under the axes, over no point."""
    with matplotlib.rc_context(STYLE):
        table = dynamic.breakaway
        rows = -(-max(len(dynamic.fits), 1) // 2)
        if len(table):
            fig = Figure(figsize=(10, 4.6 + 0.14 * rows))
            left, right = fig.subplots(1, 2)
        else:
            fig = Figure(figsize=(6, 4.6 + 0.14 * rows))
            left, right = fig.subplots(), None
        bottom = (1.05 + 0.14 * rows) / fig.get_figheight()
        fig.subplots_adjust(left=0.1, right=0.98, bottom=bottom, top=0.9, wspace=0.28)
        colors = matplotlib.colormaps["viridis"](np.linspace(0, 0.9, max(len(dynamic.fits), 1)))
        records = {r.file: r for r in dynamic.records}
        for fit, color in zip(dynamic.fits, colors, strict=True):
            record = records[fit.file]
            slow = _first_cycle(record)
            x = record.displacement[slow] * 1e6
            left.plot(x, record.force[slow], ".", ms=2, color=color, alpha=0.35)
            left.plot(
                fit.simulated[slow] * 1e6,
                record.force[slow],
                "-",
                lw=1.2,
                color=color,
                label=f"{fit.pressure / 1e5:.3g} bar: sigma_0 = {fit.sigma_0 / 1e3:.4g} N/mm",
            )
            force = np.linspace(-0.4, 0.4, 2) * np.max(np.abs(record.force[slow]))
            left.plot(force / fit.sigma_0 * 1e6, force, "--", lw=1.5, color="k")
        left.set_xlabel("displacement [um]")
        left.set_ylabel("net applied force [N]")
        left.set_title("Presliding: measured (dots), fitted model, slope sigma_0 (dashed)")
        _legend_below(left, ncol=2)
        if right is None:
            fig.text(
                0.5,
                0.01,
                "no breakaway tests: the model is not validated on force ramps",
                ha="center",
                va="bottom",
                fontsize=8,
                color="0.3",
            )
            return fig
        if len(table):
            levels = sorted(table["pressure [Pa]"].unique())
            level_colors = matplotlib.colormaps["viridis"](np.linspace(0, 0.9, len(levels)))
            for level, color in zip(levels, level_colors, strict=True):
                rows = table[table["pressure [Pa]"] == level].sort_values("force_rate [N/s]")
                rate = rows["force_rate [N/s]"]
                right.plot(
                    rate, rows["measured [N]"], "o", color=color, label=f"{level / 1e5:.3g} bar"
                )
                right.plot(rate, rows["simulated [N]"], "x--", color=color)
            rates = table["force_rate [N/s]"].to_numpy(dtype=float)
            rates = rates[rates > 0]
            decades = float(np.log10(rates.max() / rates.min())) if rates.size else None
            log_axis(right, "x", decades)
            _legend_below(right, title="o measured, x simulated", title_fontsize=7, ncol=3)
        right.set_xlabel("force rate [N/s]")
        right.set_ylabel("breakaway force [N]")
        right.set_title("Breakaway against force rate")
    return fig


def _first_cycle(record):
    """Samples of the first loading cycle: from rest to the first return to rest."""
    force = record.force
    peak = np.max(np.abs(force))
    moving = np.nonzero(np.abs(force) > 0.05 * peak)[0]
    if moving.size == 0:
        return slice(0, force.size)
    start = moving[0]
    crossings = np.nonzero(np.diff(np.sign(force[start:])) != 0)[0]
    stop = start + crossings[1] + 2 if crossings.size > 1 else force.size
    return slice(max(start - 1, 0), stop)


def dynamic_tables(dynamic: _Results) -> tuple[pd.DataFrame, pd.DataFrame]:
    """(per-pressure sigma table, breakaway table) in engineering units (bar, N/mm, N*s/mm)."""
    pp = dynamic.per_pressure
    sigma = pd.DataFrame(
        {
            "p [bar]": pp["pressure [Pa]"] / 1e5,
            "sigma_0 [N/mm]": pp["sigma_0 [N/m]"] / 1e3,
            "± [N/mm]": pp["sigma_0_stderr [N/m]"] / 1e3,
            "sigma_1 [N*s/mm]": pp["sigma_1 [N*s/m]"] / 1e3,
            "± [N*s/mm]": pp["sigma_1_stderr [N*s/m]"] / 1e3,
            "initial slope [N/mm]": pp["initial_slope [N/m]"] / 1e3,
            "RMSE [um]": pp["rmse [m]"] * 1e6,
            "file": pp["file"].map(lambda f: str(f).split("/")[-1]),
        }
    )
    b = dynamic.breakaway
    breakaway = pd.DataFrame(
        {
            "p [bar]": b["pressure [Pa]"] / 1e5,
            "force rate [N/s]": b["force_rate [N/s]"],
            "measured [N]": b["measured [N]"],
            "simulated [N]": b["simulated [N]"],
            "error [%]": b["relative_error [-]"] * 100,
            "file": b["file"].map(lambda f: str(f).split("/")[-1]),
        }
    )
    return sigma, breakaway


def dynamic_html(
    dynamic: _Results, png_base64: str | None, table: Callable[[pd.DataFrame], str]
) -> str:
    """The report section (HTML) of the dynamic parameters; ``table`` renders a DataFrame."""
    sigma, breakaway = dynamic_tables(dynamic)
    parts = ["<h2>Dynamic parameters (presliding and breakaway tests)</h2>"]
    for name, law in dynamic.laws.items():
        parts.append(f"<p class='law'>{html.escape(_law_text(name, law))}</p>")
    if png_base64:
        parts.append(
            "<figure id='dynamic'><img alt='presliding and breakaway' "
            f"src='data:image/png;base64,{png_base64}'><figcaption>Force against displacement "
            "of the presliding records with the identified model and its presliding line "
            "(slope sigma_0); breakaway force against force rate, measured and simulated with "
            "the identified model.</figcaption></figure>"
        )
    parts.append(table(sigma))
    if len(breakaway):
        errors = breakaway["error [%]"].dropna()
        parts.append(
            f"<p>Breakaway validation: RMS error {np.sqrt(np.mean(errors**2)):.2f} %, largest "
            f"{errors.abs().max():.2f} % over {len(errors)} ramp test(s).</p>"
        )
        parts.append(table(breakaway))
    for note in dynamic.notes:
        parts.append(f"<p class='note'>{html.escape(note)}</p>")
    return "\n".join(parts)


def _law_text(name, law):
    scale, unit = (1e-3, "N/mm") if name == "sigma_0" else (1e-3, "N*s/mm")
    se = law["stderr"]
    text = f"{name}(p) = {law['intercept'] * scale:.4g} ± {se['intercept'] * scale:.2g} {unit}"
    if law["law"] == "linear":
        slope, slope_se = law["slope"] * scale * 1e5, se["slope"] * scale * 1e5
        text += f" + ({slope:.4g} ± {slope_se:.2g}) {unit}/bar * p"
    return f"{text}  [{law['reason']}]"
