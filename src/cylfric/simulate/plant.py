"""A hydraulic cylinder with dynamic, pressure-dependent friction (thesis eq. 3.1/3.2).

    (m_p + m_lc) x'' = A_1 p_1 - A_2 p_2 + F_l - F_f

``simulate(cylinder, friction, drive, duration)`` returns a :class:`SimulationResult`.
Drives: :class:`PrescribedMotion` (the testing machine), :class:`AppliedForce`,
:class:`SpringPull` (the stick-slip set-up) and :class:`PositionServo` (PID).
Integrators: ``"rosenbrock"`` (default: compiled adaptive L-stable Rodas3 with the exact
Jacobian; its cost does not grow with sigma_0, see docs/simulation.md), ``"fixed"`` (compiled
impulse scheme with exact z), ``"dopri"`` (compiled adaptive Dormand-Prince 5(4); its steps
shrink as 1/sqrt(sigma_0)), ``"scipy"`` (``solve_ivp``, the validation backend, any law).
"""

from __future__ import annotations

import functools
import math
import warnings
import weakref
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numba
import numpy as np

from ..friction import get_law, law_params
from ..model import FrictionModel, ValidityWarning
from . import kernels
from .result import SimulationResult

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence
    from typing import Any

    from numpy.typing import ArrayLike

__all__ = [
    "simulate_batch",
    "BatchResult",
    "Cylinder",
    "FrictionModel",
    "PrescribedMotion",
    "AppliedForce",
    "SpringPull",
    "PositionServo",
    "simulate",
    "THESIS_CYLINDER",
    "DEFAULT_FIXED_STEP",
    "MAX_OUTPUT_BYTES",
    "PEAK_BYTES_PER_SAMPLE",
    "BATCH_PEAK_FACTOR",
    "output_bytes",
]

MAX_OUTPUT_BYTES = 2**30
"""Default limit [bytes] (1 GiB) of the estimated peak memory of a simulation (above what
the process held before the call); raise it with ``max_output_bytes=``."""

PEAK_BYTES_PER_SAMPLE = 256
"""Peak memory of :func:`simulate` [bytes per output sample], measured (issue 23): peak RSS
(``resource.getrusage``) minus the RSS before the call, in a fresh process after a 1 s
warm-up run, for 2000 s at dt = 1 ms (2e6 samples): 64 for a spring with ``"rosenbrock"``
or ``"dopri"`` (the 8 output arrays), 104 for ``"fixed"`` and prescribed motion, 112 for an
applied force or a position servo (their input grid); 212 once for a position servo in a
test run beside other processes (tests/test_simulate_limits.py); rounded up to 256."""

BATCH_PEAK_FACTOR = 2.5
"""Peak memory of :func:`simulate_batch` over the arrays it counts (records and input rows)
[-], measured as for :data:`PEAK_BYTES_PER_SAMPLE` (3 sets, 2000 s, dt = 1 ms): 1.18 for
springs, 2.23 for applied forces (each input row is built, then stacked into one array);
rounded up to 2.5."""

OUTPUT_ARRAYS = 8
"""Arrays of a :class:`SimulationResult` on the output grid: time, position, velocity, z,
friction_force, drive_force, pressure_a, pressure_b."""

DEFAULT_FIXED_STEP = 1e-4
"""Default internal step of the ``"fixed"`` integrator [s]: reaches RMS(F - F_ref)/F_c <= 1e-4
against Radau on the stick-slip and sinusoidal reference cases (see tests/test_simulate.py)."""


@dataclass(frozen=True)
class Cylinder:
    """Cylinder geometry and moving mass.

    Attributes
    ----------
    mass : float
        Moving mass ``m_p + m_lc`` (rod, piston, load cell) [kg].
    area_a, area_b : float
        Piston areas of chamber A (cap) and B (rod side) [m^2]; 0 for a rig without pressure.
    stroke : float
        Stroke length [m].
    """

    mass: float
    area_a: float = 0.0
    area_b: float = 0.0
    stroke: float = math.inf

    def __post_init__(self) -> None:
        if not (self.mass > 0 and math.isfinite(self.mass)):
            raise ValueError(
                f"Cylinder mass = {self.mass} is out of range; expected a finite mass > 0 kg"
            )
        if not (self.area_a >= 0 and self.area_b >= 0):
            raise ValueError("Cylinder areas must be >= 0 m^2")

    @classmethod
    def from_diameters(
        cls,
        bore: float,
        rod: float,
        mass: float,
        *,
        double_rod: bool = False,
        stroke: float = math.inf,
    ) -> Cylinder:
        """Build from bore and rod diameters [m]; ``double_rod`` for a symmetric cylinder."""
        if not 0 <= rod < bore:
            raise ValueError(
                f"rod diameter {rod} m must be >= 0 and smaller than the bore {bore} m"
            )
        piston = math.pi / 4 * bore**2
        annulus = piston - math.pi / 4 * rod**2
        return cls(mass, annulus if double_rod else piston, annulus, stroke)


THESIS_CYLINDER = Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.150)
"""Bosch Rexroth CGM1MF3/40/28/150 of the thesis (symmetric, bore 40 mm, rod 28 mm, stroke
150 mm). The moving mass of rod, piston and load cell is not given in the thesis: 2.5 kg is
an assumption."""


def _friction_params(friction, pressure_a, pressure_b=None) -> dict:
    """Friction parameters (SI, dynamic ones included) at chamber pressures [Pa]."""
    return friction.params_at(friction.operating_pressure(pressure_a, pressure_b))


Signal = float | np.ndarray | Callable


def _on_grid(signal: Signal, time: np.ndarray, name: str) -> np.ndarray:
    if callable(signal):
        values = np.asarray(signal(time), dtype=float)
    else:
        values = np.asarray(signal, dtype=float)
    values = np.broadcast_to(values, time.shape) if values.ndim == 0 else values
    if values.shape != time.shape:
        raise ValueError(
            f"{name} has {values.shape[0]} samples; expected {time.shape[0]} "
            "(one per grid point) or a scalar or a function of time"
        )
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{name} contains NaN or inf; expected finite values")
    return np.ascontiguousarray(values, dtype=float)


@dataclass(frozen=True)
class PrescribedMotion:
    """The testing machine prescribes the rod velocity [m/s] (function of time or samples)."""

    velocity: Signal
    position0: float = 0.0


@dataclass(frozen=True)
class AppliedForce:
    """An external force on the rod [N] (function of time, samples or constant)."""

    force: Signal


@dataclass(frozen=True)
class SpringPull:
    """A spring [N/m] whose far end moves at ``speed`` [m/s]: the classic stick-slip set-up."""

    stiffness: float
    speed: float
    damping: float = 0.0

    def __post_init__(self) -> None:
        if not (self.stiffness > 0 and math.isfinite(self.stiffness)):
            raise ValueError(
                f"SpringPull stiffness = {self.stiffness} is out of range; expected a finite "
                "stiffness > 0 N/m"
            )
        if not (math.isfinite(self.speed) and self.damping >= 0):
            raise ValueError(
                f"SpringPull speed = {self.speed} m/s and damping = {self.damping} N*s/m: "
                "expected a finite speed and a damping >= 0"
            )


@dataclass(frozen=True)
class PositionServo:
    """PID position loop: force = kp e + ki int(e) + kd de/dt, e = reference - x.

    ``reference`` [m] (function of time or samples), gains in [N/m], [N/(m*s)], [N*s/m];
    ``reference_velocity`` [m/s] defaults to the numerical derivative of the reference.
    """

    reference: Signal
    kp: float
    ki: float = 0.0
    kd: float = 0.0
    reference_velocity: Signal | None = None


def _drive_signals(drive, time, x0):
    zeros = np.zeros_like(time)
    if isinstance(drive, AppliedForce):
        return zeros, zeros, _on_grid(drive.force, time, "force"), 0.0, 0.0, 0.0
    if isinstance(drive, SpringPull):
        return (
            x0 + drive.speed * time,
            np.full_like(time, drive.speed),
            zeros,
            drive.stiffness,
            drive.damping,
            0.0,
        )
    if isinstance(drive, PositionServo):
        ref = _on_grid(drive.reference, time, "reference")
        if drive.reference_velocity is None:
            vref = np.gradient(ref, time) if time.size > 1 else zeros
        else:
            vref = _on_grid(drive.reference_velocity, time, "reference_velocity")
        return ref, vref, zeros, drive.kp, drive.kd, drive.ki
    raise TypeError(
        f"unknown drive {type(drive).__name__}; valid: PrescribedMotion, "
        "AppliedForce, SpringPull, PositionServo"
    )


METHODS = ("rosenbrock", "dopri", "fixed", "scipy")
DEFAULT_RTOL = 1e-6
"""Default relative tolerance of ``"dopri"``: RMS(F - F_ref)/F_c of about 6e-6 on the
stick-slip reference case (the accuracy goal is 1e-4)."""
ROSENBROCK_RTOL = 1e-6
"""Default relative tolerance of ``"rosenbrock"``: RMS(F - F_ref)/F_c of 5e-6 to 7e-6 over
10 s and 2e-5 to 7e-5 over 40 s of the Canudas de Wit stick-slip case for sigma_0 = 1e5 to
1e10 N/m (1e-5 drifts past the 1e-4 goal over 40 s; docs/simulation.md)."""
MAX_STEPS = 50_000_000
BATCH_RTOL = 1e-5
"""First relative tolerance of :func:`simulate_batch` (each set then runs a decade tighter)."""
BATCH_ACCURACY = 1e-4
"""Per-set accuracy check of :func:`simulate_batch`: RMS(F) difference over F_c between the
runs at successive tolerances [-]. A fixed rtol does not bound the error: over 10 s of
Canudas-like sets (sigma_0 1e5..1e10 N/m, springs 1..4 N/m at 0.05..0.2 m/s) rtol 1e-6 left
84 of 5,000 sets above 1e-4 on the 10 ms record grid, the worst at 3.8e-3 (against runs at
rtol 1e-10; issue 26)."""
BATCH_MIN_RTOL = 1e-10
"""Tightest tolerance the accuracy check of :func:`simulate_batch` goes down to."""


def rosenbrock_tolerances(
    rtol: float, params: Mapping[str, Any]
) -> tuple[float, float, float, float]:
    """Absolute tolerances of the Rosenbrock integrator from its ``rtol`` and the friction.

    Position 1 mm, velocity ``v_r``, bristle deflection ``F_c / sigma_0`` (the slip deflection)
    and friction force ``F_c`` are the scales: each absolute tolerance is ``rtol`` times its
    scale, so one ``rtol`` means the same accuracy however stiff the bristles are. Returns
    (atol position [m], velocity [m/s], z [m], force [N]).
    """
    f_c, sigma_0, v_r = params["F_c"], params["sigma_0"], params["v_r"]
    if type(f_c) is float and type(sigma_0) is float and type(v_r) is float:  # the common case
        return _rosenbrock_scales(rtol, params)
    f_c, sigma_0, v_r = (
        float(value) if np.ndim(value) == 0 else float(reduce(value))
        for value, reduce in (
            (params["F_c"], np.min),
            (params["sigma_0"], np.max),
            (params["v_r"], np.min),
        )
    )
    return _rosenbrock_scales(rtol, {"F_c": f_c, "sigma_0": sigma_0, "v_r": v_r})


def _rosenbrock_scales(rtol, params):
    """The tolerances of :func:`rosenbrock_tolerances`, elementwise (one set per element)."""
    f_c, sigma_0, v_r = params["F_c"], params["sigma_0"], params["v_r"]
    position = rtol * 1e-3 + 0 * f_c  # 1 mm scale, shaped like the others
    return position, rtol * v_r, rtol * f_c / sigma_0, rtol * f_c


def simulate(
    cylinder: Cylinder,
    friction: FrictionModel,
    drive: PrescribedMotion | AppliedForce | SpringPull | PositionServo,
    duration: float,
    *,
    dt: float = 1e-3,
    pressure_a: Signal = 0.0,
    pressure_b: Signal | None = None,
    method: str = "rosenbrock",
    step: float = DEFAULT_FIXED_STEP,
    rtol: float | None = None,
    x0: float = 0.0,
    v0: float = 0.0,
    z0: float = 0.0,
    strict: bool = False,
    max_output_bytes: float = MAX_OUTPUT_BYTES,
) -> SimulationResult:
    """Simulate the cylinder over ``duration`` [s], with outputs every ``dt`` [s].

    Parameters
    ----------
    cylinder : Cylinder
        Geometry and moving mass.
    friction : FrictionModel
        Friction law and pressure laws.
    drive : PrescribedMotion, AppliedForce, SpringPull or PositionServo
        What moves the rod.
    duration : float
        Simulated time [s].
    dt : float
        Output (and input-grid) interval [s].
    pressure_a, pressure_b : float, array or callable
        Chamber pressures [Pa]; ``pressure_b`` defaults to ``pressure_a``.
    method : {"rosenbrock", "dopri", "fixed", "scipy"}
        Integrator for the velocity-as-state drives: compiled adaptive L-stable Rosenbrock
        (Rodas3, exact Jacobian; default, cost independent of sigma_0), compiled adaptive
        Dormand-Prince 5(4), the compiled fixed-step impulse scheme, or scipy Radau
        (reference). For PrescribedMotion, ``"scipy"`` gives the Radau reference and anything
        else the exact z update with mid-step velocity.
    step : float
        Internal step of ``"fixed"`` and of prescribed motion [s] (rounded to divide ``dt``).
    rtol : float, optional
        Relative tolerance of ``"rosenbrock"`` (default 1e-6), ``"dopri"`` (default 1e-6) and
        ``"scipy"`` (default 1e-9) [-].
    x0, v0, z0 : float
        Initial position [m], velocity [m/s], bristle deflection [m].
    strict : bool
        Raise instead of warning (:class:`cylfric.model.ValidityWarning`) when the pressures
        leave the model's validity range or look like bar given as Pa (before the run), or
        when the simulated speed leaves its validity speeds (after the run; the result is
        then not returned).
    max_output_bytes : float
        Limit of the estimated peak memory [bytes] (default :data:`MAX_OUTPUT_BYTES`,
        1 GiB), checked before anything is allocated: (duration / dt + 1) samples x
        :data:`PEAK_BYTES_PER_SAMPLE` (256 bytes, measured: the 8 output arrays of 8 bytes
        and the input grid and working arrays of the integrators).

    Returns
    -------
    SimulationResult

    Raises
    ------
    ValueError
        Bad arguments; an estimated peak above ``max_output_bytes`` (the message gives the
        estimate, the limit and the ways out: a coarser ``dt``, a shorter ``duration`` or a
        higher limit).
    """
    n = _output_samples(duration, dt)
    if n is not None and not (  # the message is formatted only when it is needed
        0 < max_output_bytes and n * PEAK_BYTES_PER_SAMPLE <= max_output_bytes
    ):
        _check_output_size(
            n * PEAK_BYTES_PER_SAMPLE, max_output_bytes, f"{n:.4g} samples (duration "
            f"{duration:g} s every dt = {dt:g} s) x {PEAK_BYTES_PER_SAMPLE} bytes measured per "
            "sample", "a coarser output grid (a larger dt) or a shorter duration",
        )  # fmt: skip
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = _simulate(
            cylinder, friction, drive, duration, dt, pressure_a, pressure_b, method, step,
            rtol, x0, v0, z0, strict,
        )  # fmt: skip
    for w in caught:  # shown at the caller's line, not at this module's
        warnings.warn(w.message, w.category, stacklevel=2)
    _check_speed(friction, result.states["velocity"], strict)
    return result


def _check_speed(friction: FrictionModel, velocity, strict: bool) -> None:
    """Warn (raise with ``strict``) when a simulated speed [m/s] exceeds the model's
    validity speeds: the friction law was extrapolated there. Speeds below the range are
    not flagged (every start from rest passes through them)."""
    if friction.validity is None or not np.size(velocity):
        return
    top = float(friction.validity["velocity_max"])
    fastest = float(np.max(np.abs(velocity)))
    if fastest > top * (1 + 1e-6):
        share = float(np.mean(np.abs(velocity) > top * (1 + 1e-6)))
        message = (
            f"the simulated speed reaches {fastest * 1e3:.4g} mm/s ({share:.0%} of the samples "
            f"above {top * 1e3:.4g} mm/s), beyond the model's validity speeds "
            f"{friction.validity['velocity_min'] * 1e3:.4g}-{top * 1e3:.4g} mm/s: the friction "
            "is extrapolated there"
        )
        if strict:
            raise ValueError(message)
        warnings.warn(message, ValidityWarning, stacklevel=3)


def _batch_validity(models, what: str, values, strict: bool) -> None:
    """One warning (or error) naming the sets whose operating ``pressure`` [Pa] or largest
    ``speed`` [m/s] leaves their model's validity range (operating pressure of both
    chambers at the set's pressure; speeds below the range are not flagged)."""
    outside = []
    for i, (model, value) in enumerate(zip(models, values, strict=True)):
        val = model.validity
        if val is None:
            continue
        if what == "pressure":
            p = float(model.operating_pressure(value, value))
            tol = 1e-6 * max(abs(val["pressure_max"]), 1.0)
            bad = not (val["pressure_min"] - tol <= p <= val["pressure_max"] + tol)
        else:
            bad = value > val["velocity_max"] * (1 + 1e-6)
        if bad:
            outside.append(i)
    if not outside:
        return
    shown = ", ".join(str(i) for i in outside[:5]) + (" ..." if len(outside) > 5 else "")
    unit, scale = ("bar", 1e5) if what == "pressure" else ("mm/s", 1e-3)
    first = outside[0]
    val = models[first].validity
    low, high = (
        (val["pressure_min"], val["pressure_max"])
        if what == "pressure"
        else (val["velocity_min"], val["velocity_max"])
    )
    message = (
        f"{len(outside)} of {len(models)} set(s) ({shown}) leave their model's validity "
        f"{what}s (set {first}: {float(values[first]) / scale:.4g} {unit} against "
        f"{low / scale:.4g}-{high / scale:.4g} {unit}): the friction is extrapolated there"
    )
    if strict:
        raise ValueError(message)
    warnings.warn(message, ValidityWarning, stacklevel=3)


def output_bytes(samples: int, arrays: int = OUTPUT_ARRAYS) -> int:
    """Size [bytes] of ``arrays`` float64 arrays of ``samples`` samples."""
    return int(samples) * int(arrays) * 8


def _output_samples(duration, dt):
    """Samples of the output grid (``math.inf`` when duration / dt overflows), or None when
    the arguments are invalid (the body of the simulation refuses them with its own
    message)."""
    try:
        if 0 < dt <= duration < math.inf:
            return _samples(duration, dt)
    except TypeError:
        pass
    return None


def _samples(duration: float, dt: float) -> float:
    """Samples of a grid every ``dt`` over ``duration`` [s]; ``math.inf`` when the ratio
    overflows (a huge duration such as 1e308 s: refused by the size check, not an
    OverflowError)."""
    ratio = duration / dt
    return int(round(ratio)) + 1 if math.isfinite(ratio) else math.inf


def _check_output_size(size, limit, how, ways_out) -> None:
    """Refuse, before allocating, outputs above ``limit`` bytes; ``how`` says how the
    estimate came about, ``ways_out`` how to make it smaller."""
    if not limit > 0:
        raise ValueError(f"max_output_bytes = {limit}; expected a size > 0 bytes")
    if size <= limit:
        return
    raise ValueError(
        f"the simulation would take about {size / 2**30:.3g} GiB of memory at its peak ({how}), "
        f"above the limit of {limit / 2**30:.3g} GiB; use {ways_out}, or raise the limit "
        "(max_output_bytes= in Python, --max-output-gib on the command line)"
    )


_STATE_UNITS = {"x0": "m", "v0": "m/s", "z0": "m"}


def _check_initial_state(**states: float) -> None:
    """ValueError naming an initial state (x0 [m], v0 [m/s], z0 [m]) that is not a finite
    real number (a NaN or inf start ended in a ZeroDivisionError inside the integrator)."""
    if all(type(value) is float and math.isfinite(value) for value in states.values()):
        return  # the common case, without the conversions below
    for name, value in states.items():
        unit = _STATE_UNITS[name]
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{name} = {value!r}; expected a finite number in {unit}") from None
        if isinstance(value, bool) or not math.isfinite(number):
            raise ValueError(f"{name} = {value!r} {unit}; expected a finite number in {unit}")


@functools.lru_cache(maxsize=64)
def _constant_signal(value: float, n: int) -> np.ndarray:
    """``value`` (a pressure [Pa]) on n samples as a read-only view of one number, shared by
    repeated runs (np.broadcast_to costs about 2.5 us of each short simulation)."""
    return np.broadcast_to(value, (n,))


def _simulate(
    cylinder, friction, drive, duration, dt, pressure_a, pressure_b, method, step, rtol,
    x0, v0, z0, strict,
):  # fmt: skip
    """The body of :func:`simulate` (arguments as there)."""
    _check_initial_state(x0=x0, v0=v0, z0=z0)
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; valid: {list(METHODS)}")
    if rtol is None:
        rtol = {"scipy": 1e-9, "rosenbrock": ROSENBROCK_RTOL}.get(method, DEFAULT_RTOL)
    if not (0 < rtol < 1):
        raise ValueError(f"rtol = {rtol} is out of range; expected 0 < rtol < 1")
    if not (0 < dt <= duration < math.inf):
        raise ValueError(f"need 0 < dt <= duration < inf; got dt = {dt} s, duration = {duration} s")
    if method == "fixed" and not (0 < step < math.inf):
        raise ValueError(f"step = {step} s is out of range; expected a finite step > 0 s")
    n = int(round(duration / dt)) + 1
    constant = (type(pressure_a) is float and pressure_b is None) or (
        np.ndim(pressure_a) == 0
        and (pressure_b is None or np.ndim(pressure_b) == 0)
        and not callable(pressure_a)
        and not callable(pressure_b)
    )
    time = None
    if constant:  # the common case, checked on the two numbers (no arrays)
        p_a = float(pressure_a)
        p_b = p_a if pressure_b is None else float(pressure_b)
        for name, value in (("pressure_a", p_a), ("pressure_b", p_b)):
            if not math.isfinite(value):
                raise ValueError(f"{name} contains NaN or inf; expected finite values")
        # constant pressures as read-only views of one number (no 8 bytes per sample to write)
        pa = _constant_signal(p_a, n)
        pb = pa if pressure_b is None or p_b == p_a else _constant_signal(p_b, n)
        checked_a: float | np.ndarray = p_a
        checked_b: float | np.ndarray = p_b
    else:
        time = np.arange(n) * dt
        pa = _on_grid(pressure_a, time, "pressure_a")
        pb = pa if pressure_b is None else _on_grid(pressure_b, time, "pressure_b")
        checked_a, checked_b = pa, pb
    for name, values in (("pressure_a", checked_a), ("pressure_b", checked_b)):
        if (values if constant else np.min(values)) < 0:
            raise ValueError(
                f"{name} goes down to {np.min(values):.4g} Pa; expected pressures >= 0 Pa"
            )
    # warns outside the model's validity pressures, or for pressures that look like bar
    if constant:
        operating: float | np.ndarray = _operating_checked(friction, p_a, p_b, strict)
    else:
        operating = friction.operating_pressure(checked_a, checked_b)
        friction.check(None, operating, strict=strict)
    if constant:
        params = _params_checked(friction, float(operating))
        f_pressure: float | np.ndarray = float(cylinder.area_a * p_a - cylinder.area_b * p_b)
    else:
        params = _friction_params(friction, checked_a, checked_b)
        _check_friction(friction, params)
        f_pressure = cylinder.area_a * pa - cylinder.area_b * pb
    info = {"method": method, "dt": dt}
    compiled = friction.simulation_law == "lugre" and method in ("rosenbrock", "dopri")

    if isinstance(drive, PrescribedMotion):
        time = np.arange(n) * dt if time is None else time
        f_pressure = np.broadcast_to(f_pressure, time.shape)
        velocity = _on_grid(drive.velocity, time, "velocity")
        position = drive.position0 + np.concatenate(
            ([0.0], np.cumsum(0.5 * (velocity[1:] + velocity[:-1]) * dt))
        )
        if friction.simulation_law == "lugre" and method == "scipy":
            from .reference import solve_prescribed_reference

            z, force = solve_prescribed_reference(time, velocity, z0, params, rtol=rtol)
            info["method"] = "scipy Radau prescribed velocity"
        elif friction.simulation_law == "lugre":
            substeps = max(1, int(math.ceil(dt / step - 1e-9)))
            z, force = kernels.prescribed_velocity(
                time,
                velocity,
                z0,
                _const(params, "sigma_0"),
                _const(params, "sigma_1"),
                _arr(params["F_c"], n),
                _arr(params["F_s"], n),
                _arr(params["sigma_2"], n),
                _const(params, "v_r"),
                _const(params, "alpha"),
                substeps,
            )
            info.update(
                method="exact-z prescribed velocity", step=dt / substeps, steps=(n - 1) * substeps
            )
        else:
            z = np.zeros(n)
            force = get_law(friction.simulation_law).function(
                velocity, **law_params(friction.simulation_law, params)
            )
        acceleration = np.gradient(velocity, time)
        load = cylinder.mass * acceleration + force - f_pressure
        return SimulationResult(
            time,
            {"position": position, "velocity": velocity, "z": z},
            {"friction_force": force, "drive_force": load, "pressure_a": pa, "pressure_b": pb},
            info,
        )

    if compiled:
        # the compiled integrators take the inputs as one block and return the outputs
        sig, dt_s, ramp, k, c, ki = _signal_block(drive, n, dt, x0, f_pressure, params, time)
        scalar_pressure = type(f_pressure) is float
        offset = -f_pressure if scalar_pressure else 0.0
        lugre = (
            cylinder.mass,
            k,
            c,
            ki,
            *(_const(params, name) for name in ("sigma_0", "sigma_1", "v_r", "alpha")),
        )
        if method == "rosenbrock":
            time, out, accepted, rejected, reached = kernels.rosenbrock(  # type: ignore[call-arg]  # numba Dispatcher
                sig, dt_s, ramp, dt, n, x0, v0, z0, *lugre, rtol,
                *rosenbrock_tolerances(rtol, params), MAX_STEPS, offset,
            )  # fmt: skip
            info.update(rtol=rtol, scheme="Rodas3")
        else:
            time, out, accepted, rejected, reached = kernels.dopri(  # type: ignore[call-arg]  # numba Dispatcher
                sig, dt_s, ramp, dt, n, x0, v0, z0, *lugre, rtol, 1e-12, 1e-9, 1e-13,
                MAX_STEPS, offset,
            )  # fmt: skip
        if reached < n:
            raise RuntimeError(
                f"{method} stopped at t = {(reached - 1) * dt} s after {MAX_STEPS:.0e} steps; "
                "loosen rtol or use method='fixed'"
            )
        if not scalar_pressure:
            out[4] -= f_pressure
        info.update(accepted=int(accepted), rejected=int(rejected))
        return SimulationResult(
            time,
            {"position": out[0], "velocity": out[1], "z": out[2]},
            {"friction_force": out[3], "drive_force": out[4], "pressure_a": pa, "pressure_b": pb},
            info,
        )

    time = np.arange(n) * dt if time is None else time
    f_pressure = np.broadcast_to(f_pressure, time.shape)
    x_ref, v_ref, f_ext, k, c, ki = _drive_signals(drive, time, x0)
    f_ext = f_ext + f_pressure
    if method == "scipy" or friction.simulation_law != "lugre":
        from .reference import solve_reference

        if method != "scipy":
            raise ValueError(
                f"law {friction.simulation_law!r} runs only with method='scipy'; the compiled "
                "integrators need 'lugre'"
            )
        states, force, info_extra = solve_reference(
            time,
            cylinder.mass,
            k,
            c,
            ki,
            x_ref,
            v_ref,
            f_ext,
            friction,
            params,
            x0,
            v0,
            z0,
            rtol=rtol,
        )
        info.update(info_extra)
    else:  # method == "fixed"
        substeps = max(1, int(math.ceil(dt / step - 1e-9)))
        pos, vel, z, force, mean_force, iterations = kernels.fixed_step(  # type: ignore[call-arg]  # numba Dispatcher
            dt,
            substeps,
            *_plant_args(cylinder, friction, params, n, x0, v0, z0, k, c, ki, x_ref, v_ref, f_ext),
            1e-10,
        )
        states = {"position": pos, "velocity": vel, "z": z}
        info.update(step=dt / substeps, steps=(n - 1) * substeps, iterations=int(iterations))
    error = x_ref - states["position"]
    drive_force = k * error + c * (v_ref - states["velocity"]) + f_ext - f_pressure
    if ki:
        drive_force += ki * np.concatenate(([0.0], np.cumsum(0.5 * (error[1:] + error[:-1]) * dt)))
    return SimulationResult(
        time,
        states,
        {"friction_force": force, "drive_force": drive_force, "pressure_a": pa, "pressure_b": pb},
        info,
    )


def _signal_block(drive, n, dt, x0, f_pressure, params, time=None):
    """Input signals of the compiled integrators as one (m, 6) block (kernels order: x_ref,
    v_ref, f_ext with the pressure force, F_c, F_s, sigma_2) and (dt_s, ramp, k, c, ki).

    Constant inputs (a spring pulled at constant speed or a constant force, at constant
    pressure and friction) take two rows over the duration, the spring's pull as ``ramp``;
    otherwise one row per grid point.
    """
    names = ("F_c", "F_s", "sigma_2")
    if type(f_pressure) is float and all(type(params[name]) is float for name in names):
        ramp = None
        if isinstance(drive, SpringPull):
            f_ext, ramp, gains = 0.0, drive.speed, (drive.stiffness, drive.damping, 0.0)
        elif (
            isinstance(drive, AppliedForce)
            and not callable(drive.force)
            and np.ndim(drive.force) == 0
        ):
            f_ext, ramp, gains = float(drive.force), 0.0, (0.0, 0.0, 0.0)
            if not math.isfinite(f_ext):
                raise ValueError("force contains NaN or inf; expected finite values")
        if ramp is not None:
            row = (x0, 0.0, f_ext + f_pressure, params["F_c"], params["F_s"], params["sigma_2"])
            return (_two_rows(row), dt * (n - 1), ramp, *gains)
    time = np.arange(n) * dt if time is None else time
    x_ref, v_ref, f_ext, k, c, ki = _drive_signals(drive, time, x0)
    sig = np.empty((n, 6))
    sig[:, 0], sig[:, 1], sig[:, 2] = x_ref, v_ref, f_ext + f_pressure
    for column, name in enumerate(names, 3):
        sig[:, column] = params[name]
    return sig, dt, 0.0, k, c, ki


@functools.lru_cache(maxsize=256)
def _two_rows(row: tuple[float, ...]) -> np.ndarray:
    """The (2, 6) input block of constant inputs ``row`` (kernels order), shared by repeated
    runs: the kernels only read it, and it never leaves :func:`_simulate`."""
    return np.array([row, row])


def _plant_args(cylinder, friction, params, n, x0, v0, z0, k, c, ki, x_ref, v_ref, f_ext):
    """The plant and friction arguments shared by the compiled integrators (kernels order)."""
    return (
        x0,
        v0,
        z0,
        cylinder.mass,
        k,
        c,
        ki,
        x_ref,
        v_ref,
        f_ext,
        _arr(params["F_c"], n),
        _arr(params["F_s"], n),
        _arr(params["sigma_2"], n),
        _const(params, "sigma_0"),
        _const(params, "sigma_1"),
        _const(params, "v_r"),
        _const(params, "alpha"),
    )


_LUGRE_NAMES = ("sigma_0", "sigma_1", "sigma_2", "F_c", "F_s", "v_r", "alpha")


# model -> (its parameters, laws, pressure and simulation law; {pressure: checked params})
_PARAMS: weakref.WeakKeyDictionary[FrictionModel, tuple[tuple[Any, ...], dict[float, dict]]] = (
    weakref.WeakKeyDictionary()
)


# model -> {(p_a, p_b): (reference, validity, operating pressure)} for constant chamber
# pressures whose validity check passed without a warning (repeated runs skip it)
_CHAMBERS: weakref.WeakKeyDictionary[FrictionModel, dict[tuple[float, float], tuple]] = (
    weakref.WeakKeyDictionary()
)


def _operating_checked(friction, p_a, p_b, strict) -> float:
    """The operating pressure [Pa] of constant chamber pressures ``p_a``, ``p_b`` [Pa],
    checked against the model's validity (a warning, or a ValueError with ``strict``).
    A check that passed silently is remembered per model, pressures, reference and
    validity ranges (about 8 us of each repeated :func:`simulate` call)."""
    seen = _CHAMBERS.get(friction)
    hit = None if seen is None else seen.get((p_a, p_b))
    if hit is not None and hit[0] == friction.reference and hit[1] is friction.validity:
        return hit[2]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        operating = float(friction.operating_pressure(p_a, p_b))
        friction.check(None, operating, strict=strict)
    for w in caught:  # passed on to simulate(), which shows them at the caller's line
        warnings.warn(w.message, w.category, stacklevel=2)
    if not caught:
        seen = _CHAMBERS.setdefault(friction, {})
        if len(seen) < 256:
            seen[(p_a, p_b)] = (friction.reference, friction.validity, operating)
    return operating


def _params_checked(friction, pressure):
    """``friction.params_at(pressure)`` at a constant operating pressure [Pa], checked for the
    integrators and remembered per model (a model's parameters cannot change: its
    ``parameters`` and ``laws`` are read-only mappings of frozen values, and they are compared
    by identity). The returned dict is shared: read it, do not change it."""
    key = (friction.parameters, friction.laws, friction.pressure_law, friction.simulation_law)
    entry = _PARAMS.get(friction)
    if entry is None or any(a is not b and a != b for a, b in zip(entry[0], key, strict=True)):
        entry = _PARAMS[friction] = (key, {})
    params = entry[1].get(pressure)
    if params is None:
        params = _friction_params(friction, pressure)
        _check_friction(friction, params)
        if len(entry[1]) < 256:
            entry[1][pressure] = params
    return params


def _check_friction(friction, params) -> None:
    """Clear errors for friction parameters the integrators cannot use (checked once)."""
    if friction.simulation_law != "lugre":
        return
    if all(np.ndim(params[name]) == 0 for name in _LUGRE_NAMES):
        _check_lugre_numbers(*(float(params[name]) for name in _LUGRE_NAMES))
    else:
        _check_lugre_arrays({name: np.asarray(params[name], dtype=float) for name in params})


@functools.lru_cache(maxsize=4096)
def _check_lugre_numbers(*values) -> None:
    """The check of constant parameters, remembered: sweeps re-use the same sets."""
    _check_lugre_arrays(dict(zip(_LUGRE_NAMES, values, strict=True)))


def _check_lugre_arrays(shape) -> None:
    from ..friction import lugre_force

    try:
        lugre_force(
            0.0,
            0.0,
            *(shape[n] for n in ("sigma_0", "sigma_1", "sigma_2", "F_c", "F_s", "v_r")),
            alpha=shape["alpha"],
        )
    except ValueError as exc:
        raise ValueError(f"the friction model cannot be simulated: {exc}") from None


def _arr(value, n):
    return np.ascontiguousarray(np.broadcast_to(np.asarray(value, dtype=float), (n,)))


def _const(params, name):
    values = params[name]
    if type(values) is float:
        return values
    values = np.asarray(values, dtype=float)
    if values.ndim and not np.all(values == values.flat[0]):
        raise ValueError(f"{name} must not vary with pressure in the compiled integrators")
    return float(values.flat[0])


@dataclass(frozen=True)
class BatchResult:
    """Recorded signals of many simulated sets; ``batch[i]`` is set i as a SimulationResult.

    Attributes
    ----------
    time : ndarray
        Record times [s].
    position, velocity, z : ndarray
        (n_sets, n_records) rod positions [m], velocities [m/s], bristle deflections [m].
    friction_force, drive_force : ndarray
        (n_sets, n_records) friction force [N] (eq. 2.5) and force of the drive on the rod [N].
    pressure : ndarray
        Chamber pressure of each set [Pa] (both chambers).
    info : dict
        Integrator details; ``steps`` is an (n_sets, 2) array of accepted and rejected steps.
    """

    time: np.ndarray
    position: np.ndarray
    friction_force: np.ndarray
    pressure: np.ndarray
    velocity: np.ndarray | None = None
    z: np.ndarray | None = None
    drive_force: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return self.position.shape[0]

    def __getitem__(self, i: int) -> SimulationResult:
        """Set ``i`` as the :class:`SimulationResult` that :func:`simulate` returns."""
        # simulate_batch records all three (None only in a BatchResult built by hand)
        assert self.velocity is not None and self.z is not None
        assert self.drive_force is not None
        p = np.full(self.time.shape, self.pressure[i])
        return SimulationResult(
            self.time,
            {"position": self.position[i], "velocity": self.velocity[i], "z": self.z[i]},
            {
                "friction_force": self.friction_force[i],
                "drive_force": self.drive_force[i],
                "pressure_a": p,
                "pressure_b": p,
            },
            {
                **{
                    k: v[i] if isinstance(v, np.ndarray) else v
                    for k, v in self.info.items()
                    if k != "steps"
                },
                "set": int(i),
            },
        )

    def results(self) -> list[SimulationResult]:
        """All sets as :class:`SimulationResult` objects."""
        return [self[i] for i in range(len(self))]


def _per_set(value: Any, n_sets: int, name: str) -> list[Any]:
    """A scalar-or-sequence argument as a list of ``n_sets`` items."""
    if isinstance(value, (list, tuple)):
        if len(value) not in (1, n_sets):
            raise ValueError(
                f"{len(value)} {name} for {n_sets} sets; expected one per set (or a single one)"
            )
        return list(value) * (n_sets if len(value) == 1 else 1)
    return [value] * n_sets


def simulate_batch(
    cylinder: Cylinder | Sequence[Cylinder],
    models: FrictionModel | Sequence[FrictionModel],
    drive: AppliedForce
    | SpringPull
    | PositionServo
    | Sequence[AppliedForce | SpringPull | PositionServo],
    duration: float,
    *,
    pressures: ArrayLike | None = None,
    dt: float = 1e-3,
    record_every: int = 10,
    rtol: float | None = None,
    accuracy: float | None = BATCH_ACCURACY,
    x0: float = 0.0,
    v0: float = 0.0,
    strict: bool = False,
    max_output_bytes: float = MAX_OUTPUT_BYTES,
) -> BatchResult:
    """Simulate many heterogeneous sets at once on all cores (sweeps, Monte Carlo).

    Each set runs the compiled Rosenbrock integrator of :func:`simulate` (the default
    method: LuGre friction, constant pressure per set); sets run in parallel with
    ``numba.prange``. Every argument may be one value for all sets or a sequence with one
    value per set: the plant, the friction model, the drive (e.g. springs of different
    stiffness and speed) and the pressure.

    Parameters
    ----------
    cylinder : Cylinder or sequence of Cylinder
        Plant(s).
    models : FrictionModel or sequence of FrictionModel
        LuGre model(s).
    drive : AppliedForce, SpringPull or PositionServo, or a sequence of them
        Drive(s).
    duration : float
        Simulated time [s].
    pressures : float or array_like, optional
        Chamber pressure of each set [Pa] (both chambers; the models' reference applies).
        Default 0 Pa.
    dt : float
        Input-grid interval [s]; signals are recorded every ``record_every`` intervals.
    rtol : float, optional
        Relative tolerance of the integrator's first run of each set [-] (default
        :data:`BATCH_RTOL`, 1e-5).
    accuracy : float or None
        Per-set accuracy goal, RMS(F - F_true)/F_c on the record grid [-] (default
        :data:`BATCH_ACCURACY`, 1e-4): every set runs at ``rtol`` and at ``rtol / 10``, and
        again a decade tighter (down to 1e-10) until two successive runs' friction records
        differ by at most half of ``accuracy``; the tighter run is kept.
        ``info["rtol"]`` holds each set's final tolerance; a set that never passes gives a
        RuntimeWarning (a ValueError with ``strict``). None runs each set once at ``rtol``.
    x0, v0 : float
        Initial position [m] and velocity [m/s].
    strict : bool
        Raise instead of warning (:class:`cylfric.model.ValidityWarning`, one warning for
        all sets) when a set's pressure leaves its model's validity pressures (before the
        run) or its recorded speed leaves the validity speeds (after it).
    max_output_bytes : float
        Limit of the estimated peak memory [bytes] (default :data:`MAX_OUTPUT_BYTES`,
        1 GiB), checked before anything is allocated: the recorded outputs (sets x 5 signals
        x records x 8 bytes) plus the full-rate input rows (3 per distinct non-spring drive,
        and one shared, x samples x 8 bytes), times :data:`BATCH_PEAK_FACTOR` (2.5, measured).

    Returns
    -------
    BatchResult
        ``batch[i]`` is set i as the :class:`SimulationResult` of :func:`simulate` (on the
        record grid).

    Raises
    ------
    ValueError
        Bad arguments; an estimated peak above ``max_output_bytes`` (the message gives the
        estimate, the limit and the ways out).
    """
    rtol = BATCH_RTOL if rtol is None else rtol
    _check_initial_state(x0=x0, v0=v0)
    if not (0 < rtol < 1):
        raise ValueError(f"rtol = {rtol} is out of range; expected 0 < rtol < 1")
    if accuracy is not None and not (0 < accuracy < math.inf):
        raise ValueError(f"accuracy = {accuracy}; expected a finite RMS(F)/F_c > 0 or None")
    if isinstance(models, FrictionModel):
        models = [models]
    models = list(models)
    drives = list(drive) if isinstance(drive, (list, tuple)) else [drive]
    cylinders = list(cylinder) if isinstance(cylinder, (list, tuple)) else [cylinder]
    if pressures is None:
        pressures = [0.0]
    pressures = np.atleast_1d(np.asarray(pressures, dtype=float))
    n_sets = max(len(models), len(drives), len(cylinders), pressures.size)
    if pressures.size not in (1, n_sets) or len(models) not in (1, n_sets):
        raise ValueError(
            f"{len(models)} models for {pressures.size} pressures; expected one "
            "model per pressure (or a single model)"
        )
    models = _per_set(models, n_sets, "models")
    drives = _per_set(drives, n_sets, "drives")
    cylinders = _per_set(cylinders, n_sets, "cylinders")
    pressures = np.broadcast_to(pressures, (n_sets,)).copy()
    if not np.all(np.isfinite(pressures)) or pressures.min() < 0:
        raise ValueError(
            f"pressures go down to {pressures.min():.4g} Pa or are not finite; expected "
            "finite pressures >= 0 Pa"
        )
    if any(m.simulation_law != "lugre" for m in models):
        raise ValueError("simulate_batch needs LuGre models (simulation_law='lugre')")
    if any(isinstance(d, PrescribedMotion) for d in drives):
        raise ValueError(
            "simulate_batch takes AppliedForce, SpringPull or PositionServo; "
            "prescribed motion needs no integration of the mechanics"
        )
    if not (0 < dt <= duration < math.inf and record_every >= 1):
        raise ValueError(
            f"need 0 < dt <= duration and record_every >= 1 (duration < inf); got dt = {dt} s, "
            f"duration = {duration} s, record_every = {record_every}"
        )
    n = _samples(duration, dt)
    records = -(-n // int(record_every)) if n < math.inf else n
    input_rows = 1 + len({id(d) for d in drives if not isinstance(d, SpringPull)})
    _check_output_size(
        BATCH_PEAK_FACTOR * (5 * n_sets * records + (3 * input_rows + 1) * n) * 8,
        max_output_bytes,
        f"{n_sets} sets x 5 signals x {records:.4g} records, plus {3 * input_rows + 1} "
        f"input rows x {n:.4g} samples (duration {duration:g} s every dt = {dt:g} s), "
        f"x 8 bytes x {BATCH_PEAK_FACTOR} measured",
        "a larger dt or record_every, a shorter duration or fewer sets",
    )
    n = int(n)  # finite: an overflowing count was refused by the size check above
    time = np.arange(n) * dt
    # input signals: springs pulled at constant speed share one zero row (their ramp is a
    # per-set number); other drives get one row per distinct drive object
    zeros = np.zeros(n)
    rows_x, rows_v, rows_f = [x0 + zeros], [zeros], [zeros]
    row_of = {}
    columns = {
        name: np.zeros(n_sets) for name in ("row", "ramp", "mass", "k", "c", "ki", "f_offset")
    }
    friction = {
        name: np.empty(n_sets)
        for name in ("F_c", "F_s", "sigma_2", "v_r", "alpha", "sigma_0", "sigma_1")
    }
    params_of = {}
    for i, (cyl, model, drv, p) in enumerate(
        zip(cylinders, models, drives, pressures, strict=True)
    ):
        if isinstance(drv, SpringPull):
            columns["ramp"][i] = drv.speed
            columns["k"][i], columns["c"][i] = drv.stiffness, drv.damping
        else:
            if id(drv) not in row_of:
                x_r, v_r_, f_e, k, c, ki = _drive_signals(drv, time, x0)
                row_of[id(drv)] = (len(rows_x), k, c, ki)
                rows_x.append(x_r)
                rows_v.append(v_r_)
                rows_f.append(f_e)
            columns["row"][i], columns["k"][i], columns["c"][i], columns["ki"][i] = row_of[id(drv)]
        columns["mass"][i] = cyl.mass
        # both chambers at the set's pressure: net pressure force (A_a - A_b) p
        columns["f_offset"][i] = (cyl.area_a - cyl.area_b) * p
        key = (id(model), float(p))
        if key not in params_of:  # a model at a pressure is evaluated once
            params_of[key] = _friction_params(model, p)
        for name in friction:
            friction[name][i] = float(params_of[key][name])
    _batch_validity(models, "pressure", pressures, strict)
    try:  # all sets checked at once; on a failure, set by set to name the first bad one
        _check_lugre_arrays(friction)
    except ValueError:
        for i, model in enumerate(models):
            try:
                _check_friction(model, {name: friction[name][i] for name in friction})
            except ValueError as exc:
                raise ValueError(f"set {i}: {exc}") from None
    atol = _rosenbrock_scales(rtol, friction)
    out, steps, reached, final_rtol, passed = kernels.rosenbrock_batch(  # type: ignore[call-arg]  # numba Dispatcher
        dt, n, record_every, x0, v0, columns["row"].astype(np.int64), columns["ramp"],
        columns["mass"], columns["k"], columns["c"], columns["ki"], columns["f_offset"],
        np.array(rows_x), np.array(rows_v), np.array(rows_f),
        *(friction[name] for name in ("F_c", "F_s", "sigma_2", "sigma_0", "sigma_1", "v_r")),
        friction["alpha"], rtol, *(np.broadcast_to(a, (n_sets,)).copy() for a in atol),
        MAX_STEPS, 8 * numba.get_num_threads(), 0.0 if accuracy is None else accuracy,
        BATCH_MIN_RTOL,
    )  # fmt: skip
    if (reached < out.shape[2]).any():
        raise RuntimeError(
            f"{int((reached < out.shape[2]).sum())} set(s) stopped after {MAX_STEPS:.0e} steps; "
            "loosen rtol"
        )
    if accuracy is not None and not passed.all():
        failed = np.flatnonzero(~passed)
        message = (
            f"{failed.size} set(s) ({', '.join(map(str, failed[:10]))}"
            f"{', ...' if failed.size > 10 else ''}) did not pass the accuracy check "
            f"(RMS(F)/F_c <= {accuracy:g} between successive tolerances down to rtol "
            f"{BATCH_MIN_RTOL:g}); their results are the tightest run"
        )
        if strict:
            raise ValueError(message)
        warnings.warn(message, RuntimeWarning, stacklevel=2)
    rec = np.arange(0, n, record_every) * dt
    position, velocity, z, force, drive_force = (out[:, q, :] for q in range(5))
    _batch_validity(models, "speed", np.max(np.abs(velocity), axis=1), strict)
    return BatchResult(
        rec,
        position,
        force,
        pressures,
        velocity=velocity,
        z=z,
        drive_force=drive_force,
        info={
            "method": "rosenbrock",
            "scheme": "Rodas3",
            "rtol": final_rtol,
            "first_rtol": rtol,
            "accuracy": accuracy,
            "accuracy_passed": passed,
            "dt": dt,
            "record_every": record_every,
            "steps": steps,
        },
    )
