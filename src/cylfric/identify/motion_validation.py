"""Validation of a motion fit by simulation: the identified axis in its recorded servo loop.

The EMPS benchmark (Janot, Gautier and Brunot 2019) validates an identified model by
simulating it in closed loop with the recorded position reference and the recorded
controller, then comparing the simulated position and force with the measured ones by their
relative error norms. The EMPS controller is a cascade of a proportional position loop and a
proportional velocity loop, sampled at 1 kHz:

    u[k] = sat(kv * (kp * (q_ref[k] - q[k]) - (f[k] - f[k-1]) / T)) + d[k],
    f[k] = (q[k] + q[k-1]) / 2,

with ``sat`` the output limit, ``d`` an added disturbance (the pulses of
``DATA_EMPS_PULSES.mat``), held over the sample (zero-order hold). On ``DATA_EMPS.mat`` this
law reproduces the recorded controller output from the recorded positions to 0.24 % RMS
(``tests/test_motion_emps.py``). The plant ``mass * q'' = force_scale * u - friction - offset``
is integrated with a small implicit (backward Euler) scheme whose Coulomb term is set-valued,
so the axis sticks exactly when the drive force cannot overcome ``F_c``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.identify.motion import MotionFit
    from cylfric.io.motion_config import MotionConfig

__all__ = ["ServoReplay", "controller_output", "replay_closed_loop", "relative_error"]


def relative_error(measured: ArrayLike, simulated: ArrayLike) -> float:
    """Relative error norm ||measured - simulated|| / ||measured|| [-] (the benchmark's)."""
    measured = np.asarray(measured, dtype=float)
    return float(np.linalg.norm(measured - np.asarray(simulated)) / np.linalg.norm(measured))


def controller_output(
    reference: ArrayLike,
    position: ArrayLike,
    *,
    kp: float,
    kv: float,
    sample_time: float,
    saturation: float = math.inf,
) -> np.ndarray:
    """The cascade P-P controller's output from recorded signals (no plant).

    Parameters
    ----------
    reference, position : array_like
        Position reference and measured position [m].
    kp : float
        Position gain [1/s].
    kv : float
        Velocity gain [output unit per m/s].
    sample_time : float
        Controller period [s].
    saturation : float
        Output limit [output unit].

    Returns
    -------
    ndarray
        Controller output [output unit] (before any added disturbance).
    """
    q = np.asarray(position, dtype=float)
    half = 0.5 * (q + np.concatenate(([q[0]], q[:-1])))
    velocity = np.diff(half, prepend=half[0]) / sample_time
    u = kv * (kp * (np.asarray(reference, dtype=float) - q) - velocity)
    return np.clip(u, -saturation, saturation)


@dataclass(frozen=True)
class ServoReplay:
    """Result of :func:`replay_closed_loop` (simulated and measured signals, SI).

    Attributes
    ----------
    time : ndarray
        [s].
    position, velocity, force : ndarray
        Simulated position [m], velocity [m/s] and drive force [N].
    measured_position, measured_velocity, measured_force : ndarray
        Filtered measured position [m], its central-difference velocity [m/s] and the
        measured force [N].
    errors : dict
        Relative error norms [-] ``position``, ``velocity`` and ``force`` over the samples
        past ``border``.
    """

    time: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    force: np.ndarray
    measured_position: np.ndarray
    measured_velocity: np.ndarray
    measured_force: np.ndarray
    errors: dict

    def to_dict(self) -> dict:
        """JSON form: the relative errors in % and what was compared."""
        return {
            "procedure": (
                "closed-loop simulation of the identified model with the recorded position "
                "reference through the recorded cascade P-P controller (EMPS benchmark); "
                "relative error norms against the filtered measured position and the "
                "measured force"
            ),
            "relative_position_error [%]": 100 * self.errors["position"],
            "relative_velocity_error [%]": 100 * self.errors["velocity"],
            "relative_force_error [%]": 100 * self.errors["force"],
            "samples": int(self.time.size),
        }


def _step_parameters(fit):
    p = fit.parameters
    if fit.per_direction:
        return p["mass"], p["F_v_pos"], p["F_c_pos"], p["F_v_neg"], p["F_c_neg"], p["offset"]
    return p["mass"], p["F_v"], p["F_c"], p["F_v"], p["F_c"], p["offset"]


def replay_closed_loop(
    fit: MotionFit,
    time: ArrayLike,
    reference: ArrayLike,
    measured_position: ArrayLike,
    measured_force: ArrayLike,
    *,
    kp: float,
    kv: float,
    force_scale: float,
    saturation: float = math.inf,
    disturbance: ArrayLike | None = None,
    substeps: int = 10,
    border: int = 50,
    cutoff: float | int = 100.0,
    order: int = 4,
) -> ServoReplay:
    """Simulate an identified axis in its recorded servo loop and compare with the record.

    Parameters
    ----------
    fit : MotionFit
        The identified model (:func:`cylfric.identify.motion.fit_motion`).
    time : array_like
        [s], uniformly sampled (the controller period is its median step).
    reference : array_like
        Recorded position reference [m].
    measured_position : array_like
        Recorded position [m] (filtered like the identification for the comparison).
    measured_force : array_like
        Recorded drive force [N].
    kp, kv : float
        Controller gains [1/s] and [controller unit per m/s].
    force_scale : float
        Force per controller unit [N per unit] (EMPS: gtau [N/V]).
    saturation : float
        Controller output limit [controller unit].
    disturbance : array_like, optional
        Added to the controller output after the limit [controller unit].
    substeps : int
        Integration steps per controller period [-].
    border : int
        Samples left out of the error norms at each end [-].
    cutoff, order : float, int
        Zero-phase low-pass of the measured position for the comparison [Hz], [-].

    Returns
    -------
    ServoReplay
    """
    from .motion import motion_signals

    time = np.asarray(time, dtype=float)
    reference = np.asarray(reference, dtype=float)
    n = time.size
    period = float(np.median(np.diff(time)))
    d = np.zeros(n) if disturbance is None else np.asarray(disturbance, dtype=float)
    filtered, velocity, _ = motion_signals(time, measured_position, cutoff=cutoff, order=order)
    mass, fv_pos, fc_pos, fv_neg, fc_neg, offset = _step_parameters(fit)
    h = period / substeps
    x, v = float(filtered[0]), float(velocity[0])
    previous_q, previous_half = x, x
    positions = np.empty(n)
    velocities = np.empty(n)
    forces = np.empty(n)
    limit = float(saturation)
    for k in range(n):
        half = 0.5 * (x + previous_q)
        u = kv * (kp * (reference[k] - x) - (half - previous_half) / period)
        u = min(max(u, -limit), limit) + d[k]
        previous_q, previous_half = x, half
        positions[k] = x
        velocities[k] = v
        force = force_scale * u
        forces[k] = force
        drive = h * (force - offset)
        for _ in range(substeps):
            # backward Euler: mass (v+ - v) = h (force - offset - friction(v+)), set-valued at 0
            impulse = mass * v + drive
            if impulse > h * fc_pos:
                v = (impulse - h * fc_pos) / (mass + h * fv_pos)
            elif impulse < -h * fc_neg:
                v = (impulse + h * fc_neg) / (mass + h * fv_neg)
            else:
                v = 0.0
            x += h * v
    keep = slice(border, n - border if border else n)
    measured_force = np.asarray(measured_force, dtype=float)
    return ServoReplay(
        time=time,
        position=positions,
        velocity=velocities,
        force=forces,
        measured_position=filtered,
        measured_velocity=velocity,
        measured_force=measured_force,
        errors={
            "position": relative_error(filtered[keep], positions[keep]),
            "velocity": relative_error(velocity[keep], velocities[keep]),
            "force": relative_error(measured_force[keep], forces[keep]),
        },
    )


def validate_on_record(fit: MotionFit, path: StrPath, config: MotionConfig) -> ServoReplay:
    """Closed-loop replay of ``fit`` on a second record, as ``config.validation`` describes.

    Parameters
    ----------
    fit : MotionFit
        The identified model.
    path : path-like
        The validation record (same signal names as the identification record).
    config : MotionConfig
        Its ``[validation]`` table names the reference, the gains ``kp`` [1/s] and ``kv``
        [controller unit per m/s] (numbers or scalar variables), ``saturation`` and the
        optional ``disturbance``; ``force_scale`` converts the controller output to [N].

    Returns
    -------
    ServoReplay
    """
    from ..io.motion_config import read_motion_record

    if not config.validation:
        raise config.error(
            None,
            "validation",
            "a closed-loop validation needs a [validation] table (reference, kp, kv)",
        )
    record = read_motion_record(path, config)
    spec = config.validation

    def vector(key):
        name = spec[key]
        if name not in record.variables:
            raise config.error(
                "validation",
                key,
                f"validation.{key} = {name!r} is not a variable of {record.file}; found "
                f"{sorted(record.variables)}",
            )
        return record.variables[name]

    def gain(key):
        value = spec[key]
        if isinstance(value, str):
            if value not in record.scalars:
                raise config.error(
                    "validation",
                    key,
                    f"validation.{key} = {value!r} is not a scalar variable of {record.file}; "
                    f"scalars: {sorted(record.scalars)} (or give a number)",
                )
            value = record.scalars[value]
        return float(value)

    return replay_closed_loop(
        fit,
        record.time,
        vector("reference"),
        record.position,
        record.force,
        kp=gain("kp"),
        kv=gain("kv"),
        force_scale=record.force_scale,
        saturation=spec.get("saturation", math.inf),
        disturbance=vector("disturbance") if "disturbance" in spec else None,
        border=config.border,
        cutoff=config.cutoff,
        order=config.order,
    )
