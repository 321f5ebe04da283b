"""Virtual test bench: the thesis experiment (ch. 3) as a simulation that writes raw files.

A testing machine (MTS 858 Mini Bionix) drives the rod of a symmetric cylinder whose two
chambers sit at the same pressure: descend the stroke, then ascend, at constant speed, with a
trapezoidal velocity reference (finite acceleration) followed through a first-order servo
lag. The load cell reads (eq. 3.1 with A1 p1 = A2 p2)::

    F_l = m x'' + F_f(v, z, p) + F_cushion(x, v) + W + noise (+ rare spikes)

``W`` is the constant weight offset: the thesis saw the descending curves 35.67 N below the
ascending ones (Fig. 4.3), i.e. ``W = 35.67 / 2`` N in this signed reading. Friction is the
dynamic LuGre model with the pressure laws, integrated with the exact z update.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from ..io.campaign import DYNAMIC_TESTS
from ..io.writers import write_manifest, write_mts_text
from . import kernels
from .plant import THESIS_CYLINDER, Cylinder, FrictionModel

if TYPE_CHECKING:
    from collections.abc import Callable, Iterable, Mapping, Sequence

    from numpy.typing import ArrayLike

    from cylfric._typing import StrPath

__all__ = [
    "BenchSettings",
    "VirtualRun",
    "run_virtual_test",
    "generate_campaign",
    "THESIS_PRESSURES_BAR",
    "THESIS_SPEEDS_MM_S",
    "run_file_name",
    "TESTS",
    "DYNAMIC_TESTS",
    "DynamicTestSettings",
    "DynamicRun",
    "run_dynamic_test",
    "generate_dynamic_tests",
    "write_test_manifest",
    "run_plan",
    "draw_truth",
    "truth_check",
    "TRUTH_COLUMNS",
]

THESIS_PRESSURES_BAR = (0.1, 20.7, 38.0, 55.0, 69.0, 83.0, 103.0, 124.0, 141.0, 159.0)
"""Ten pressure levels 0.1-159 bar [bar]: the thesis' first two (0.1, 20.7) and the four of
Table 4.1 (55, 83, 124, 159); the other four are spread between them."""

THESIS_SPEEDS_MM_S = (
    1,
    2,
    3,
    4,
    5,
    6,
    7,
    8,
    10,
    12,
    15,
    18,
    20,
    25,
    30,
    35,
    40,
    45,
    50,
    60,
    70,
    80,
    90,
    100,
    110,
    120,
    135,
)
"""27 speeds 1-135 mm/s [mm/s], denser at low speed where the Stribeck dip lies."""

MAX_SAMPLES = 10_001
"""At most 10,001 samples per file, as the thesis' acquisition software allowed."""


@dataclass(frozen=True)
class BenchSettings:
    """Everything the virtual bench needs (SI units unless the name says otherwise).

    The friction default is the thesis law (eq. 4.1-4.3, alpha = 1, v_r = 10 mm/s) with
    ``sigma_0 = 1e6 N/m`` (presliding deflection F_s/sigma_0 of about 0.1 mm, typical of
    hydraulic seals) and ``sigma_1 = sqrt(sigma_0 m)`` = 1.58e3 N*s/m for m = 2.5 kg
    (critically damped bristles); the thesis does not identify them.

    **Rough by default** (issue 22; :meth:`clean` turns it all off, bit for bit the earlier
    bench). Levels measured on the shared Zillen O-ring257 repeatability data (3 sessions x
    1, 3, 5, 7 bar x 10 strokes; ``docs/bench_calibration.py``, docs/virtual_bench.md):

    * ``session_scatter`` 9 % and ``pressure_scatter`` 12 % (lognormal s.d.): the s.d. of a
      pressure's level between sessions is 8.4, 10.9, 17.6, 19.7 % (RMS 14.9 %); its split
      is weakly determined by 3 sessions (two-way ANOVA of ln level: session x pressure
      16.8 %, session 0 %, 2 d.o.f.; a MixedLM on the strokes: ~12 % run); 12 % goes to the
      block of runs at one pressure in one session, sqrt(14.9^2 - 12^2) = 9 % to the session.
    * ``stroke_scatter`` 1 %: the s.d. of one stroke's level about its file's linear drift
      is 1.0 % (median of both directions; 0.3-3.2 %); each stroke (direction) of a run
      draws its own multiplier from the noise stream (``seed``), so a new noise seed is a
      new stroke of the same run (the repeatability of a point).
    * ``run_scatter`` 3 %: a re-run of a file on the same mount is not in the shared data
      (one file per pressure and session); the stroke-pair levels inside a file scatter
      3.6 % (median; 0.8-9.1 %), most of it the drift: 3 % is an assumption inside the
      1-15 % real rigs show between runs.
    * ``warmup_amplitude`` 9 %: the level moves 1.1 %/stroke in a file (0.97 to 1.06 of the
      mean over 10 strokes, 12 files, t = 3.7); the sign is the thesis' (ch. 5: later, warmer
      runs gave lower friction; Zillen's pneumatic seal rose). ``warmup_time_constant``
      900 s and ``run_pause`` 30 s are assumptions (neither source gives a time scale).
    * ``startup_force_overshoot`` 0.7 x level, peak at ``startup_time_constant`` 40 ms: the
      force from rest peaks 0.69 x the level above it (median of 12 files) 30-50 ms after
      the start and is back within 10 % after 50 ms (median). ``startup_velocity_overshoot``
      8 %: median velocity overshoot at a stroke start (at the resolution of the position).
    * ``load_cell_offset_std`` 2.1 N: s.d. between sessions of (extend + retract)/2 - pA,
      0.111 N on a 5.83 N mean level (1.9 %), scaled to this bench's ~110 N mean F_c.
    * ``force_step`` 0.28 N, ``pressure_step`` 2.3 kPa, ``position_step`` 4 um: smallest
      value steps 0.015 N (0.26 % of the 5.83 N level, scaled to 110 N), 0.001 bar (of a
      7 bar range, scaled to 159 bar) and 0.004 mm (absolute).

    Seeds: session effects from ``session_seed``, run effects from ``run_seed``, noise from
    ``seed`` (see :func:`draw_truth`); the true multiplier of every run is returned.
    """

    cylinder: Cylinder = THESIS_CYLINDER
    friction: FrictionModel = field(default_factory=FrictionModel)
    pressures_bar: tuple = THESIS_PRESSURES_BAR
    speeds_mm_s: tuple = THESIS_SPEEDS_MM_S
    acceleration: float = 1.0  # [m/s^2] of the velocity reference
    servo_time_constant: float = 0.010  # [s], first-order lag of the machine
    dwell: float = 1.0  # [s] before, between and after the strokes
    stroke_margin: float = 0.002  # [m] kept from each end of the stroke
    cushion_length: float = 0.012  # [m] end-of-stroke cushioning zone
    cushion_coefficient: float = 2.0e4  # [N*s^2/m^2], force c v^2 at full engagement
    weight_offset: float = 35.67 / 2  # [N], W in the load-cell reading
    force_noise: float = 0.8  # [N], standard deviation
    position_noise: float = 2e-6  # [m], standard deviation
    pressure_noise: float = 0.3e5  # [Pa], standard deviation of a pressure channel
    spike_probability: float = 2e-4  # [-] per sample
    spike_amplitude: float = 150.0  # [N]
    slow_speed_count: int = 2  # the slowest speeds sampled at 20 ms, the rest at 10 ms
    slow_interval: float = 0.020  # [s]
    fast_interval: float = 0.010  # [s]
    internal_step: float = 1e-4  # [s], simulation step
    decimal_comma: bool = False
    force_unit: str = "kN"
    pressure_channel: bool = False
    crlf: bool = False
    seed: int = 0
    points: tuple | None = None  # explicit ((pressure [bar], speed [mm/s]), ...) in run order
    # --- roughness of a real rig (on by default; BenchSettings.clean() turns it all off) ---
    sessions: int = 1  # [-] sessions (remount, another day), each a full pass of the runs
    session_scatter: float = 0.09  # [-] s.d. of ln(friction multiplier) per session
    pressure_scatter: float = 0.12  # [-] s.d. of ln(multiplier) per pressure block/session
    run_scatter: float = 0.03  # [-] s.d. of ln(multiplier) per run (file)
    stroke_scatter: float = 0.010  # [-] s.d. of ln(multiplier) per stroke (one direction)
    warmup_amplitude: float = 0.09  # [-] extra friction of a cold rig (falls as it warms)
    warmup_time_constant: float = 900.0  # [s] of the exponential warm-up
    run_pause: float = 30.0  # [s] between two runs (elapsed time of the warm-up)
    startup_force_overshoot: float = 0.7  # [-] peak force transient / steady friction level
    startup_velocity_overshoot: float = 0.08  # [-] peak velocity overshoot / speed
    startup_time_constant: float = 0.04  # [s] rise time to the transient's peak
    load_cell_offset_std: float = 2.1  # [N] s.d. of the load-cell offset of a session
    force_step: float = 0.28  # [N] ADC step of the force channel (0: none)
    position_step: float = 4e-6  # [m] ADC step of the position channel (0: none)
    pressure_step: float = 2.3e3  # [Pa] ADC step of the pressure channel (0: none)
    session_seed: int | None = None  # seed of the session effects (None: ``seed``)
    run_seed: int | None = None  # seed of the run effects (None: ``seed``)

    ROUGH_FIELDS = (
        "session_scatter",
        "pressure_scatter",
        "run_scatter",
        "stroke_scatter",
        "warmup_amplitude",
        "startup_force_overshoot",
        "startup_velocity_overshoot",
        "load_cell_offset_std",
        "force_step",
        "position_step",
        "pressure_step",
    )
    """Settings a clean bench sets to 0 (see :meth:`clean`)."""

    def __post_init__(self) -> None:
        if not (isinstance(self.sessions, int) and self.sessions >= 1):
            raise ValueError(f"sessions = {self.sessions!r}; expected a whole number >= 1")
        for name in (*self.ROUGH_FIELDS, "run_pause"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"bench setting {name} = {value}; expected a number >= 0")
        for name in ("warmup_time_constant", "startup_time_constant"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"bench setting {name} = {value} s; expected a time > 0 s")

    @classmethod
    def clean(cls, **changes: Any) -> BenchSettings:
        """The clean bench of cylfric before issue 22: no session, pressure or run scatter,
        no warm-up, no start-up transient, no load-cell offset, no quantisation (the output
        is bit for bit that of the earlier bench). ``changes`` set any field, a rough one
        included (e.g. ``BenchSettings.clean(run_scatter=0.05)``)."""
        return cls(**{**dict.fromkeys(cls.ROUGH_FIELDS, 0.0), **changes})

    @property
    def is_clean(self) -> bool:
        """True when no roughness is on and there is one session: the files, their names
        and manifest.csv are those of the clean bench."""
        return self.sessions == 1 and not any(getattr(self, f) for f in self.ROUGH_FIELDS)

    def runs(self) -> tuple:
        """(pressure [bar], speed [mm/s]) of every run in run order: ``points`` when given,
        else the full grid ``pressures_bar`` x ``speeds_mm_s`` (pressure by pressure)."""
        if self.points is not None:
            return tuple((float(p), float(v)) for p, v in self.points)
        return tuple((p, v) for p in self.pressures_bar for v in self.speeds_mm_s)

    def slow_speeds(self) -> set:
        """Speeds [mm/s] sampled at ``slow_interval``: the slowest ``slow_speed_count``
        distinct speeds of the runs."""
        return set(sorted({v for _, v in self.runs()})[: self.slow_speed_count])


@dataclass(frozen=True)
class VirtualRun:
    """One simulated run with its ground truth.

    Attributes are arrays at the sample times: ``time`` [s], ``position`` [m],
    ``force`` [N] (load-cell reading with offset, noise, spikes), ``velocity`` [m/s] (true),
    ``friction`` [N] (true dynamic LuGre force), ``cushion`` [N], ``pressure`` [Pa],
    ``steady`` (bool: velocity settled within 1 % of nominal and no cushioning) and
    ``segment`` (0 descend, 1 ascend), plus the nominal ``pressure_nominal`` [Pa],
    ``speed`` [m/s] and ``sample_interval`` [s] and ``steps`` simulated.
    """

    time: np.ndarray
    position: np.ndarray
    force: np.ndarray
    velocity: np.ndarray
    friction: np.ndarray
    cushion: np.ndarray
    pressure: np.ndarray
    steady: np.ndarray
    segment: np.ndarray
    pressure_nominal: float
    speed: float
    sample_interval: float
    steps: int


@njit(cache=True, nogil=True)
def _bench_kernel(
    h,
    n_sub,
    n_samples,
    x_top,
    speed,
    accel,
    dwell,
    length,
    tau,
    stroke,
    cushion_len,
    cushion_coef,
    sigma_0,
    sigma_1,
    F_c,
    F_s,
    sigma_2,
    v_r,
    alpha,
    overshoot=0.0,
    settle_tau=1.0,
):
    t_acc = speed / accel
    t_move = length / speed + t_acc  # trapezoid: accelerate, cruise, decelerate
    starts = (dwell, 2 * dwell + t_move)
    out = np.empty((7, n_samples))
    x = x_top
    v = 0.0
    z = 0.0
    lag = -math.expm1(-h / tau)
    for i in range(n_samples):
        for j in range(n_sub if i > 0 else 0):
            t = ((i - 1) * n_sub + j + 0.5) * h
            v_ref = 0.0
            for seg in range(2):
                s = t - starts[seg]
                if 0.0 <= s <= t_move:
                    shape = min(1.0, s / t_acc, (t_move - s) / t_acc)
                    if overshoot > 0.0 and s > t_acc:  # start-up overshoot of the servo
                        u = (s - t_acc) / settle_tau
                        shape *= 1.0 + overshoot * u * math.exp(1.0 - u)
                    v_ref = speed * shape if seg == 1 else -speed * shape
            v_old = v
            v = v + (v_ref - v) * lag
            vm = 0.5 * (v_old + v)
            x += vm * h
            z, _ = kernels.z_step(z, vm, h, sigma_0, F_c, F_s, v_r, alpha)
            out[2, i] = (v - v_old) / h
        t = i * n_sub * h
        in_cruise = False
        for seg in range(2):
            s = t - starts[seg]
            if t_acc <= s <= t_move - t_acc:
                in_cruise = True
        if i == 0:
            out[2, i] = 0.0
        out[0, i] = x
        out[1, i] = v
        out[3, i] = kernels.lugre_instant(v, z, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha)
        if v < 0:
            engage = (cushion_len - x) / cushion_len
        else:
            engage = (x - (stroke - cushion_len)) / cushion_len
        engage = min(1.0, max(0.0, engage))
        out[4, i] = cushion_coef * v * abs(v) * engage
        steady = in_cruise and engage == 0.0 and abs(abs(v) - speed) <= 0.01 * speed
        out[5, i] = 1.0 if steady else 0.0
        out[6, i] = 0.0 if t < starts[1] else 1.0
    return out


def _stroke_plan(settings: BenchSettings, speed: float, interval: float):
    """Stroke length [m] and sample count for one speed within the 10,001-sample budget."""
    usable = settings.cylinder.stroke - 2 * settings.stroke_margin
    budget = (MAX_SAMPLES - 1) * interval
    t_acc = speed / settings.acceleration
    by_time = speed * ((budget - 3 * settings.dwell) / 2 - t_acc) * 0.98
    length = min(usable, by_time)
    if length < 5 * speed * t_acc:
        raise ValueError(f"speed {speed * 1e3:g} mm/s does not fit the stroke and sample budget")
    duration = 2 * (length / speed + t_acc) + 3 * settings.dwell
    n = min(MAX_SAMPLES, int(math.ceil(duration / interval)) + 1)
    return length, n


def run_plan(
    speed: float, settings: BenchSettings | None = None, *, slow: bool = False
) -> tuple[float, float, int]:
    """Stroke length [m], sample interval [s] and sample count of a run at ``speed`` [m/s].

    ``slow`` selects ``slow_interval``. Raises ValueError when the speed does not fit the
    stroke and the 10,001-sample budget (the bench cannot realise it).
    """
    s = settings or BenchSettings()
    interval = s.slow_interval if slow else s.fast_interval
    length, n = _stroke_plan(s, speed, interval)
    return length, interval, n


def run_virtual_test(
    pressure_bar: float,
    speed_mm_s: float,
    settings: BenchSettings | None = None,
    *,
    rng: np.random.Generator | None = None,
    slow: bool | None = None,
    friction_scale: float = 1.0,
    load_cell_offset: float = 0.0,
) -> VirtualRun:
    """Simulate one run of the virtual bench at ``pressure_bar`` [bar] and ``speed_mm_s`` [mm/s].

    ``slow`` forces the 20 ms sample interval (default: the slowest ``slow_speed_count``
    speeds of ``settings.speeds_mm_s``). ``friction_scale`` [-] multiplies the friction law
    (F_c, F_s and sigma_2: the whole steady-state curve) of this run, and
    ``load_cell_offset`` [N] is added to the load-cell reading (both drawn per run and per
    session by :func:`generate_campaign`). The start-up transients and the quantisation of
    ``settings`` act here.
    """
    s = settings or BenchSettings()
    rng = rng if rng is not None else np.random.default_rng(s.seed)
    pressure = pressure_bar * 1e5
    speed = speed_mm_s * 1e-3
    if not (pressure >= 0 and speed > 0):
        raise ValueError(
            f"need pressure >= 0 bar and speed > 0 mm/s; got {pressure_bar}, {speed_mm_s}"
        )
    if slow is None:
        slow = speed_mm_s in s.slow_speeds()
    interval = s.slow_interval if slow else s.fast_interval
    n_sub = max(1, int(round(interval / s.internal_step)))
    h = interval / n_sub
    length, n = _stroke_plan(s, speed, interval)
    stroke = s.cylinder.stroke
    x_top = stroke / 2 + length / 2
    params = s.friction.params_at(s.friction.operating_pressure(pressure))
    if not (math.isfinite(friction_scale) and friction_scale > 0):
        raise ValueError(f"friction_scale = {friction_scale}; expected a number > 0")
    if friction_scale != 1.0:
        params = {
            k: v * friction_scale if k in ("F_c", "F_s", "sigma_2") else v
            for k, v in params.items()
        }
    raw = _bench_kernel(
        h,
        n_sub,
        n,
        x_top,
        speed,
        s.acceleration,
        s.dwell,
        length,
        s.servo_time_constant,
        stroke,
        s.cushion_length,
        s.cushion_coefficient,
        params["sigma_0"],
        params["sigma_1"],
        params["F_c"],
        params["F_s"],
        params["sigma_2"],
        params["v_r"],
        params["alpha"],
        s.startup_velocity_overshoot,
        s.startup_time_constant,
    )
    position, velocity, acceleration, friction, cushion = raw[:5]
    if s.stroke_scatter:  # each stroke (direction) of the run its own level, from the noise
        strokes = np.exp(rng.normal(0.0, s.stroke_scatter, 2))
        friction = friction * strokes[raw[6].astype(np.intp)]
    time = np.arange(n) * interval
    steady = raw[5].astype(bool)
    force = s.cylinder.mass * acceleration + friction + cushion + s.weight_offset
    if load_cell_offset:
        force = force + load_cell_offset
    if s.startup_force_overshoot:
        transient, settled = _startup_force(time, s, params, speed, length)
        force = force + transient
        steady &= settled
    force = force + rng.normal(0.0, s.force_noise, n)
    spikes = rng.random(n) < s.spike_probability
    force[spikes] += rng.choice([-1.0, 1.0], spikes.sum()) * s.spike_amplitude
    position = position + rng.normal(0.0, s.position_noise, n)
    measured_pressure = pressure + rng.normal(0.0, s.pressure_noise, n)
    return VirtualRun(
        time=time,
        position=_quantise(position, s.position_step),
        force=_quantise(force, s.force_step),
        velocity=velocity,
        friction=friction,
        cushion=cushion,
        pressure=_quantise(measured_pressure, s.pressure_step),
        steady=steady,
        segment=raw[6].astype(np.int8),
        pressure_nominal=pressure,
        speed=speed,
        sample_interval=interval,
        steps=(n - 1) * n_sub,
    )


def _quantise(values: np.ndarray, step: float) -> np.ndarray:
    """``values`` rounded to whole ADC steps of ``step`` (same unit; 0: unchanged)."""
    return np.round(values / step) * step if step else values


STARTUP_SETTLED = 7.6
"""The start-up force transient ``a (u) e^(1-u)``, ``u = t / startup_time_constant``, is
below 1 % of its peak for ``u`` > 7.6: a sample is steady only after that."""


def _startup_force(time, s: BenchSettings, params, speed: float, length: float):
    """Force transient [N] at the start of each stroke and the mask of samples past it.

    Each stroke starts from rest (the dwell) with a breakaway-and-settling force in the
    direction of motion: ``sign * a * F_ss * u e^(1-u)``, ``u = (t - t_start) / tau``, with
    ``a = startup_force_overshoot``, ``F_ss`` the run's steady friction at ``speed`` [N]
    and ``tau = startup_time_constant`` [s] (peak at ``tau``).
    """
    from ..friction import stribeck

    level = float(
        stribeck(
            speed,
            params["F_c"],
            params["F_s"],
            params["v_r"],
            params["sigma_2"],
            alpha=params["alpha"],
        )
    )
    t_move = length / speed + speed / s.acceleration
    transient = np.zeros_like(time)
    settled = np.ones(time.size, dtype=bool)
    for sign, start in ((-1.0, s.dwell), (1.0, 2 * s.dwell + t_move)):
        u = (time - start) / s.startup_time_constant
        on = (u > 0) & (u < 50)
        transient[on] += sign * s.startup_force_overshoot * level * u[on] * np.exp(1 - u[on])
        settled &= ~((u > 0) & (u < STARTUP_SETTLED))
    return transient, settled


def run_file_name(
    index: int, pressure_bar: float, speed_mm_s: float, session: int | None = None
) -> str:
    """``run_007_p55bar_v10mms.txt``: file-name tokens the campaign reader understands;
    with ``session`` the session group first: ``s2_run_007_p55bar_v10mms.txt``."""
    prefix = "" if session is None else f"s{session}_"
    return f"{prefix}run_{index:03d}_p{pressure_bar:g}bar_v{speed_mm_s:g}mms.txt"


_FORCE_SCALE = {"N": 1.0, "kN": 1e-3}


def _write_run(path: Path, run: VirtualRun, s: BenchSettings, index: int) -> None:
    scale = _FORCE_SCALE[s.force_unit]
    units = {"Time": "s", "Axial Displacement": "mm", "Axial Force": s.force_unit}
    decimals = {"Time": 3, "Axial Displacement": 4, "Axial Force": 5 if s.force_unit == "kN" else 2}
    if s.pressure_channel:
        units["Pressure"] = "bar"
        decimals["Pressure"] = 2 if s.is_clean else 3  # 1 mbar: the ADC step shows
    segments = []
    for seg in (0, 1):
        sel = run.segment == seg
        cols = {
            "Time": run.time[sel],
            "Axial Displacement": run.position[sel] * 1e3,
            "Axial Force": run.force[sel] * scale,
        }
        if s.pressure_channel:
            cols["Pressure"] = run.pressure[sel] / 1e5
        segments.append(cols)
    header = {
        "Station Name": "858 Mini Bionix (virtual)",
        "Test File Name": f"friction_{index:03d}.tst",
        "Test Run Name": path.stem,
        "Pressure": f"{run.pressure_nominal / 1e5:g} bar",
        "Nominal velocity": f"{run.speed * 1e3:g} mm/s",
        "Sample interval": f"{run.sample_interval * 1e3:g} ms",
    }
    write_mts_text(
        path,
        segments,
        header=header,
        units=units,
        decimals=decimals,
        decimal_comma=s.decimal_comma,
        newline="\r\n" if s.crlf else "\n",
    )


TRUTH_COLUMNS = ("session", "friction_scale", "load_cell_offset_N")
"""Columns manifest.csv of a rough campaign adds: the session (``s1``, ``s2``, ...), the
friction multiplier the run was simulated with [-] and the session's load-cell offset [N]."""

SESSION_STREAM, RUN_STREAM = 0x5E55, 0x2A17
"""Entropy added to ``session_seed`` and ``run_seed`` (independent streams of the noise)."""


def draw_truth(settings: BenchSettings) -> list[dict[str, Any]]:
    """The rough bench's random effects of every constant-velocity run, in run order.

    Seeding scheme (three independent streams): the session effects (session multiplier,
    the pressure-block multipliers of that session, load-cell offset) come from
    ``SeedSequence([session_seed, SESSION_STREAM])``; the run multipliers from
    ``SeedSequence([run_seed, RUN_STREAM])``; the measurement noise of each file from
    ``SeedSequence(seed)`` (as the clean bench). ``session_seed`` and ``run_seed`` default to
    ``seed``. The same ``session_seed`` with a new ``run_seed`` and ``seed`` draws new runs
    of the same sessions; a new ``session_seed`` draws new sessions.

    Each multiplier is ``exp(N(0, sd))`` (lognormal, median 1; ``sd`` is about the relative
    s.d.). The warm-up multiplier is ``1 + warmup_amplitude exp(-t / warmup_time_constant)``,
    ``t`` [s] the session's elapsed time at the middle of the run (run durations plus
    ``run_pause`` between runs; each session starts cold).

    Returns one dict per run: ``index`` (within its session), ``file``, ``session``
    (``"s1"``, ...; None on a clean bench), ``session_index``, ``pressure_bar``,
    ``velocity_mm_s``, ``elapsed_s`` [s], ``session_scale``, ``pressure_scale``,
    ``run_scale``, ``warmup_scale`` and their product ``friction_scale`` [-] (the TRUE
    multiplier of the friction law in that run), and ``load_cell_offset_N`` [N].
    """
    s = settings
    runs = s.runs()
    slow = s.slow_speeds()
    pressures = sorted({p for p, _ in runs})
    session_seed = s.seed if s.session_seed is None else s.session_seed
    run_seed = s.seed if s.run_seed is None else s.run_seed
    session_streams = np.random.SeedSequence([session_seed, SESSION_STREAM]).spawn(s.sessions)
    run_streams = np.random.SeedSequence([run_seed, RUN_STREAM]).spawn(s.sessions)
    durations = []
    for _, v in runs:
        _, interval, n = run_plan(v * 1e-3, s, slow=v in slow)
        durations.append((n - 1) * interval)
    truth = []
    for k in range(s.sessions):
        srng = np.random.default_rng(session_streams[k])
        session_scale = math.exp(srng.normal(0.0, s.session_scatter))
        offset = float(srng.normal(0.0, s.load_cell_offset_std))
        block = {p: math.exp(srng.normal(0.0, s.pressure_scatter)) for p in pressures}
        rrng = np.random.default_rng(run_streams[k])
        run_scales = np.exp(rrng.normal(0.0, s.run_scatter, len(runs)))
        elapsed = 0.0
        for i, ((p, v), duration) in enumerate(zip(runs, durations, strict=True)):
            middle = elapsed + duration / 2
            warm = 1.0 + s.warmup_amplitude * math.exp(-middle / s.warmup_time_constant)
            elapsed += duration + s.run_pause
            scale = session_scale * block[p] * float(run_scales[i]) * warm
            truth.append(
                {
                    "index": i,
                    "file": run_file_name(i, p, v, None if s.is_clean else k + 1),
                    "session": None if s.is_clean else f"s{k + 1}",
                    "session_index": k,
                    "pressure_bar": p,
                    "velocity_mm_s": v,
                    "elapsed_s": middle,
                    "session_scale": session_scale,
                    "pressure_scale": block[p],
                    "run_scale": float(run_scales[i]),
                    "warmup_scale": warm,
                    "friction_scale": 1.0 if s.is_clean else scale,
                    "load_cell_offset_N": offset if offset else 0.0,
                }
            )
    return truth


def generate_campaign(
    out_dir: StrPath,
    settings: BenchSettings | None = None,
    *,
    progress: Callable[..., Any] | None = None,
    workers: int | None = None,
    tests: Iterable[str] = ("constant-velocity",),
    dynamic: DynamicTestSettings | None = None,
) -> dict:
    """Write a virtual campaign: one file per pressure x speed, plus ``manifest.csv``.

    With ``settings.points`` the runs are those (pressure, speed) pairs in their order
    (a test plan) instead of the full grid.

    Deterministic for a given ``settings.seed`` (each run draws from its own seeded stream).
    With ``tests`` naming ``"presliding"`` or ``"breakaway"`` (see :data:`TESTS`), the
    force-controlled tests of :func:`generate_dynamic_tests` are written too and
    ``manifest.csv`` gains the columns ``test`` and ``force_rate_N_s``.

    Parameters
    ----------
    out_dir : path-like
        Folder to create or fill.
    settings : BenchSettings, optional
        Bench, cylinder, friction and noise settings.
    progress : callable, optional
        Called with the file name after each file is written.
    workers : int, optional
        Threads (default: the number of cores, at most 2 on this project's machines).
    tests : iterable of str
        Which tests to write (:data:`TESTS`); default the constant-velocity runs only.
    dynamic : DynamicTestSettings, optional
        Design of the presliding and breakaway tests.

    Returns
    -------
    dict
        ``files`` (paths), ``steps`` (simulated steps), ``samples``, ``settings`` and, with
        dynamic tests, ``dynamic`` (their manifest rows with the simulated runs).
    """
    s = settings or BenchSettings()
    tests = tuple(tests)
    unknown = [t for t in tests if t not in TESTS]
    if unknown or not tests:
        raise ValueError(f"unknown tests {unknown or tests}; valid: {list(TESTS)}")
    from .._paths import make_folder

    out = make_folder(out_dir, "out_dir")  # a symbolic link is refused, not written through
    dynamic_tests = tuple(t for t in tests if t in DYNAMIC_TESTS)
    if "constant-velocity" not in tests:
        dynamic_rows = generate_dynamic_tests(
            out, s, tests=dynamic_tests, dynamic=dynamic, progress=progress
        )
        write_test_manifest(out / "manifest.csv", dynamic_rows)
        return {
            "files": [out / r["file"] for r in dynamic_rows],
            "steps": 0,
            "samples": int(sum(r["run"].time.size for r in dynamic_rows)),
            "settings": s,
            "dynamic": dynamic_rows,
        }
    slow = s.slow_speeds()
    truth = draw_truth(s)
    jobs = [(j, row) for j, row in enumerate(truth)]
    seeds = np.random.SeedSequence(s.seed).spawn(len(jobs))

    def one(job):
        j, row = job
        p, v = row["pressure_bar"], row["velocity_mm_s"]
        run = run_virtual_test(
            p,
            v,
            s,
            rng=np.random.default_rng(seeds[j]),
            slow=v in slow,
            friction_scale=row["friction_scale"],
            load_cell_offset=row["load_cell_offset_N"],
        )
        path = out / row["file"]
        _write_run(path, run, s, row["index"])
        if progress is not None:
            progress(path.name)
        return path, run.steps, run.time.size

    workers = workers or min(2, os.cpu_count() or 1)
    with ThreadPoolExecutor(max_workers=workers) as pool:
        results = list(pool.map(one, jobs))
    rows = [(r["file"], r["pressure_bar"], r["velocity_mm_s"]) for r in truth]
    info: dict[str, Any] = {
        "files": [r[0] for r in results],
        "steps": int(sum(r[1] for r in results)),
        "samples": int(sum(r[2] for r in results)),
        "settings": s,
        "truth": truth,
    }
    if not s.is_clean:
        constant = [{**r, "test": "constant-velocity"} for r in truth]
        if dynamic_tests:
            extra = generate_dynamic_tests(
                out,
                s,
                tests=dynamic_tests,
                dynamic=dynamic,
                start_index=len(rows),
                progress=progress,
            )
            info["files"] += [out / r["file"] for r in extra]
            info["samples"] += int(sum(r["run"].time.size for r in extra))
            info["dynamic"] = extra
            constant += extra
        write_test_manifest(out / "manifest.csv", constant, truth_columns=True)
        return info
    if not dynamic_tests:
        write_manifest(out / "manifest.csv", rows)
        return info
    extra = generate_dynamic_tests(
        out, s, tests=dynamic_tests, dynamic=dynamic, start_index=len(rows), progress=progress
    )
    constant = [
        {"file": f, "pressure_bar": p, "velocity_mm_s": v, "test": "constant-velocity"}
        for f, p, v in rows
    ]
    write_test_manifest(out / "manifest.csv", constant + extra)
    info["files"] += [out / r["file"] for r in extra]
    info["samples"] += int(sum(r["run"].time.size for r in extra))
    info["dynamic"] = extra
    return info


def with_seed(settings: BenchSettings, seed: int) -> BenchSettings:
    """A copy of ``settings`` with another seed."""
    return replace(settings, seed=seed)


# ---------------------------------------------------------------------- dynamic tests
TESTS = ("constant-velocity", "presliding", "breakaway")
"""Tests the virtual bench can write: the thesis' constant-velocity strokes, and the
force-controlled presliding and breakaway tests that identify ``sigma_0`` and ``sigma_1``."""

"""Force-controlled tests, told apart from constant-velocity runs by the ``test`` column of
``manifest.csv`` (and the ``Test:`` header line)."""


@dataclass(frozen=True)
class DynamicTestSettings:
    """Force-controlled tests of the virtual bench (SI units).

    The testing machine holds the rod at rest (load-cell reading = the weight offset) for
    ``hold`` seconds, then adds a net force ``F(t)`` to it:

    * presliding: sinusoids of amplitude ``presliding_fraction * F_c(p)`` (below breakaway)
      at ``presliding_frequencies`` for ``presliding_periods`` periods each, one after the
      other (a slow cycle traces the force-displacement hysteresis; the faster ones excite
      the bristle damping through the moving mass);
    * breakaway: ramps ``F = rate t`` at each of ``breakaway_rates`` [N/s]; the machine stops
      the test once the rod has travelled ``breakaway_stop``.

    Both record at ``sample_interval`` (a ramp too long for the 10,001-sample budget is
    sampled coarser, in multiples of it).
    """

    sample_interval: float = 2.5e-4  # [s]
    hold: float = 0.05  # [s] at zero net force before the excitation
    presliding_fraction: float = 0.5  # [-] force amplitude / F_c(p)
    presliding_frequencies: tuple = (2.0, 20.0, 40.0, 60.0)  # [Hz]
    presliding_periods: tuple = (1, 6, 16, 32)  # [-] periods at each frequency
    breakaway_rates: tuple = (50.0, 200.0, 1000.0)  # [N/s]
    breakaway_stop: float = 1.0e-3  # [m] travel at which the machine ends a ramp

    def __post_init__(self) -> None:
        if len(self.presliding_frequencies) != len(self.presliding_periods):
            raise ValueError(
                "presliding_frequencies and presliding_periods need the same length; got "
                f"{len(self.presliding_frequencies)} and {len(self.presliding_periods)}"
            )
        checks = {
            "sample_interval [s]": self.sample_interval,
            "hold [s]": self.hold,
            "presliding_fraction [-]": self.presliding_fraction,
            "breakaway_stop [m]": self.breakaway_stop,
            **{f"presliding_frequencies [Hz] {f}": f for f in self.presliding_frequencies},
            **{f"presliding_periods [-] {n}": n for n in self.presliding_periods},
            **{f"breakaway_rates [N/s] {r}": r for r in self.breakaway_rates},
        }
        for name, value in checks.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"dynamic test setting {name} = {value}; expected a number > 0")
        if self.presliding_fraction >= 1:
            raise ValueError(
                f"presliding_fraction = {self.presliding_fraction}; expected < 1 (a presliding "
                "test stays below the breakaway force)"
            )


@dataclass(frozen=True)
class DynamicRun:
    """One simulated force-controlled run with its ground truth.

    ``time`` [s], ``position`` [m] (measured, with noise), ``force`` [N] (load-cell reading:
    weight offset + net force + noise + spikes), ``applied`` [N] (true net force),
    ``displacement`` [m] (true), ``friction`` [N] (true LuGre force), plus ``test``
    (``"presliding"`` or ``"breakaway"``), ``pressure_nominal`` [Pa], ``force_rate`` [N/s]
    (breakaway; NaN otherwise) and ``sample_interval`` [s].
    """

    time: np.ndarray
    position: np.ndarray
    force: np.ndarray
    applied: np.ndarray
    displacement: np.ndarray
    friction: np.ndarray
    pressure: np.ndarray
    test: str
    pressure_nominal: float
    force_rate: float
    sample_interval: float


def presliding_force(
    time: ArrayLike, amplitude: float, settings: DynamicTestSettings
) -> np.ndarray:
    """Net force [N] of the presliding test at ``time`` [s] (zero during the hold)."""
    time = np.asarray(time, dtype=float)
    force = np.zeros_like(time)
    start = settings.hold
    for frequency, periods in zip(
        settings.presliding_frequencies, settings.presliding_periods, strict=True
    ):
        stop = start + periods / frequency
        inside = (time >= start) & (time < stop)
        force[inside] = amplitude * np.sin(2 * np.pi * frequency * (time[inside] - start))
        start = stop
    return force


def presliding_duration(settings: DynamicTestSettings) -> float:
    """Length of a presliding record [s]: hold, the sinusoids, and a final hold."""
    cycles = sum(
        n / f
        for f, n in zip(settings.presliding_frequencies, settings.presliding_periods, strict=True)
    )
    return 2 * settings.hold + cycles


RAMP_DOUBLINGS = 3
"""A breakaway ramp (first 1.5 x the model's breakaway level over the rate) is simulated again
twice as long, up to this many times, until the rod has travelled ``breakaway_stop``."""


def run_dynamic_test(
    test: str,
    pressure_bar: float,
    settings: BenchSettings | None = None,
    *,
    force_rate: float | None = None,
    dynamic: DynamicTestSettings | None = None,
    rng: np.random.Generator | None = None,
) -> DynamicRun:
    """Simulate one force-controlled test of the virtual bench.

    Uses the public :func:`cylfric.simulate.simulate` with an
    :class:`~cylfric.simulate.AppliedForce` drive, the bench's friction model (its
    ``sigma_0`` [N/m] and ``sigma_1`` [N*s/m] are the ground truth) and moving mass.

    Parameters
    ----------
    test : {"presliding", "breakaway"}
        Which test.
    pressure_bar : float
        Chamber pressure, both chambers [bar].
    settings : BenchSettings, optional
        Bench (friction model, cylinder, noise, weight offset).
    force_rate : float, optional
        Ramp rate of a breakaway test [N/s].
    dynamic : DynamicTestSettings, optional
        Test design.
    rng : numpy.random.Generator, optional
        Noise stream (default: seeded by ``settings.seed``).
    """
    from .plant import AppliedForce, Cylinder, simulate

    s = settings or BenchSettings()
    d = dynamic or DynamicTestSettings()
    rng = rng if rng is not None else np.random.default_rng(s.seed)
    if test not in DYNAMIC_TESTS:
        raise ValueError(f"unknown dynamic test {test!r}; valid: {list(DYNAMIC_TESTS)}")
    if not (math.isfinite(pressure_bar) and pressure_bar >= 0):
        raise ValueError(f"pressure = {pressure_bar} bar; expected a finite pressure >= 0 bar")
    pressure = pressure_bar * 1e5
    params = s.friction.params_at(s.friction.operating_pressure(pressure))
    interval = d.sample_interval
    if test == "presliding":
        amplitude = d.presliding_fraction * float(params["F_c"])
        duration = presliding_duration(d)

        def applied(t):
            return presliding_force(t, amplitude, d)

        rate = math.nan
    else:
        if force_rate is None or not (math.isfinite(force_rate) and force_rate > 0):
            raise ValueError(f"force_rate = {force_rate} N/s; expected a rate > 0 N/s")
        rate = float(force_rate)
        ramp = 1.5 * max(float(params["F_s"]), float(params["F_c"])) / rate

        def applied(t):
            return rate * np.clip(np.asarray(t) - d.hold, 0.0, None)

    mass_cylinder = Cylinder(s.cylinder.mass)  # both chambers at one pressure: no net force
    for _ in range(RAMP_DOUBLINGS + 1):
        if test == "breakaway":
            duration = d.hold + ramp
            interval = d.sample_interval * max(
                1, math.ceil(duration / ((MAX_SAMPLES - 1) * d.sample_interval))
            )
        n = int(round(duration / interval)) + 1
        result = simulate(
            mass_cylinder,
            s.friction,
            AppliedForce(applied),
            (n - 1) * interval,
            dt=interval,
            pressure_a=pressure,
        )
        displacement = result.states["position"]
        if test != "breakaway" or np.any(displacement > d.breakaway_stop):
            break
        ramp *= 2  # a ramp that ends before the rod has travelled breakaway_stop: longer
    else:
        raise ValueError(
            f"breakaway ramp at {rate:g} N/s, {pressure_bar:g} bar: the rod travelled "
            f"{float(np.max(displacement)) * 1e3:.3g} mm in {ramp / 2:.3g} s of ramp (up to "
            f"{rate * ramp / 2:.0f} N), not the {d.breakaway_stop * 1e3:g} mm the machine "
            "stops at; check the friction model's viscous term"
        )
    time = result.time
    friction = result.outputs["friction_force"]
    net = applied(time)
    if test == "breakaway":
        beyond = np.nonzero(displacement > d.breakaway_stop)[0]
        keep = beyond[0] + 1
        time, displacement, friction, net = (a[:keep] for a in (time, displacement, friction, net))
    n = time.size
    force = s.weight_offset + net + rng.normal(0.0, s.force_noise, n)
    spikes = rng.random(n) < s.spike_probability
    force[spikes] += rng.choice([-1.0, 1.0], spikes.sum()) * s.spike_amplitude
    position = s.cylinder.stroke / 2 + displacement + rng.normal(0.0, s.position_noise, n)
    return DynamicRun(
        time=time,
        position=position,
        force=force,
        applied=net,
        displacement=displacement,
        friction=friction,
        pressure=pressure + rng.normal(0.0, s.pressure_noise, n),
        test=test,
        pressure_nominal=pressure,
        force_rate=rate,
        sample_interval=interval,
    )


def dynamic_file_name(
    index: int, test: str, pressure_bar: float, force_rate: float | None = None
) -> str:
    """``dyn_004_p55bar_breakaway_r200Ns.txt``: the test kind and pressure in the name."""
    rate = "" if force_rate is None or math.isnan(force_rate) else f"_r{force_rate:g}Ns"
    return f"dyn_{index:03d}_p{pressure_bar:g}bar_{test}{rate}.txt"


def _write_dynamic_run(path: Path, run: DynamicRun, s: BenchSettings, index: int) -> None:
    scale = _FORCE_SCALE[s.force_unit]
    units = {"Time": "s", "Axial Displacement": "mm", "Axial Force": s.force_unit}
    decimals = {
        "Time": 6,
        "Axial Displacement": 5,
        "Axial Force": 5 if s.force_unit == "kN" else 2,
    }
    columns = {
        "Time": run.time,
        "Axial Displacement": run.position * 1e3,
        "Axial Force": run.force * scale,
    }
    if s.pressure_channel:
        units["Pressure"] = "bar"
        decimals["Pressure"] = 2
        columns["Pressure"] = run.pressure / 1e5
    header = {
        "Station Name": "858 Mini Bionix (virtual)",
        "Test File Name": f"{run.test}_{index:03d}.tst",
        "Test Run Name": path.stem,
        "Test": run.test,
        "Pressure": f"{run.pressure_nominal / 1e5:g} bar",
        "Moving mass": f"{s.cylinder.mass:g} kg",
        "Sample interval": f"{run.sample_interval * 1e3:g} ms",
    }
    if run.test == "breakaway":
        header["Force rate"] = f"{run.force_rate:g} N/s"
    write_mts_text(
        path,
        [columns],
        header=header,
        units=units,
        decimals=decimals,
        decimal_comma=s.decimal_comma,
        newline="\r\n" if s.crlf else "\n",
    )


def generate_dynamic_tests(
    out_dir: StrPath,
    settings: BenchSettings | None = None,
    *,
    tests: Sequence[str] = DYNAMIC_TESTS,
    dynamic: DynamicTestSettings | None = None,
    start_index: int = 0,
    progress: Callable[..., Any] | None = None,
) -> list[dict[str, Any]]:
    """Write presliding and breakaway runs at each pressure of ``settings``.

    Returns the manifest rows: ``file``, ``pressure_bar``, ``test``, ``force_rate_N_s``
    (empty for presliding) and the simulated ``run`` (:class:`DynamicRun`). The noise
    streams are seeded from ``settings.seed`` (deterministic).
    """
    s = settings or BenchSettings()
    d = dynamic or DynamicTestSettings()
    unknown = set(tests) - set(DYNAMIC_TESTS)
    if unknown:
        raise ValueError(f"unknown dynamic tests {sorted(unknown)}; valid: {list(DYNAMIC_TESTS)}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    jobs = []
    for p in s.pressures_bar:
        if "presliding" in tests:
            jobs.append(("presliding", p, None))
        if "breakaway" in tests:
            jobs.extend(("breakaway", p, r) for r in d.breakaway_rates)
    seeds = np.random.SeedSequence([s.seed, 14]).spawn(len(jobs))
    rows = []
    for k, (test, p, rate) in enumerate(jobs):
        index = start_index + k
        run = run_dynamic_test(
            test, p, s, force_rate=rate, dynamic=d, rng=np.random.default_rng(seeds[k])
        )
        path = out / dynamic_file_name(index, test, p, rate)
        _write_dynamic_run(path, run, s, index)
        rows.append(
            {"file": path.name, "pressure_bar": p, "test": test, "force_rate": rate, "run": run}
        )
        if progress is not None:
            progress(path.name)
    return rows


def write_test_manifest(
    path: StrPath, rows: Iterable[Mapping[str, Any]], *, truth_columns: bool = False
) -> Path:
    """``manifest.csv`` with the test kind: ``file,pressure_bar,velocity_mm_s,test,force_rate_N_s``.

    ``rows`` are dicts with ``file``, ``pressure_bar`` [bar], and ``velocity_mm_s`` [mm/s]
    (constant-velocity runs) or ``force_rate`` [N/s] (breakaway runs); ``test`` names the
    kind. Readers that know only the first three columns keep the others as extra metadata.
    With ``truth_columns`` the columns :data:`TRUTH_COLUMNS` follow (``session``,
    ``friction_scale`` [-], ``load_cell_offset_N`` [N]; empty for a row without them).
    """
    from ..io.writers import atomic_write_text

    header = ["file", "pressure_bar", "velocity_mm_s", "test", "force_rate_N_s"]
    lines = [",".join(header + list(TRUTH_COLUMNS if truth_columns else ()))]
    for row in rows:
        velocity = row.get("velocity_mm_s")
        rate = row.get("force_rate")
        cells = [
            row["file"],
            f"{row['pressure_bar']:g}",
            "" if velocity is None else f"{velocity:g}",
            row["test"],
            "" if rate is None or math.isnan(rate) else f"{rate:g}",
        ]
        if truth_columns:
            scale, offset = row.get("friction_scale"), row.get("load_cell_offset_N")
            cells += [
                row.get("session") or "",
                "" if scale is None else f"{scale:.6g}",
                "" if offset is None else f"{offset:.4g}",
            ]
        lines.append(",".join(cells))
    return atomic_write_text(path, "\n".join(lines) + "\n")


def truth_check(model: FrictionModel, settings: BenchSettings, level: float = 0.95) -> dict:
    """A fit of a virtual campaign judged against the bench's own truth.

    The bench simulates every run with ``settings.friction`` (the thesis law by default)
    times the run's multiplier (:func:`draw_truth`: session x pressure block x run x warm-up;
    1 on a clean bench). Returns plain numbers (SI unless the key names another unit):

    - ``true_law``: the law the bench was given (``F_c``, ``F_s``, ``sigma_2`` as
      ``(intercept, slope)`` [N, N/Pa] or [N*s/m, N*s/m/Pa]);
    - ``campaign_law``: per parameter ``(intercept, slope)`` of the straight line through
      the campaign's true values (the law's value at each pressure times the mean multiplier
      of that pressure's runs): what a fit of this campaign can recover;
    - ``multipliers``: ``session`` (one per session), ``pressure_block`` (min, max),
      ``run`` (min, max), ``warmup`` (min, max), ``total`` (min, max) [-];
    - ``run_band_coverage``: the share of runs whose true friction (the law at the run's
      speed and pressure times its multiplier) lies in the model's ``level`` band of a new
      run (``prediction_band(scope="run")``), and ``runs``;
    - ``session_band_coverage``: the share of the runs' (speed, pressure) at which the
      bench's law itself (multiplier 1: the median session) lies in the band of a new
      session (``scope="session"``);
    - ``offset``: the true load-cell offsets [N] (weight offset plus each session's).
    """
    import warnings

    truth = draw_truth(settings)
    law = settings.friction
    velocity = np.array([t["velocity_mm_s"] for t in truth]) * 1e-3
    pressure = np.array([t["pressure_bar"] for t in truth]) * 1e5
    scale = np.array([t["friction_scale"] for t in truth])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a band at the edge of the validity range
        nominal = np.asarray(law.friction(velocity, pressure), dtype=float)
        low, high = model.prediction_band(velocity, pressure, level, scope="run")
        run_inside = (low <= nominal * scale) & (nominal * scale <= high)
        low, high = model.prediction_band(velocity, pressure, level, scope="session")
        session_inside = (low <= nominal) & (nominal <= high)
    levels = sorted(set(pressure.tolist()))
    mean_scale = [scale[pressure == p].mean() for p in levels]
    campaign = {}
    for name in ("F_c", "F_s", "sigma_2"):
        values = np.array(
            [law.params_at(p)[name] * k for p, k in zip(levels, mean_scale, strict=True)]
        )
        line = np.polyfit(levels, values, 1) if len(levels) > 1 else (0.0, values[0])
        campaign[name] = (float(line[1]), float(line[0]))
    coefficients = law.coefficients()

    def span(key: str) -> tuple[float, float]:
        values = [t[key] for t in truth if t.get(key) is not None]
        return (min(values), max(values)) if values else (1.0, 1.0)

    clean = settings.is_clean
    return {
        "true_law": {
            name: (coefficients[name]["intercept"], coefficients[name]["slope"])
            for name in ("F_c", "F_s", "sigma_2")
            if isinstance(coefficients[name], dict)
        },
        "campaign_law": campaign,
        "multipliers": {
            "session": sorted({t["session_scale"] for t in truth}) if not clean else [1.0],
            "pressure_block": (1.0, 1.0) if clean else span("pressure_scale"),
            "run": (1.0, 1.0) if clean else span("run_scale"),
            "warmup": (1.0, 1.0) if clean else span("warmup_scale"),
            "total": span("friction_scale"),
        },
        "run_band_coverage": float(run_inside.mean()),
        "session_band_coverage": float(session_inside.mean()),
        "runs": len(truth),
        "level": level,
        "offset": sorted({settings.weight_offset + t["load_cell_offset_N"] for t in truth}),
    }
