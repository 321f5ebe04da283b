"""Friction identification from any logged motion: the inverse dynamic model by least squares.

The inverse dynamic identification model (IDIM) of a single axis,

    force = mass * acceleration + F_v * velocity + F_c * sign(velocity) + offset,

is linear in its parameters. :func:`fit_motion` follows the identification procedure of the
EMPS benchmark (Janot, Gautier and Brunot 2019): the measured position is low-pass filtered
without phase shift (Butterworth, applied forward and backward), velocity and acceleration
are central differences of the filtered position, every column of the regression and the
force are decimated (``scipy.signal.decimate``: its anti-alias filter, then every r-th
sample), and the decimated system is solved by ordinary least squares (IDIM-LS) with the
usual standard errors ``sigma^2 (W^T W)^-1``. ``per_direction=True`` splits ``F_v`` and
``F_c`` by the sign of the velocity.

When the record has chamber pressures, :func:`fit_motion` then refines the friction part to
the pressure-dependent steady-state model of :class:`cylfric.model.FrictionModel` (thesis
eq. 2.7 with linear pressure laws, or Coulomb + viscous) by nonlinear least squares on the
same decimated samples: ``force = mass * acceleration + offset + model.friction(v, p)``.

References
----------
A. Janot, M. Gautier, M. Brunot, "Data set and reference models of EMPS", Workshop on
Nonlinear System Identification Benchmarks, Eindhoven, 2019.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..model import PARAMETER_BOUNDS, FrictionModel
from .motion_plausibility import check_plausibility

if TYPE_CHECKING:
    from collections.abc import Mapping

    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath
    from cylfric.io.motion_config import MotionRecord

    from ..io.motion_config import MotionConfig

__all__ = [
    "MotionFit",
    "PressureRefinement",
    "fit_motion",
    "motion_signals",
    "central_difference",
    "PARAMETER_UNITS",
]

PARAMETER_UNITS = {
    "mass": "kg",
    "F_v": "N*s/m",
    "F_c": "N",
    "F_v_pos": "N*s/m",
    "F_c_pos": "N",
    "F_v_neg": "N*s/m",
    "F_c_neg": "N",
    "offset": "N",
}
"""SI unit of each IDIM parameter."""

MIN_PRESSURE_SPREAD = 1e5
"""Pressure spread [Pa] below which the refinement fits constants (no pressure slope)."""


def central_difference(values: ArrayLike, step: float) -> np.ndarray:
    """Derivative by central differences (one-sided at the two ends).

    Parameters
    ----------
    values : array_like
        Uniformly sampled signal [unit].
    step : float
        Sample interval [s].

    Returns
    -------
    ndarray
        The derivative [unit/s].

    Examples
    --------
    >>> central_difference([0.0, 1.0, 4.0, 9.0], 1.0).tolist()
    [1.0, 2.0, 4.0, 5.0]
    """
    x = np.asarray(values, dtype=float)
    out = np.empty_like(x)
    out[1:-1] = (x[2:] - x[:-2]) / (2 * step)
    out[0] = (x[1] - x[0]) / step
    out[-1] = (x[-1] - x[-2]) / step
    return out


def motion_signals(
    time: ArrayLike, position: ArrayLike, *, cutoff: float = 100.0, order: int = 4
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Filtered position, velocity and acceleration of a uniformly sampled record.

    Parameters
    ----------
    time : array_like
        [s], uniformly sampled.
    position : array_like
        Measured position [m].
    cutoff : float
        Cut-off of the Butterworth low-pass [Hz], below the Nyquist frequency.
    order : int
        Filter order [-]; ``scipy.signal.filtfilt`` applies it forward and backward (no phase
        shift).

    Returns
    -------
    position, velocity, acceleration : ndarray
        [m], [m/s], [m/s^2]; velocity and acceleration are central differences.
    """
    from scipy import signal

    time = np.asarray(time, dtype=float)
    step = float(np.median(np.diff(time)))
    nyquist = 0.5 / step
    if not 0 < cutoff < nyquist:
        raise ValueError(
            f"filter cutoff = {cutoff:g} Hz; expected 0 < cutoff < the Nyquist frequency "
            f"{nyquist:g} Hz of the record"
        )
    b, a = signal.butter(order, cutoff / nyquist)
    filtered = signal.filtfilt(b, a, np.asarray(position, dtype=float))
    velocity = central_difference(filtered, step)
    return filtered, velocity, central_difference(velocity, step)


@dataclass(frozen=True)
class PressureRefinement:
    """The pressure-dependent friction model refined from a motion record.

    Attributes
    ----------
    model : FrictionModel or None
        The refined model (None when refused).
    mass, mass_stderr : float
        Moving mass refitted with it [kg].
    offset, offset_stderr : float
        Force offset refitted with it [N].
    relative_error : float
        ||force - prediction|| / ||force|| on the regression samples [-].
    rmse : float
        [N].
    notes : tuple of str
        What was simplified or why the model was refused.
    """

    model: FrictionModel | None
    mass: float
    mass_stderr: float
    offset: float
    offset_stderr: float
    relative_error: float
    rmse: float
    notes: tuple = ()


@dataclass(frozen=True)
class MotionFit:
    """Result of :func:`fit_motion`.

    Attributes
    ----------
    parameters : dict
        Name -> value (SI: ``mass`` [kg], ``F_v`` [N*s/m], ``F_c`` [N], ``offset`` [N], or
        ``F_v_pos``, ``F_c_pos``, ``F_v_neg``, ``F_c_neg`` per direction). ``F_c_neg`` and
        ``F_v_neg`` are magnitudes: the friction force for v < 0 is
        ``-(F_c_neg + F_v_neg * |v|)``.
    stderr : dict
        Standard errors of ``parameters`` (same units).
    covariance : ndarray
        Covariance of the parameters in the order of ``parameters``.
    relative_error : float
        ||F - W theta|| / ||F|| on the decimated regression [-] (the benchmark's relative
        error norm of the force).
    rmse : float
        Root mean square force residual [N].
    per_direction : bool
        Whether F_v and F_c were split by direction.
    signals : dict
        The decimated regression signals: ``"time [s]"``, ``"position [m]"``,
        ``"velocity [m/s]"``, ``"acceleration [m/s^2]"``, ``"force [N]"``,
        ``"predicted force [N]"`` and the pressures (``"pressure_a [Pa]"``) when recorded.
    settings : dict
        ``cutoff`` [Hz], ``order``, ``decimation``, ``border``, ``sample_time`` [s],
        ``samples`` (record) and ``regression_samples``.
    refinement : PressureRefinement or None
        The pressure-dependent refinement (None without pressures).
    notes : tuple of str
        Conventions and simplifications worth knowing.
    joint : dict or None
        Per direction: the joint fit's ``{name: (value, stderr)}`` (``mass``, ``F_v``,
        ``F_c``, ``offset``).
    flags : tuple of PlausibilityFlag
        Implausible magnitudes (:mod:`cylfric.identify.motion_plausibility`): a unit off by
        1000, a negative or unsupported mass, friction above the forces recorded. Empty for
        a plausible fit; ``cylfric fit-motion`` refuses a flagged fit unless told
        ``--accept-implausible``.
    """

    parameters: dict
    stderr: dict
    covariance: np.ndarray
    relative_error: float
    rmse: float
    per_direction: bool
    signals: dict
    settings: dict
    refinement: PressureRefinement | None = None
    notes: tuple = field(default=())
    joint: dict | None = None
    flags: tuple = field(default=())

    def predict(self, velocity: ArrayLike, acceleration: ArrayLike) -> np.ndarray:
        """Force [N] of the identified IDIM at velocity [m/s] and acceleration [m/s^2]."""
        v = np.asarray(velocity, dtype=float)
        W = _regressors(v, np.asarray(acceleration, dtype=float), self.per_direction)
        names = _names(self.per_direction)
        theta = np.array([self.parameters[n] for n in names])
        return W @ theta + (self.parameters["offset"] if self.per_direction else 0.0)

    def to_dict(self) -> dict:
        """The JSON form (``motion_fit.json``): values, standard errors and units, SI."""
        params = {
            name: {
                "value": value,
                "stderr": self.stderr[name],
                "relative_stderr [%]": (
                    100 * self.stderr[name] / abs(value) if value != 0 else None
                ),
                "unit": PARAMETER_UNITS[name],
            }
            for name, value in self.parameters.items()
        }
        names = list(self.parameters)
        out = {
            "model": _EQUATION[self.per_direction],
            "method": (
                "IDIM-LS: zero-phase Butterworth low-pass of the position (filtfilt), central "
                "differences, regression and force decimated (scipy.signal.decimate), ordinary "
                "least squares"
            ),
            "parameters": params,
            "covariance": {"names": names, "matrix": self.covariance.tolist()},
            "relative_force_error": self.relative_error,
            "relative_force_error [%]": 100 * self.relative_error,
            "rmse [N]": self.rmse,
            "settings": dict(self.settings),
            "notes": list(self.notes),
            "plausibility": [flag.to_dict() for flag in self.flags],
            "refinement": None,
        }
        if self.joint is not None:
            out["joint_fit"] = {
                n: {"value": v, "stderr": e, "unit": PARAMETER_UNITS[n]}
                for n, (v, e) in self.joint.items()
            }
        ref = self.refinement
        if ref is not None:
            out["refinement"] = {
                "status": "identified" if ref.model is not None else "refused",
                "mass": {"value": ref.mass, "stderr": ref.mass_stderr, "unit": "kg"},
                "offset": {"value": ref.offset, "stderr": ref.offset_stderr, "unit": "N"},
                "relative_force_error": ref.relative_error,
                "rmse [N]": ref.rmse,
                "notes": list(ref.notes),
                "model_lines": ref.model.law_lines() if ref.model is not None else None,
            }
        return out


_EQUATION = {
    False: "force = mass * acceleration + F_v * velocity + F_c * sign(velocity) + offset",
    True: (
        "force = mass * acceleration + offset + (F_v_pos * velocity + F_c_pos) for velocity > 0,"
        " + (F_v_neg * velocity - F_c_neg) for velocity < 0"
    ),
}


def _regressors(velocity, acceleration, per_direction):
    """Columns of the observation matrix W (parameters in the order of :func:`_names`).

    Per direction there is no constant column: with the axis never at rest, a constant and
    the two direction indicators are collinear, so the offset is held at the joint fit's.
    """
    sign = np.sign(velocity)
    if not per_direction:
        return np.column_stack([acceleration, velocity, sign, np.ones_like(velocity)])
    pos, neg = velocity > 0, velocity < 0
    return np.column_stack([acceleration, velocity * pos, 1.0 * pos, velocity * neg, -1.0 * neg])


def _names(per_direction):
    if per_direction:
        return ("mass", "F_v_pos", "F_c_pos", "F_v_neg", "F_c_neg")
    return ("mass", "F_v", "F_c", "offset")


def fit_motion(
    record: MotionRecord | StrPath,
    config: MotionConfig | None = None,
    *,
    per_direction: bool = False,
    plausibility: Mapping[str, Any] | None = None,
) -> MotionFit:
    """Identify mass, viscous and Coulomb friction and offset from a logged motion (IDIM-LS).

    Parameters
    ----------
    record : MotionRecord or path-like
        The record (:func:`cylfric.io.motion_config.read_motion_record`); a path needs
        ``config``.
    config : MotionConfig, optional
        Filter and refinement settings (default: the EMPS benchmark's, 100 Hz 4th-order
        Butterworth, decimation 10, 50 border samples).
    per_direction : bool
        Split F_v and F_c by the sign of the velocity.
    plausibility : dict, optional
        Overrides of the limits of the plausibility gates
        (:data:`cylfric.identify.motion_plausibility.LIMITS`, e.g. ``{"max_stroke": 50.0}``
        [m]).

    Returns
    -------
    MotionFit
        Parameters with standard errors, relative force error, regression signals, the
        plausibility ``flags`` and, when the record has pressures, the refined
        pressure-dependent model.

    Raises
    ------
    ValueError
        A signal holding NaN or inf (naming it and the first sample index), too short a
        record for the decimation, a cut-off above the Nyquist frequency, no motion (or none
        in one direction with ``per_direction``), a singular regression, an unknown
        plausibility limit.
    """
    from scipy import signal

    from ..io.motion_config import MotionConfig, read_motion_record

    if not hasattr(record, "time"):
        if config is None:
            raise ValueError(
                f"{record}: a record given as a path needs its config (motion.toml) to name "
                "the signals"
            )
        record = read_motion_record(record, config)
    record = cast("MotionRecord", record)  # a record (or an object with its signals)
    if config is None:
        config = MotionConfig(signals={})
    _check_finite(record)
    time, force = record.time, record.force
    step = float(np.median(np.diff(time)))
    r, border = config.decimation, config.border
    if time.size < 30 * r + 2 * border + 10:
        raise ValueError(
            f"{record.file}: {time.size} samples are too few for decimation {r} and "
            f"{border} border samples; expected at least {30 * r + 2 * border + 10}"
        )
    position, velocity, acceleration = motion_signals(
        time, record.position, cutoff=config.cutoff, order=config.order
    )
    names = _names(per_direction)
    W = _regressors(velocity, acceleration, per_direction)
    if per_direction:  # the joint regression too (its offset is held in the per-direction one)
        W = np.column_stack([W, _regressors(velocity, acceleration, False)])
    columns = {
        "time [s]": time,
        "position [m]": position,
        "velocity [m/s]": velocity,
        "acceleration [m/s^2]": acceleration,
        "force [N]": force,
    }
    for name, values in (("pressure_a", record.pressure_a), ("pressure_b", record.pressure_b)):
        if values is not None:
            columns[f"{name} [Pa]"] = values
    if r > 1:
        W = signal.decimate(W, r, axis=0)
        decimated = {k: signal.decimate(v, r) for k, v in columns.items() if k != "time [s]"}
        decimated["time [s]"] = time[::r][: W.shape[0]]
        columns = {k: decimated[k] for k in columns}
    trim = math.ceil(border / r)
    keep = slice(trim, W.shape[0] - trim)
    W = W[keep]
    columns = {k: v[keep] for k, v in columns.items()}
    F = columns["force [N]"]
    if not np.ptp(record.position) > 0:
        raise ValueError(f"{record.file}: the position does not change; no motion to identify")
    if per_direction:
        v = columns["velocity [m/s]"]
        for side, count in (("positive", np.sum(v > 0)), ("negative", np.sum(v < 0))):
            if count < 10:
                raise ValueError(
                    f"{record.file}: only {count} regression samples move in the {side} "
                    "direction; fit both directions together (no --per-direction)"
                )
    joint = None
    notes = []
    if per_direction:
        W, W_joint = W[:, : len(names)], W[:, len(names) :]
        joint = _least_squares(W_joint, F, record.file, _names(False))
        offset, offset_variance = joint[0][3], joint[1][3, 3]
        theta, covariance, residual = _least_squares(W, F - offset, record.file, names)
        names = (*names, "offset")
        theta = np.append(theta, offset)
        covariance = np.pad(covariance, ((0, 1), (0, 1)))
        covariance[-1, -1] = offset_variance
        notes.append(
            "per direction, the offset is held at the joint fit's: a constant and the two "
            "direction indicators are collinear when the axis is never at rest"
        )
    else:
        theta, covariance, residual = _least_squares(W, F, record.file, names)
    stderr = np.sqrt(np.diag(covariance))
    columns["predicted force [N]"] = F - residual
    fit = MotionFit(
        parameters={n: float(v) for n, v in zip(names, theta, strict=True)},
        stderr={n: float(s) for n, s in zip(names, stderr, strict=True)},
        covariance=covariance,
        notes=tuple(notes),
        joint=None
        if joint is None
        else {
            n: (float(v), float(e))
            for n, v, e in zip(_names(False), joint[0], np.sqrt(np.diag(joint[1])), strict=True)
        },
        relative_error=float(np.linalg.norm(residual) / np.linalg.norm(F)),
        rmse=float(np.sqrt(np.mean(residual**2))),
        per_direction=per_direction,
        signals=columns,
        settings={
            "cutoff [Hz]": config.cutoff,
            "order": config.order,
            "decimation": r,
            "border": border,
            "sample_time [s]": step,
            "samples": int(time.size),
            "regression_samples": int(F.size),
            "force_scale": record.force_scale,
        },
    )
    fit = replace(fit, flags=check_plausibility(fit, record.position, **(plausibility or {})))
    if record.pressure_a is None and record.pressure_b is None:
        return fit
    refinement = refine_pressure_model(
        fit,
        config,
        velocity=velocity,
        pressure_a=record.pressure_a,
        pressure_b=record.pressure_b,
    )
    return replace(fit, refinement=refinement)


def _check_finite(record) -> None:
    """Refuse a record (also one built in Python) holding NaN or inf in a signal it uses."""
    for name in ("time", "position", "force", "pressure_a", "pressure_b"):
        values = getattr(record, name)
        if values is None:
            continue
        bad = np.flatnonzero(~np.isfinite(np.asarray(values, dtype=float)))
        if bad.size:
            raise ValueError(
                f"{record.file}: the {name} signal holds {values[bad[0]]} at sample "
                f"{int(bad[0])} ({bad.size} non-finite samples); expected finite numbers: "
                "remove or interpolate the gap (or cut the record) before the identification"
            )


def _least_squares(W, F, file, names):
    """Ordinary least squares with covariance sigma^2 (W^T W)^-1 (sigma^2 = RSS / (n - p))."""
    try:
        theta, _, rank, _ = np.linalg.lstsq(W, F, rcond=None)
        inverse = np.linalg.inv(W.T @ W) if rank == W.shape[1] else None
    except np.linalg.LinAlgError as exc:
        raise ValueError(
            f"{file}: the least-squares fit of {list(names)} failed ({exc}); check the "
            "record's signals for spikes or a wrong unit"
        ) from None
    if rank < W.shape[1]:
        raise ValueError(
            f"{file}: the regression is singular (rank {rank} of {W.shape[1]}): the motion "
            f"does not excite every parameter of {list(names)}"
        )
    residual = F - W @ theta
    dof = max(F.size - W.shape[1], 1)
    variance = float(residual @ residual) / dof
    covariance = variance * inverse
    return theta, covariance, residual


def refine_pressure_model(
    fit: MotionFit,
    config: MotionConfig,
    *,
    velocity: np.ndarray | None = None,
    pressure_a: np.ndarray | None = None,
    pressure_b: np.ndarray | None = None,
) -> PressureRefinement:
    """Refine the friction of an IDIM fit to a pressure-dependent steady-state model.

    Nonlinear least squares (``scipy.optimize.least_squares``) of ``force = mass *
    acceleration + offset + model.friction(velocity, p)`` on the decimated regression
    samples of ``fit``, with ``p`` the operating pressure of the chamber pressures
    (``config.reference``). ``F_c``, ``F_s - F_c`` and ``sigma_2`` follow linear pressure laws
    fitted through their values at the lowest and highest recorded pressure, each bounded at
    zero, so the model is physical over the recorded range (as :mod:`.linear_fit` does);
    constants when the pressures spread less than 1 bar. ``v_r`` is fitted, ``alpha`` held
    at ``config.alpha``.

    Parameters
    ----------
    fit : MotionFit
        An IDIM fit of a record with pressures (its ``signals`` hold them).
    config : MotionConfig
        ``friction_law`` (``"stribeck"`` or ``"coulomb_viscous"``), ``reference``,
        ``alpha`` [-], ``v_r`` (starting value) [m/s], ``min_speed`` [m/s] (slower samples
        are left out).
    velocity, pressure_a, pressure_b : ndarray, optional
        The record's full-rate velocity [m/s] and chamber pressures [Pa]. With them the
        friction is evaluated at full rate and decimated like the regression columns (the
        published IDIM procedure decimates every column; decimating after the nonlinear law
        keeps the reversals consistent); without them it is evaluated on the decimated
        samples.

    Returns
    -------
    PressureRefinement
        The model carries its covariance, statistics and validity range.
    """
    from scipy import signal
    from scipy.optimize import least_squares

    from ..friction import operating_pressure

    sig = fit.signals
    full = velocity is not None
    if full:
        pa, pb = pressure_a, pressure_b
        r, border = fit.settings["decimation"], fit.settings["border"]
        trim = math.ceil(border / r)

        def reduce(values):  # as the regression columns: decimate, drop the border
            values = signal.decimate(values, r) if r > 1 else values
            return values[trim : values.size - trim]
    else:
        pa, pb = sig.get("pressure_a [Pa]"), sig.get("pressure_b [Pa]")

        def reduce(values):
            return values

    if pa is None:
        pa, pb = pb, None
    assert pa is not None  # a record with pressures: fit_motion calls only with one or two
    reference = config.reference if pb is not None else "a"
    pressure = np.asarray(operating_pressure(pa, pb, reference=reference), dtype=float)
    v_eval = velocity if full else sig["velocity [m/s]"]
    assert v_eval is not None  # full: the velocity was given
    v, acc, F = sig["velocity [m/s]"], sig["acceleration [m/s^2]"], sig["force [N]"]
    ones = reduce(np.ones_like(v_eval))
    notes = []
    # the steady-state law does not hold while the axis sticks (presliding): leave out the
    # samples slower than min_speed
    moving = np.abs(v) >= config.min_speed
    if moving.sum() < 20:
        raise ValueError(
            f"only {int(moving.sum())} regression samples move faster than refinement.min_speed"
            f" = {config.min_speed * 1e3:g} mm/s; too few for the pressure refinement"
        )
    if not moving.all():
        notes.append(
            f"{int((~moving).sum())} of {moving.size} samples slower than "
            f"{config.min_speed * 1e3:g} mm/s left out (the steady-state law does not hold "
            "while the axis sticks)"
        )
    acc, F, ones = acc[moving], F[moving], ones[moving]
    v_sel = v[moving]
    p_sel = reduce(pressure)[moving]
    p_lo, p_hi = float(p_sel.min()), float(p_sel.max())
    if reference != config.reference:
        notes.append(
            f"only one chamber pressure recorded: the laws see it (not {config.reference})"
        )
    sloped = p_hi - p_lo >= MIN_PRESSURE_SPREAD
    if not sloped:
        notes.append(
            f"pressures spread {(p_hi - p_lo) / 1e5:.3g} bar (< 1 bar): constant friction "
            "parameters, no pressure law"
        )
    stribeck = config.friction_law == "stribeck"
    keys = ("F_c", "dF_s", "sigma_2") if stribeck else ("F_c", "sigma_2")
    ends = ("lo", "hi") if sloped else ("lo",)
    labels = ["mass", "offset"] + [f"{k}@{e}" for k in keys for e in ends]
    labels += ["v_r"] if stribeck else []
    # starting values: the IDIM with pressure-proportional Coulomb and viscous terms, a
    # linear least-squares problem (columns a, 1, sign(v), p sign(v), v, p v)
    sign = np.sign(v_eval)
    if sloped:
        columns = [sign, pressure * sign, v_eval, pressure * v_eval]
    else:
        columns = [sign, v_eval]
    W = np.column_stack([acc, ones] + [reduce(c)[moving] for c in columns])
    theta0 = np.linalg.lstsq(W, F, rcond=None)[0]
    if sloped:
        level = {e: theta0[2] + theta0[3] * p for e, p in (("lo", p_lo), ("hi", p_hi))}
        viscous = {e: theta0[4] + theta0[5] * p for e, p in (("lo", p_lo), ("hi", p_hi))}
    else:
        level, viscous = {"lo": theta0[2]}, {"lo": theta0[3]}
    start = {"mass": theta0[0], "offset": theta0[1], "v_r": config.v_r}
    for end in ends:
        # a Stribeck hump starts at 20 % of the level: the level seen by the IDIM is the
        # Coulomb level plus part of the hump
        start[f"F_c@{end}"] = level[end] / (1.1 if stribeck else 1.0)
        start[f"dF_s@{end}"] = 0.2 * level[end] / 1.1
        start[f"sigma_2@{end}"] = viscous[end]
    x0 = np.array([start[lab] for lab in labels])
    lower = np.array(
        [
            1e-9 if lab == "mass" else -np.inf if lab == "offset" else 0.0
            for lab in labels[:-1] + ([] if stribeck else labels[-1:])
        ]
        + ([PARAMETER_BOUNDS["v_r"][0]] if stribeck else [])
    )
    upper = np.array([PARAMETER_BOUNDS["v_r"][1] if lab == "v_r" else np.inf for lab in labels])
    x0 = np.clip(x0, lower, upper)
    # fit vector -> model coefficients: a linear map (F_s = F_c + dF_s; the two end values
    # -> intercept and slope), used for the coefficients and for the covariance
    names, T = _model_transform(labels, p_lo, p_hi, stribeck, sloped)

    def build(x, **extra):
        theta = T @ x
        coeffs: dict[str, Any] = {}
        for key in ("F_c", "F_s", "sigma_2"):
            if sloped and f"{key}.intercept" in names:
                coeffs[key] = {
                    "intercept": theta[names.index(f"{key}.intercept")],
                    "slope": theta[names.index(f"{key}.slope")],
                }
            elif key in names:
                coeffs[key] = theta[names.index(key)]
        if stribeck:
            coeffs.update(v_r=theta[names.index("v_r")], alpha=config.alpha)
        else:
            coeffs.update(F_s=None, v_r=None, alpha=None)
        return FrictionModel(
            coeffs,
            pressure_law="linear" if sloped else "constant",
            friction_law=config.friction_law,
            reference=config.reference,
            **extra,
        )

    def residual(x):
        friction = reduce(build(x).friction(v_eval, pressure))[moving]
        return x[0] * acc + x[1] * ones + friction - F

    result = least_squares(residual, x0, bounds=(lower, upper), x_scale="jac", method="trf")
    res = result.fun
    dof = max(res.size - len(labels), 1)
    try:
        cov_x = float(res @ res) / dof * np.linalg.inv(result.jac.T @ result.jac)
    except np.linalg.LinAlgError:
        cov_x = np.full((len(labels), len(labels)), np.nan)
    cov_model = T @ cov_x @ T.T
    err = dict(zip(names, np.sqrt(np.clip(np.diag(cov_model), 0, None)), strict=True))
    stderr: dict[str, Any] = {}
    for key in ("F_c", "F_s", "sigma_2"):
        if sloped and f"{key}.intercept" in names:
            stderr[key] = {c: float(err[f"{key}.{c}"]) for c in ("intercept", "slope")}
        elif key in names:
            stderr[key] = float(err[key])
    if stribeck:
        stderr["v_r"] = float(err["v_r"])
    for label, value, low in zip(labels, result.x, lower, strict=True):
        if label not in ("mass", "offset") and value <= low + 1e-9 * max(1.0, abs(low)):
            key, _, end = label.partition("@")
            at = {"lo": p_lo, "hi": p_hi}.get(end, p_lo)
            notes.append(
                f"{'F_s - F_c' if key == 'dF_s' else key} is at its bound "
                f"({low:g}) at {at / 1e5:.4g} bar: the record does not resolve it"
            )
    rmse = float(np.sqrt(np.mean(res**2)))
    speed = np.abs(v_sel)
    covariance = (tuple(names), cov_model) if np.all(np.isfinite(cov_model)) else None
    model = build(
        result.x,
        stderr=stderr,
        fixed=("alpha",) if stribeck else (),
        covariance=covariance,
        statistics={
            "n_points": int(res.size),
            "n_variables": len(labels),
            "rmse": rmse,
            "residual_std": float(np.sqrt(res @ res / dof)),
            "dof": int(dof),
        },
        validity={
            "pressure_min": p_lo,
            "pressure_max": p_hi,
            "velocity_min": float(speed.min()),
            "velocity_max": float(speed.max()),
        },
        provenance={
            "method": "motion record: IDIM-LS, then nonlinear least squares of the steady-state "
            "law with mass and offset (cylfric fit-motion)",
        },
    )
    return PressureRefinement(
        model=model,
        mass=float(result.x[0]),
        mass_stderr=float(math.sqrt(max(cov_x[0, 0], 0.0))),
        offset=float(result.x[1]),
        offset_stderr=float(math.sqrt(max(cov_x[1, 1], 0.0))),
        relative_error=float(np.linalg.norm(res) / np.linalg.norm(F)),
        rmse=rmse,
        notes=tuple(notes),
    )


def _mean_of(fit, name):
    """F_c or F_v of an IDIM fit (the mean of both directions for a per-direction fit)."""
    if name in fit.parameters:
        return fit.parameters[name]
    return 0.5 * (fit.parameters[f"{name}_pos"] + fit.parameters[f"{name}_neg"])


def _model_transform(labels, p_lo, p_hi, stribeck, sloped):
    """Names of the model coefficients and the linear map T from the fit vector to them."""
    keys = ("F_c", "F_s", "sigma_2") if stribeck else ("F_c", "sigma_2")
    coefficients = ("intercept", "slope") if sloped else ("",)
    names = [f"{k}.{c}" if c else k for k in keys for c in coefficients]
    names += ["v_r"] if stribeck else []
    index = {label: i for i, label in enumerate(labels)}
    T = np.zeros((len(names), len(labels)))
    span = p_hi - p_lo
    # value(p) = lo + (hi - lo) (p - p_lo) / span: intercept and slope of the two end values
    weights = {
        "intercept": {"lo": 1 + p_lo / span, "hi": -p_lo / span} if sloped else {},
        "slope": {"lo": -1 / span, "hi": 1 / span} if sloped else {},
        "": {"lo": 1.0},
    }
    for row, name in enumerate(names):
        if name == "v_r":
            T[row, index["v_r"]] = 1.0
            continue
        key, _, c = name.partition(".")
        parts = ("F_c", "dF_s") if key == "F_s" else (key,)
        for part in parts:
            for end, w in weights[c].items():
                T[row, index[f"{part}@{end}"]] += w
    return names, T
