"""Simscape export: best-fit parameters of Simscape's friction blocks, with loss reports.

Simscape has no block for a pressure-dependent Stribeck/LuGre law with its own pressure law
per parameter, so this export is lossy. It fits, by least squares over the datasheet's
validity range (:func:`cylfric.export.loss.loss_grid`), the parameters of

* **Cylinder Friction (IL)** (Simscape Fluids, Isothermal Liquid / Actuators / Auxiliary
  Components), the current block. Its documented equations (MathWorks, "Cylinder Friction
  (IL)" reference page): the Stribeck and viscous parts as in the Foundation library's
  Translational Friction block, ``F = F_Stribeck + F_Coulomb + F_viscous`` with
  ``F_Stribeck = sqrt(2e) (R_brk - 1) F_C x exp(-x^2)`` with ``x = v/v_st``,
  ``v_st = sqrt(2) v_brk``,
  ``F_Coulomb = F_C tanh(v/v_Coul)``, ``v_Coul = v_brk/10``, ``F_viscous = f v``, and the
  Coulomb force from the seal preload and the chamber pressures,
  ``F_C = F_pr + f_cfr (p_A + p_B)`` (the IL page's text at hand states this part in words;
  the sum of the chamber pressures is the form the legacy block's page writes out).
* **Cylinder Friction** (Simscape Fluids, Hydraulics (Isothermal), to be removed since
  R2020a), the block :func:`cylfric.friction.simscape_cylinder_friction` already imports
  from: ``F = F_C (1 + (K_brk - 1) exp(-c_v |v|)) sign(v) + f_vfr v``,
  ``F_C = F_pr + f_cfr (p_A + p_B)``, linear below ``|v| <= v_th``. Its equations are that
  function's (with :func:`cylfric.friction.stribeck`), not written again here.
* **Translational Friction** (Simscape Foundation library), one parameter set per pressure
  level (the datasheet's measured levels): breakaway force, Coulomb force, viscous
  coefficient and breakaway velocity (Stribeck velocity threshold ``sqrt(2) v_brk``).

The output is a MATLAB script that builds a parameter struct (SI, with units) and sets the
blocks with ``set_param`` (the dialog parameter behind each documented prompt is looked up on
the block, so the script does not depend on internal parameter names), and one loss report
per block (:mod:`cylfric.export.loss`).

References
----------
MathWorks, Simscape Fluids reference: "Cylinder Friction (IL)",
https://www.mathworks.com/help/hydro/ref/cylinderfrictionil.html ; "Cylinder Friction",
https://www.mathworks.com/help/hydro/ref/cylinderfriction.html ; Simscape reference:
"Translational Friction", https://www.mathworks.com/help/simscape/ref/translationalfriction.html
"""

from __future__ import annotations

import math
from pathlib import Path
from string import Template
from typing import TYPE_CHECKING

import numpy as np

from ..escape import identifier, matlab_comment
from ..friction import simscape_cylinder_friction, stribeck
from ..friction.pressure import linear, operating_pressure
from ..io.writers import atomic_write_text
from .loss import chamber_pressure, chamber_pressures, loss_grid, loss_report
from .matlab import scatter_struct_lines
from .result import ExportResult

if TYPE_CHECKING:
    from collections.abc import Sequence

    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "translational_friction",
    "cylinder_friction_il",
    "cylinder_friction",
    "fit_cylinder_friction_il",
    "fit_cylinder_friction",
    "fit_translational_friction",
    "export_simscape",
    "SOURCES",
]

SOURCES = {
    "cylinder_friction_il": "MathWorks, Simscape Fluids reference, Cylinder Friction (IL), "
    "https://www.mathworks.com/help/hydro/ref/cylinderfrictionil.html",
    "cylinder_friction": "MathWorks, Simscape Fluids reference, Cylinder Friction "
    "(Hydraulics (Isothermal), to be removed), "
    "https://www.mathworks.com/help/hydro/ref/cylinderfriction.html",
    "translational_friction": "MathWorks, Simscape reference, Translational Friction, "
    "https://www.mathworks.com/help/simscape/ref/translationalfriction.html",
}
"""Where each block's equations are documented."""

SQRT_2E = math.sqrt(2.0 * math.e)
"""Peak factor of the Stribeck term: its maximum over v is (F_brk - F_C), at v = v_brk."""

LEGACY_VELOCITY_THRESHOLD = 1e-4
"""``v_th`` [m/s] written for the legacy Cylinder Friction block (its linear region around
zero velocity); the loss grid starts above it unless the data reach below 0.1 mm/s."""


def translational_friction(
    velocity: float | np.ndarray,
    *,
    breakaway_force: float | np.ndarray,
    coulomb_force: float | np.ndarray,
    viscous_coefficient: float | np.ndarray,
    breakaway_velocity: float | np.ndarray,
) -> float | np.ndarray:
    """Friction force of Simscape's Translational Friction block [N] (documented equations).

    ``F = sqrt(2e) (F_brk - F_C) x exp(-x^2) + F_C tanh(v/v_Coul) + f v``, ``x = v/v_st``, with
    the Stribeck velocity threshold ``v_st = sqrt(2) v_brk`` and the Coulomb velocity
    threshold ``v_Coul = v_brk / 10`` (MathWorks, Translational Friction reference page).

    Parameters
    ----------
    velocity : float or array_like
        Relative velocity [m/s].
    breakaway_force : float or array_like
        Breakaway friction force ``F_brk`` [N], >= ``coulomb_force``.
    coulomb_force : float or array_like
        Coulomb friction force ``F_C`` [N].
    viscous_coefficient : float or array_like
        Viscous friction coefficient ``f`` [N*s/m].
    breakaway_velocity : float or array_like
        Breakaway friction velocity ``v_brk`` [m/s], > 0.
    """
    v = np.asarray(velocity, dtype=float)
    v_st = math.sqrt(2.0) * np.asarray(breakaway_velocity, dtype=float)
    ratio = v / v_st
    stribeck_part = SQRT_2E * (breakaway_force - coulomb_force) * np.exp(-(ratio**2)) * ratio
    coulomb_part = coulomb_force * np.tanh(10.0 * v / np.asarray(breakaway_velocity))
    return stribeck_part + coulomb_part + viscous_coefficient * v


def cylinder_friction_il(
    velocity: float | np.ndarray,
    pressure_a: ArrayLike,
    pressure_b: ArrayLike,
    *,
    preload_force: float,
    coulomb_friction_coefficient: float,
    breakaway_ratio: float,
    breakaway_velocity: float,
    viscous_coefficient: float,
) -> np.ndarray | float:
    """Friction force of Simscape Fluids' Cylinder Friction (IL) block [N].

    The Translational Friction equations (:func:`translational_friction`) with the Coulomb
    force ``F_C = F_pr + f_cfr (p_A + p_B)`` (cylfric's linear pressure law of the *sum* of
    the chamber pressures) and the breakaway force ``R_brk F_C``.

    Parameters
    ----------
    velocity : float or array_like
        Relative velocity rod - case [m/s].
    pressure_a, pressure_b : float or array_like
        Chamber pressures [Pa].
    preload_force : float
        Preload force ``F_pr`` [N].
    coulomb_friction_coefficient : float
        Coulomb friction force coefficient ``f_cfr`` [N/Pa].
    breakaway_ratio : float
        Breakaway to Coulomb friction force ratio ``R_brk`` [-], >= 1.
    breakaway_velocity : float
        Breakaway friction velocity ``v_brk`` [m/s].
    viscous_coefficient : float
        Viscous friction coefficient ``f`` [N*s/m].
    """
    pressure = operating_pressure(pressure_a, pressure_b, reference="sum")
    coulomb = linear(pressure, preload_force, coulomb_friction_coefficient)
    return translational_friction(
        velocity,
        breakaway_force=breakaway_ratio * coulomb,
        coulomb_force=coulomb,
        viscous_coefficient=viscous_coefficient,
        breakaway_velocity=breakaway_velocity,
    )


def cylinder_friction(
    velocity: float | np.ndarray,
    pressure_a: ArrayLike,
    pressure_b: ArrayLike,
    *,
    preload_force: float,
    coulomb_friction_coefficient: float,
    breakaway_ratio: float,
    transition_coefficient: float,
    viscous_coefficient: float,
    velocity_threshold: float = LEGACY_VELOCITY_THRESHOLD,
) -> np.ndarray | float:
    """Friction force of the legacy Simscape Fluids Cylinder Friction block [N].

    :func:`cylfric.friction.simscape_cylinder_friction` (the block as a Stribeck parameter
    set) evaluated by :func:`cylfric.friction.stribeck`, linear in velocity for
    ``|v| <= v_th`` as the block documents (``F = K v``, K matching the force at ``v_th``).
    Units as :func:`cylinder_friction_il`; ``transition_coefficient`` ``c_v`` [s/m],
    ``velocity_threshold`` ``v_th`` [m/s].
    """
    v = np.asarray(velocity, dtype=float)
    params = simscape_cylinder_friction(
        pressure_a,
        pressure_b,
        preload_force=preload_force,
        coulomb_friction_coefficient=coulomb_friction_coefficient,
        breakaway_ratio=breakaway_ratio,
        viscous_coefficient=viscous_coefficient,
        transition_coefficient=transition_coefficient,
    )
    outside = np.where(np.abs(v) > velocity_threshold, v, np.copysign(velocity_threshold, v))
    force = stribeck(outside, **params)
    return np.where(np.abs(v) > velocity_threshold, force, force * np.abs(v) / velocity_threshold)


# ---------------------------------------------------------------------------------- fitting
def _least_squares(residual, starts, lower, upper):
    """Best of bounded least-squares runs from each start (deterministic)."""
    from scipy.optimize import least_squares

    best = None
    for start in starts:
        x0 = np.clip(np.asarray(start, dtype=float), lower, upper)
        fit = least_squares(residual, x0, bounds=(lower, upper), x_scale="jac", method="trf")
        if best is None or fit.cost < best.cost:
            best = fit
    assert best is not None  # starts is never empty
    return best.x


def _grid_and_start(model, speeds, pressures):
    """(p_A, p_B, V) grid [Pa, Pa, m/s] (:func:`~cylfric.export.loss.chamber_pressures`), the
    model's friction there [N], and starting values from its levels: slope [N/Pa] and
    preload [N] of F_c against p_A + p_B, the mean F_s/F_c [-], sigma_2 [N*s/m] and v_r [m/s]."""
    P, V = np.meshgrid(pressures, speeds, indexing="ij")
    PA, PB = chamber_pressures(model, P)
    target = model.friction(V, model.operating_pressure(PA, PB))
    levels = _model_levels(model, pressures)
    total = np.add(*chamber_pressures(model, pressures))
    slope, preload = np.polyfit(total, np.broadcast_to(levels["F_c"], pressures.shape), 1)
    ratio = float(np.mean(np.asarray(levels["F_s"]) / np.asarray(levels["F_c"])))
    viscous = float(np.mean(levels["sigma_2"]))
    v_r = float(np.mean(levels["v_r"]))
    return (PA, PB), V, target, (slope, preload, ratio, viscous, v_r)


def _model_levels(model, pressures):
    """Parameters of the cylfric model at chamber pressures [Pa] (p_A = p_B, or the working
    chamber's: :func:`~cylfric.export.loss.chamber_pressures`)."""
    return model.params_at(model.operating_pressure(*chamber_pressures(model, pressures)))


def fit_cylinder_friction_il(
    model: FrictionModel, speeds: ArrayLike, pressures: ArrayLike
) -> dict[str, float]:
    """Best-fit Cylinder Friction (IL) parameters over a grid (least squares) [SI].

    Parameters
    ----------
    model : FrictionModel
        The cylfric model.
    speeds : array_like
        Positive speeds [m/s] (the block and the model are odd in velocity).
    pressures : array_like
        Chamber pressures [Pa]: both chambers at them, or a single-acting cylinder's working
        chamber with the other at 0 gauge (:func:`~cylfric.export.loss.chamber_pressures`).

    Returns
    -------
    dict
        ``preload_force`` [N], ``coulomb_friction_coefficient`` [N/Pa], ``breakaway_ratio``
        [-], ``breakaway_velocity`` [m/s], ``viscous_coefficient`` [N*s/m].
    """
    speeds, pressures = np.asarray(speeds, float), np.asarray(pressures, float)
    P, V, target, (slope, preload, ratio, viscous, v_r) = _grid_and_start(model, speeds, pressures)

    def unpack(x):  # optimizer units: N, N/bar, -, mm/s, N*s/mm
        return {
            "preload_force": x[0],
            "coulomb_friction_coefficient": x[1] * 1e-5,
            "breakaway_ratio": x[2],
            "breakaway_velocity": x[3] * 1e-3,
            "viscous_coefficient": x[4] * 1e3,
        }

    def residual(x):
        return (cylinder_friction_il(V, *P, **unpack(x)) - target).ravel()

    starts = [
        [max(preload, 0.0), max(slope, 0.0) * 1e5, max(ratio, 1.0), v * 1e3, viscous * 1e-3]
        for v in (speeds[0], v_r / 3, v_r)
    ]
    lower = [0.0, 0.0, 1.0, 1e-3, 0.0]
    upper = [np.inf, np.inf, 100.0, 1e4, np.inf]
    return {k: float(v) for k, v in unpack(_least_squares(residual, starts, lower, upper)).items()}


def fit_cylinder_friction(
    model: FrictionModel,
    speeds: ArrayLike,
    pressures: ArrayLike,
    *,
    velocity_threshold: float | None = None,
) -> dict[str, float]:
    """Best-fit legacy Cylinder Friction parameters over a grid (least squares) [SI].

    As :func:`fit_cylinder_friction_il`; returns ``preload_force`` [N],
    ``coulomb_friction_coefficient`` [N/Pa], ``breakaway_ratio`` [-],
    ``transition_coefficient`` [s/m], ``viscous_coefficient`` [N*s/m] and
    ``velocity_threshold`` [m/s] (below the lowest speed of the grid).
    """
    speeds, pressures = np.asarray(speeds, float), np.asarray(pressures, float)
    if velocity_threshold is None:
        velocity_threshold = min(LEGACY_VELOCITY_THRESHOLD, float(speeds[0]) / 2)
    P, V, target, (slope, preload, ratio, viscous, v_r) = _grid_and_start(model, speeds, pressures)

    def unpack(x):  # optimizer units: N, N/bar, -, s/mm, N*s/mm
        return {
            "preload_force": x[0],
            "coulomb_friction_coefficient": x[1] * 1e-5,
            "breakaway_ratio": x[2],
            "transition_coefficient": x[3] * 1e3,
            "viscous_coefficient": x[4] * 1e3,
        }

    def residual(x):
        force = cylinder_friction(V, *P, velocity_threshold=velocity_threshold, **unpack(x))
        return (force - target).ravel()

    starts = [
        [max(preload, 0.0), max(slope, 0.0) * 1e5, max(ratio, 1.0), 1e-3 / v_r, viscous * 1e-3]
    ]
    lower = [0.0, 0.0, 1.0, 1e-6, 0.0]
    upper = [np.inf, np.inf, 100.0, 1e3, np.inf]
    out = {k: float(v) for k, v in unpack(_least_squares(residual, starts, lower, upper)).items()}
    out["velocity_threshold"] = float(velocity_threshold)
    return out


def fit_translational_friction(
    model: FrictionModel, speeds: ArrayLike, pressure: float
) -> dict[str, float]:
    """Best-fit Translational Friction parameters at one chamber pressure [Pa] (SI).

    Returns ``breakaway_force`` [N], ``coulomb_force`` [N], ``viscous_coefficient``
    [N*s/m], ``breakaway_velocity`` [m/s] (least squares over ``speeds`` [m/s]).
    """
    speeds = np.asarray(speeds, float)
    target = model.friction(speeds, model.operating_pressure(*chamber_pressures(model, pressure)))
    level = _model_levels(model, pressure)

    def unpack(x):  # optimizer units: N, N, N*s/mm, mm/s; x[1] is F_brk - F_C
        return {
            "breakaway_force": x[0] + x[1],
            "coulomb_force": x[0],
            "viscous_coefficient": x[2] * 1e3,
            "breakaway_velocity": x[3] * 1e-3,
        }

    def residual(x):
        return translational_friction(speeds, **unpack(x)) - target

    excess = max(float(level["F_s"] - level["F_c"]), 0.0)
    starts = [
        [float(level["F_c"]), excess, float(level["sigma_2"]) * 1e-3, v * 1e3]
        for v in (speeds[0], float(level["v_r"]) / 3, float(level["v_r"]))
    ]
    lower = [0.0, 0.0, 0.0, 1e-3]
    upper = [np.inf, np.inf, np.inf, 1e4]
    return {k: float(v) for k, v in unpack(_least_squares(residual, starts, lower, upper)).items()}


# ---------------------------------------------------------------------------------- export
_IL_UNITS = {
    "preload_force": "N",
    "coulomb_friction_coefficient": "N/Pa",
    "breakaway_ratio": "1",
    "breakaway_velocity": "m/s",
    "viscous_coefficient": "N*s/m",
}
_IL_PROMPTS = {
    "preload_force": "Preload force",
    "coulomb_friction_coefficient": "Coulomb friction force coefficient",
    "breakaway_ratio": "Breakaway to Coulomb friction force ratio",
    "breakaway_velocity": "Breakaway friction velocity",
    "viscous_coefficient": "Viscous friction coefficient",
}
_LEGACY_UNITS = {
    "preload_force": "N",
    "coulomb_friction_coefficient": "N/Pa",
    "breakaway_ratio": "1",
    "transition_coefficient": "s/m",
    "viscous_coefficient": "N*s/m",
    "velocity_threshold": "m/s",
}
_LEGACY_PROMPTS = {
    "preload_force": "Preload force",
    "coulomb_friction_coefficient": "Coulomb friction coefficient",
    "breakaway_ratio": "Breakaway friction increase coefficient",
    "transition_coefficient": "Transition coefficient",
    "viscous_coefficient": "Viscous friction coefficient",
    "velocity_threshold": "Velocity threshold",
}
_TF_UNITS = {
    "breakaway_force": "N",
    "coulomb_force": "N",
    "viscous_coefficient": "N*s/m",
    "breakaway_velocity": "m/s",
}
_TF_PROMPTS = {
    "breakaway_force": "Breakaway friction force",
    "coulomb_force": "Coulomb friction force",
    "viscous_coefficient": "Viscous friction coefficient",
    "breakaway_velocity": "Breakaway friction velocity",
}


def _num(x: float) -> str:
    return format(float(x), ".10g")


def _matlab_struct(prefix, params, units) -> str:
    lines = []
    for key, value in params.items():
        lines.append(f"{prefix}.{key} = {_num(value)};  % [{units[key]}]")
        lines.append(f"{prefix}.units.{key} = '{units[key]}';")
    return "\n".join(lines)


def _matlab_sets(block_var, struct, params, prompts, units) -> str:
    lines = []
    for key in params:
        lines.append(
            f"    cylfric_set({block_var}, '{prompts[key]}', {struct}.{key}, '{units[key]}');"
        )
    return "\n".join(lines)


def _levels(model, pressure_range, levels):
    """Operating pressures [Pa] of the Translational Friction blocks."""
    if levels is not None:
        out = np.asarray(levels, dtype=float)
    else:
        table = model.record.get("per_pressure") or []
        out = np.array(sorted({float(row["pressure"]) for row in table if "pressure" in row}))
        if out.size == 0:
            if pressure_range is None and model.validity is not None:
                pressure_range = (model.validity["pressure_min"], model.validity["pressure_max"])
            if pressure_range is None:
                return None
            out = np.linspace(float(pressure_range[0]), float(pressure_range[1]), 5)
    if out.ndim != 1 or out.size == 0 or not np.all(np.isfinite(out)) or np.any(out < 0):
        raise ValueError(f"levels = {levels!r}: expected pressures >= 0 Pa")
    return out


def export_simscape(
    model: FrictionModel,
    out: StrPath,
    *,
    name: str | None = None,
    velocity_range: tuple[float, float] | None = None,
    pressure_range: tuple[float, float] | None = None,
    levels: Sequence[float] | None = None,
    n_velocity: int | None = None,
    n_pressure: int | None = None,
) -> ExportResult:
    """Fit Simscape's friction blocks to the model and write a MATLAB script and loss reports.

    Parameters
    ----------
    model : FrictionModel
        The cylfric model (a datasheet's).
    out : path-like
        Output folder (created): ``<name>_simscape.m`` and ``loss_<block>.csv/.txt/.png``.
    name : str, optional
        Stem of the script (a MATLAB identifier is made of it); default the datasheet's
        name or ``cylfric``.
    velocity_range : (float, float), optional
        (min, max) speed [m/s] of the fit and the loss grid; default the model's validity.
    pressure_range : (float, float), optional
        (min, max) operating pressure [Pa]; default the model's validity.
    levels : sequence of float, optional
        Operating pressures [Pa] of the Translational Friction blocks; default the
        datasheet's measured levels, else 5 levels over the pressure range.
    n_velocity, n_pressure : int, optional
        Size of the grid (:data:`~cylfric.export.loss.N_VELOCITY` x
        :data:`~cylfric.export.loss.N_PRESSURE`).

    Returns
    -------
    ExportResult
        The files and three loss reports (Cylinder Friction (IL), Cylinder Friction,
        Translational Friction per level).
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
    il = fit_cylinder_friction_il(model, speeds, pressures)
    legacy = fit_cylinder_friction(model, speeds, pressures)
    operating = _levels(model, pressure_range, levels)
    chamber = chamber_pressure(model, operating)
    per_level = [fit_translational_friction(model, speeds, p) for p in chamber]

    reports = [
        loss_report(
            model,
            lambda v, pa, pb: cylinder_friction_il(v, pa, pb, **il),
            target="simscape_cylinder_friction_il",
            title="Simscape Fluids Cylinder Friction (IL)",
            speeds=speeds,
            pressures=pressures,
            parameters={k: (v, _IL_UNITS[k]) for k, v in il.items()},
            notes=(
                f"equations: {SOURCES['cylinder_friction_il']}",
                "F_C = F_pr + f_cfr (p_A + p_B); breakaway R_brk F_C at v_brk, a Gaussian "
                "Stribeck hump (not the exponential decay of thesis eq. 2.7); constant "
                "ratio R_brk and constant viscous coefficient over pressure",
                "the FMU export carries the full model (lossless)",
            ),
        ),
        loss_report(
            model,
            lambda v, pa, pb: cylinder_friction(v, pa, pb, **legacy),
            target="simscape_cylinder_friction",
            title="Simscape Fluids Cylinder Friction (legacy Hydraulics)",
            speeds=speeds,
            pressures=pressures,
            parameters={k: (v, _LEGACY_UNITS[k]) for k, v in legacy.items()},
            notes=(
                f"equations: {SOURCES['cylinder_friction']}",
                "eq. 2.7 with alpha = 1, F_s / F_c and sigma_2 constant over pressure, "
                "pressure law on p_A + p_B (cylfric.friction.simscape_cylinder_friction)",
            ),
        ),
        loss_report(
            model,
            lambda v, pa, pb: _per_level(v, pa, chamber, per_level),
            target="simscape_translational_friction",
            title="Simscape Translational Friction (one block per pressure level)",
            speeds=speeds,
            pressures=chamber,
            parameters={
                f"level{k + 1}.{key}": (value, _TF_UNITS.get(key, "Pa"))
                for k, params in enumerate(per_level)
                for key, value in {"pressure": float(operating[k]), **params}.items()
            },
            notes=(
                f"equations: {SOURCES['translational_friction']}",
                "exact only at its own pressure level: the grid is the levels themselves",
            ),
        ),
    ]
    script = _script(stem, model, il, legacy, operating, per_level, reports)
    files = [atomic_write_text(out / f"{stem}_simscape.m", script)]
    for report in reports:
        files += report.write(out)
    return ExportResult("simscape", tuple(files), tuple(reports))


def _per_level(velocity, pressure, chamber, per_level):
    force = np.zeros(np.shape(velocity))
    for p, params in zip(chamber, per_level, strict=True):
        sel = np.isclose(pressure, p, rtol=1e-12, atol=1e-9)
        force = np.where(sel, translational_friction(velocity, **params), force)
    return force


def _script(stem, model, il, legacy, operating, per_level, reports) -> str:
    template = Template(
        (Path(__file__).parent / "templates" / "simscape.m.tmpl").read_text(encoding="utf-8")
    )
    levels = []
    for k, (p, params) in enumerate(zip(operating, per_level, strict=True), start=1):
        levels.append(f"P.translational_friction({k}).pressure = {_num(p)};  % [Pa] operating")
        levels.append(_matlab_struct(f"P.translational_friction({k})", params, _TF_UNITS))
    source = model.provenance.get("source") or {}
    return template.substitute(
        stem=stem,
        name=matlab_comment(model.record.get("name", "cylfric model")),
        reference=matlab_comment(model.reference),
        losses="\n".join(f"%   {matlab_comment(r.summary(), limit=None)}" for r in reports),
        il_struct=_matlab_struct("P.cylinder_friction_il", il, _IL_UNITS),
        legacy_struct=_matlab_struct("P.cylinder_friction", legacy, _LEGACY_UNITS),
        tf_struct="\n".join(levels),
        il_sets=_matlab_sets(
            "cylinder_friction_il_block", "P.cylinder_friction_il", il, _IL_PROMPTS, _IL_UNITS
        ),
        legacy_sets=_matlab_sets(
            "cylinder_friction_block", "P.cylinder_friction", legacy, _LEGACY_PROMPTS, _LEGACY_UNITS
        ),
        tf_sets=_matlab_sets(
            "translational_friction_blocks{k}",
            "P.translational_friction(k)",
            per_level[0],
            _TF_PROMPTS,
            _TF_UNITS,
        ),
        campaign=matlab_comment(source.get("campaign", "")) if isinstance(source, dict) else "",
        scatter_comments=_scatter_comments(model),
        scatter_struct="\n".join(scatter_struct_lines(model, "P")),
    )


def _scatter_comments(model) -> str:
    """Comment lines of the script header: the scatter record and how to form a band."""
    import textwrap

    from .scatter import summary_lines

    lines = []
    for line in summary_lines(model):
        lines += textwrap.wrap(matlab_comment(line, limit=None), 86)
    return "\n".join(f"%   {line}" for line in lines)
