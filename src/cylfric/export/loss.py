"""What a simpler simulator block loses against the cylfric model: the loss report.

A lossy export (Simscape, Hopsan) replaces the pressure-dependent Stribeck/LuGre model by a
target block with its own documented equations and best-fit parameters. The loss report
evaluates both over a (velocity, pressure) grid of the datasheet's validity range, in both
directions, and says how far apart they are: RMS and maximum difference, and where the
difference is largest. It is written beside every lossy export as CSV (the grid, engineering
units), a text summary and a figure.

Pressures: the grid runs over the chamber pressure with both chambers at the same pressure
(``p_A = p_B``, as on the thesis rig), or, for a single-acting cylinder (the datasheet's
``model.pressure_reference_basis``), with the working chamber at it and the other at
atmosphere (0 bar gauge), as the cylinder runs (:func:`chamber_pressures`); cylfric sees
``model.operating_pressure(p_A, p_B)``, the target block its own combination (Simscape's
Cylinder Friction: ``p_A + p_B``), so the block's parameters are fitted where the cylinder
works.
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..io.writers import atomic_write_bytes, atomic_write_text

if TYPE_CHECKING:
    from collections.abc import Callable, Mapping, Sequence

    import pandas as pd
    from matplotlib.figure import Figure
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "LossReport",
    "loss_grid",
    "loss_report",
    "chamber_pressure",
    "chamber_pressures",
    "N_VELOCITY",
    "N_PRESSURE",
]

N_VELOCITY = 40
"""Speeds of the loss grid per direction, log-spaced over the validity range (the way test
campaigns space their speeds, so that the Stribeck region counts as much as the fast end)."""
N_PRESSURE = 9
"""Pressures of the loss grid, evenly spaced over the validity range."""


class ExportRangeError(ValueError):
    """A model without validity ranges was exported without explicit ranges."""


def chamber_pressure(model: FrictionModel, operating: ArrayLike) -> np.ndarray:
    """Chamber pressure [Pa] with ``p_A = p_B`` that gives the operating pressure [Pa].

    The operating-pressure rule of the model (``mean``, ``sum``, ...) is applied to equal
    chamber pressures: ``operating / rule(1, 1)``.
    """
    return np.asarray(operating, dtype=float) / float(model.operating_pressure(1.0, 1.0))


def chamber_pressures(model: FrictionModel, pressure: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Chamber pressures ``(p_A, p_B)`` [Pa] of the grid's chamber pressure [Pa].

    A single-acting cylinder (``model.pressure_reference_basis`` kind ``"single-acting"``):
    its working chamber at ``pressure`` and the other at atmosphere, 0 gauge. Any other:
    both chambers at ``pressure`` (``p_A = p_B``).
    """
    p = np.asarray(pressure, dtype=float)
    basis = model.pressure_reference_basis
    if basis is not None and basis["kind"] == "single-acting":
        zero = np.zeros_like(p)
        return (zero, p) if basis.get("chamber") == "b" else (p, zero)
    return p, p


def chambers_text(model: FrictionModel) -> str:
    """How the grid sets the chambers, in words (for the loss reports)."""
    basis = model.pressure_reference_basis
    if basis is not None and basis["kind"] == "single-acting":
        working = str(basis.get("chamber") or "a").upper()
        other = "A" if working == "B" else "B"
        return f"single-acting: p_{working} = the chamber pressure, p_{other} = 0 gauge"
    return "p_A = p_B"


def _range(model, given, low, high, what, unit):
    if given is not None:
        lo, hi = (float(x) for x in given)
    elif model.validity is not None:
        lo, hi = float(model.validity[low]), float(model.validity[high])
    else:
        raise ExportRangeError(
            f"the model has no validity range; give {what}_range=(min, max) in {unit} "
            "(the range the loss report and the best fit cover)"
        )
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ExportRangeError(
            f"{what}_range = ({lo}, {hi}) {unit} is not a range; expected 0 <= min < max"
        )
    return lo, hi


def loss_grid(
    model: FrictionModel,
    *,
    velocity_range: tuple[float, float] | None = None,
    pressure_range: tuple[float, float] | None = None,
    n_velocity: int = N_VELOCITY,
    n_pressure: int = N_PRESSURE,
) -> tuple[np.ndarray, np.ndarray]:
    """Speeds [m/s] and chamber pressures [Pa] of the loss grid over the validity range.

    Parameters
    ----------
    model : FrictionModel
        The model; its ``validity`` gives the ranges unless they are given.
    velocity_range : (float, float), optional
        (min, max) speed [m/s]; default the model's validity (min > 0: log spacing).
    pressure_range : (float, float), optional
        (min, max) operating pressure [Pa]; default the model's validity.
    n_velocity, n_pressure : int
        Grid size (speeds per direction, pressures).

    Returns
    -------
    speeds : ndarray
        Positive speeds [m/s], log-spaced (``n_velocity``).
    pressures : ndarray
        Chamber pressures [Pa] with ``p_A = p_B`` (``n_pressure``), see
        :func:`chamber_pressure`.
    """
    v_lo, v_hi = _range(model, velocity_range, "velocity_min", "velocity_max", "velocity", "m/s")
    p_lo, p_hi = _range(model, pressure_range, "pressure_min", "pressure_max", "pressure", "Pa")
    if v_lo <= 0:
        raise ExportRangeError(
            f"velocity_range starts at {v_lo} m/s; expected a positive lowest speed "
            "(the grid is log-spaced)"
        )
    if int(n_velocity) < 2 or int(n_pressure) < 1:
        raise ExportRangeError(
            f"grid of {n_velocity} speeds x {n_pressure} pressures; expected at least 2 x 1"
        )
    speeds = np.geomspace(v_lo, v_hi, int(n_velocity))
    operating = np.linspace(p_lo, p_hi, int(n_pressure))
    return speeds, chamber_pressure(model, operating)


@dataclass(frozen=True)
class LossReport:
    """The difference between a target block and the cylfric model over a grid.

    Attributes
    ----------
    target : str
        Short name used in file and column names (``"simscape_cylinder_friction_il"``).
    title : str
        The block's name as its tool calls it.
    velocity : ndarray
        Velocity of each grid point [m/s] (both signs).
    pressure : ndarray
        Chamber pressure of each grid point [Pa] (``p_A = p_B``, or the working chamber's:
        ``chambers``).
    cylfric : ndarray
        Steady-state friction of the cylfric model [N].
    approximation : ndarray
        Friction of the target block with the exported parameters [N].
    parameters : dict
        The exported parameters: name -> (value, SI unit).
    notes : tuple of str
        Where the equations come from, and what the block cannot represent.
    chambers : str
        How the grid sets the chambers (:func:`chambers_text`).
    """

    target: str
    title: str
    velocity: np.ndarray
    pressure: np.ndarray
    cylfric: np.ndarray
    approximation: np.ndarray
    parameters: dict = field(default_factory=dict)
    notes: tuple = ()
    chambers: str = "p_A = p_B"

    @property
    def difference(self) -> np.ndarray:
        """Target minus cylfric [N] at each grid point."""
        return self.approximation - self.cylfric

    @property
    def rms(self) -> float:
        """Root-mean-square difference over the grid [N]."""
        return float(np.sqrt(np.mean(self.difference**2)))

    @property
    def max_abs(self) -> float:
        """Largest absolute difference over the grid [N]."""
        return float(np.max(np.abs(self.difference)))

    @property
    def worst(self) -> tuple[float, float, float]:
        """(velocity [m/s], chamber pressure [Pa], difference [N]) where it is largest."""
        i = int(np.argmax(np.abs(self.difference)))
        return float(self.velocity[i]), float(self.pressure[i]), float(self.difference[i])

    def table(self) -> pd.DataFrame:
        """The grid as a DataFrame in engineering units (mm/s, bar, N)."""
        import pandas as pd

        return pd.DataFrame(
            {
                "velocity [mm/s]": self.velocity * 1e3,
                "pressure [bar]": self.pressure / 1e5,
                "cylfric [N]": self.cylfric,
                f"{self.target} [N]": self.approximation,
                "difference [N]": self.difference,
            }
        )

    def summary(self) -> str:
        """One line: RMS, maximum and where (engineering units)."""
        v, p, d = self.worst
        return (
            f"{self.title}: RMS difference {self.rms:.3f} N, maximum {abs(d):.3f} N "
            f"at {v * 1e3:+.4g} mm/s and {p / 1e5:.4g} bar "
            f"(the block gives {'more' if d * v > 0 else 'less'} friction than cylfric)"
        )

    def text(self) -> str:
        """The text report: summary, grid, parameters and notes."""
        speeds = np.abs(self.velocity)
        lines = [
            f"Loss report: {self.title} against the cylfric model",
            "",
            self.summary(),
            "",
            f"grid: {np.unique(self.velocity).size} velocities "
            f"({speeds.min() * 1e3:.4g} to {speeds.max() * 1e3:.4g} mm/s, both directions, "
            f"log-spaced) x {np.unique(self.pressure).size} chamber pressures "
            f"({self.pressure.min() / 1e5:.4g} to {self.pressure.max() / 1e5:.4g} bar, "
            f"{self.chambers})",
            "difference = target block - cylfric, steady-state friction [N]",
            "",
            "exported parameters (SI):",
        ]
        lines += [
            f"  {name} = {value:.10g} {unit}" for name, (value, unit) in self.parameters.items()
        ]
        if self.notes:
            lines += ["", "notes:"] + [f"  - {note}" for note in self.notes]
        return "\n".join(lines) + "\n"

    def figure(self) -> Figure:
        """Friction against speed at a few pressures (both models) and the difference map."""
        from matplotlib.figure import Figure
        from matplotlib.ticker import FuncFormatter, LogLocator, NullLocator

        fig = Figure(figsize=(10, 4.2))
        left, right = fig.subplots(1, 2)
        fig.subplots_adjust(left=0.07, right=0.97, bottom=0.13, top=0.87, wspace=0.28)
        positive = self.velocity > 0
        levels = np.unique(self.pressure)
        picks = np.linspace(0, levels.size - 1, min(4, levels.size)).round().astype(int)
        shown = levels[np.unique(picks)]
        for k, p in enumerate(shown.astype(float)):
            sel = positive & (self.pressure == p)
            order = np.argsort(self.velocity[sel])
            v = self.velocity[sel][order] * 1e3
            color = f"C{k}"
            right_label = f"{p / 1e5:.3g} bar"
            left.plot(v, self.cylfric[sel][order], color=color, label=f"cylfric {right_label}")
            left.plot(v, self.approximation[sel][order], "--", color=color, label="block")
        left.set_xscale("log")
        left.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        left.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
        left.xaxis.set_minor_locator(NullLocator())
        left.set_xlabel("velocity [mm/s]")
        left.set_ylabel("friction force [N]")
        left.set_title("cylfric (solid) and the block (dashed)", fontsize=9)
        left.legend(fontsize=6, ncol=2, loc="best")
        left.grid(alpha=0.3)
        speeds = np.unique(self.velocity[positive])
        grid = np.full((levels.size, speeds.size), np.nan)
        rows = np.searchsorted(levels, self.pressure[positive])
        cols = np.searchsorted(speeds, self.velocity[positive])
        grid[rows, cols] = self.difference[positive]
        limit = max(float(np.nanmax(np.abs(grid))), 1e-12)
        if levels.size > 1:
            mesh = right.pcolormesh(
                speeds * 1e3,
                levels / 1e5,
                grid,
                cmap="RdBu_r",
                vmin=-limit,
                vmax=limit,
                shading="nearest",
            )
            right.set_ylabel("chamber pressure [bar]")
            fig.colorbar(mesh, ax=right, label="block - cylfric [N]")
        else:
            right.plot(speeds * 1e3, grid[0], color="C3")
            right.set_ylabel("block - cylfric [N]")
        right.set_xscale("log")
        right.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        right.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
        right.xaxis.set_minor_locator(NullLocator())
        right.set_xlabel("velocity [mm/s] (extension; retraction is its mirror)")
        right.set_title("difference", fontsize=9)
        fig.suptitle(f"{self.title}: RMS {self.rms:.3f} N, max {self.max_abs:.3f} N", fontsize=10)
        return fig

    def write(self, folder: StrPath, stem: str | None = None) -> list[Path]:
        """Write ``<stem>.csv``, ``<stem>.txt`` and ``<stem>.png`` into ``folder`` atomically.

        ``stem`` defaults to ``loss_<target>``. Returns the paths.
        """
        folder = Path(folder)
        stem = stem or f"loss_{self.target}"
        buffer = io.StringIO()
        self.table().to_csv(buffer, index=False, float_format="%.9g", lineterminator="\n")
        png = io.BytesIO()
        self.figure().savefig(png, format="png", dpi=100, metadata={"Software": None})
        return [
            atomic_write_text(folder / f"{stem}.csv", buffer.getvalue()),
            atomic_write_text(folder / f"{stem}.txt", self.text()),
            atomic_write_bytes(folder / f"{stem}.png", png.getvalue()),
        ]


def loss_report(
    model: FrictionModel,
    block_force: Callable[..., Any],
    *,
    target: str,
    title: str,
    speeds: ArrayLike,
    pressures: ArrayLike,
    parameters: Mapping[str, Any] | None = None,
    notes: Sequence[str] = (),
) -> LossReport:
    """Evaluate a target block and the cylfric model over a grid, both directions.

    Parameters
    ----------
    model : FrictionModel
        The cylfric model (``model.friction(v, model.operating_pressure(p_A, p_B))``).
    block_force : callable
        ``block_force(velocity [m/s], pressure_a [Pa], pressure_b [Pa]) -> force [N]``:
        the target block's documented equations with the exported parameters, vectorised.
    target, title : str
        Short name (file and column names) and the block's full name.
    speeds : array_like
        Positive speeds [m/s]; the grid uses each with both signs.
    pressures : array_like
        Chamber pressures [Pa] (:func:`chamber_pressures` sets both chambers from them).
    parameters : dict, optional
        Name -> (value, SI unit) of the exported parameters, for the text report.
    notes : sequence of str
        Sources and limits, for the text report.
    """
    speeds = np.asarray(speeds, dtype=float)
    velocity_axis = np.concatenate([-speeds[::-1], speeds])
    pressure, velocity = np.meshgrid(
        np.asarray(pressures, dtype=float), velocity_axis, indexing="ij"
    )
    velocity, pressure = velocity.ravel(), pressure.ravel()
    pressure_a, pressure_b = chamber_pressures(model, pressure)
    cylfric = np.asarray(
        model.friction(velocity, model.operating_pressure(pressure_a, pressure_b)), dtype=float
    )
    block = np.asarray(block_force(velocity, pressure_a, pressure_b), dtype=float)
    block = np.broadcast_to(block, velocity.shape).copy()
    if not np.all(np.isfinite(block)):
        raise ValueError(f"{title}: the block's force is not finite on the grid")
    return LossReport(
        target=target,
        title=title,
        velocity=velocity,
        pressure=pressure,
        cylfric=cylfric,
        approximation=block,
        parameters=dict(parameters or {}),
        notes=tuple(notes),
        chambers=chambers_text(model),
    )
