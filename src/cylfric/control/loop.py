"""The closed loop from Python: references, compensators, one run, every compensator.

The controller (at the axis's ``control_rate``, zero-order hold):

    u = (v_ref + t_l a_ref) / K_vel(p_A, p_B) + k_p e + k_i sum(e T) + k_d (v_ref - v_meas) + u_c

with ``e = x_ref - x``, ``K_vel`` the piston speed per unit opening at the measured chamber
pressures (the reference-velocity feedforward with the valve's flow linearised: the mean of
``K sqrt(p_S - p_A) / A_A`` and ``K sqrt(p_B - p_T) / A_B`` for extension, and of the
mirrored pair for retraction; Jelali & Kroll 2003 sec. 7.2), ``a_ref`` the reference
acceleration (central difference of the reference velocity) and ``t_l`` the lead of
:func:`~.tuning.feedforward_lead` (half a sample plus the spool's delay), ``v_meas`` the
backward difference of the sampled position, and the integral held while ``u`` saturates
(conditional integration). The compensation ``u_c`` turns the compensator's friction force
estimate ``F`` [N] into the flow that changes the cylinder force by as much and holds it
against the cross-piston leakage: ``u_c = (dF/dt + R_L(F)) / G_F``, ``dF/dt = (F_k -
F_{k-1}) / T``, ``R_L(F) = beta C_i (F / A_m) (A_A / V_A + A_B / V_B)`` the force rate the
leakage ``C_i (p_A - p_B)`` takes away from a force F (``A_m = (A_A + A_B)/2``, exact for a
double-rod cylinder) and ``G_F = beta (A_A K_A / V_A + A_B K_B / V_B)`` the force rate per
unit opening at the measured pressures and position (the inverse of the pressure build-up
equations, Jelali & Kroll 2003 eq. 3.8; the force appears as the integral of the flow, as in
the backstepping designs of hydraulic force control, e.g. Jelali & Kroll 2003 sec. 7.4).

Compensators (:data:`COMPENSATORS`):

- ``none``: the PI(D) and feedforward alone;
- ``coulomb``: ``F = F_c tanh(v_ref / v_s)``, one constant level (the datasheet's F_c at the
  axis's rest operating pressure), keyed to the reference velocity;
- ``static``: the datasheet's steady law at the measured pressures, ``F = g(v_ref)
  tanh(v_ref / v_s) + sigma_2 v_ref`` (eq. 2.7 with the sign smoothed);
- ``lugre``: the observer of Canudas de Wit et al. (1995, eq. 12): ``dz^/dt = v - sigma_0
  |v| z^ / g(v) + k_o e`` with the measured velocity, the datasheet's sigma_0, sigma_1 and
  pressure laws at the measured pressures, ``F = sigma_0 z^ + sigma_1 (v - sigma_0 |v| z^ /
  g(v)) + sigma_2 v``; z^ advanced by the exact update at constant v over T, then the
  correction ``k_o e T``;
- ``oracle``: the plant's own friction force at the sample, fed in exactly (the bound no
  compensator can beat through this force path).

Sign smoothing: ``v_s`` (default 1 mm/s, :data:`SMOOTHING_VELOCITY`); observer gain
``k_o`` (default :data:`OBSERVER_GAIN`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .axis import DEFAULT_AXIS, Axis
from .kernel import (
    COMPENSATOR_CODES,
    COMPENSATOR_STATE,
    OUTPUTS,
    REFERENCE_CODES,
    closed_loop,
    compensator_step,
    friction_table,
    run_compensator,
)
from .tuning import Tuning, feedforward_lead, tune

if TYPE_CHECKING:
    import pandas as pd

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "COMPENSATORS",
    "REFERENCES",
    "Reference",
    "LoopRun",
    "make_reference",
    "read_reference",
    "simulate_loop",
    "SMOOTHING_VELOCITY",
    "OBSERVER_GAIN",
    "FORCE_FILTER",
    "PlantFriction",
    "compensator_constants",
    "compensator_function",
    "compensator_outputs",
    "MEASUREMENTS",
    "ramp_in",
    "RAMP_IN_SPEED",
]

COMPENSATORS = tuple(COMPENSATOR_CODES)
REFERENCES = ("sine", "steps", "ramp")
SMOOTHING_VELOCITY = 1e-3
"""Sign smoothing velocity v_s of the Coulomb and static terms [m/s]."""
OBSERVER_GAIN = 0.0
"""Observer gain k_o of the LuGre observer [1/s] (0: open-loop observer)."""
FORCE_FILTER = 0.0
"""Time constant tau_f of the first-order filter on the compensator's force estimate [s]
(0: no filter). The position's quantum makes the backward-difference velocity jump by
q/T (1 mm/s for 1 um at 1 kHz) and the LuGre force's sigma_1 dz/dt + sigma_2 v with it; a
filter of a few samples smooths that at the price of its lag (measured on the example
differential axis with 1 um resolution: tau_f = 3 ms took the LuGre error from 0.90x to
0.80x of PI alone in the reference loop, nothing on its double-rod twin; default off)."""


@dataclass(frozen=True)
class Reference:
    """A position reference at the controller's samples: ``time`` [s], ``position`` [m],
    ``velocity`` [m/s] (its derivative), ``name``."""

    time: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    name: str


def make_reference(
    name: str,
    axis: Axis = DEFAULT_AXIS,
    *,
    duration: float = 10.0,
    amplitude: float = 5e-3,
    period: float = 5.0,
) -> Reference:
    """A built-in reference from the axis's start position.

    ``sine``: ``x0 + A (1 - cos(2 pi t / P))`` (starts at rest; peak speed ``2 pi A / P``:
    6.3 mm/s by default, below the demo datasheet's Stribeck velocity, where friction
    dominates); ``steps``: holds of ``P / 2`` at x0 + A, x0 - A, ... (steady state and
    hunting); ``ramp``: a triangle between x0 and x0 + 2A at ``4 A / P`` [m/s]. ``amplitude``
    A [m], ``period`` P [s], ``duration`` [s].
    """
    if name not in REFERENCES:
        raise ValueError(f"unknown reference {name!r}; valid: {list(REFERENCES)} or a CSV file")
    t = np.arange(0.0, duration + 0.5 * axis.sample_time, axis.sample_time)
    x0, a, w = axis.start_position, amplitude, 2 * math.pi / period
    if name == "sine":
        x, v = x0 + a * (1 - np.cos(w * t)), a * w * np.sin(w * t)
    elif name == "steps":
        level = np.where(np.floor(t / (period / 2)) % 2 == 0, 1.0, -1.0)
        level[t < 0.5] = 0.0
        x, v = x0 + a * level, np.zeros_like(t)
    else:
        phase = (t / period) % 1.0
        x = x0 + 2 * a * np.where(phase < 0.5, 2 * phase, 2 - 2 * phase)
        v = np.where(phase < 0.5, 4 * a / period, -4 * a / period)
    return Reference(t, x, v, name)


def read_reference(path: StrPath, axis: Axis = DEFAULT_AXIS) -> Reference:
    """A reference from a CSV file: columns ``time [s]`` and ``position [m]`` (or
    ``position [mm]``), resampled linearly at the controller rate; the velocity by
    central differences."""
    import csv

    path = Path(path)
    with path.open(encoding="utf-8", newline="") as handle:
        rows = list(csv.reader(handle))
    if not rows:
        raise ValueError(f"{path}: empty; expected columns 'time [s]' and 'position [m]'")
    header = [h.strip() for h in rows[0]]
    scales = {"position [m]": 1.0, "position [mm]": 1e-3}
    if "time [s]" not in header or not any(h in scales for h in header):
        raise ValueError(
            f"{path}, line 1: expected columns 'time [s]' and 'position [m]' "
            f"(or 'position [mm]'), found {header}"
        )
    it = header.index("time [s]")
    name = next(h for h in header if h in scales)
    ip = header.index(name)
    t, x = [], []
    for number, row in enumerate(rows[1:], 2):
        try:
            t.append(float(row[it]))
            x.append(float(row[ip]) * scales[name])
        except (ValueError, IndexError):
            raise ValueError(f"{path}, line {number}: expected two numbers, got {row}") from None
    time, position = np.array(t), np.array(x)
    if len(time) < 2 or not np.all(np.isfinite(time)) or not np.all(np.isfinite(position)):
        raise ValueError(f"{path}: expected at least two rows of finite numbers")
    if np.any(np.diff(time) <= 0):
        bad = int(np.nonzero(np.diff(time) <= 0)[0][0]) + 3
        raise ValueError(f"{path}, line {bad}: time is not increasing")
    if position.min() <= 0 or position.max() >= axis.stroke:
        raise ValueError(f"{path}: positions must lie inside the stroke (0, {axis.stroke} m)")
    grid = np.arange(time[0], time[-1] + 0.5 * axis.sample_time, axis.sample_time)
    xs = np.interp(grid, time, position)
    return Reference(grid - grid[0], xs, np.gradient(xs, axis.sample_time), path.name)


RAMP_IN_SPEED = 5e-3
"""Peak speed [m/s] of the ramp that brings the axis from its start position to a reference
file's first position (:func:`ramp_in`)."""


def ramp_in(reference: Reference, axis: Axis, *, speed: float = RAMP_IN_SPEED) -> Reference:
    """``reference`` preceded by a smooth move (half a cosine, peak ``speed`` [m/s]) from the
    axis's start position to its first position, and a 0.5 s hold; unchanged when it starts
    within a micrometre of the start position. The name says it was ramped in."""
    gap = float(reference.position[0]) - axis.start_position
    if abs(gap) <= 1e-6:
        return reference
    t_s = axis.sample_time
    duration = max(math.pi * abs(gap) / (2.0 * speed), 10 * t_s)
    n_move, n_hold = int(math.ceil(duration / t_s)), int(round(0.5 / t_s))
    phase = np.arange(n_move) * t_s / duration
    move = axis.start_position + gap * 0.5 * (1 - np.cos(math.pi * phase))
    move_v = gap * 0.5 * math.pi / duration * np.sin(math.pi * phase)
    position = np.r_[move, np.full(n_hold, reference.position[0]), reference.position]
    velocity = np.r_[move_v, np.zeros(n_hold), reference.velocity]
    time = np.arange(position.size) * t_s
    return Reference(time, position, velocity, f"{reference.name} (ramped in)")


@dataclass(frozen=True)
class PlantFriction:
    """How the plant's friction differs from the datasheet: ``level`` scales F_c, F_s,
    sigma_2 [-], ``slope`` their pressure dependence [-], ``offset`` [N] shifts F_c and F_s,
    ``model`` replaces the datasheet (another session's fit), ``stiffness`` scales sigma_0;
    ``name`` labels the case."""

    name: str = "datasheet"
    level: float = 1.0
    slope: float = 1.0
    offset: float = 0.0
    model: Any = None
    stiffness: float = 1.0
    """Factor on sigma_0 (sigma_1 by its square root) of the plant [-]."""


@dataclass
class LoopRun:
    """One closed-loop run: the compensator, the reference, the outputs at the samples."""

    compensator: str
    reference: Reference
    outputs: np.ndarray
    tuning: Tuning
    plant: PlantFriction = field(default_factory=PlantFriction)

    @property
    def time(self) -> np.ndarray:
        """Sample times [s]."""
        return self.reference.time

    @property
    def error(self) -> np.ndarray:
        """Tracking error x_ref - x [m]."""
        return self.reference.position - self.outputs[:, 0]

    def measurements(self) -> np.ndarray:
        """What a compensator read at each sample: rows of :data:`MEASUREMENTS`."""
        o = self.outputs
        return np.column_stack(
            [o[:, 0], o[:, 2], o[:, 3], self.reference.position, self.reference.velocity]
        )

    def to_pandas(self) -> pd.DataFrame:
        """Time series with units in the column names."""
        import pandas as pd

        frame = pd.DataFrame(self.outputs, columns=list(OUTPUTS))
        frame.insert(0, "time [s]", self.time)
        frame.insert(1, "reference [m]", self.reference.position)
        frame.insert(2, "reference velocity [m/s]", self.reference.velocity)
        frame["error [m]"] = self.error
        return frame


def rest_state(axis: Axis) -> np.ndarray:
    """(x, v, p_A, p_B, z) at rest [SI]."""
    pa, pb = axis.rest_pressures()
    return np.array([axis.start_position, 0.0, pa, pb, 0.0])


def controller_vector(
    axis: Axis,
    tuning: Tuning | None,
    model: FrictionModel,
    *,
    smoothing_velocity: float = SMOOTHING_VELOCITY,
    observer_gain: float = OBSERVER_GAIN,
    force_filter: float = FORCE_FILTER,
    velocity_input: bool = False,
) -> np.ndarray:
    """The compiled loop's controller vector (``kernel.CTRL``); ``force_filter`` tau_f [s];
    ``velocity_input``: the compensator reads the measured velocity instead of differencing
    the position."""
    if not (math.isfinite(force_filter) and force_filter >= 0):
        raise ValueError(f"force_filter = {force_filter!r} s; expected >= 0")
    pa, pb = axis.rest_pressures()
    coulomb = float(model.params_at(float(model.operating_pressure(pa, pb)))["F_c"])
    gains = (0.0, 0.0, 0.0) if tuning is None else (tuning.kp, tuning.ki, tuning.kd)
    return np.array(
        [
            *gains,
            1.0,
            feedforward_lead(axis),
            smoothing_velocity,
            observer_gain,
            coulomb,
            0.0,
            axis.sample_time,
            -math.expm1(-axis.sample_time / force_filter) if force_filter > 0 else 1.0,
            1.0 if velocity_input else 0.0,
        ]
    )


def compensator_constants(
    model: FrictionModel,
    axis: Axis = DEFAULT_AXIS,
    *,
    smoothing_velocity: float = SMOOTHING_VELOCITY,
    observer_gain: float = OBSERVER_GAIN,
    force_filter: float = FORCE_FILTER,
    velocity_input: bool = False,
) -> np.ndarray:
    """The controller vector with the PID off: what the compensator step alone reads
    (sign smoothing [m/s], observer gain [1/s], Coulomb level [N], sample time [s], the
    force filter's gain [-], the velocity input's switch [-])."""
    ctrl = controller_vector(
        axis,
        None,
        model,
        smoothing_velocity=smoothing_velocity,
        observer_gain=observer_gain,
        force_filter=force_filter,
        velocity_input=velocity_input,
    )
    ctrl[:4] = 0.0
    return ctrl


def compensator_function(
    model: FrictionModel,
    axis: Axis = DEFAULT_AXIS,
    kind: str = "lugre",
    *,
    force_filter: float = FORCE_FILTER,
):
    """The compensator step (:func:`~.kernel.compensator_step`, what the C, FMU and MATLAB
    exports run) as a per-sample callable with its own state:
    ``step(x, pa, pb, x_ref, v_ref) -> (force [N], command [-])`` from the position [m],
    the chamber pressures [Pa] and the reference [m, m/s], one call per controller sample
    (to drive it in an axis model of one's own, as tests/test_control_reference.py does)."""
    table, rule = friction_table(model), REFERENCE_CODES[model.reference]
    ctrl = compensator_constants(model, axis, force_filter=force_filter)
    vector, code = axis.vector(), COMPENSATOR_CODES[kind]
    state = np.zeros(len(COMPENSATOR_STATE))

    def step(x, pa, pb, x_ref, v_ref):
        return compensator_step(
            code, table, rule, ctrl, vector, state, x, pa, pb, x_ref, v_ref, 0.0
        )

    return step


MEASUREMENTS = (
    "position [m]",
    "pressure_a [Pa]",
    "pressure_b [Pa]",
    "position_reference [m]",
    "velocity_reference [m/s]",
)
"""Columns of the measurements a compensator reads at each sample (:func:`compensator_outputs`)."""


def compensator_outputs(
    model: FrictionModel,
    compensator: str,
    measurements: np.ndarray,
    *,
    axis: Axis = DEFAULT_AXIS,
    smoothing_velocity: float = SMOOTHING_VELOCITY,
    observer_gain: float = OBSERVER_GAIN,
    force_filter: float = FORCE_FILTER,
    velocity_input: bool = False,
) -> np.ndarray:
    """The compensator (``kernel.compensator_step``) along recorded measurements.

    ``measurements``: rows of :data:`MEASUREMENTS` at the controller samples (e.g.
    :meth:`LoopRun.measurements` of a closed-loop run); returns rows (force [N], command
    [-]), from the zero state. The reference the exported C, FMU and MATLAB steps match.
    """
    if compensator not in COMPENSATOR_CODES or compensator == "oracle":
        raise ValueError(
            f"compensator {compensator!r}: expected one of "
            f"{[c for c in COMPENSATORS if c != 'oracle']} (the oracle reads the plant)"
        )
    data = np.ascontiguousarray(measurements, dtype=float)
    if data.ndim != 2 or data.shape[1] not in (len(MEASUREMENTS), len(MEASUREMENTS) + 1):
        raise ValueError(
            f"measurements of shape {data.shape}; expected (n, 5) columns {list(MEASUREMENTS)}"
            " and optionally a sixth, 'velocity [m/s]'"
        )
    if velocity_input and data.shape[1] != len(MEASUREMENTS) + 1:
        raise ValueError("velocity_input needs a sixth column 'velocity [m/s]'")
    return run_compensator(
        COMPENSATOR_CODES[compensator],
        friction_table(model),
        REFERENCE_CODES[model.reference],
        compensator_constants(
            model,
            axis,
            smoothing_velocity=smoothing_velocity,
            observer_gain=observer_gain,
            force_filter=force_filter,
            velocity_input=velocity_input,
        ),
        axis.vector(),
        data,
    )


def simulate_loop(
    model: FrictionModel,
    compensator: str = "none",
    *,
    axis: Axis = DEFAULT_AXIS,
    reference: Reference | str = "sine",
    tuning: Tuning | None = None,
    plant: PlantFriction | None = None,
    smoothing_velocity: float = SMOOTHING_VELOCITY,
    observer_gain: float = OBSERVER_GAIN,
    force_filter: float = FORCE_FILTER,
    velocity_input: bool = False,
) -> LoopRun:
    """Run the loop with one compensator; the compensator always uses ``model`` (the
    datasheet), the plant ``plant`` (default: the datasheet itself). ``force_filter`` [s]
    and ``velocity_input`` (the compensator reads the plant's true velocity, a velocity
    sensor) as in :func:`controller_vector`."""
    if compensator not in COMPENSATOR_CODES:
        raise ValueError(f"unknown compensator {compensator!r}; valid: {list(COMPENSATORS)}")
    if isinstance(reference, str):
        reference = make_reference(reference, axis)
    plant = plant or PlantFriction()
    if tuning is None:
        tuning = tune(axis, viscous=_rest_viscous(model, axis))
    plant_model = plant.model if plant.model is not None else model
    outputs = closed_loop(
        axis.vector(),
        friction_table(
            plant_model,
            level=plant.level,
            slope=plant.slope,
            offset=plant.offset,
            stiffness=plant.stiffness,
        ),
        REFERENCE_CODES[plant_model.reference],
        friction_table(model),
        REFERENCE_CODES[model.reference],
        COMPENSATOR_CODES[compensator],
        controller_vector(
            axis,
            tuning,
            model,
            smoothing_velocity=smoothing_velocity,
            observer_gain=observer_gain,
            force_filter=force_filter,
            velocity_input=velocity_input,
        ),
        np.ascontiguousarray(reference.position),
        np.ascontiguousarray(reference.velocity),
        axis.substeps,
        rest_state(axis),
    )
    return LoopRun(compensator, reference, outputs, tuning, plant)


def _rest_viscous(model: FrictionModel, axis: Axis) -> float:
    pa, pb = axis.rest_pressures()
    return float(model.params_at(float(model.operating_pressure(pa, pb)))["sigma_2"])
