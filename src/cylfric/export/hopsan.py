"""Hopsan export: best-fit friction parameters of Hopsan's cylinder and mass, with a loss report.

Hopsan's hydraulic cylinders carry only viscous friction: ``B_p`` [Ns/m] ("Viscous friction")
of HydraulicCylinderC enters the characteristic impedance of the mechanical port
(``Zx3 = A1^2 Zc1 + A2^2 Zc2 + bp``), and HydraulicCylinderQ has ``B_p`` ("Viscous Friction
Coefficient of Piston") and ``B_l`` (load) (Hopsan source,
``componentLibraries/defaultLibrary/Hydraulic/LinearActuators/HydraulicCylinderC.hpp`` and
``HydraulicCylinderQ.hpp``). Coulomb and static friction live in the mass component the
cylinder drives, MechanicTranslationalMassWithCoulombFriction (``f_s`` "Static Friction
Force", ``f_k`` "Kinetic Friction Force", ``b`` "Viscous Friction Coefficient";
``componentLibraries/defaultLibrary/Mechanic/Linear/
MechanicTranslationalMassWithCoulombFriction.hpp``, integrated by
``DoubleIntegratorWithDampingAndCoulombFriction``: at rest until the force exceeds ``f_s``,
then ``f_k`` opposes the motion). In steady sliding the pair gives

    F = f_k sign(v) + (B_p + b) v,

with no Stribeck drop and no pressure dependence. This export fits ``f_k`` and ``B_p`` to the
model over the validity range by (bounded, linear) least squares, sets ``f_s`` to the
model's breakaway force at the middle of the pressure range and ``b = 0`` (all viscous
friction in the cylinder), and writes an HCOM script, a parameter table, a note, and the
loss report. The lossless route into Hopsan is the FMU export (Hopsan imports FMUs through
its FMIWrapper component).
"""

from __future__ import annotations

import io
from pathlib import Path
from string import Template
from typing import TYPE_CHECKING

import numpy as np

from ..escape import hcom_comment, identifier, markdown_text, printable
from ..friction.pressure import linear, operating_pressure
from ..io.writers import atomic_write_text
from .loss import chamber_pressures, loss_grid, loss_report
from .result import ExportResult
from .scatter import summary_lines
from .simscape import _num

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "export_hopsan",
    "fit_hopsan",
    "fit_hopsan_pressure_signal",
    "hopsan_friction",
    "hopsan_friction_pressure_signal",
    "PARAMETERS",
    "SOURCES",
]

SOURCES = (
    "Hopsan source (github.com/Hopsan/hopsan): componentLibraries/defaultLibrary/Hydraulic/"
    "LinearActuators/HydraulicCylinderC.hpp and HydraulicCylinderQ.hpp (B_p), "
    "componentLibraries/defaultLibrary/Mechanic/Linear/"
    "MechanicTranslationalMassWithCoulombFriction.hpp (f_s, f_k, b)"
)

PARAMETERS = {
    "B_p": ("HydraulicCylinderC", "N*s/m", "Viscous friction (also B_p of HydraulicCylinderQ)"),
    "f_s": ("MechanicTranslationalMassWithCoulombFriction", "N", "Static Friction Force"),
    "f_k": ("MechanicTranslationalMassWithCoulombFriction", "N", "Kinetic Friction Force"),
    "b": ("MechanicTranslationalMassWithCoulombFriction", "N*s/m", "Viscous Friction Coefficient"),
}
"""Hopsan parameter -> (component, SI unit, Hopsan's description)."""


def hopsan_friction(
    velocity: ArrayLike,
    *,
    f_k: float | np.ndarray,
    B_p: float,
    b: float = 0.0,
    f_s: float | None = None,
) -> np.ndarray:
    """Steady sliding friction of a Hopsan cylinder + Coulomb-friction mass [N].

    ``f_k sign(v) + (B_p + b) v`` (``f_s`` acts only at rest and does not enter).

    Parameters
    ----------
    velocity : float or array_like
        Velocity [m/s].
    f_k : float
        Kinetic friction force [N].
    B_p, b : float
        Viscous friction of the cylinder and of the mass [N*s/m].
    f_s : float, optional
        Static friction force [N] (unused in sliding; accepted so a parameter set plugs in).
    """
    v = np.asarray(velocity, dtype=float)
    return f_k * np.sign(v) + (B_p + b) * v


def fit_hopsan(model: FrictionModel, speeds: ArrayLike, pressures: ArrayLike) -> dict[str, float]:
    """Best-fit Hopsan friction parameters over a grid [SI].

    ``f_k`` [N] and ``B_p`` [N*s/m] by bounded linear least squares of
    ``f_k + B_p |v|`` against the model at the grid's speeds [m/s] and chamber pressures
    [Pa] (``p_A = p_B``, or a single-acting cylinder's working chamber with the other at 0
    gauge: :func:`~cylfric.export.loss.chamber_pressures`); ``f_s`` [N] is the model's
    breakaway force ``F_s`` at the middle chamber pressure; ``b = 0``.
    """
    from scipy.optimize import lsq_linear

    speeds, pressures = np.asarray(speeds, float), np.asarray(pressures, float)
    P, V = np.meshgrid(pressures, speeds, indexing="ij")
    target = model.friction(V, model.operating_pressure(*chamber_pressures(model, P))).ravel()
    design = np.column_stack([np.ones(V.size), V.ravel() * 1e3])  # N, N per mm/s
    solution = lsq_linear(design, target, bounds=(0.0, np.inf), method="bvls").x
    middle = 0.5 * (pressures[0] + pressures[-1])
    breakaway = float(
        model.params_at(model.operating_pressure(*chamber_pressures(model, middle)))["F_s"]
    )
    return {
        "B_p": float(solution[1] * 1e3),
        "f_s": max(breakaway, float(solution[0])),
        "f_k": float(solution[0]),
        "b": 0.0,
    }


def hopsan_friction_pressure_signal(
    velocity: ArrayLike,
    pressure_a: ArrayLike,
    pressure_b: ArrayLike,
    *,
    f_k0: float,
    f_k_pressure_coefficient: float,
    B_p: float,
) -> np.ndarray:
    """Steady sliding friction [N] with ``f_k`` driven by a pressure signal.

    ``f_k`` is an input variable of MechanicTranslationalMassWithCoulombFriction, so a Hopsan
    model can compute it from the chamber pressures with signal components:
    ``f_k = f_k0 + k_p (p_1 + p_2)`` (cylfric's linear law of the pressure sum), then
    ``F = f_k sign(v) + B_p v``. ``f_k0`` [N], ``f_k_pressure_coefficient`` ``k_p`` [N/Pa],
    ``B_p`` [N*s/m], velocity [m/s], pressures [Pa].
    """
    kinetic = linear(
        operating_pressure(pressure_a, pressure_b, reference="sum"), f_k0, f_k_pressure_coefficient
    )
    return hopsan_friction(velocity, f_k=kinetic, B_p=B_p)


def fit_hopsan_pressure_signal(
    model: FrictionModel, speeds: ArrayLike, pressures: ArrayLike
) -> dict[str, float]:
    """Best-fit ``f_k0`` [N], ``f_k_pressure_coefficient`` [N/Pa], ``B_p`` [N*s/m] (bounded
    linear least squares over the grid), for :func:`hopsan_friction_pressure_signal`."""
    from scipy.optimize import lsq_linear

    speeds, pressures = np.asarray(speeds, float), np.asarray(pressures, float)
    P, V = np.meshgrid(pressures, speeds, indexing="ij")
    PA, PB = chamber_pressures(model, P)
    target = model.friction(V, model.operating_pressure(PA, PB)).ravel()
    total = (PA + PB).ravel()  # the block's f_k sees p_1 + p_2
    design = np.column_stack([np.ones(V.size), total / 1e5, V.ravel() * 1e3])
    solution = lsq_linear(design, target, bounds=(0.0, np.inf), method="bvls").x
    return {
        "f_k0": float(solution[0]),
        "f_k_pressure_coefficient": float(solution[1] / 1e5),
        "B_p": float(solution[2] * 1e3),
    }


def _scatter_table(model: FrictionModel) -> list[tuple[str, str, str, str]]:
    """(record.field, value, unit, meaning) of fit.scatter and quality.lack_of_fit: numbers
    as ``repr`` text, the records' texts as they are (unit ``"text"``: escape them)."""
    from .scatter import NOT_COMPUTED, scatter_records

    records = scatter_records(model)
    table = []
    for prefix, key, numbers, texts, units in records:
        if numbers is None or texts is None:
            table.append((f"{prefix}.computed", "0", "1", NOT_COMPUTED.format(key=key)))
            continue
        table.append((f"{prefix}.computed", "1", "1", f"the datasheet carries {key}"))
        for name, value in numbers.items():
            unit, meaning = units[name]
            table.append((f"{prefix}.{name}", repr(float(value)), unit, meaning))
        for name, words in texts.items():
            table.append((f"{prefix}.{name}", words, "text", "the record's text"))
    return table


def _scatter_csv(model: FrictionModel) -> str:
    """``<stem>_hopsan_scatter.csv``: field, value, unit, description of the scatter record."""
    import csv

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["field", "value", "unit", "description"])
    for field, value, unit, meaning in _scatter_table(model):
        writer.writerow([field, printable(value) if unit == "text" else value, unit, meaning])
    return buffer.getvalue()


def _scatter_markdown(model: FrictionModel) -> str:
    """The README's section on the scatter record and on bands for a new session."""
    from .scatter import summary_lines

    def user(text: str) -> str:
        return markdown_text(text, limit=None)

    lines = summary_lines(model, user)
    rows = [
        f"| `{field}` | {user(value) if unit == 'text' else value} | {unit} | {meaning} |"
        for field, value, unit, meaning in _scatter_table(model)
    ]
    return "\n\n".join(
        [
            *lines,
            "| field | value | unit | meaning |\n|---|---|---|---|\n" + "\n".join(rows),
        ]
    )


def export_hopsan(
    model: FrictionModel,
    out: StrPath,
    *,
    name: str | None = None,
    velocity_range: tuple[float, float] | None = None,
    pressure_range: tuple[float, float] | None = None,
    n_velocity: int | None = None,
    n_pressure: int | None = None,
) -> ExportResult:
    """Fit Hopsan's cylinder friction to the model; write HCOM script, table, note, loss report.

    Parameters
    ----------
    model : FrictionModel
        The cylfric model.
    out : path-like
        Output folder: ``<name>_hopsan.hcom``, ``<name>_hopsan_parameters.csv``,
        ``<name>_hopsan_scatter.csv`` (the datasheet's fit.scatter and quality.lack_of_fit,
        :mod:`cylfric.export.scatter`), ``README_hopsan.md``, ``loss_hopsan.csv/.txt/.png`` and
        ``loss_hopsan_pressure_signal.csv/.txt/.png`` (``f_k`` wired to the pressures).
    name : str, optional
        Stem of the files; default the datasheet's name or ``cylfric``.
    velocity_range : (float, float), optional
        (min, max) speed [m/s]; default the model's validity.
    pressure_range : (float, float), optional
        (min, max) operating pressure [Pa]; default the model's validity.
    n_velocity, n_pressure : int, optional
        Size of the grid.

    Returns
    -------
    ExportResult
        The files and two loss reports (constant parameters; ``f_k`` from a pressure
        signal).
    """
    out = Path(out)
    grid = {}
    if n_velocity is not None:
        grid["n_velocity"] = n_velocity
    if n_pressure is not None:
        grid["n_pressure"] = n_pressure
    speeds, pressures = loss_grid(
        model, velocity_range=velocity_range, pressure_range=pressure_range, **grid
    )
    stem = identifier(name or model.record.get("name") or "cylfric")
    params = fit_hopsan(model, speeds, pressures)
    ends = model.params_at(model.operating_pressure(*chamber_pressures(model, pressures[[0, -1]])))
    low, high = np.broadcast_to(np.asarray(ends["F_s"], dtype=float), (2,))
    report = loss_report(
        model,
        lambda v, pa, pb: hopsan_friction(v, **params),
        target="hopsan",
        title="Hopsan HydraulicCylinderC (B_p) + MechanicTranslationalMassWithCoulombFriction",
        speeds=speeds,
        pressures=pressures,
        parameters={k: (v, PARAMETERS[k][1]) for k, v in params.items()},
        notes=(
            f"equations: {SOURCES}",
            "steady sliding F = f_k sign(v) + (B_p + b) v: no Stribeck drop, no pressure "
            "dependence",
            f"f_s = the model's F_s at the middle pressure; F_s runs from {float(low):.4g} N "
            f"to {float(high):.4g} N over the pressure range",
            "the FMU export is the lossless route into Hopsan (FMIWrapper component)",
        ),
    )
    signal = fit_hopsan_pressure_signal(model, speeds, pressures)
    signal_units = {"f_k0": "N", "f_k_pressure_coefficient": "N/Pa", "B_p": "N*s/m"}
    signal_report = loss_report(
        model,
        lambda v, pa, pb: hopsan_friction_pressure_signal(v, pa, pb, **signal),
        target="hopsan_pressure_signal",
        title="Hopsan, f_k driven by a pressure signal (f_k = f_k0 + k_p (p_1 + p_2))",
        speeds=speeds,
        pressures=pressures,
        parameters={k: (v, signal_units[k]) for k, v in signal.items()},
        notes=(
            f"equations: {SOURCES}",
            "f_k is an input variable of the mass component: wire pressure sensors of both "
            "chambers, their sum times k_p plus f_k0, to it; no Stribeck drop",
        ),
    )
    rows = io.StringIO()
    rows.write("component,parameter,value,unit,description\n")
    for key, value in params.items():
        component, unit, description = PARAMETERS[key]
        rows.write(f"{component},{key},{_num(value)},{unit},{description}\n")
    template = Template(
        (Path(__file__).parent / "templates" / "hopsan.hcom.tmpl").read_text(encoding="utf-8")
    )
    note = Template(
        (Path(__file__).parent / "templates" / "hopsan_readme.md.tmpl").read_text(encoding="utf-8")
    )
    values = {k: _num(v) for k, v in params.items()}
    label = model.record.get("name", "cylfric model")
    text = {
        "stem": stem,
        "name": hcom_comment(label),
        "loss": hcom_comment(report.summary(), limit=None),
        "rms": f"{report.rms:.3f}",
        "max": f"{report.max_abs:.3f}",
        "signal_rms": f"{signal_report.rms:.3f}",
        "signal_max": f"{signal_report.max_abs:.3f}",
        "f_k0": _num(signal["f_k0"]),
        "k_p": _num(signal["f_k_pressure_coefficient"]),
        "B_p_signal": _num(signal["B_p"]),
        "sources": SOURCES,
        **values,
    }
    text["scatter"] = "\n".join(
        f"# {hcom_comment(line, limit=None)}" for line in summary_lines(model)
    )
    readme = {**text, "name": markdown_text(label), "scatter": _scatter_markdown(model)}
    files = [
        atomic_write_text(out / f"{stem}_hopsan.hcom", template.substitute(text)),
        atomic_write_text(out / f"{stem}_hopsan_parameters.csv", rows.getvalue()),
        atomic_write_text(out / f"{stem}_hopsan_scatter.csv", _scatter_csv(model)),
        atomic_write_text(out / "README_hopsan.md", note.substitute(readme)),
    ]
    files += report.write(out)
    files += signal_report.write(out)
    return ExportResult("hopsan", tuple(files), (report, signal_report))
