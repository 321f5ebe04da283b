"""Compare catalogued seals: friction against velocity and pressure with 95 % bands, a table.

Everything is evaluated through :class:`~cylfric.model.FrictionModel` (``friction``,
``band``, ``check``); this module only arranges and draws.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np

from ..escape import plot_text

if TYPE_CHECKING:
    from collections.abc import Sequence

    import pandas as pd
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = ["friction_with_band", "compare", "comparison_table"]


def friction_with_band(
    model: FrictionModel, velocity: ArrayLike, pressure: ArrayLike, level: float = 0.95
) -> tuple[np.ndarray | float, np.ndarray, np.ndarray, np.ndarray]:
    """Friction [N], band limits [N] and whether inside the validity ranges, quietly.

    Parameters
    ----------
    model : FrictionModel
    velocity : float or array
        Speed [m/s].
    pressure : float or array
        Operating pressure [Pa].
    level : float
        Confidence level of the band of the mean friction [-].

    Returns
    -------
    tuple of arrays
        ``(friction, lower, upper, inside)``; the band limits are NaN for a model
        without covariance.
    """
    from ..model import ValidityWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        inside = model.check(velocity, pressure)
        friction = model.friction(velocity, pressure)
        if model.covariance is None:
            lower = upper = np.full(np.shape(friction), np.nan)
        else:
            lower, upper = model.band(velocity, pressure, level)
    return friction, lower, upper, inside


def comparison_table(
    models: dict, pressures: Sequence[float], velocities: Sequence[float], level: float = 0.95
) -> pd.DataFrame:
    """Friction of each model at every (pressure, velocity) pair.

    Parameters
    ----------
    models : dict
        Name -> FrictionModel.
    pressures : sequence of float
        Operating pressures [Pa].
    velocities : sequence of float
        Speeds [m/s].

    Returns
    -------
    pandas.DataFrame
        ``name``, ``pressure [Pa]``, ``velocity [m/s]``, ``friction [N]``, ``lower [N]``,
        ``upper [N]``, ``inside validity``.
    """
    import pandas as pd

    rows = []
    for name, model in models.items():
        for p in pressures:
            for v in velocities:
                f, lo, hi, inside = friction_with_band(model, abs(v), p, level)
                rows.append(
                    {
                        "name": name,
                        "pressure [Pa]": float(p),
                        "velocity [m/s]": float(abs(v)),
                        "friction [N]": float(f),
                        "lower [N]": float(lo),
                        "upper [N]": float(hi),
                        "inside validity": bool(inside),
                    }
                )
    return pd.DataFrame.from_records(rows)


def _span(models, key_min, key_max, fallback):
    lows = [m.validity[key_min] for m in models if m.validity is not None]
    highs = [m.validity[key_max] for m in models if m.validity is not None]
    if not lows:
        return fallback
    return min(lows), max(highs)


def _figure(models: dict, pressures, velocities, level):
    """Two panels: friction against velocity (at ``pressures``) and against pressure."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import ScalarFormatter

    fig = Figure(figsize=(10, 4.2), layout="constrained")
    ax_v, ax_p = fig.subplots(1, 2)
    v_lo, v_hi = _span(models.values(), "velocity_min", "velocity_max", (1e-3, 0.2))
    v_lo, v_hi = min(v_lo, *velocities), max(v_hi, *velocities)
    p_lo, p_hi = _span(models.values(), "pressure_min", "pressure_max", (0.0, 200e5))
    p_lo, p_hi = min(p_lo, *pressures), max(p_hi, *pressures)
    v_grid = np.geomspace(max(v_lo, 1e-5), v_hi, 120)
    p_grid = np.linspace(p_lo, p_hi, 60)
    styles = ["-", "--", ":", "-."]
    colors = [f"C{i}" for i in range(10)]
    for i, (name, model) in enumerate(models.items()):
        color = colors[i % len(colors)]
        for j, p in enumerate(pressures):
            f, lo, hi, inside = friction_with_band(model, v_grid, p, level)
            f = np.where(inside, f, np.nan)
            ax_v.plot(
                v_grid * 1e3,
                f,
                styles[j % 4],
                color=color,
                label=f"{plot_text(name)}, {p / 1e5:g} bar",
            )
            ax_v.fill_between(
                v_grid * 1e3, np.where(inside, lo, np.nan), hi, color=color, alpha=0.15, lw=0
            )
        for j, v in enumerate(velocities):
            f, lo, hi, inside = friction_with_band(model, abs(v), p_grid, level)
            f = np.where(inside, f, np.nan)
            ax_p.plot(
                p_grid / 1e5,
                f,
                styles[j % 4],
                color=color,
                label=f"{plot_text(name)}, {abs(v) * 1e3:g} mm/s",
            )
            ax_p.fill_between(
                p_grid / 1e5, np.where(inside, lo, np.nan), hi, color=color, alpha=0.15, lw=0
            )
    ax_v.set_xscale("log")
    ax_v.xaxis.set_major_formatter(ScalarFormatter())
    ax_v.xaxis.set_minor_formatter(ScalarFormatter())
    ax_v.tick_params(axis="x", which="minor", labelsize=7)
    ax_v.set_xlabel("velocity [mm/s]")
    ax_v.set_ylabel("friction [N]")
    ax_v.set_title("friction against velocity")
    ax_p.set_xlabel("pressure [bar]")
    ax_p.set_ylabel("friction [N]")
    ax_p.set_title("friction against pressure")
    for ax in (ax_v, ax_p):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(
        f"Catalogue comparison: lines = model inside its validity range, "
        f"shading = {level:.0%} band of the mean friction",
        fontsize=9,
    )
    return fig


def compare(
    models: dict,
    out: StrPath,
    pressures: Sequence[float],
    velocities: Sequence[float],
    *,
    level: float = 0.95,
) -> dict:
    """Write ``compare.csv`` and ``compare.png`` / ``compare.svg`` into ``out``.

    Parameters
    ----------
    models : dict
        Name -> FrictionModel.
    out : path-like
        Output folder (created; a symbolic link is refused).
    pressures : sequence of float
        Pressures [Pa]: one curve of friction against velocity each, and the table rows.
    velocities : sequence of float
        Speeds [m/s]: one curve of friction against pressure each, and the table rows.
    level : float
        Confidence level of the bands [-].

    Returns
    -------
    dict
        ``table`` (DataFrame, see :func:`comparison_table`), ``csv``, ``png``, ``svg`` paths.
    """
    import io

    from ..io.writers import atomic_write_bytes, atomic_write_text

    pressures = [float(p) for p in pressures]
    velocities = [float(v) for v in velocities]
    if not pressures or not velocities:
        raise ValueError("compare: give at least one pressure [Pa] and one velocity [m/s]")
    from .._paths import make_folder

    out = make_folder(out)  # a symbolic link is refused, not written through
    table = comparison_table(models, pressures, velocities, level)
    from ..escape import csv_frame

    paths = {"csv": atomic_write_text(out / "compare.csv", csv_frame(table).to_csv(index=False))}
    fig = _figure(models, pressures, velocities, level)
    for fmt in ("png", "svg"):
        buffer = io.BytesIO()
        fig.savefig(buffer, format=fmt, dpi=110)
        paths[fmt] = atomic_write_bytes(out / f"compare.{fmt}", buffer.getvalue())
    return {"table": table, **paths}
