"""Identification of the LuGre bristle parameters sigma_0 and sigma_1 (eq. 2.5) from
force-controlled tests: presliding records (force below breakaway) and breakaway ramps.

Method
------
A presliding record holds the rod at rest, then applies a net force ``F(t)`` below the
breakaway force (sinusoids, force reversals) and logs the rod displacement ``x(t)``. With the
moving mass ``m`` and the steady-state law of the model (``g(v)`` and ``sigma_2``, from the
constant-velocity fit), the plant ``m x'' = F - F_f(v, z)`` with the LuGre force (eq. 2.5)
is simulated from the measured force (:func:`cylfric.simulate.simulate`, AppliedForce drive)
and ``sigma_0`` [N/m], ``sigma_1`` [N*s/m] are the values whose simulated displacement
matches the measured one in the least-squares sense (output error: the noise is on the
displacement). Standard errors come from the Jacobian of that fit (``s^2 (J^T J)^-1``).

* ``sigma_0`` sets the slope of force against displacement at zero bristle deflection: the
  initial slope of the virgin curve and of the hysteresis (quasi-static, the LuGre
  presliding curve is ``dx/dF = 1 / (sigma_0 (1 - sign(v) F / g))``).
* ``sigma_1`` (with ``sigma_2`` and ``m``) sets the phase and the energy lost per cycle of
  the faster sinusoids (bristle damping).

Per pressure level one pair is fitted; their pressure dependence is a pressure law of
:mod:`cylfric.friction.pressure` (linear when the data resolve a slope, else constant).

Breakaway
---------
The breakaway force of a ramp test is the net applied force at the moment the rod has
travelled ``travel`` (0.5 mm by default) from rest: gross sliding, past any presliding
deflection. The same definition is applied to the measured record and to the identified
model simulated with the record's force, so :func:`validate_breakaway` states how well the
model reproduces breakaway against force rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import pandas as pd

from ..io.campaign import DYNAMIC_TESTS
from ..model import FrictionModel

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping, Sequence


__all__ = [
    "DYNAMIC_TESTS",
    "DynamicRecord",
    "DynamicDataError",
    "PreslidingFit",
    "DynamicIdentification",
    "dynamic_record",
    "clean_force",
    "simulate_record",
    "fit_presliding",
    "breakaway_force",
    "ramp_fit",
    "validate_breakaway",
    "breakaway_notes",
    "identify_dynamic",
]

"""Test kinds (the ``test`` column of ``manifest.csv``, or a ``Test:`` header line)."""

HOLD = 0.04
"""Initial rest of a record [s] used for the force offset and the position zero."""

BREAKAWAY_TRAVEL = 0.5e-3
"""Travel from rest that marks breakaway [m] (gross sliding)."""

FORCE_CUTOFF = 90.0
"""Cut-off of the zero-phase low-pass applied to the measured force before it drives the
model [Hz]. Load-cell noise is measurement noise, not force the rod felt: fed to the
simulation it excites the bristle resonance (sqrt(sigma_0/m)/(2 pi): 100 Hz at 1e6 N/m and
2.5 kg, 320 Hz at 1e7 N/m) and biases sigma_1 upwards (+56 % at 1e7 N/m unfiltered with the
virtual bench's 0.8 N noise; per-level scatter of sigma_1 5-10 % with a 200 Hz cut-off and
2-3 % with this one, over 12 virtual records per set). Presliding excitation must stay
below about 60 Hz (the virtual bench's does)."""

SPIKE_SIGMA = 8.0
"""Force samples further than this many robust standard deviations from their running
median are spikes [-] (replaced by the median)."""


class DynamicDataError(ValueError):
    """A presliding or breakaway record cannot be used; the message names the file."""


@dataclass(frozen=True)
class DynamicRecord:
    """One force-controlled test, SI.

    Attributes
    ----------
    file : str
        Source file (for messages and tables).
    test : str
        ``"presliding"`` or ``"breakaway"``.
    time : ndarray
        Sample times from 0 [s], uniform.
    displacement : ndarray
        Rod displacement from its rest position [m] (extension > 0).
    force : ndarray
        Net applied force [N]: load-cell reading minus its value at rest, spikes removed,
        low-passed (:data:`FORCE_CUTOFF`).
    pressure : float
        Chamber pressure (both chambers) [Pa].
    mass : float
        Moving mass [kg].
    offset : float
        Load-cell reading at rest [N] (removed from ``force``).
    force_rate : float
        Nominal ramp rate of a breakaway test [N/s] (NaN otherwise).
    spikes : int
        Force samples replaced as spikes.
    force_noise : float
        Standard deviation of the raw force at rest [N] (load-cell noise), for the input-noise
        part of the standard errors.
    cutoff : float or None
        Low-pass cut-off applied to the force [Hz].
    """

    file: str
    test: str
    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    pressure: float
    mass: float
    offset: float
    force_rate: float = math.nan
    spikes: int = 0
    force_noise: float = 0.0
    cutoff: float | None = None

    @property
    def interval(self) -> float:
        """Sample interval [s]."""
        return float(self.time[1] - self.time[0])


def clean_force(force: np.ndarray, *, sigma: float = SPIKE_SIGMA) -> tuple[np.ndarray, int]:
    """Force [N] with isolated spikes replaced by the mean of their neighbours; and their count.

    A sample is a spike when its departure from the mean of its two neighbours (the second
    difference, which a smooth force keeps small) exceeds ``sigma`` robust standard
    deviations of that departure (1.4826 times its median absolute value) and is the largest
    of its three neighbours.
    """
    force = np.asarray(force, dtype=float)
    out = force.copy()
    if force.size < 5:
        return out, 0
    departure = np.zeros_like(force)
    departure[1:-1] = force[1:-1] - 0.5 * (force[:-2] + force[2:])
    size = np.abs(departure)
    scale = max(1.4826 * float(np.median(size[1:-1])), 1e-9 * float(np.max(np.abs(force))))
    if scale == 0:
        return out, 0
    peak = np.zeros_like(force, dtype=bool)
    peak[1:-1] = (size[1:-1] >= size[:-2]) & (size[1:-1] >= size[2:])
    spikes = np.nonzero(peak & (size > sigma * scale))[0]
    out[spikes] = 0.5 * (force[spikes - 1] + force[spikes + 1])
    return out, int(spikes.size)


_PRESSURE_COLUMNS = ("pressure [Pa]", "pressure_a [Pa]", "pressure_b [Pa]")

_RATE = {"n/s": 1.0, "kn/s": 1e3, "": 1.0}


def _force_rate(text, where) -> float:
    """A force rate [N/s] from ``"200"``, ``"200 N/s"`` or ``"0.2 kN/s"``."""
    import re

    match = re.fullmatch(r"\s*([-+0-9.eE]+)\s*([A-Za-z/]*)\s*", str(text).replace(",", "."))
    unit = match.group(2).lower() if match else None
    if not match or unit not in _RATE:
        raise DynamicDataError(
            f"{where}: cannot read the force rate {text!r}; expected e.g. 200 or '200 N/s'"
        )
    try:
        return float(match.group(1)) * _RATE[unit]
    except ValueError:
        raise DynamicDataError(
            f"{where}: cannot read the force rate {text!r}; expected e.g. 200 or '200 N/s'"
        ) from None


def lowpass(signal: np.ndarray, interval: float, cutoff: float | None = FORCE_CUTOFF) -> np.ndarray:
    """Zero-phase 8th-order Butterworth low-pass of ``signal`` sampled every ``interval`` [s].

    ``cutoff`` [Hz]; the signal is returned unchanged when the cut-off is at or above
    0.45 times the sampling frequency (nothing to remove).
    """
    from scipy.signal import butter, sosfiltfilt

    signal = np.asarray(signal, dtype=float)
    nyquist = 0.5 / interval
    if cutoff is None or cutoff >= 0.9 * nyquist:
        return signal.copy()
    sos = butter(8, cutoff / nyquist, output="sos")
    return sosfiltfilt(sos, signal)


def dynamic_record(
    data: Mapping[str, Any],
    metadata: Mapping[str, Any],
    *,
    test: str | None = None,
    mass: float | None = None,
    position_sign: float = 1.0,
    force_sign: float = 1.0,
    hold: float = HOLD,
    cutoff: float | None = FORCE_CUTOFF,
    reference: str | None = None,
) -> DynamicRecord:
    """A :class:`DynamicRecord` from a read run (``cylfric.io.campaign.read_run`` output).

    Parameters
    ----------
    data : mapping
        SI arrays ``time [s]``, ``position [m]``, ``force [N]``; a measured pressure
        (``pressure [Pa]``, or the mean of ``pressure_a [Pa]`` and ``pressure_b [Pa]``)
        wins over the nominal one.
    metadata : dict
        ``path``/``file``, ``pressure`` [Pa], ``extra`` (manifest columns: ``test``,
        ``force_rate_n_s`` [N/s]) and ``header`` (``Test``, ``Moving mass``, ``Force rate``).
    test : str, optional
        Test kind; default from the manifest or the header.
    mass : float, optional
        Moving mass [kg]; default from the header line ``Moving mass: 2.5 kg``.
    position_sign, force_sign : float
        +1 or -1 (``campaign.toml`` force_balance signs).
    hold : float
        Length of the initial rest [s] (force offset and position zero).
    cutoff : float or None
        Low-pass cut-off of the force [Hz] (:data:`FORCE_CUTOFF`; None: no filter).
    reference : {"a", "b", "sum", "mean", "max"}, optional
        The campaign's pressure reference (``CampaignConfig.pressure_reference``): the
        record's pressure is the chambers combined by it, as the steady-state points' are
        (a nominal value is both chambers' pressure: ``"sum"`` doubles it). None: the mean
        of the pressure columns, or the nominal value (as before).
    """
    from ..units import UnitError, parse_quantity

    where = str(metadata.get("path") or metadata.get("file") or "record")
    header = {str(k).lower(): v for k, v in (metadata.get("header") or {}).items()}
    extra = {str(k).lower(): v for k, v in (metadata.get("extra") or {}).items()}
    test = test or extra.get("test") or header.get("test")
    if test not in DYNAMIC_TESTS:
        raise DynamicDataError(
            f"{where}: test kind {test!r}; expected one of {list(DYNAMIC_TESTS)} (manifest "
            "column 'test' or a 'Test:' header line)"
        )
    try:
        if mass is None or not mass > 0:
            if "moving mass" not in header:
                raise DynamicDataError(
                    f"{where}: no moving mass: give force_balance.moving_mass in campaign.toml "
                    "or a 'Moving mass: 2.5 kg' header line (the dynamic fit needs the inertia)"
                )
            mass = parse_quantity(str(header["moving mass"]), "mass", default_unit="kg")
        rate = extra.get("force_rate_n_s") or header.get("force rate")
        force_rate = _force_rate(rate, where) if rate else math.nan
    except UnitError as exc:
        raise DynamicDataError(f"{where}: {exc}") from None
    for column in ("time [s]", "position [m]", "force [N]"):
        if column not in data:
            raise DynamicDataError(f"{where}: no {column.split()[0]} column; found {list(data)}")
    time = np.asarray(data["time [s]"], dtype=float)
    position = position_sign * np.asarray(data["position [m]"], dtype=float)
    force = force_sign * np.asarray(data["force [N]"], dtype=float)
    if time.size < 50:
        raise DynamicDataError(f"{where}: {time.size} samples; a dynamic test needs at least 50")
    steps = np.diff(time)
    interval = float(np.median(steps))
    if not (interval > 0 and np.all(np.abs(steps - interval) <= 1e-3 * interval + 1e-9)):
        raise DynamicDataError(
            f"{where}: the time column is not uniformly sampled (median step "
            f"{interval:.4g} s); the dynamic fit needs a uniform sample interval"
        )
    if not (np.all(np.isfinite(position)) and np.all(np.isfinite(force))):
        raise DynamicDataError(f"{where}: NaN or inf in the position or force column")
    pressure = float(metadata.get("pressure", math.nan))
    measured = [np.asarray(data[c], dtype=float) for c in _PRESSURE_COLUMNS if c in data]
    if reference is not None:  # the chambers combined as the steady-state points' are
        from ..friction.pressure import operating_pressure

        common = data.get("pressure [Pa]")
        pa = data.get("pressure_a [Pa]", common)
        pb = data.get("pressure_b [Pa]", common)
        if pa is None and pb is None:
            pa = pb = np.asarray(pressure)
        pa = pb if pa is None else pa
        pb = pa if pb is None else pb
        combined = operating_pressure(np.asarray(pa), np.asarray(pb), reference=reference)
        pressure = float(np.median(combined))
    elif measured:  # a measured pressure wins over the nominal one (as in the steady state)
        pressure = float(np.median(np.mean(measured, axis=0)))
    if not (math.isfinite(pressure) and pressure >= 0):
        raise DynamicDataError(
            f"{where}: unknown pressure; give pressure_bar in manifest.csv or a "
            "'Pressure: 55 bar' header line"
        )
    rest = time - time[0] <= hold
    if rest.sum() < 5:
        raise DynamicDataError(
            f"{where}: fewer than 5 samples in the first {hold * 1e3:g} ms; a dynamic test "
            "starts with the rod at rest for the force offset"
        )
    force, spikes = clean_force(force)
    noise = float(np.std(force[rest], ddof=1))
    force = lowpass(force, interval, cutoff)
    offset = float(np.median(force[rest]))
    return DynamicRecord(
        file=where,
        test=test,
        time=time - time[0],
        displacement=position - float(np.mean(position[rest])),
        force=force - offset,
        pressure=pressure,
        mass=float(mass),
        offset=offset,
        force_rate=float(force_rate),
        spikes=spikes,
        force_noise=noise,
        cutoff=cutoff,
    )


def simulate_record(model: FrictionModel, record: DynamicRecord, **changes: Any) -> np.ndarray:
    """Displacement [m] of ``model`` driven by the record's net force (public simulator).

    ``changes`` (``sigma_0=``, ``sigma_1=``) are applied to the model first.
    """
    from ..simulate import AppliedForce, Cylinder, simulate

    if changes:
        model = model.replace(**changes)
    result = simulate(
        Cylinder(record.mass),
        model,
        AppliedForce(record.force),
        float(record.time[-1]),
        dt=record.interval,
        pressure_a=record.pressure,
        rtol=RTOL,
    )
    return result.states["position"][: record.time.size]


@dataclass(frozen=True)
class PreslidingFit:
    """Least-squares fit of sigma_0 and sigma_1 to one presliding record.

    ``sigma_0`` [N/m], ``sigma_1`` [N*s/m] with standard errors, ``initial_slope`` [N/m]
    (slope of force against displacement on the virgin curve below half the peak force, a
    model-free check), ``rmse`` [m] of the displacement, ``n`` samples, ``simulated``
    displacement [m] of the fitted model, ``force_offset`` [N] (a correction of the
    load-cell offset fitted with them) and its standard error, ``success`` and ``message``.
    """

    file: str
    pressure: float
    sigma_0: float
    sigma_0_stderr: float
    sigma_1: float
    sigma_1_stderr: float
    initial_slope: float
    rmse: float
    n: int
    simulated: np.ndarray = field(repr=False)
    force_offset: float = 0.0
    force_offset_stderr: float = math.nan
    success: bool = True
    message: str = ""


def initial_slope(record: DynamicRecord, *, fraction: float = 0.5) -> float:
    """Slope of force against displacement [N/m] on the first loading from rest.

    Fits displacement against force (the force is the accurate signal) over the samples of
    the first monotone loading whose force stays below ``fraction`` of its first peak.
    """
    f = record.force
    peak_index = int(np.argmax(np.abs(f) >= 0.95 * np.max(np.abs(f))))
    sign = math.copysign(1.0, f[peak_index]) if f[peak_index] else 1.0
    first = np.arange(peak_index + 1)
    load = sign * f[first]
    keep = first[(load > 0.05 * load.max()) & (load < fraction * load.max())]
    if keep.size < 5:
        return math.nan
    slope = np.polyfit(f[keep], record.displacement[keep], 1)[0]
    return float(1.0 / slope) if slope > 0 else math.nan


RTOL = 1e-9
"""Relative tolerance of the simulations of the fit [-]: tighter than the simulator's default
1e-6, so that the finite-difference Jacobian sees the parameters, not the adaptive
integrator's step-selection jitter."""

DIFF_STEP = [1e-3, 1e-3, 0.1]
"""Finite-difference steps of the presliding fit: relative for log sigma_0 and log sigma_1
(about 1.4 % and 0.9 % of the parameters), 0.1 N for the force offset. A smaller offset step
drowns in the adaptive integrator's step-selection jitter (a Jacobian column 3600 times too
large), and the offset then never moves (+21 % on sigma_1 in one virtual record)."""


def _input_noise_spread(record, model, theta, residual, draws):
    """RMS shift of the fitted (log sigma_0, log sigma_1, offset) when the force input gets
    another draw of its own noise (low-passed white noise of ``record.force_noise``).

    The Jacobian's covariance counts only the displacement noise; the load-cell noise also
    drives the simulation (errors in variables). Seeded: the result is deterministic.
    """
    from scipy.optimize import least_squares

    if draws <= 0 or not record.force_noise > 0:
        return np.zeros(theta.size)
    rng = np.random.default_rng(0)
    shifts = []
    for _ in range(draws):
        extra = lowpass(
            rng.normal(0.0, record.force_noise, record.force.size), record.interval, record.cutoff
        )
        noisy = replace(record, force=record.force + extra)

        def perturbed(t, noisy=noisy):
            s0, s1 = np.exp(t[:2])
            x = simulate_record(
                model, replace(noisy, force=noisy.force - t[2]), sigma_0=s0, sigma_1=s1
            )
            return (x - record.displacement) * 1e6

        solution = least_squares(perturbed, theta, method="trf", diff_step=DIFF_STEP, max_nfev=30)
        shifts.append(solution.x - theta)
    return np.sqrt(np.mean(np.square(shifts), axis=0))


def fit_presliding(record: DynamicRecord, model: FrictionModel, *, draws: int = 2) -> PreslidingFit:
    """Fit ``sigma_0`` [N/m] and ``sigma_1`` [N*s/m] to one presliding record.

    ``model`` supplies the steady-state law (g(v), sigma_2) at the record's pressure; its
    own sigma_0 and sigma_1 are replaced. The fit works on the logarithms (both positive),
    starts from the initial slope and ``sqrt(sigma_0 m)``, and is a trust-region least
    squares on the displacement residual. A small correction of the force offset [N] is
    fitted with them: the offset read in the 40 ms at rest is uncertain by about 0.1 N, and
    under LuGre a constant force error makes the rod creep, which the damping would
    otherwise absorb (+17 % on sigma_1 in one virtual record at sigma_0 = 1e7 N/m). The
    offset has local minima: after the fit it is scanned over +-0.5 N (or 0.6 times the force
    noise) at the fitted sigmas, and the fit restarts from a better one.

    Standard errors: the Jacobian's (displacement noise) combined with the spread of
    ``draws`` refits whose force input gets another draw of the load-cell noise (the noise
    that also drives the simulation; see :data:`FORCE_CUTOFF`).
    """
    from scipy.optimize import least_squares

    if record.test != "presliding":
        raise DynamicDataError(f"{record.file}: a {record.test} record is not a presliding test")
    measured = record.displacement
    start_0 = initial_slope(record)
    if not (math.isfinite(start_0) and start_0 > 0):
        peak = float(np.max(np.abs(record.force)))
        travel = float(np.max(np.abs(measured)))
        start_0 = peak / travel if travel > 0 else 1e6
    start = np.r_[np.log([start_0, math.sqrt(start_0 * record.mass)]), 0.0]
    base = model

    def shifted(offset):
        return replace(record, force=record.force - offset)

    def residual(theta):
        s0, s1 = np.exp(theta[:2])
        x = simulate_record(base, shifted(theta[2]), sigma_0=s0, sigma_1=s1)
        return (x - measured) * 1e6

    def solve(first):
        return least_squares(
            residual, first, method="trf", diff_step=DIFF_STEP, x_scale=1.0, xtol=1e-6, max_nfev=80
        )

    solution = solve(start)
    # the force offset has local minima (a creep the damping can absorb): scan it at the
    # fitted sigmas and refit from a better offset (twice at most)
    width = max(0.5, 0.6 * record.force_noise)  # [N]
    for _ in range(2):
        cost = float(solution.fun @ solution.fun)
        grid = solution.x[2] + np.linspace(-width, width, 21)
        costs = [float(np.sum(residual(np.r_[solution.x[:2], g]) ** 2)) for g in grid]
        if min(costs) >= cost * (1 - 1e-6):
            break
        candidate = solve(np.r_[solution.x[:2], grid[int(np.argmin(costs))]])
        if float(candidate.fun @ candidate.fun) >= cost:
            break
        solution = candidate
    theta = solution.x
    n = measured.size
    dof = max(n - theta.size, 1)
    s2 = float(solution.fun @ solution.fun) / dof
    jac = solution.jac
    try:
        cov = np.linalg.inv(jac.T @ jac) * s2
        se = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        se = np.full(theta.size, math.inf)
    se = np.hypot(se, _input_noise_spread(record, base, theta, residual, draws))
    s0, s1 = np.exp(theta[:2])
    simulated = simulate_record(base, shifted(theta[2]), sigma_0=s0, sigma_1=s1)
    return PreslidingFit(
        file=record.file,
        pressure=record.pressure,
        sigma_0=float(s0),
        sigma_0_stderr=float(s0 * se[0]),
        sigma_1=float(s1),
        sigma_1_stderr=float(s1 * se[1]),
        force_offset=float(theta[2]),
        force_offset_stderr=float(se[2]),
        initial_slope=initial_slope(record),
        rmse=float(math.sqrt(np.mean((simulated - measured) ** 2))),
        n=int(n),
        simulated=simulated,
        success=bool(solution.success),
        message=str(solution.message),
    )


def breakaway_force(
    record_or_time: DynamicRecord | np.ndarray,
    force: np.ndarray | None = None,
    displacement: np.ndarray | None = None,
    *,
    travel: float = BREAKAWAY_TRAVEL,
) -> float:
    """Net applied force [N] when the rod has first travelled ``travel`` [m] from rest.

    Takes a :class:`DynamicRecord` or ``(time [s], force [N], displacement [m])``. The force
    at the crossing is read from a straight line fitted to the force over the 20 samples
    before it (the ramp; this averages the load-cell noise). NaN when the rod never travels
    that far.
    """
    if isinstance(record_or_time, DynamicRecord):
        time, force, displacement = (
            record_or_time.time,
            record_or_time.force,
            record_or_time.displacement,
        )
    else:
        time = np.asarray(record_or_time, dtype=float)
    # the (time, force, displacement) form: the caller gives all three
    assert force is not None and displacement is not None
    beyond = np.nonzero(np.asarray(displacement) >= travel)[0]
    if beyond.size == 0 or beyond[0] == 0:
        return math.nan
    i = int(beyond[0])
    x0, x1 = displacement[i - 1], displacement[i]
    t_cross = time[i - 1] + (travel - x0) / (x1 - x0) * (time[i] - time[i - 1])
    lo = max(0, i - 20)
    line = np.polyfit(time[lo : i + 1], force[lo : i + 1], 1)
    return float(np.polyval(line, t_cross))


def ramp_fit(record: DynamicRecord, *, travel: float = BREAKAWAY_TRAVEL) -> tuple[float, float]:
    """(rate [N/s], start time [s]) of the straight line fitted to a ramp test's force.

    Fitted over the samples between 10 % of the force reached at breakaway (or of the peak
    force) and breakaway itself, where the force is the machine's ramp.
    """
    beyond = np.nonzero(record.displacement >= travel)[0]
    stop = int(beyond[0]) if beyond.size else record.time.size
    force = record.force[:stop]
    ramp = np.nonzero(force > 0.1 * np.max(force))[0] if stop > 2 else np.array([], int)
    if ramp.size < 3:
        raise DynamicDataError(f"{record.file}: no force ramp before breakaway")
    rate, intercept = np.polyfit(record.time[ramp], force[ramp], 1)
    if not rate > 0:
        raise DynamicDataError(f"{record.file}: the force does not rise; expected a force ramp")
    return float(rate), float(-intercept / rate)


BREAKAWAY_SEARCH = 3.0
"""The model's ramp is simulated until its force reaches this many times the model's
breakaway level max(F_s, F_c) at the record's pressure [-] (or the record's end, if later):
a model that breaks away after the measured rod (a record the machine stopped at 1 mm of
travel) still gets its breakaway force."""


def _simulated_breakaway(
    model: FrictionModel, record: DynamicRecord, rate: float, start: float, travel: float
) -> float:
    """Breakaway force [N] of ``model`` on the ramp ``rate (t - start)``: over the record,
    and when the model has not broken away by its end, over a ramp continued to
    :data:`BREAKAWAY_SEARCH` times the model's breakaway level (the rod then slides far
    beyond the model's validity speeds; only the first crossing of ``travel`` is read, so
    that part's validity warnings are not passed on)."""
    import warnings

    from ..model import ValidityWarning

    ramp = rate * np.clip(record.time - start, 0.0, None)
    simulated = breakaway_force(
        record.time, ramp, simulate_record(model, replace(record, force=ramp)), travel=travel
    )
    if math.isfinite(simulated):
        return simulated
    params = model.params_at(record.pressure)
    level = max(float(params["F_s"]), float(params["F_c"]))
    end = max(float(record.time[-1]), start + BREAKAWAY_SEARCH * level / rate)
    h = record.interval
    time = np.arange(int(math.ceil(end / h - 1e-9)) + 1) * h
    ramp = rate * np.clip(time - start, 0.0, None)
    longer = replace(record, time=time, force=ramp, displacement=np.zeros_like(time))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ValidityWarning)
        displacement = simulate_record(model, longer)
    return breakaway_force(time, ramp, displacement, travel=travel)


def validate_breakaway(
    model: FrictionModel,
    records: Iterable[DynamicRecord],
    *,
    travel: float = BREAKAWAY_TRAVEL,
    progress: Callable[..., Any] | None = None,
) -> pd.DataFrame:
    """Breakaway forces of the ramp tests, measured and simulated with ``model``.

    Each breakaway record's ramp (:func:`ramp_fit`: the straight line the machine followed,
    free of load-cell noise) drives the model (:func:`simulate_record`), continued past the
    record's end until the model breaks away (up to :data:`BREAKAWAY_SEARCH` times its
    breakaway level); both displacements go through :func:`breakaway_force`. Columns:
    ``file``, ``pressure [Pa]``, ``force_rate [N/s]`` (fitted), ``measured [N]``,
    ``simulated [N]``, ``error [N]``, ``relative_error [-]``, ``ramp_length [s]`` (of the
    record, from the ramp's start), ``travel_reached [m]`` (the record's largest
    displacement) and ``ramp_needed [s]`` (ramp time the model needs to break away: the
    simulated breakaway force over the rate, or F_s over the rate when the model does not
    break away). ``progress`` is called with each ramp's file name once simulated.
    """
    rows = []
    for record in records:
        if record.test != "breakaway":
            continue
        measured = breakaway_force(record, travel=travel)
        rate, start = ramp_fit(record, travel=travel)
        simulated = _simulated_breakaway(model, record, rate, start, travel)
        level = float(model.params_at(record.pressure)["F_s"])
        rows.append(
            {
                "file": record.file,
                "pressure [Pa]": record.pressure,
                "force_rate [N/s]": rate,
                "measured [N]": measured,
                "simulated [N]": simulated,
                "error [N]": simulated - measured,
                "relative_error [-]": (simulated - measured) / measured,
                "ramp_length [s]": float(record.time[-1]) - start,
                "travel_reached [m]": float(np.max(record.displacement)),
                "ramp_needed [s]": (simulated if math.isfinite(simulated) else level) / rate,
            }
        )
        if progress is not None:
            progress(record.file)
    columns = [
        "file",
        "pressure [Pa]",
        "force_rate [N/s]",
        "measured [N]",
        "simulated [N]",
        "error [N]",
        "relative_error [-]",
        "ramp_length [s]",
        "travel_reached [m]",
        "ramp_needed [s]",
    ]
    return pd.DataFrame(rows, columns=columns)


def breakaway_notes(table: pd.DataFrame, travel: float = BREAKAWAY_TRAVEL) -> list[str]:
    """One note per ramp of :func:`validate_breakaway`'s ``table`` without a breakaway.

    A record whose rod never travelled ``travel`` [m] says how far it got, how long its
    ramp ran and how long it must run (the model's breakaway force over the force rate,
    with half again for the travel); a model that never breaks away says so.
    """
    notes = []
    for row in table.to_dict("records"):
        rate, needed = row["force_rate [N/s]"], row["ramp_needed [s]"]
        if not math.isfinite(row["measured [N]"]):
            notes.append(
                f"{row['file']}: no breakaway within the record: the rod travelled "
                f"{row['travel_reached [m]'] * 1e3:.3g} mm of the {travel * 1e3:g} mm that "
                f"mark breakaway in {row['ramp_length [s]']:.3g} s of ramp (up to "
                f"{rate * row['ramp_length [s]']:.0f} N at {rate:.4g} N/s); the model breaks "
                f"away at {rate * needed:.0f} N, {needed:.3g} s into the ramp: run ramps of "
                f"at least {1.5 * needed:.3g} s at this rate (force rate x time above the "
                f"breakaway force F_s), or let the machine stop at 1 mm of travel, not before"
            )
        elif not math.isfinite(row["simulated [N]"]):
            notes.append(
                f"{row['file']}: the identified model does not break away on this ramp "
                f"within {BREAKAWAY_SEARCH:g} x its F_s ({rate * needed:.0f} N); check the "
                "steady-state law at this pressure"
            )
    return notes


@dataclass
class DynamicIdentification:
    """sigma_0 and sigma_1 identified from force-controlled tests.

    Attributes
    ----------
    model : FrictionModel
        The input model with ``sigma_0`` [N/m] and ``sigma_1`` [N*s/m] replaced (constants
        or pressure laws), status ``identified``, standard errors in its parameters.
    fits : list of PreslidingFit
        One per presliding record.
    per_pressure : DataFrame
        ``pressure [Pa]``, ``sigma_0 [N/m]``, ``sigma_0_stderr [N/m]``, ``sigma_1 [N*s/m]``,
        ``sigma_1_stderr [N*s/m]``, ``initial_slope [N/m]``, ``rmse [m]``, ``n [-]``, ``file``.
    laws : dict
        Parameter -> ``{"law", coefficients, "stderr": {...}, "reason"}``.
    breakaway : DataFrame
        :func:`validate_breakaway` of the identified model (empty without ramp tests).
    records : list of DynamicRecord
    notes : list of str
    """

    model: FrictionModel
    fits: list
    per_pressure: pd.DataFrame
    laws: dict
    breakaway: pd.DataFrame
    records: list = field(repr=False, default_factory=list)
    notes: list = field(default_factory=list)

    def summary(self) -> dict:
        """JSON-ready record of the identification (SI) for the datasheet's ``dynamic_fit``."""
        errors = self.breakaway["relative_error [-]"].to_numpy(dtype=float)
        errors = errors[np.isfinite(errors)]
        return {
            "method": METHOD,
            "units": {"sigma_0": "N/m", "sigma_1": "N*s/m", "pressure": "Pa", "force": "N"},
            "laws": self.laws,
            "per_pressure": [
                {cast("str", k).split(" [")[0]: v for k, v in row.items()}
                for row in self.per_pressure.to_dict("records")
            ],
            "breakaway_validation": {
                "travel": BREAKAWAY_TRAVEL,
                "rms_relative_error": float(np.sqrt(np.mean(errors**2))) if errors.size else None,
                "max_relative_error": float(np.max(np.abs(errors))) if errors.size else None,
                "tests": [
                    {cast("str", k).split(" [")[0]: v for k, v in row.items()}
                    for row in self.breakaway.to_dict("records")
                ],
            },
            "notes": list(self.notes),
        }


METHOD = (
    "LuGre output-error least squares on presliding records (displacement simulated from the "
    "measured force, steady-state law and mass given); pressure law by weighted regression"
)


def _pressure_law(pressure, value, stderr, name):
    """Constant or linear law of one parameter across pressure levels, with standard errors.

    Linear when at least three levels and the slope differs from zero by more than twice its
    standard error (and the law stays positive over the levels); else the weighted mean. The
    standard errors are scaled by the Birge ratio when the scatter exceeds them.
    """
    p = np.asarray(pressure, dtype=float)
    y = np.asarray(value, dtype=float)
    se = np.asarray(stderr, dtype=float)
    se = np.where(np.isfinite(se) & (se > 0), se, np.nanmax(np.r_[se[np.isfinite(se)], y * 0.1]))
    w = 1.0 / se**2
    if p.size >= 3 and np.ptp(p) > 0:
        design = np.column_stack([np.ones_like(p), p])
        a = design * np.sqrt(w)[:, None]
        coef, *_ = np.linalg.lstsq(a, y * np.sqrt(w), rcond=None)
        cov = np.linalg.inv(a.T @ a)
        chi2 = float(np.sum(w * (y - design @ coef) ** 2)) / (p.size - 2)
        cov *= max(chi2, 1.0)
        slope_se = math.sqrt(cov[1, 1])
        positive = np.all(design @ coef > 0)
        if abs(coef[1]) > 2 * slope_se and positive:
            return {
                "law": "linear",
                "intercept": float(coef[0]),
                "slope": float(coef[1]),
                "stderr": {"intercept": math.sqrt(cov[0, 0]), "slope": slope_se},
                "reason": f"{name} changes with pressure by more than twice the slope's "
                f"standard error over {p.size} levels",
            }
    mean = float(np.sum(w * y) / np.sum(w))
    se_mean = math.sqrt(1.0 / np.sum(w))
    if p.size > 1:
        chi2 = float(np.sum(w * (y - mean) ** 2)) / (p.size - 1)
        se_mean *= math.sqrt(max(chi2, 1.0))
    reason = (
        f"no pressure dependence resolved over {p.size} levels"
        if p.size >= 3
        else f"{p.size} pressure level(s): too few for a pressure law"
    )
    return {
        "law": "constant",
        "intercept": mean,
        "stderr": {"intercept": se_mean},
        "reason": reason,
    }


def identify_dynamic(
    records: Sequence[DynamicRecord],
    model: FrictionModel,
    *,
    progress: Callable[..., Any] | None = None,
    travel: float = BREAKAWAY_TRAVEL,
) -> DynamicIdentification:
    """Identify sigma_0 [N/m] and sigma_1 [N*s/m] from presliding records; validate on ramps.

    Parameters
    ----------
    records : sequence of DynamicRecord
        Presliding records (one or more per pressure level) and, optionally, breakaway ramps.
    model : FrictionModel
        The steady-state model (g(v), sigma_2 and the pressure laws); its sigma_0 and sigma_1
        are replaced.
    progress : callable, optional
        Called with each record's file name once fitted (presliding) or simulated
        (breakaway): one call per presliding and per breakaway record.
    travel : float
        Breakaway travel [m] (:func:`breakaway_force`).

    Returns
    -------
    DynamicIdentification
    """
    records = list(records)
    presliding = [r for r in records if r.test == "presliding"]
    if not presliding:
        raise DynamicDataError(
            "no presliding record: sigma_0 and sigma_1 are identified from presliding tests "
            f"(force below breakaway); got {len(records)} record(s) of kinds "
            f"{sorted({r.test for r in records})}"
        )
    fits = []
    for record in presliding:
        fits.append(fit_presliding(record, model))
        if progress is not None:
            progress(record.file)
    per_pressure = pd.DataFrame(
        {
            "pressure [Pa]": [f.pressure for f in fits],
            "sigma_0 [N/m]": [f.sigma_0 for f in fits],
            "sigma_0_stderr [N/m]": [f.sigma_0_stderr for f in fits],
            "sigma_1 [N*s/m]": [f.sigma_1 for f in fits],
            "sigma_1_stderr [N*s/m]": [f.sigma_1_stderr for f in fits],
            "initial_slope [N/m]": [f.initial_slope for f in fits],
            "rmse [m]": [f.rmse for f in fits],
            "n [-]": [f.n for f in fits],
            "file": [f.file for f in fits],
        }
    ).sort_values("pressure [Pa]", ignore_index=True)
    notes = [f"{f.file}: fit did not converge ({f.message})" for f in fits if not f.success]
    laws, values, errors, status = {}, {}, {}, {}
    for name, unit in (("sigma_0", "N/m"), ("sigma_1", "N*s/m")):
        law = _pressure_law(
            per_pressure["pressure [Pa]"],
            per_pressure[f"{name} [{unit}]"],
            per_pressure[f"{name}_stderr [{unit}]"],
            name,
        )
        laws[name] = law
        coefficients = {k: law[k] for k in ("intercept", "slope") if k in law}
        if law["law"] == "constant":
            values[name], errors[name] = law["intercept"], law["stderr"]["intercept"]
        else:
            values[name] = {"law": law["law"], **coefficients}
            errors[name] = dict(law["stderr"])
        status[name] = (
            "identified",
            f"presliding tests at {per_pressure.shape[0]} record(s), LuGre output-error fit; "
            f"{law['law']} in pressure",
        )
    stderr = {**model.stderr(), **errors}
    identified = model.replace(
        sigma_0=values["sigma_0"], sigma_1=values["sigma_1"], dynamic_status=status, stderr=stderr
    )
    breakaway = validate_breakaway(identified, records, travel=travel, progress=progress)
    notes.extend(breakaway_notes(breakaway, travel))
    return DynamicIdentification(identified, fits, per_pressure, laws, breakaway, records, notes)
