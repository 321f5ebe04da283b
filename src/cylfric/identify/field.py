"""Friction in service, from a working machine's own logs (``cylfric fit-field``; docs/field.md).

No load cell: the piston force comes from the chamber pressures,
``F = p_A A_A - p_B A_B``, and carries the external load, which changes with position,
and the inertia of the linkage. The model, per log (one payload)::

    F = F_load(x) + m(x) a + 1/2 m'(x) v^2 + sign(v) (F_c + k_p p) + F_v v

with ``F_load`` a Legendre series in position (degree ``load_degree``), the reflected mass
``m(x)`` a Legendre series of degree ``mass_degree`` (Lagrange's equation in the rod
coordinate gives the ``1/2 m' v^2`` term), and cylfric's Coulomb + viscous law with an
optional pressure slope. The load is the same for extension and retraction at one position,
so the friction is what separates the two directions: that is what identifies it, and why
an asymmetry of the friction between directions cannot be identified (the load is only
known through the mean of the two).

Velocity and acceleration are central differences of the low-passed position (zero-phase
Butterworth); the force is filtered by the same filter, so the equation holds for the
filtered signals (linear terms exactly). Least squares on the moving samples
(``|v| > min_speed``, clear of rest by a period of the cut-off), decimated; the
covariance is cluster-robust by stroke (CR1; a stroke is one movement in one direction).

Beside it a model-free cross-check: at steady motion (settled speed, no valve step) the
extension and retraction forces at equal position and speed band, within one log, give
``friction = (F_ext - F_ret) / 2``; its standard error by a delete-one-stroke jackknife.

Per day the same model gives the friction level at a reference speed with its band; a
change test compares days against the within-day bands and the between-day
reproducibility scatter (successive differences, robust to a trend; or stated).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Sequence

    from ..io.fieldlog import FieldConfig, FieldRecord

__all__ = [
    "FieldSignals",
    "FieldFit",
    "prepare_log",
    "fit_field",
    "cross_check",
    "holding_check",
    "DEFAULTS",
]

DEFAULTS: dict[str, Any] = {
    "min_speed": 0.010,  # m/s: below it the Coulomb term is regularised in real seals
    "load_degree": 6,
    "mass_degree": 3,
    "level": 0.95,
    "change_level": 0.99,  # 1 % false alarms per comparison: <= 1 in 20 comparisons is likely
    "reproducibility": None,  # relative between-day scatter; None: estimated (>= 4 days)
    "cutoff": 6.0,  # Hz, zero-phase low-pass of position and force
    "cutoff_check": 0.7,  # the systematic band: the fit again at this share of the cut-off
    "rest_guard": 1.0,  # periods of the cut-off kept clear of rest (a reversal, a stop)
    "decimate": 0.04,  # s between the regression's samples
    "steady_acceleration": 0.02,  # m/s^2
    "steady_spread": 0.08,  # relative speed spread within +-0.5 s at steady motion
    "step_guard": 1.0,  # s around a valve step left out of the steady samples
    "step_rate": 5.0,  # valve command change per second, in its range, that is a step [1/s]
    "position_bins": 12,
    "band_ratio": 1.25,  # a new speed band beyond this ratio [-]
    "min_band_samples": 40,
    "min_strokes": 3,
    "speed_ratio": 1.5,  # speeds spanning less than this: speed dependence not identified
    "pressure_spread": 10e5,  # Pa: pressure independent of position needed for a slope
    "vif_limit": 10.0,
    "hold_time": 1.0,  # s at rest for a holding episode
    "payload_step": 0.1,  # a held force changing by this share of the log's force: new payload
    "collapse_ratio": 0.3,  # valve-side check: held pressure below this share of moving
}

PARAMETER_UNITS = {"F_c": "N", "F_v": "N*s/m", "k_p": "N/Pa"}


@dataclass
class FieldSignals:
    """One log's prepared signals (SI), full rate unless said otherwise."""

    name: str
    day: str
    time: np.ndarray
    position: np.ndarray  # filtered [m]
    velocity: np.ndarray  # [m/s]
    acceleration: np.ndarray  # [m/s^2]
    force: np.ndarray  # filtered piston force [N]
    pressure: np.ndarray  # filtered mean chamber pressure [Pa]
    pressure_a: np.ndarray  # as logged [Pa]
    pressure_b: np.ndarray  # as logged [Pa]
    stroke: np.ndarray  # stroke id (-1 at rest), global across logs after fit_field
    steady: np.ndarray  # bool
    usable: np.ndarray  # bool: chamber pressures valid here
    rate: float
    steps: int  # valve steps found
    acceleration_noise: float = 0.0  # variance of the acceleration's noise [m^2/s^4]
    notes: list[str] = field(default_factory=list)


def _lowpass(values, rate, cutoff):
    """Zero-phase Butterworth low-pass (order 4, run forward and back) [same units]."""
    from scipy.signal import butter, sosfiltfilt

    sos = butter(4, min(cutoff, 0.45 * rate), fs=rate, output="sos")
    return sosfiltfilt(sos, values)


def _strokes(velocity, min_speed):
    """Stroke id per sample: runs of one sign with |v| > min_speed (-1 elsewhere)."""
    sign = np.where(velocity > min_speed, 1, np.where(velocity < -min_speed, -1, 0)).astype(np.int8)
    change = np.flatnonzero(np.diff(sign) != 0) + 1
    starts = np.concatenate(([0], change))
    ids = np.repeat(np.arange(starts.size), np.diff(np.concatenate((starts, [sign.size]))))
    ids = ids.astype(np.int64)
    ids[sign == 0] = -1
    # renumber the moving runs 0..n-1
    moving = ids >= 0
    _, compact = np.unique(ids[moving], return_inverse=True)
    ids[moving] = compact
    return ids


def _acceleration_noise(position, rate, cutoff, dt) -> float:
    """Variance of the noise the position sensor puts into the acceleration [m^2/s^4].

    The sensor's noise from the third differences of the logged position (robust: MAD;
    a white noise of variance s^2 gives 20 s^2 there, the motion itself almost nothing at
    100 Hz), carried through the low-pass and the two central differences (the sum of the
    squares of their impulse response). Used to correct the mass columns' normal equations
    for errors in variables (Fuller 1987, *Measurement Error Models*, sec. 1.2): without
    it the mass comes out low where few accelerations were logged.
    """
    if position.size < 50:
        return 0.0
    third = np.diff(position, 3)
    spread = 1.4826 * float(np.median(np.abs(third - np.median(third))))
    sigma2 = (spread**2) / 20.0
    n = int(8 * rate / cutoff) * 2 + 101
    impulse = np.zeros(n)
    impulse[n // 2] = 1.0
    response = np.gradient(np.gradient(_lowpass(impulse, rate, cutoff), dt), dt)
    return sigma2 * float(np.sum(response**2))


def _renumber(stroke):
    """Stroke ids 0..n-1 after samples were set to -1: each contiguous moving run its own."""
    moving = stroke >= 0
    out = np.full(stroke.size, -1, dtype=np.int64)
    if np.any(moving):
        # a new id wherever a moving run starts
        start = moving & ~np.concatenate(([False], moving[:-1]))
        out[moving] = (np.cumsum(start) - 1)[moving]
    return out


def holding_check(
    pressure: np.ndarray,
    velocity: np.ndarray,
    rate: float,
    *,
    hold_time: float = DEFAULTS["hold_time"],
    ratio: float = DEFAULTS["collapse_ratio"],
    min_drop: float = 10e5,
) -> dict[str, Any]:
    """Does a pressure collapse while the rod holds still (a sensor on the valve side of a
    counter-balance valve reads the line, at tank pressure, while the chamber holds the load)?

    Holding episodes: ``|v| < 1 mm/s`` for ``hold_time`` [s]. An episode collapses when the
    pressure's median in its second half is below ``ratio`` times the median in the 2 s of
    motion before it and at least ``min_drop`` [Pa] lower. Returns ``episodes``,
    ``collapsed``, ``held`` and ``moving`` (median pressures [Pa]) and ``flagged`` (more than
    half of at least 3 episodes collapse).
    """
    still = np.abs(velocity) < 1e-3
    edges = np.flatnonzero(np.diff(np.concatenate(([0], still.view(np.int8), [0]))))
    starts, ends = edges[::2], edges[1::2]
    n_hold = int(hold_time * rate)
    before = int(2 * rate)
    episodes = collapsed = 0
    held, moving = [], []
    for s, e in zip(starts, ends, strict=True):
        if e - s < n_hold or s < before:
            continue
        move = pressure[s - before : s][~still[s - before : s]]
        if move.size < 5:
            continue
        p_hold = float(np.median(pressure[(s + e) // 2 : e]))
        p_move = float(np.median(move))
        episodes += 1
        held.append(p_hold)
        moving.append(p_move)
        if p_hold < ratio * p_move and p_move - p_hold > min_drop:
            collapsed += 1
    return {
        "episodes": episodes,
        "collapsed": collapsed,
        "held [Pa]": float(np.median(held)) if held else math.nan,
        "moving [Pa]": float(np.median(moving)) if moving else math.nan,
        "flagged": episodes >= 3 and collapsed > episodes / 2,
    }


def prepare_log(
    record: FieldRecord, config: FieldConfig, options: dict[str, Any] | None = None
) -> FieldSignals:
    """Filter one log, find its strokes, valve steps and steady motion, check its sensors."""
    o = {**DEFAULTS, **config.fit, **(options or {})}
    dt = float(np.median(np.diff(record.time)))
    rate = 1.0 / dt
    cutoff = o["cutoff"]
    # internally the position grows with extension (velocity > 0 extends); the curves are
    # reported in the log's own coordinate (FieldFit: position_sign)
    x = record.position if config.extension == "position increases" else -record.position
    # one zero-phase low-pass for position and force; the derivatives of the filtered
    # position by central differences, so that filter(m a) = m filter(a) holds exactly for
    # constant m (an own derivative filter would not match the force's filter at the
    # linkage's hydraulic resonance, a few Hz, and bias the mass)
    position = _lowpass(x, rate, cutoff)
    velocity = np.gradient(position, dt)
    acceleration = np.gradient(velocity, dt)
    acceleration_noise = _acceleration_noise(x, rate, cutoff, dt)
    area_a, area_b = config.areas()
    notes: list[str] = []
    usable = np.ones(x.size, dtype=bool)
    # sensors on the valve side of a load-holding valve: check, and use only where they
    # read the chamber (flow into that chamber through the check valve)
    for role, into in (("pressure_a", 1.0), ("pressure_b", -1.0)):
        raw = getattr(record, role)
        # the chamber that lifts (holds) the load is the one whose flow enters on extension
        direction = into if config.orientation == "A extends" else -into
        check = holding_check(raw, velocity, rate)
        valve_side = config.sensors.get(role) == "valve side"
        if check["flagged"]:
            notes.append(
                f"{record.name}: {role} collapses while the rod holds still "
                f"({check['collapsed']} of {check['episodes']} holds: median "
                f"{check['held [Pa]'] / 1e5:.1f} bar held against {check['moving [Pa]'] / 1e5:.1f} "
                "bar moving): a sensor on the valve side of a counter-balance or load-holding "
                "valve; not used as the chamber pressure at rest nor when the flow leaves "
                "that chamber" + ("" if valve_side else " (field.toml says 'chamber')")
            )
        if valve_side or check["flagged"]:
            usable &= np.sign(velocity) == direction
    force = _lowpass(record.pressure_a * area_a - record.pressure_b * area_b, rate, cutoff)
    pressure = _lowpass(0.5 * (record.pressure_a + record.pressure_b), rate, cutoff)
    stroke = _strokes(velocity, o["min_speed"])
    # the low-pass spreads the friction's sign change at a reversal or a stop over about
    # one period of the cut-off: samples that close to rest are not used
    from scipy.ndimage import maximum_filter1d, minimum_filter1d

    reach = int(o["rest_guard"] * rate / cutoff)
    near_rest = maximum_filter1d((stroke < 0).view(np.int8), 2 * reach + 1) > 0
    stroke[near_rest] = -1
    # gaps in the log (the logger paused): the filter and the differences bridge them, so
    # the samples within a few cut-off periods of a gap are not used
    gaps = np.flatnonzero(np.diff(record.time) > 3 * dt)
    if gaps.size:
        reach_gap = int(3 * rate / cutoff) + 1
        for g in gaps:
            stroke[max(0, g - reach_gap) : g + reach_gap + 1] = -1
        notes.append(
            f"{record.name}: {gaps.size} gap(s) in time (longer than 3 sampling periods); "
            "the samples next to them are not used"
        )
    if gaps.size or np.any(stroke >= 0):
        stroke = _renumber(stroke)
    # valve steps: the command moving faster than step_rate (its range per second)
    steps = np.zeros(x.size, dtype=bool)
    n_steps = 0
    if record.valve is not None:
        span = float(np.ptp(record.valve)) or 1.0
        jump = np.abs(np.diff(record.valve, prepend=record.valve[0])) * rate / span
        steps = jump > o["step_rate"]
        n_steps = int(np.count_nonzero(np.diff(steps.view(np.int8), prepend=0) == 1))
    else:
        # no valve command: a jerk far beyond the moves' marks a step
        jerk = np.abs(np.gradient(acceleration, dt))
        scale = np.median(jerk[stroke >= 0]) if np.any(stroke >= 0) else 0.0
        steps = jerk > 20 * scale if scale > 0 else steps
    guard = int(o["step_guard"] * rate) * 2 + 1
    near_step = maximum_filter1d(steps.view(np.int8), guard) > 0
    half = int(0.5 * rate) * 2 + 1
    v_hi = maximum_filter1d(velocity, half)
    v_lo = minimum_filter1d(velocity, half)
    settled = (v_hi - v_lo) < o["steady_spread"] * np.abs(velocity)
    steady = (
        (stroke >= 0)
        & settled
        & (np.abs(acceleration) < o["steady_acceleration"])
        & ~near_step
        & usable
    )
    return FieldSignals(
        name=record.name,
        day=record.day,
        time=record.time,
        position=position,
        velocity=velocity,
        acceleration=acceleration,
        force=force,
        pressure=pressure,
        pressure_a=record.pressure_a,
        pressure_b=record.pressure_b,
        stroke=stroke,
        steady=steady,
        usable=usable,
        rate=rate,
        steps=n_steps,
        acceleration_noise=acceleration_noise,
        notes=notes,
    )


def payload_segments(
    signals: FieldSignals, *, hold_time: float = 1.0, step: float = 0.1
) -> list[slice]:
    """Split a log where its payload changes: while the rod holds still (``hold_time`` [s]
    at ``|v| < 1 mm/s``) the piston force changes by more than ``step`` times the median
    moving force (a load picked up or set down); cut in the middle of that hold. A log
    whose pressures are not valid at rest (a valve-side sensor) is not split."""
    n = signals.time.size
    if not np.all(signals.usable):
        return [slice(0, n)]
    still = np.abs(signals.velocity) < 1e-3
    edges = np.flatnonzero(np.diff(np.concatenate(([0], still.view(np.int8), [0]))))
    moving = signals.stroke >= 0
    if not np.any(moving):
        return [slice(0, n)]
    scale = float(np.median(np.abs(signals.force[moving])))
    n_hold = int(hold_time * signals.rate)
    edge = max(1, int(0.3 * signals.rate))
    cuts = []
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a < n_hold:
            continue
        before = np.median(signals.force[a : a + edge])
        after = np.median(signals.force[b - edge : b])
        if abs(after - before) > step * scale:
            cuts.append((a + b) // 2)
    bounds = [0, *cuts, n]
    return [slice(bounds[i], bounds[i + 1]) for i in range(len(bounds) - 1)]


def _segment(signals: FieldSignals, part: slice) -> FieldSignals:
    t = signals.time[part]
    return FieldSignals(
        name=f"{signals.name} [{t[0]:.6g}-{t[-1]:.6g} s]",
        day=signals.day,
        time=t,
        position=signals.position[part],
        velocity=signals.velocity[part],
        acceleration=signals.acceleration[part],
        force=signals.force[part],
        pressure=signals.pressure[part],
        pressure_a=signals.pressure_a[part],
        pressure_b=signals.pressure_b[part],
        stroke=signals.stroke[part],
        steady=signals.steady[part],
        usable=signals.usable[part],
        rate=signals.rate,
        steps=signals.steps,
        acceleration_noise=signals.acceleration_noise,
        notes=[],
    )


def _prepare_all(records, config, o, notes) -> list[FieldSignals]:
    """prepare_log each record, split where the payload changes (one load curve each)."""
    out = []
    for record in records:
        s = prepare_log(record, config, o)
        parts = payload_segments(s, hold_time=o["hold_time"], step=o["payload_step"])
        if len(parts) == 1:
            out.append(s)
            continue
        if notes is not None:
            notes.append(
                f"{s.name}: the held force changes {len(parts) - 1} time(s) at rest (a payload "
                f"picked up or set down): {len(parts)} segments, each with its own load curve "
                "and mass"
            )
        out.extend(_segment(s, p) for p in parts)
    return out


def _legendre(xi, degree):
    return np.polynomial.legendre.legvander(xi, degree)


def _legendre_derivative(xi, degree):
    out = np.empty((xi.size, degree + 1))
    for j in range(degree + 1):
        coef = np.zeros(degree + 1)
        coef[j] = 1.0
        out[:, j] = np.polynomial.legendre.legval(xi, np.polynomial.legendre.legder(coef))
    return out


@dataclass
class _Rows:
    """The regression's rows of one or more logs (decimated moving samples)."""

    log: np.ndarray
    xi: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    force: np.ndarray
    pressure: np.ndarray
    cluster: np.ndarray
    steady: np.ndarray
    acceleration_noise: np.ndarray


def _rows(signals: Sequence[FieldSignals], ranges, options) -> _Rows:
    parts = []
    offset = 0
    for k, s in enumerate(signals):
        step = max(1, int(round(options["decimate"] * s.rate)))
        take = np.flatnonzero((s.stroke >= 0) & s.usable)[::1]
        take = take[take % step == 0]
        lo, hi = ranges[k]
        xi = (2 * s.position[take] - (lo + hi)) / (hi - lo)
        parts.append(
            (
                np.full(take.size, k),
                xi,
                s.velocity[take],
                s.acceleration[take],
                s.force[take],
                s.pressure[take],
                s.stroke[take] + offset,
                s.steady[take],
                np.full(take.size, s.acceleration_noise),
            )
        )
        offset += int(s.stroke.max()) + 1 if s.stroke.size else 0
    cat = [np.concatenate(p) for p in zip(*parts, strict=True)]
    return _Rows(*cat)


def _design(rows: _Rows, n_logs, ranges, load_degree, mass_degree, friction_cols):
    """Columns: per log load (Legendre), per log mass (with 1/2 m' v^2), then friction."""
    n = rows.xi.size
    nl, nm = load_degree + 1, mass_degree + 1
    k = n_logs * (nl + nm) + len(friction_cols)
    X = np.zeros((n, k))
    basis_l = _legendre(rows.xi, load_degree)
    basis_m = _legendre(rows.xi, mass_degree)
    dbasis_m = _legendre_derivative(rows.xi, mass_degree)
    for j in range(n_logs):
        sel = rows.log == j
        lo, hi = ranges[j]
        dxi_dx = 2.0 / (hi - lo)
        c0 = j * (nl + nm)
        X[sel, c0 : c0 + nl] = basis_l[sel]
        a = rows.acceleration[sel][:, None]
        v2 = rows.velocity[sel][:, None] ** 2
        X[sel, c0 + nl : c0 + nl + nm] = basis_m[sel] * a + 0.5 * dbasis_m[sel] * dxi_dx * v2
    sign = np.sign(rows.velocity)
    for i, name in enumerate(friction_cols):
        col = {"F_c": sign, "F_v": rows.velocity, "k_p": sign * rows.pressure}[name]
        X[:, n_logs * (nl + nm) + i] = col
    return X


def _speed_bands(speed, ratio, min_samples):
    """Band edges grouping steady speeds [m/s]: a new band beyond ``ratio`` x its start."""
    values = np.sort(speed)
    if values.size == 0:
        return []
    # histogram peaks in log speed: split where the gap between sorted speeds is widest
    bands = []
    start = 0
    for i in range(1, values.size + 1):
        if i == values.size or values[i] > ratio * values[start]:
            if i - start >= min_samples:
                bands.append((float(values[start]), float(values[i - 1])))
            start = i
    return bands


def cross_check(signals: Sequence[FieldSignals], ranges, options) -> list[dict[str, Any]]:
    """Model-free friction per speed band: (F_ext - F_ret) / 2 at equal position, speed band
    and log, averaged over the position bins where both directions were steady; standard
    error by a delete-one-stroke jackknife. Rows: ``speed [m/s]`` (mean of the band),
    ``friction [N]``, ``stderr [N]``, ``cells``, ``strokes``."""
    nb = options["position_bins"]
    speeds, logs, bins, dirs, forces, strokes, chambers = [], [], [], [], [], [], []
    for k, s in enumerate(signals):
        idx = np.flatnonzero(s.steady)
        lo, hi = ranges[k]
        b = np.clip(((s.position[idx] - lo) / (hi - lo) * nb).astype(int), 0, nb - 1)
        speeds.append(np.abs(s.velocity[idx]))
        logs.append(np.full(idx.size, k))
        bins.append(b)
        dirs.append((s.velocity[idx] > 0).astype(int))
        forces.append(s.force[idx])
        strokes.append(s.stroke[idx] + k * 10_000_000)
        chambers.append(np.column_stack((s.pressure_a[idx], s.pressure_b[idx])))
    if not speeds:
        return []
    speed = np.concatenate(speeds)
    if speed.size == 0:
        return []
    log, pbin, direction = np.concatenate(logs), np.concatenate(bins), np.concatenate(dirs)
    force, stroke = np.concatenate(forces), np.concatenate(strokes)
    chamber = np.concatenate(chambers)
    out = []
    for lo_v, hi_v in _speed_bands(speed, options["band_ratio"], options["min_band_samples"]):
        sel = (speed >= lo_v) & (speed <= hi_v)
        cell = (log[sel] * nb + pbin[sel]) * 2 + direction[sel]
        ncell = len(signals) * nb * 2
        _, sid = np.unique(stroke[sel], return_inverse=True)
        g = sid.max() + 1
        total = np.bincount(cell, force[sel], ncell)
        count = np.bincount(cell, minlength=ncell).astype(float)
        per_stroke_sum = np.zeros((g, ncell))
        per_stroke_n = np.zeros((g, ncell))
        np.add.at(per_stroke_sum, (sid, cell), force[sel])
        np.add.at(per_stroke_n, (sid, cell), 1.0)
        n_ext = np.unique(sid[direction[sel] == 1]).size
        n_ret = np.unique(sid[direction[sel] == 0]).size
        if min(n_ext, n_ret) < options["min_strokes"]:
            continue

        def level(tot, cnt):
            ext, ret = tot[..., 1::2], tot[..., 0::2]
            ce, cr = cnt[..., 1::2], cnt[..., 0::2]
            both = (ce > 0) & (cr > 0)
            w = np.where(both, np.minimum(ce, cr), 0.0)
            with np.errstate(invalid="ignore", divide="ignore"):
                f = np.where(
                    both, (ext / np.where(ce > 0, ce, 1) - ret / np.where(cr > 0, cr, 1)) / 2, 0
                )
                return (w * f).sum(axis=-1) / w.sum(axis=-1), both.sum(axis=-1)

        f_all, cells = level(total, count)
        if not cells or not np.isfinite(f_all):
            continue
        f_jack, _ = level(total[None, :] - per_stroke_sum, count[None, :] - per_stroke_n)
        f_jack = f_jack[np.isfinite(f_jack)]
        m = f_jack.size
        se = math.sqrt((m - 1) / m * np.sum((f_jack - f_jack.mean()) ** 2)) if m > 1 else math.nan
        out.append(
            {
                "speed [m/s]": float(np.mean(speed[sel])),
                "speed low [m/s]": lo_v,
                "speed high [m/s]": hi_v,
                "friction [N]": float(f_all),
                "stderr [N]": se,
                "cells": int(cells),
                "strokes": int(g),
                "pressure_a [Pa]": float(np.median(chamber[sel, 0])),
                "pressure_b [Pa]": float(np.median(chamber[sel, 1])),
            }
        )
    return out


@dataclass
class FieldFit:
    """What :func:`fit_field` found (SI). ``to_dict()`` is the field.json record."""

    parameters: dict[str, float | None]
    stderr: dict[str, float | None]
    status: dict[str, str]
    covariance: np.ndarray
    friction_names: list[str]
    cross_check: list[dict[str, Any]]
    selection: dict[str, Any]
    flags: list[str]
    notes: list[str]
    level: float
    reference_speed: float
    rmse: float
    identified: bool
    force_check: dict[str, list[float]] = field(default_factory=dict)
    # filled by fit_field once the friction is identified (empty until then)
    loads: list[dict[str, Any]] = field(default_factory=list)
    masses: list[dict[str, Any]] = field(default_factory=list)
    bands: list[dict[str, Any]] = field(default_factory=list)
    days: list[dict[str, Any]] = field(default_factory=list)
    changes: list[dict[str, Any]] = field(default_factory=list)
    reproducibility: dict[str, Any] = field(default_factory=dict)

    def friction(self, velocity, pressure=None) -> np.ndarray:
        """The identified friction law at ``velocity`` [m/s] (and mean pressure [Pa])."""
        v = np.asarray(velocity, dtype=float)
        p = np.zeros_like(v) if pressure is None else np.asarray(pressure, dtype=float)
        prm = {k: (0.0 if val is None else val) for k, val in self.parameters.items()}
        return np.sign(v) * (prm["F_c"] + prm["k_p"] * p) + prm["F_v"] * v

    def friction_band(self, velocity, pressure=None, level=None):
        """(friction, half width) of the ``level`` band of the law at ``velocity`` [m/s]."""
        v = np.atleast_1d(np.asarray(velocity, dtype=float))
        p = np.zeros_like(v) if pressure is None else np.asarray(pressure, dtype=float)
        cols = {"F_c": np.sign(v), "F_v": v, "k_p": np.sign(v) * p}
        J = np.column_stack([cols[n] for n in self.friction_names])
        var = np.einsum("ij,jk,ik->i", J, self.covariance, J)
        z = _normal_quantile(0.5 + (level or self.level) / 2)
        return self.friction(v, p), z * np.sqrt(np.maximum(var, 0))

    def to_dict(self) -> dict[str, Any]:
        law = {
            name: {
                "value": self.parameters[name],
                "stderr": self.stderr[name],
                "unit": PARAMETER_UNITS[name],
                "status": self.status[name],
            }
            for name in ("F_c", "F_v", "k_p")
        }
        return {
            "friction": {
                "law": "coulomb_viscous",
                "form": "F = sign(v) (F_c + k_p p_mean) + F_v v",
                "identified": self.identified,
                "parameters": law,
                "direction_asymmetry": self.status["asymmetry"],
                "level": self.level,
                "reference speed [m/s]": self.reference_speed,
                "bands": self.bands,
            },
            "cross_check": self.cross_check,
            "load": self.loads,
            "effective_mass": self.masses,
            "trend": {
                "days": self.days,
                "changes": self.changes,
                "reproducibility": self.reproducibility,
            },
            "selection": self.selection,
            "flags": self.flags,
            "notes": self.notes,
            "rmse [N]": self.rmse,
        }


def _normal_quantile(q):
    from scipy.special import ndtri

    return float(ndtri(q))


def _solve(rows, n_logs, ranges, o, names):
    """Least squares by normal equations accumulated log by log (each log's load and mass
    columns are its own, the friction columns shared), so the memory is one log's design;
    pinv of the column-scaled Gram matrix. Returns (vif, coef, residual, cov, clusters):
    ``vif(j)`` the variance inflation of column j, the covariance CR1 by stroke."""
    nl, nm, nf = o["load_degree"] + 1, o["mass_degree"] + 1, len(names)
    per_log = nl + nm
    k = n_logs * per_log + nf
    gram = np.zeros((k, k))
    rhs = np.zeros(k)
    total = np.zeros(k)
    square = np.zeros(k)
    blocks = []
    bounds = np.searchsorted(rows.log, np.arange(n_logs + 1))  # rows are in log order
    for j in range(n_logs):
        part = slice(bounds[j], bounds[j + 1])
        sub = _Rows(*(getattr(rows, f)[part] for f in _Rows.__dataclass_fields__))
        sub.log = np.zeros(sub.xi.size, dtype=int)
        D = _design(sub, 1, [ranges[j]], o["load_degree"], o["mass_degree"], names)
        index = np.r_[j * per_log : (j + 1) * per_log, n_logs * per_log : k]
        local = D.T @ D
        if o.get("errors_in_variables", True) and sub.xi.size:
            # E[(P a_measured)'(P a_measured)] = (P a)'(P a) + var_a P'P: take the noise out
            basis = _legendre(sub.xi, o["mass_degree"])
            correction = float(sub.acceleration_noise[0]) * (basis.T @ basis)
            block = slice(nl, nl + nm)
            corrected = local[block, block] - correction
            if np.all(
                np.linalg.eigvalsh(corrected) > 0.1 * np.linalg.eigvalsh(local[block, block]).min()
            ):
                local[block, block] = corrected
        gram[np.ix_(index, index)] += local
        rhs[index] += D.T @ sub.force
        total[index] += D.sum(axis=0)
        square[index] += np.einsum("ij,ij->j", D, D)
        blocks.append((part, D, index))
    scale = np.sqrt(np.diag(gram)).copy()
    scale[scale == 0] = 1.0
    bread = np.linalg.pinv(gram / np.outer(scale, scale))
    coef = (bread @ (rhs / scale)) / scale
    residual = np.empty(rows.force.size)
    scores = []
    for part, D, index in blocks:
        r = rows.force[part] - D @ coef[index]
        residual[part] = r
        cluster = rows.cluster[part]
        if cluster.size == 0:
            continue
        starts = np.flatnonzero(np.diff(cluster, prepend=cluster[0] - 1))
        local = np.add.reduceat(D * r[:, None], starts, axis=0) / scale[index]
        full = np.zeros((local.shape[0], k))
        full[:, index] = local
        scores.append(full)
    S = np.concatenate(scores) if scores else np.zeros((0, k))
    g, n = S.shape[0], rows.force.size
    factor = g / max(g - 1, 1) * (n - 1) / max(n - k, 1)
    cov = factor * bread @ (S.T @ S) @ bread / np.outer(scale, scale)

    def vif(column):
        centred = square[column] - total[column] ** 2 / max(n, 1)
        return float(centred * bread[column, column] / scale[column] ** 2)

    return vif, coef, residual, cov, g


def _pressure_independent_spread(rows, n_logs, degree):
    """Spread (5-95 %) of the mean pressure not explained by position, per log and direction
    (Pa): what a pressure slope could be identified from."""
    spreads = []
    for j in range(n_logs):
        for d in (-1, 1):
            sel = (rows.log == j) & (np.sign(rows.velocity) == d) & rows.steady
            if np.count_nonzero(sel) < 50:
                continue
            B = _legendre(rows.xi[sel], degree)
            beta, *_ = np.linalg.lstsq(B, rows.pressure[sel], rcond=None)
            r = rows.pressure[sel] - B @ beta
            q = np.quantile(r, [0.05, 0.95])
            spreads.append(float(q[1] - q[0]))
    return max(spreads) if spreads else 0.0


def _fit_block(signals, ranges, o, names):
    rows = _rows(signals, ranges, o)
    vif, coef, residual, cov, clusters = _solve(rows, len(signals), ranges, o, names)
    return rows, vif, coef, residual, cov, clusters


def fit_field(
    records: Sequence[FieldRecord], config: FieldConfig, options: dict[str, Any] | None = None
) -> FieldFit:
    """Identify load curves, effective masses and the friction law from machine logs.

    Parameters
    ----------
    records : sequence of FieldRecord
        The logs (:func:`cylfric.io.fieldlog.read_field_logs`); one payload per log.
    config : FieldConfig
        Areas, orientation, sensors, fit options (``[fit]``).
    options : dict, optional
        Overrides of :data:`DEFAULTS`.

    Returns
    -------
    FieldFit
    """
    if not records:
        raise ValueError("no logs given; expected at least one")
    from threadpoolctl import threadpool_limits

    # tall, narrow matrices: BLAS threads only contend (as in identify.steady)
    with threadpool_limits(limits=1, user_api="blas"):
        return _fit_field(records, config, options)


def _fit_field(records, config, options) -> FieldFit:
    o = {**DEFAULTS, **config.fit, **(options or {})}
    notes: list[str] = []
    signals = _prepare_all(records, config, o, notes)
    flags = list(dict.fromkeys(n for s in signals for n in s.notes))
    ranges = []
    for s in signals:
        moving = s.position[(s.stroke >= 0) & s.usable]
        if moving.size < 100:
            moving = s.position
        lo, hi = np.quantile(moving, [0.01, 0.99])  # the logged stroke
        ranges.append((float(lo), float(max(hi, lo + 1e-3))))
    status = {
        "F_c": "identified",
        "F_v": "identified",
        "k_p": "identified",
        "asymmetry": "not identified: without a load cell the load is known only through "
        "the mean of extension and retraction, so only the friction's mean over the two "
        "directions is identified (symmetric law assumed)",
    }
    # a log counts if it moved both ways with chamber pressures valid in both
    kept, ranges_kept, dropped = [], [], []
    for s, r in zip(signals, ranges, strict=True):
        moving = s.stroke >= 0
        use = moving & s.usable
        ext, ret = use & (s.velocity > 0), use & (s.velocity < 0)
        n_ext, n_ret = np.unique(s.stroke[ext]).size, np.unique(s.stroke[ret]).size
        if min(n_ext, n_ret) >= o["min_strokes"]:
            lo = max(np.min(s.position[ext]), np.min(s.position[ret]))
            hi = min(np.max(s.position[ext]), np.max(s.position[ret]))
            if hi - lo >= 0.5 * (r[1] - r[0]):
                kept.append(s)
                ranges_kept.append(r)
            else:
                dropped.append(
                    f"{s.name}: extension and retraction overlap over {1e3 * max(hi - lo, 0):.3g}"
                    f" mm of {1e3 * (r[1] - r[0]):.3g} mm (needs half the logged stroke)"
                )
        elif min(n_ext, n_ret) > 0:
            dropped.append(
                f"{s.name}: {n_ext} extension and {n_ret} retraction strokes with chamber "
                f"pressures (needs {o['min_strokes']} each)"
            )
        elif np.any(s.velocity[moving] > 0) and np.any(s.velocity[moving] < 0):
            dropped.append(
                f"{s.name}: chamber pressures valid in one direction only (a sensor on the "
                "valve side of a load-holding valve)"
            )
        else:
            dropped.append(f"{s.name}: no motion in both directions above the minimum speed")
    notes.extend(f"{d}; not used" for d in dropped)
    steady_speed = np.concatenate([np.abs(s.velocity[s.steady]) for s in signals])
    reference = float(np.median(steady_speed)) if steady_speed.size else math.nan
    selection = {
        "samples": int(sum(s.time.size for s in signals)),
        "moving": int(sum(np.count_nonzero(s.stroke >= 0) for s in signals)),
        "steady": int(sum(np.count_nonzero(s.steady) for s in signals)),
        "strokes": int(sum(int(s.stroke.max()) + 1 for s in signals if s.stroke.size)),
        "valve steps": int(sum(s.steps for s in signals)),
        "logs": [
            {
                "log": s.name,
                "day": s.day,
                "samples": int(s.time.size),
                "rate [Hz]": s.rate,
                "steady": int(np.count_nonzero(s.steady)),
                "position range [m]": sorted(
                    (1.0 if config.extension == "position increases" else -1.0) * r
                    for r in ranges[k]
                ),
            }
            for k, s in enumerate(signals)
        ],
    }
    if not kept:
        reason = (
            "not identified: the friction needs both directions at equal position with "
            "chamber pressures; " + "; ".join(dropped)
        )
        for name in ("F_c", "F_v", "k_p"):
            status[name] = reason
        return FieldFit(
            parameters=dict.fromkeys(("F_c", "F_v", "k_p")),
            stderr=dict.fromkeys(("F_c", "F_v", "k_p")),
            status=status,
            covariance=np.zeros((0, 0)),
            friction_names=[],
            cross_check=[],
            selection=selection,
            flags=flags,
            notes=notes,
            level=o["level"],
            reference_speed=reference,
            rmse=math.nan,
            identified=False,
        )
    signals, ranges = kept, ranges_kept
    steady_speed = np.concatenate([np.abs(s.velocity[s.steady]) for s in signals])
    reference = float(np.median(steady_speed)) if steady_speed.size else math.nan
    names = ["F_c", "F_v", "k_p"]
    # speed dependence: identified only over a range of speeds
    if steady_speed.size:
        q10, q90 = np.quantile(steady_speed, [0.1, 0.9])
    else:
        q10 = q90 = math.nan
    if not (q90 / q10 >= o["speed_ratio"]):
        names.remove("F_v")
        status["F_v"] = (
            f"not identified: the steady speeds span {1e3 * q10:.3g}-{1e3 * q90:.3g} mm/s "
            f"(ratio below {o['speed_ratio']}); the machine ran at one speed, so F_c is the "
            "friction level at that speed"
        )
    rows = _rows(signals, ranges, o)
    spread = _pressure_independent_spread(rows, len(signals), o["load_degree"])
    if spread < o["pressure_spread"]:
        names.remove("k_p")
        status["k_p"] = (
            f"not identified: within each log the pressure follows the position (the load; "
            f"spread at a given position {spread / 1e5:.2g} bar, below "
            f"{o['pressure_spread'] / 1e5:.3g} bar) and changes otherwise only between logs, "
            "where a pressure slope cannot be told from a change of friction between logs or "
            "from a friction that changes along the stroke"
        )
    vif_of, coef, residual, cov, clusters = _solve(rows, len(signals), ranges, o, names)
    nf = len(names)
    if "k_p" in names:
        vif = vif_of(coef.size - nf + names.index("k_p"))
        if vif > o["vif_limit"]:
            names.remove("k_p")
            status["k_p"] = (
                f"not identified: the pressure is confounded with the load and the direction "
                f"(variance inflation {vif:.3g} > {o['vif_limit']:g})"
            )
            _, coef, residual, cov, clusters = _solve(rows, len(signals), ranges, o, names)
            nf = len(names)
    friction_cov = cov[-nf:, -nf:]
    # systematic part: the same fit with a lower cut-off (0.7x); the change of the friction
    # coefficients is the filter's bias scale, added as a covariance outer(d, d)
    low = {**o, "cutoff": o["cutoff"] * o["cutoff_check"]}
    by_name = {s.name: s for s in _prepare_all(records, config, low, None)}
    if all(s.name in by_name for s in signals):  # the same logs and segments
        signals_low = [by_name[s.name] for s in signals]
        rows_low = _rows(signals_low, ranges, low)
        coef_low = _solve(rows_low, len(signals), ranges, low, names)[1]
        systematic = coef[-nf:] - coef_low[-nf:]
        del signals_low, rows_low
    else:
        systematic = np.zeros(nf)
        notes.append("the filter's systematic part of the band is not computed (segments differ)")
    del by_name
    # and the errors-in-variables correction of the mass: the fit without it, the same way
    plain = _solve(rows, len(signals), ranges, {**o, "errors_in_variables": False}, names)[1]
    attenuation = coef[-nf:] - plain[-nf:]
    friction_cov = (
        friction_cov + np.outer(systematic, systematic) + np.outer(attenuation, attenuation)
    )
    parameters: dict[str, float | None] = dict.fromkeys(("F_c", "F_v", "k_p"))
    stderr: dict[str, float | None] = dict.fromkeys(("F_c", "F_v", "k_p"))
    for i, name in enumerate(names):
        parameters[name] = float(coef[-nf + i])
        stderr[name] = float(math.sqrt(max(friction_cov[i, i], 0.0)))
    if "F_v" not in names:
        parameters["F_v"] = None
    if "k_p" not in names:
        parameters["k_p"] = None
    fit = FieldFit(
        parameters=parameters,
        stderr=stderr,
        status=status,
        covariance=friction_cov,
        friction_names=names,
        cross_check=cross_check(signals, ranges, o),
        selection=selection,
        flags=flags,
        notes=notes,
        level=o["level"],
        reference_speed=reference,
        rmse=float(np.sqrt(np.mean(residual**2))),
        force_check=_force_sample(rows, residual),
        identified=True,
    )
    sign = 1.0 if config.extension == "position increases" else -1.0
    fit.loads, fit.masses = _curves(coef, cov, signals, ranges, o, sign)
    fit.bands = _bands(fit)
    _compare_cross_check(fit)
    fit.days, fit.changes, fit.reproducibility = _trend(signals, ranges, o, names, reference)
    if any(c["significant"] for c in fit.changes):
        notes.append(
            "the friction changed between days (trend): the law above is the mean over all "
            "logs; the per-day levels are in the trend"
        )
    for s in signals:
        if s.rate < 20:
            notes.append(f"{s.name}: logged at {s.rate:.3g} Hz; accelerations need >= 20 Hz")
    return fit


def _force_sample(rows, residual, n=4000):
    """Measured and predicted piston force [N] at up to ``n`` regression rows (evenly)."""
    take = np.linspace(0, rows.force.size - 1, min(n, rows.force.size)).astype(int)
    return {
        "measured [N]": rows.force[take].tolist(),
        "predicted [N]": (rows.force[take] - residual[take]).tolist(),
    }


def _curves(coef, cov, signals, ranges, o, sign=1.0):
    nl, nm = o["load_degree"] + 1, o["mass_degree"] + 1
    z = _normal_quantile(0.5 + o["level"] / 2)
    loads, masses = [], []
    for j, s in enumerate(signals):
        lo, hi = ranges[j]
        x = np.linspace(lo, hi, 41)
        xi = (2 * x - (lo + hi)) / (hi - lo)
        c0 = j * (nl + nm)
        B = _legendre(xi, o["load_degree"])
        load = B @ coef[c0 : c0 + nl]
        var = np.einsum("ij,jk,ik->i", B, cov[c0 : c0 + nl, c0 : c0 + nl], B)
        M = _legendre(xi, o["mass_degree"])
        mass = M @ coef[c0 + nl : c0 + nl + nm]
        mvar = np.einsum("ij,jk,ik->i", M, cov[c0 + nl : c0 + nl + nm, c0 + nl : c0 + nl + nm], M)
        loads.append(
            {
                "log": s.name,
                "position [m]": (sign * x).tolist(),
                "load [N]": load.tolist(),
                "band [N]": (z * np.sqrt(np.maximum(var, 0))).tolist(),
            }
        )
        masses.append(
            {
                "log": s.name,
                "position [m]": (sign * x).tolist(),
                "mass [kg]": mass.tolist(),
                "band [kg]": (z * np.sqrt(np.maximum(mvar, 0))).tolist(),
            }
        )
    return loads, masses


def _bands(fit: FieldFit) -> list[dict[str, Any]]:
    """The law with its band at the cross-check's speed bands (or the reference speed)."""
    speeds = [c["speed [m/s]"] for c in fit.cross_check] or [fit.reference_speed]
    rows = []
    for v in speeds:
        for sign, direction in ((1, "extension"), (-1, "retraction")):
            f, half = fit.friction_band(np.array([sign * v]))
            rows.append(
                {
                    "direction": direction,
                    "speed [m/s]": v,
                    "friction [N]": float(abs(f[0])),
                    "band [N]": float(half[0]),
                }
            )
    return rows


def _compare_cross_check(fit: FieldFit) -> None:
    for c in fit.cross_check:
        model = float(abs(fit.friction(np.array([c["speed [m/s]"]]))[0]))
        c["model [N]"] = model
        c["difference [%]"] = 100 * (c["friction [N]"] - model) / model if model else math.nan


def _trend(signals, ranges, o, names, reference):
    """Friction level per day at the reference speed, with band, and the change tests."""
    days: dict[str, list[int]] = {}
    for k, s in enumerate(signals):
        days.setdefault(s.day, []).append(k)
    z = _normal_quantile(0.5 + o["level"] / 2)
    out = []
    for day, members in days.items():
        sub = [signals[k] for k in members]
        sub_ranges = [ranges[k] for k in members]
        day_names = list(names)
        speeds = np.concatenate([np.abs(s.velocity[s.steady]) for s in sub])
        if "F_v" in day_names and (
            speeds.size == 0
            or np.quantile(speeds, 0.9) / np.quantile(speeds, 0.1) < o["speed_ratio"]
        ):
            day_names.remove("F_v")
        both = all(
            np.any(s.velocity[(s.stroke >= 0) & s.usable] > 0)
            and np.any(s.velocity[(s.stroke >= 0) & s.usable] < 0)
            for s in sub
        )
        if not both:
            continue
        rows, _, coef, residual, cov, _ = _fit_block(sub, sub_ranges, o, day_names)
        nf = len(day_names)
        J = np.array([{"F_c": 1.0, "F_v": reference, "k_p": 0.0}[n] for n in day_names])
        if "k_p" in day_names:
            J[day_names.index("k_p")] = float(np.median(rows.pressure))
        level = float(J @ coef[-nf:])
        se = float(math.sqrt(max(J @ cov[-nf:, -nf:] @ J, 0.0)))
        out.append(
            {
                "day": day,
                "logs": [signals[k].name for k in members],
                "friction [N]": level,
                "stderr [N]": se,
                "band [N]": z * se,
                "speed [m/s]": reference,
            }
        )
    repro = _reproducibility(out, o)
    tau = repro["between-day [N]"]
    zc = _normal_quantile(0.5 + o["change_level"] / 2)
    changes = []
    pairs = [(0, i) for i in range(1, len(out))]
    pairs += [(i - 1, i) for i in range(2, len(out))]
    for a, b in pairs:
        da, db = out[a], out[b]
        change = db["friction [N]"] - da["friction [N]"]
        se = math.sqrt(da["stderr [N]"] ** 2 + db["stderr [N]"] ** 2 + 2 * tau**2)
        zval = change / se if se > 0 else math.nan
        changes.append(
            {
                "from": da["day"],
                "to": db["day"],
                "change [N]": change,
                "change [%]": 100 * change / da["friction [N]"],
                "stderr [N]": se,
                "z [-]": zval,
                "significant": bool(abs(zval) > zc),
            }
        )
    return out, changes, repro


def _reproducibility(days, o) -> dict[str, Any]:
    """Between-day scatter of the friction level [N]: stated (relative), or from the
    successive differences of >= 4 days (von Neumann: robust to a slow trend)."""
    if o.get("reproducibility") is not None:
        mean = float(np.mean([d["friction [N]"] for d in days])) if days else math.nan
        return {
            "between-day [N]": o["reproducibility"] * mean,
            "source": f"stated: {100 * o['reproducibility']:.3g} % ([fit] reproducibility)",
            "change level": o["change_level"],
        }
    if len(days) >= 4:
        level = np.array([d["friction [N]"] for d in days])
        se = np.array([d["stderr [N]"] for d in days])
        mssd = float(np.mean(np.diff(level) ** 2) / 2)
        tau2 = max(0.0, mssd - float(np.mean(se**2)))
        return {
            "between-day [N]": math.sqrt(tau2),
            "source": f"estimated from {len(days)} days (mean square successive difference "
            "less the within-day variance)",
            "change level": o["change_level"],
        }
    return {
        "between-day [N]": 0.0,
        "source": f"not estimable from {len(days)} day(s) (needs 4); the tests use the "
        "within-day bands alone; state [fit] reproducibility to include it",
        "change level": o["change_level"],
    }


def compare_datasheet(fit: FieldFit, model: Any, *, level: float | None = None) -> dict[str, Any]:
    """The in-service friction against a seal datasheet at the machine's operating points.

    Operating points: the cross-check's speed bands, each at the median logged chamber
    pressures of its steady samples (combined by the datasheet's own pressure reference).
    At each: the datasheet's friction and its session-scope prediction band (a new mount of
    the seal, :meth:`cylfric.model.FrictionModel.prediction_band`), the in-service law and its
    band, the difference and a verdict: ``"as the datasheet"`` when the difference is inside
    the combined band, else ``"above the datasheet"`` / ``"below the datasheet"``.

    Parameters
    ----------
    fit : FieldFit
        An identified field fit.
    model : cylfric.model.FrictionModel
        The seal's datasheet (of this cylinder's size: the catalogue's size rule is not
        applied here).
    level : float, optional
        Two-sided level of the bands [-] (default: the fit's).

    Returns
    -------
    dict
        ``points`` (one row per operating point), ``verdict`` (over the points) and ``notes``.
    """
    import warnings

    level = level or fit.level
    z = _normal_quantile(0.5 + level / 2)
    points: list[dict[str, Any]] = []
    notes: list[str] = []
    if not fit.identified or not fit.cross_check:
        return {
            "points": [],
            "verdict": "not compared: the in-service friction is not identified",
            "notes": notes,
        }
    for c in fit.cross_check:
        v = c["speed [m/s]"]
        pressure = float(model.operating_pressure(c["pressure_a [Pa]"], c["pressure_b [Pa]"]))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sheet = float(model.friction(v, pressure))
            lower = upper = np.array([sheet])
            for scope in ("session", "point"):  # a new mount of the seal; else a new point
                try:
                    lower, upper = model.prediction_band(
                        np.array([v]), np.array([pressure]), level, scope=scope
                    )
                except ValueError as exc:  # a datasheet without scatter or covariance
                    notes.append(f"no {scope}-scope band from the datasheet: {exc}")
                    continue
                break
        if caught:
            notes.append(f"at {1e3 * v:.3g} mm/s, {pressure / 1e5:.3g} bar: {caught[0].message}")
        sheet_half = float(upper[0] - lower[0]) / 2
        service, half = fit.friction_band(np.array([v]), level=level)
        service_value, service_half = float(abs(service[0])), float(half[0])
        difference = service_value - sheet
        combined = math.hypot(sheet_half, service_half)
        verdict = (
            "as the datasheet"
            if abs(difference) <= combined
            else ("above the datasheet" if difference > 0 else "below the datasheet")
        )
        points.append(
            {
                "speed [m/s]": v,
                "pressure [Pa]": pressure,
                "datasheet [N]": sheet,
                "datasheet band [N]": sheet_half,
                "in service [N]": service_value,
                "in service band [N]": service_half,
                "difference [N]": difference,
                "difference [%]": 100 * difference / sheet if sheet else math.nan,
                "z [-]": z * difference / combined if combined > 0 else math.nan,
                "verdict": verdict,
            }
        )
    verdicts = {p["verdict"] for p in points}
    overall = (
        verdicts.pop()
        if len(verdicts) == 1
        else "mixed: "
        + ", ".join(f"{p['verdict']} at {1e3 * p['speed [m/s]']:.3g} mm/s" for p in points)
    )
    notes = list(dict.fromkeys(notes))
    return {"points": points, "verdict": overall, "notes": notes, "level": level}
