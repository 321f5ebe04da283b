"""The raw traces of one run with its strokes and steady windows (``cylfric inspect``).

:func:`figure_run` draws what the extraction saw in a run file: position, velocity and the
force-balance signal (eq. 3.1, with the load cell's weight offset) against time, each
stroke's extent, and the steady window chosen in each stroke shaded by its flag (ok
extension, ok retraction, or flagged: short, unsettled, excluded). Engineering units (mm,
mm/s, N, s). Takes plain arrays and the windows table: it knows nothing of campaigns.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from ..escape import plot_text
from ..io.writers import atomic_write_bytes
from .figures import PNG_COMPRESS_LEVEL, STYLE

__all__ = ["figure_run", "save_png", "envelope", "TRACE_BINS", "WINDOW_COLOURS"]

TRACE_BINS = 4000
"""A trace longer than twice this is drawn as the minimum and maximum of this many bins
(:func:`envelope`): every spike stays visible and a record of millions of samples draws as
fast as a short one [-]."""

WINDOW_COLOURS = {"extension": "tab:green", "retraction": "tab:blue", "flagged": "tab:red"}
"""Shading of the steady windows: ok windows by direction, flagged ones (any flag but ok)."""


def envelope(time, values, bins: int = TRACE_BINS) -> tuple[np.ndarray, np.ndarray]:
    """(time, values) reduced to the minimum and maximum of each of ``bins`` bins of
    samples, in time order; the arrays as they are when they have at most 2 x ``bins``
    samples."""
    time, values = np.asarray(time, dtype=float), np.asarray(values, dtype=float)
    if time.size <= 2 * bins:
        return time, values
    edges = np.linspace(0, time.size, bins + 1).astype(int)
    lows = np.minimum.reduceat(values, edges[:-1])
    highs = np.maximum.reduceat(values, edges[:-1])
    starts = time[edges[:-1]]
    stops = time[edges[1:] - 1]
    t = np.column_stack([starts, stops]).ravel()
    v = np.column_stack([lows, highs]).ravel()
    return t, v


def _shade(ax, windows) -> None:
    """Each window as a band across ``ax``, coloured by its direction and flag."""
    for row in windows:
        start, end = row["window_start [s]"], row["window_end [s]"]
        if not (math.isfinite(start) and math.isfinite(end)):
            continue
        ax.axvspan(start, end, color=_colour(row), alpha=0.18, lw=0)


def _highlight(ax, time, values, windows) -> None:
    """The samples of each window drawn again over the trace, thick, in its colour."""
    for row in windows:
        start, end = row["window_start [s]"], row["window_end [s]"]
        if not (math.isfinite(start) and math.isfinite(end)):
            continue
        inside = (time >= start) & (time <= end)
        colour = _colour(row)
        ax.plot(*envelope(time[inside], values[inside]), color=colour, lw=1.8)


def _colour(row) -> str:
    if row["flag"] != "ok":
        return WINDOW_COLOURS["flagged"]
    return WINDOW_COLOURS["extension" if row["direction [-]"] > 0 else "retraction"]


def _strokes(ax, time, stroke) -> None:
    """Thin marks at the start and end of each stroke (samples in motion)."""
    if stroke is None:
        return
    stroke = np.asarray(stroke)
    if stroke.size != np.asarray(time).size:
        return
    change = np.flatnonzero(np.diff(stroke) != 0) + 1
    for i in change:
        ax.axvline(time[i], color="0.55", lw=0.5, ls=":")


def figure_run(
    time,
    velocity,
    force,
    windows,
    *,
    position=None,
    stroke=None,
    offset=math.nan,
    title: str = "",
    nominal_speed=math.nan,
) -> Figure:
    """Position, velocity and force-balance signal of a run, windows shaded.

    Parameters
    ----------
    time : array
        [s].
    velocity : array
        Velocity the extraction used (> 0 extension) [m/s].
    force : array
        Force-balance signal ``F_f sign(v)`` plus the weight offset [N].
    windows : iterable of dict
        One per stroke with ``window_start [s]``, ``window_end [s]`` (NaN: no window),
        ``direction [-]``, ``force [N]`` (the window's mean) and ``flag``
        (:data:`cylfric.inspect.WINDOW_COLUMNS`).
    position : array, optional
        Position (> 0 towards extension) [m]; its panel is left out without it.
    stroke : array, optional
        Stroke index per sample (-1 at rest): the stroke ends are marked.
    offset : float
        Weight offset removed from the force [N] (drawn as a line when finite).
    title : str
        Figure title (the file name), drawn as text (no mathtext).
    nominal_speed : float
        Nominal speed [m/s] (drawn as +/- lines when finite).

    Returns
    -------
    matplotlib.figure.Figure
    """
    rows = list(windows)
    time = np.asarray(time, dtype=float)
    with matplotlib.rc_context(STYLE):
        panels = 3 if position is not None else 2
        fig = Figure(figsize=(9, 2.1 * panels + 0.9))
        axes = fig.subplots(panels, 1, sharex=True)
        fig.subplots_adjust(
            left=0.09, right=0.98, top=0.92, bottom=0.6 / (2.1 * panels + 0.9) + 0.06, hspace=0.12
        )
        i = 0
        if position is not None:
            axes[0].plot(*_scaled(time, position, 1e3), color="0.2", lw=0.8)
            _highlight(axes[0], time, np.asarray(position, dtype=float) * 1e3, rows)
            axes[0].set_ylabel("position [mm]")
            i = 1
        ax_v, ax_f = axes[i], axes[i + 1]
        ax_v.plot(*_scaled(time, velocity, 1e3), color="0.2", lw=0.8)
        _highlight(ax_v, time, np.asarray(velocity, dtype=float) * 1e3, rows)
        if math.isfinite(nominal_speed) and nominal_speed:
            for sign in (1, -1):
                ax_v.axhline(sign * abs(nominal_speed) * 1e3, color="tab:orange", lw=0.7, ls="--")
        ax_v.set_ylabel("velocity [mm/s]")
        ax_f.plot(*_scaled(time, force, 1.0), color="0.2", lw=0.6)
        _highlight(ax_f, time, np.asarray(force, dtype=float), rows)
        for row in rows:
            start, end, level = row["window_start [s]"], row["window_end [s]"], row["force [N]"]
            if math.isfinite(start) and math.isfinite(end) and math.isfinite(level):
                ax_f.plot([start, end], [level, level], color="black", lw=1.0, zorder=4)
        if math.isfinite(offset):
            ax_f.axhline(offset, color="tab:purple", lw=0.8, ls="--")
        ax_f.set_ylabel("force balance [N]")
        ax_f.set_xlabel("time [s]")
        for ax in axes:
            _shade(ax, rows)
            _strokes(ax, time, stroke)
        ok = sum(1 for r in rows if r["flag"] == "ok")
        handles = [
            Patch(color=WINDOW_COLOURS["extension"], alpha=0.35, label="window, extension"),
            Patch(color=WINDOW_COLOURS["retraction"], alpha=0.35, label="window, retraction"),
            Patch(color=WINDOW_COLOURS["flagged"], alpha=0.35, label="window flagged"),
            Line2D([], [], color="black", lw=1.4, label="window mean"),
            Line2D([], [], color="tab:purple", lw=0.8, ls="--", label="weight offset"),
        ]
        fig.legend(handles=handles, loc="lower center", ncol=5, frameon=False, fontsize=8)
        fig.suptitle(
            f"{plot_text(title)}: {len(rows)} strokes, {ok} steady windows ok "
            "(shaded; stroke ends dotted)",
            fontsize=10,
        )
    return fig


def _scaled(time, values, scale):
    """(time, values x scale), reduced by :func:`envelope` for drawing."""
    return envelope(time, np.asarray(values, dtype=float) * scale)


def save_png(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` as a PNG file atomically (in the report's style); return the path."""
    buffer = io.BytesIO()
    with matplotlib.rc_context(STYLE):
        fig.savefig(buffer, format="png", pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    return atomic_write_bytes(path, buffer.getvalue())
