"""LuGre sigma_0 and sigma_1 identified on the servo axis itself, without a load cell.

A short logged motion of the user's axis (position, chamber pressures, valve command; e.g. a
small sine around a reversal and a slow ramp, at most 10 s) gives the piston force from the
chamber pressures, and the friction from the load's equation of motion (Merritt 1967, eq.
6-21; Jelali & Kroll 2003, eq. 3.8):

    A_A p_A - A_B p_B - m a - F_0 = F_f = sigma_0 z + sigma_1 dz/dt + sigma_2 v    (eq. 2.5)

with ``dz/dt = v - sigma_0 |v| z / g(v)`` the LuGre bristle state (Canudas de Wit et al.
1995). The position is low-pass filtered without phase shift (Butterworth, forward and
backward, as the EMPS identification of :mod:`cylfric.identify.motion`), the same filter
is applied to the pressures so that both sides of the equation see the same frequencies;
velocity and acceleration are central differences of the filtered position. ``z`` follows
from the measured velocity by the exact update of eq. 2.5 at constant velocity
(:func:`cylfric.simulate.kernels.z_step`, the same step as the compensator's observer), so
for each ``sigma_0`` the friction is known up to the linear terms; ``sigma_0``, ``sigma_1``,
the force offset ``F_0`` (a load, the pressure transducers' offsets) and a friction level
``c`` (the datasheet's ``g(v)`` and ``sigma_2`` scaled by ``c``: the axis's seal need not run
at the bench's level) are the least-squares solution of the force equation (equation error:
the noise of the pressure transducers is on the force side). The mass is the axis's unless
``fit_mass``. The datasheet's steady-state law is kept: ``c`` is a check of it, reported,
not written.

Standard errors: ``s^2 (J^T J)^-1`` times the residuals' integrated autocorrelation time
(the filtered residuals are correlated over many samples; without the factor the errors
would be about 5 times too small).

Identifiability: in presliding (force below breakaway) ``z`` follows the displacement
and the force-displacement slope is ``sigma_0``; in gross sliding ``z`` sits at ``g/sigma_0``
and the force says nothing about ``sigma_0``. A log without a presliding regime (a sine too
large to stay below breakaway, a position resolution coarser than the presliding range
``g / sigma_0``) is refused with :class:`AxisIdentificationError` saying what to record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from ..friction.laws import lugre_force, lugre_g
from ..simulate.kernels import g_function, z_step

if TYPE_CHECKING:
    from collections.abc import Mapping

    from ..model import FrictionModel

__all__ = [
    "AxisLog",
    "AxisFit",
    "AxisIdentificationError",
    "axis_log",
    "fit_axis_lugre",
    "bristle_trajectory",
    "LOG_COLUMNS",
    "CUTOFF",
    "MAX_RELATIVE_STDERR",
    "RECORDING_ADVICE",
]

LOG_COLUMNS = ("time [s]", "position [m]", "pressure_a [Pa]", "pressure_b [Pa]")
"""Columns an axis log needs (SI); ``command [-]`` (the valve command) is optional."""

CUTOFF = 15.0
"""Cut-off of the zero-phase low-pass of position and pressures [Hz]: above the presliding
sine (0.5-5 Hz), below the hydraulic and bristle resonances (70-150 Hz on servo axes). A
1 um quantised position differentiated makes velocity noise that biases sigma_1 low (errors
in the regressor): over 8 virtual logs sigma_1 was -5.7 % (scatter 4.9 %) at 15 Hz, -7.8 %
at 20 Hz and -15.7 % at 30 Hz; sigma_0 within 1 % at each."""

FILTER_ORDER = 4
"""Order of the Butterworth low-pass [-] (applied forward and backward)."""

MAX_RELATIVE_STDERR = 0.10
"""Largest relative standard error of sigma_0 accepted [-]; above it the log is refused."""

PRESLIDING_SATURATION = 0.7
"""Bristle deflection, as a fraction of its sliding value g/sigma_0, below which the rod is
in presliding [-] (a reversal beyond it is one step from gross sliding: on the virtual
axis the 1 mm sine's reversals reached 0.9 with a wrong sigma_0, the 8 um sine's 0.45)."""

MIN_PRESLIDING_REVERSALS = 4
"""Fewest presliding reversals (two cycles) a log must hold [-]."""

MIN_REVERSAL_STEPS = 5
"""A presliding reversal sweeps at least this many position steps [-]."""

SLIDING_SPEED = 1e-4
"""Speed above which the rod is taken as sliding, for the friction level [m/s]."""

MIN_SLIDING_TIME = 0.5
"""Sliding time [s] a log needs for the friction level to be fitted (else it is 1)."""

LEVEL_BOUNDS = (0.2, 5.0)
"""Bounds of the friction level [-]."""

SIGMA_1_NOTE = 0.25
"""Relative standard error of sigma_1 above which a note says it is poorly determined [-]."""

MIN_SAMPLES = 500
"""Fewest samples of a log [-]."""

START_SIGMA_0 = 1e6
"""Starting value of sigma_0 [N/m] (the fit is started from the datasheet's value when it
differs)."""

RECORDING_ADVICE = (
    "record, with the position loop closed, a sine of 5-10 um amplitude at 0.5-2 Hz around "
    "one position for at least 3 s (the rod stays in presliding: force below breakaway), "
    "then a slow move of about 1 mm at 0.5 mm/s and back; at least 500 Hz, position "
    "resolution 1 um or finer, both chamber pressures; 10 s in all (docs/dynamic_parameters.md)"
)
"""What to record when a log is refused."""


class AxisIdentificationError(ValueError):
    """An axis log cannot give sigma_0: the message names the log and what to record."""


@dataclass(frozen=True)
class AxisLog:
    """A logged motion of the axis, SI.

    Attributes
    ----------
    time : ndarray
        Sample times [s], uniform.
    position : ndarray
        Piston position [m] (extension > 0).
    pressure_a, pressure_b : ndarray
        Chamber pressures [Pa] (gauge): A the piston side, B the rod side.
    command : ndarray or None
        Valve command [-] (kept for the report; the fit does not need it).
    source : str
        File or description (for messages).
    """

    time: np.ndarray
    position: np.ndarray
    pressure_a: np.ndarray
    pressure_b: np.ndarray
    command: np.ndarray | None = None
    source: str = "axis log"

    @property
    def interval(self) -> float:
        """Sample interval [s]."""
        return float(self.time[1] - self.time[0])

    @property
    def duration(self) -> float:
        """Length of the log [s]."""
        return float(self.time[-1] - self.time[0])

    def to_pandas(self):
        """The log as a DataFrame with units in the column names (SI)."""
        import pandas as pd

        columns = dict(
            zip(
                LOG_COLUMNS,
                (self.time, self.position, self.pressure_a, self.pressure_b),
                strict=True,
            )
        )
        if self.command is not None:
            columns["command [-]"] = self.command
        return pd.DataFrame(columns)


def axis_log(data: Mapping[str, Any], source: str = "axis log") -> AxisLog:
    """An :class:`AxisLog` from SI columns (``cylfric.io.text.read_bench_arrays`` output).

    Parameters
    ----------
    data : mapping
        ``time [s]``, ``position [m]``, ``pressure_a [Pa]``, ``pressure_b [Pa]`` and,
        optionally, ``command [-]``.
    source : str
        The file, named in every message.
    """
    missing = [c for c in LOG_COLUMNS if c not in data]
    if missing:
        raise AxisIdentificationError(
            f"{source}: no {', '.join(missing)} column; an axis log needs time, position and "
            f"both chamber pressures with units in the header (e.g. 'time [s]', 'position "
            f"[mm]', 'pressure_a [bar]', 'pressure_b [bar]', 'command [-]'); found {list(data)}"
        )
    arrays = [np.asarray(data[c], dtype=float) for c in LOG_COLUMNS]
    command = next(
        (np.asarray(data[c], dtype=float) for c in data if c.startswith("command")), None
    )
    if len({a.size for a in arrays}) != 1:
        raise AxisIdentificationError(
            f"{source}: the columns differ in length ({[a.size for a in arrays]} samples)"
        )
    for name, values in zip(LOG_COLUMNS, arrays, strict=True):
        bad = np.nonzero(~np.isfinite(values))[0]
        if bad.size:
            raise AxisIdentificationError(
                f"{source}: {name} is not a finite number at sample {int(bad[0])} (data row "
                f"{int(bad[0]) + 1}); remove or repair that row"
            )
    time = arrays[0]
    if time.size < MIN_SAMPLES:
        raise AxisIdentificationError(
            f"{source}: {time.size} samples; an axis log needs at least {MIN_SAMPLES}: "
            f"{RECORDING_ADVICE}"
        )
    steps = np.diff(time)
    interval = float(np.median(steps))
    if not (interval > 0 and np.all(np.abs(steps - interval) <= 1e-3 * interval + 1e-9)):
        raise AxisIdentificationError(
            f"{source}: the time column is not uniformly sampled (median step {interval:.4g} s); "
            "log at a fixed rate (the controller's sample rate)"
        )
    if 0.5 / interval <= 2 * CUTOFF:
        raise AxisIdentificationError(
            f"{source}: sampled at {1 / interval:.4g} Hz; the fit needs at least "
            f"{4 * CUTOFF:g} Hz (its low-pass cuts at {CUTOFF:g} Hz)"
        )
    pressures = np.concatenate(arrays[2:])
    if np.nanmax(np.abs(pressures)) < 1e4:
        raise AxisIdentificationError(
            f"{source}: chamber pressures below 0.1 bar throughout; expected the working "
            "pressures (is the unit in the header, e.g. 'pressure_a [bar]'?)"
        )
    return AxisLog(time - time[0], arrays[1], arrays[2], arrays[3], command, source)


@njit(cache=True)
def bristle_trajectory(velocity, interval, sigma_0, F_c, F_s, v_r, alpha):
    """Bristle deflection z [m] and its rate dz/dt [m/s] along a velocity record.

    ``velocity`` [m/s] at uniform ``interval`` [s]; the steady-law parameters per sample
    (arrays [N], [N], [m/s], [-]); ``z`` advanced by the exact update of eq. 2.5 at the
    mid-interval velocity (:func:`cylfric.simulate.kernels.z_step`), from z = 0.
    """
    n = velocity.size
    z = np.empty(n)
    rate = np.empty(n)
    zk = 0.0
    for k in range(n):
        z[k] = zk
        g = g_function(abs(velocity[k]), F_c[k], F_s[k], v_r[k], alpha[k])
        rate[k] = velocity[k] - sigma_0 * abs(velocity[k]) * zk / g
        if k < n - 1:
            v_mid = 0.5 * (velocity[k] + velocity[k + 1])
            zk, _ = z_step(zk, v_mid, interval, sigma_0, F_c[k], F_s[k], v_r[k], alpha[k])
    return z, rate


@dataclass
class AxisFit:
    """sigma_0 and sigma_1 identified on the axis (:func:`fit_axis_lugre`).

    Attributes
    ----------
    params : dict
        ``sigma_0`` [N/m], ``sigma_1`` [N*s/m], ``force_offset`` [N], ``friction_level``
        [-] (the axis's sliding friction over the datasheet's), ``mass`` [kg].
    stderr : dict
        Standard errors of ``params`` (0 for the mass when it was given).
    model : FrictionModel
        The datasheet's model with sigma_0 and sigma_1 replaced, status ``identified``.
    residual : ndarray
        Force residual [N] per sample.
    rmse : float
        RMS of the residual [N].
    correlation_time : float
        The residuals' integrated autocorrelation time [samples] (the standard errors'
        factor).
    presliding_time : float
        Time the rod spent moving in presliding (|z| below :data:`PRESLIDING_SATURATION`
        of g/sigma_0) [s].
    presliding_range : float
        Largest bristle deflection range swept in presliding [m] (the peak-to-peak of z
        over the presliding samples).
    signals : dict
        Filtered signals [SI] for plots: time, position, velocity, acceleration, piston
        force, friction (measured: force - m a - F_0) and model friction.
    success, message : bool, str
        Optimiser status.
    notes : list of str
    source : str
    """

    params: dict
    stderr: dict
    model: Any
    residual: np.ndarray = field(repr=False)
    rmse: float
    correlation_time: float
    presliding_time: float
    presliding_range: float
    signals: dict = field(repr=False)
    success: bool = True
    message: str = ""
    notes: list = field(default_factory=list)
    source: str = ""

    @property
    def relative_stderr(self) -> float:
        """Relative standard error of sigma_0 [-]."""
        return self.stderr["sigma_0"] / self.params["sigma_0"]

    def summary(self) -> dict:
        """JSON-ready record (SI) for the datasheet's ``axis_fit`` key."""
        return {
            "method": METHOD,
            "log": self.source,
            "units": {
                "sigma_0": "N/m",
                "sigma_1": "N*s/m",
                "force_offset": "N",
                "friction_level": "-",
                "mass": "kg",
                "rmse": "N",
            },
            "parameters": {k: float(v) for k, v in self.params.items()},
            "stderr": {k: float(v) for k, v in self.stderr.items()},
            "rmse": float(self.rmse),
            "correlation_time_samples": float(self.correlation_time),
            "presliding_time_s": float(self.presliding_time),
            "presliding_range_m": float(self.presliding_range),
            "samples": int(self.residual.size),
            "notes": list(self.notes),
        }

    def report(self) -> str:
        """Plain-text table of the identified parameters."""
        units = self.summary()["units"]
        lines = [f"LuGre parameters identified on the axis from {self.source}"]
        for name, value in self.params.items():
            se = self.stderr[name]
            lines.append(f"  {name:15s} {value:12.5g} +- {se:.2g} {units[name]}")
        lines.append(
            f"  force residual RMS {self.rmse:.3g} N; {self.presliding_time:.3g} s in presliding "
            f"over {self.presliding_range * 1e6:.3g} um of bristle deflection"
        )
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)


METHOD = (
    "LuGre equation error on the axis: piston force from the chamber pressures minus m a, "
    "zero-phase Butterworth on position and pressures, z by the exact update of eq. 2.5 from "
    "the measured velocity; sigma_0, sigma_1, force offset and friction level by least "
    "squares; standard errors s^2 (J^T J)^-1 times the residuals' autocorrelation time"
)


def position_resolution(position: np.ndarray) -> float:
    """The position's resolution [m]: the smallest step between samples that is not zero
    (to 1 % of the largest; a quantised sensor's step, else its noise floor)."""
    steps = np.abs(np.diff(np.asarray(position, dtype=float)))
    steps = steps[steps > 1e-12 + 1e-9 * float(np.max(np.abs(position)))]
    if steps.size == 0:
        return math.inf
    return float(np.quantile(steps, 0.05))


def presliding_reversals(z: np.ndarray, unsaturated: np.ndarray, prominence: float) -> int:
    """Number of reversals of the bristle deflection ``z`` [m] (extrema of at least
    ``prominence`` [m]) at which the bristles are ``unsaturated`` (a presliding reversal:
    z turns back before the rod slides)."""
    from scipy.signal import find_peaks

    count = 0
    for signal in (z, -z):
        peaks, _ = find_peaks(signal, prominence=prominence)
        count += int(np.count_nonzero(unsaturated[peaks]))
    return count


def _lowpass(signal: np.ndarray, interval: float, cutoff: float) -> np.ndarray:
    from scipy.signal import butter, sosfiltfilt

    sos = butter(FILTER_ORDER, cutoff * 2 * interval, output="sos")
    return sosfiltfilt(sos, signal)


def _correlation_time(residual: np.ndarray) -> float:
    """Integrated autocorrelation time [samples] of ``residual`` (sum up to the first lag
    where the autocorrelation falls below 0.05; at least 1)."""
    r = residual - residual.mean()
    n = r.size
    spectrum = np.fft.rfft(r, 2 * n)
    acf = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    if acf[0] <= 0:
        return 1.0
    acf = acf / acf[0]
    below = np.nonzero(acf < 0.05)[0]
    stop = int(below[0]) if below.size else n
    return max(1.0, 1.0 + 2.0 * float(np.sum(acf[1:stop])))


def fit_axis_lugre(
    log: AxisLog,
    model: FrictionModel,
    axis: Any,
    *,
    fit_mass: bool = False,
    cutoff: float = CUTOFF,
    max_relative_stderr: float = MAX_RELATIVE_STDERR,
) -> AxisFit:
    """Identify sigma_0 [N/m] and sigma_1 [N*s/m] from a logged motion of the axis.

    Parameters
    ----------
    log : AxisLog
        Position and chamber pressures (:func:`axis_log`).
    model : FrictionModel
        The datasheet: its steady-state law (g(v), sigma_2, pressure laws and rule) is kept,
        its sigma_0 and sigma_1 replaced.
    axis : Axis-like
        ``area_a`` [m^2] (piston side), ``area_b`` [m^2] (rod side), ``mass`` [kg]
        (:class:`cylfric.control.axis.Axis`).
    fit_mass : bool
        Fit the moving mass too (a small sine and a slow ramp barely accelerate it: expect
        a large standard error).
    cutoff : float
        Low-pass cut-off [Hz] (:data:`CUTOFF`).
    max_relative_stderr : float
        Refuse the log when sigma_0's relative standard error exceeds this [-].

    Returns
    -------
    AxisFit

    Raises
    ------
    AxisIdentificationError
        The log does not determine sigma_0 (no presliding regime); the message says what to
        record instead.
    """
    from scipy.optimize import least_squares

    area_a, area_b, mass = float(axis.area_a), float(axis.area_b), float(axis.mass)
    h = log.interval
    if not 0 < cutoff < 0.25 / h:
        raise AxisIdentificationError(
            f"{log.source}: cut-off {cutoff:g} Hz; expected between 0 and a quarter of the "
            f"sample rate ({0.25 / h:g} Hz)"
        )
    position = _lowpass(log.position, h, cutoff)
    pa = _lowpass(log.pressure_a, h, cutoff)
    pb = _lowpass(log.pressure_b, h, cutoff)
    velocity = np.gradient(position, h)
    acceleration = np.gradient(velocity, h)
    force = area_a * pa - area_b * pb
    p = model.params_at(model.operating_pressure(pa, pb))
    law = {
        k: np.ascontiguousarray(np.broadcast_to(np.asarray(p[k], dtype=float), position.shape))
        for k in ("F_c", "F_s", "sigma_2", "v_r", "alpha")
    }
    sheet_sigma_0 = float(np.median(np.asarray(p["sigma_0"], dtype=float)))

    sliding = float(np.count_nonzero(np.abs(velocity) > SLIDING_SPEED) * h)
    fit_level = sliding >= MIN_SLIDING_TIME
    free = [0, 1, 2] + ([3] if fit_level else []) + ([4] if fit_mass else [])
    full = np.array([0.0, 0.0, 0.0, 1.0, mass])

    def expand(theta):
        values = full.copy()
        values[free] = theta
        return values

    def friction(values):
        s0, s1, level = math.exp(values[0]), math.exp(values[1]), values[3]
        F_c, F_s = level * law["F_c"], level * law["F_s"]
        z, _ = bristle_trajectory(velocity, h, s0, F_c, F_s, law["v_r"], law["alpha"])
        force = lugre_force(  # thesis eq. 2.5, the friction library's
            velocity, z, s0, s1, level * law["sigma_2"], F_c, F_s, law["v_r"], alpha=law["alpha"]
        )
        return np.asarray(force, dtype=float), z

    def residual(theta):
        values = expand(theta)
        return force - values[4] * acceleration - values[2] - friction(values)[0]

    lower = np.array([math.log(1e3), math.log(1e-3), -np.inf, LEVEL_BOUNDS[0], 0.1 * mass])
    upper = np.array([math.log(1e10), math.log(1e9), np.inf, LEVEL_BOUNDS[1], 10 * mass])
    best = None
    for start in sorted({START_SIGMA_0, sheet_sigma_0}):
        full[:2] = math.log(start), math.log(2 * math.sqrt(start * mass))
        solution = least_squares(
            residual, full[free], bounds=(lower[free], upper[free]), method="trf", x_scale="jac"
        )
        if best is None or solution.cost < best.cost:
            best = solution
    assert best is not None
    r = best.fun
    dof = max(r.size - best.x.size, 1)
    s2 = float(r @ r) / dof
    tau = _correlation_time(r)
    se = np.zeros(5)
    try:
        cov = np.linalg.inv(best.jac.T @ best.jac) * s2 * tau
        se[free] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        se[free] = math.inf
    theta = expand(best.x)
    s0, s1 = math.exp(theta[0]), math.exp(theta[1])
    params = {
        "sigma_0": s0,
        "sigma_1": s1,
        "force_offset": float(theta[2]),
        "friction_level": float(theta[3]),
        "mass": float(theta[4]),
    }
    stderr = {
        "sigma_0": s0 * float(se[0]),
        "sigma_1": s1 * float(se[1]),
        "force_offset": float(se[2]),
        "friction_level": float(se[3]),
        "mass": float(se[4]),
    }
    model_friction, z = friction(theta)
    level = theta[3]
    g = level * np.asarray(  # g(v) of eq. 2.5 at the fitted level
        lugre_g(velocity, law["F_c"], law["F_s"], law["v_r"], alpha=law["alpha"]), dtype=float
    )
    moving = np.abs(np.diff(position, prepend=position[0])) > 0.0
    unsaturated = np.abs(z) * s0 < PRESLIDING_SATURATION * g
    presliding = unsaturated & moving & (np.abs(velocity) > 1e-7)
    pre_time = float(np.count_nonzero(presliding) * h)
    pre_range = float(np.ptp(z[presliding])) if presliding.any() else 0.0
    resolution = position_resolution(log.position)
    reversals = presliding_reversals(z, unsaturated, MIN_REVERSAL_STEPS * resolution)
    breakaway = float(np.median(level * law["F_s"]))
    relative = stderr["sigma_0"] / s0
    advice = (
        f"Presliding needs reversals with the force below breakaway (F_s about "
        f"{breakaway:.0f} N at the log's pressures): a displacement amplitude of about "
        f"F_s/(2 sigma_0), {0.5 * breakaway / 1e8 * 1e6:.2g}-{0.5 * breakaway / 1e6 * 1e6:.3g} "
        f"um for sigma_0 between 1e8 and 1e6 N/m. To fix: {RECORDING_ADVICE}"
    )
    if reversals < MIN_PRESLIDING_REVERSALS:
        raise AxisIdentificationError(
            f"{log.source}: no presliding regime: the rod reversed {reversals} time(s) with "
            f"the bristles below {PRESLIDING_SATURATION:.0%} of their sliding deflection "
            f"(by at least {MIN_REVERSAL_STEPS} position steps of {resolution * 1e6:.2g} um), "
            f"{MIN_PRESLIDING_REVERSALS} needed; every reversal in this log passes into gross "
            f"sliding, so sigma_0 (fit {s0:.3g} N/m) rests on the transitions alone and on the "
            f"filter. {advice}"
        )
    if not (math.isfinite(relative) and relative <= max_relative_stderr):
        raise AxisIdentificationError(
            f"{log.source}: sigma_0 is not determined by this motion (fit {s0:.3g} N/m with a "
            f"relative standard error of {relative:.0%}, limit {max_relative_stderr:.0%}): the "
            f"rod moved {pre_time:.2g} s in presliding over {pre_range * 1e6:.3g} um. {advice}"
        )
    notes = []
    if not fit_level:
        notes.append(
            f"no gross sliding in the log ({sliding:.2g} s above {SLIDING_SPEED * 1e3:g} mm/s): "
            "the friction level is the datasheet's (add a slow move to check it)"
        )
    if not best.success:
        notes.append(f"the optimiser stopped: {best.message}")
    if abs(level - 1) > 3 * stderr["friction_level"] and abs(level - 1) > 0.1:
        notes.append(
            f"the axis's sliding friction is {level:.2f} x the datasheet's (+- "
            f"{stderr['friction_level']:.2g}); the datasheet's steady-state law is kept"
        )
    if stderr["sigma_1"] > SIGMA_1_NOTE * s1:
        notes.append(
            f"sigma_1 is poorly determined by this motion ({s1:.3g} +- {stderr['sigma_1']:.2g} "
            "N*s/m): the presliding velocity is small against the position's resolution; a "
            "faster presliding sine (2-5 Hz) or a finer position sensor determines it better"
        )
    if fit_mass and stderr["mass"] > 0.2 * abs(params["mass"]):
        notes.append(
            f"the mass is poorly determined by this motion ({params['mass']:.3g} +- "
            f"{stderr['mass']:.2g} kg); give it (axis.toml) rather than fit it"
        )
    reason = (
        f"identified on the axis from {log.source} ({log.duration:.3g} s, LuGre equation "
        f"error from the chamber pressures); standard error {stderr['sigma_0']:.3g} N/m"
    )
    reason_1 = reason.replace(f"{stderr['sigma_0']:.3g} N/m", f"{stderr['sigma_1']:.3g} N*s/m")
    identified = model.replace(
        sigma_0=s0,
        sigma_1=s1,
        dynamic_status={
            **dict(model.dynamic_status),
            "sigma_0": ("identified", reason),
            "sigma_1": ("identified", reason_1),
        },
    )
    m = params["mass"]
    signals = {
        "time [s]": log.time,
        "position [m]": position,
        "velocity [m/s]": velocity,
        "acceleration [m/s^2]": acceleration,
        "piston force [N]": force,
        "friction [N]": force - m * acceleration - params["force_offset"],
        "model friction [N]": model_friction,
        "z [m]": z,
    }
    return AxisFit(
        params=params,
        stderr=stderr,
        model=identified,
        residual=r,
        rmse=float(math.sqrt(np.mean(r**2))),
        correlation_time=tau,
        presliding_time=pre_time,
        presliding_range=pre_range,
        signals=signals,
        success=bool(best.success),
        message=str(best.message),
        notes=notes,
        source=log.source,
    )
