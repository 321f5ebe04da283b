"""A hydraulic cylinder with dynamic, pressure-dependent friction (thesis eq. 3.1/3.2).

    (m_p + m_lc) x'' = A_1 p_1 - A_2 p_2 + F_l - F_f

``simulate(cylinder, friction, drive, duration)`` returns a :class:`SimulationResult`.
Drives: :class:`PrescribedMotion` (the testing machine), :class:`AppliedForce`,
:class:`SpringPull` (the stick-slip set-up) and :class:`PositionServo` (PID).
Integrators: ``"fixed"`` (compiled impulse scheme with exact z), ``"dopri"`` (compiled adaptive
Dormand-Prince 5(4)), ``"scipy"`` (``solve_ivp``, the validation backend, any law).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..friction import get_law, law_params
from ..model import FrictionModel
from . import kernels
from .result import SimulationResult

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
]

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

    def __post_init__(self):
        if not (self.mass > 0 and math.isfinite(self.mass)):
            raise ValueError(
                f"Cylinder mass = {self.mass} is out of range; expected a finite mass > 0 kg"
            )
        if not (self.area_a >= 0 and self.area_b >= 0):
            raise ValueError("Cylinder areas must be >= 0 m^2")

    @classmethod
    def from_diameters(cls, bore, rod, mass, *, double_rod=False, stroke=math.inf):
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

    def __post_init__(self):
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


METHODS = ("dopri", "fixed", "scipy")
DEFAULT_RTOL = 1e-6
"""Default relative tolerance of ``"dopri"``: RMS(F - F_ref)/F_c of about 6e-6 on the
stick-slip reference case (the accuracy goal is 1e-4)."""


def simulate(
    cylinder: Cylinder,
    friction: FrictionModel,
    drive,
    duration: float,
    *,
    dt: float = 1e-3,
    pressure_a: Signal = 0.0,
    pressure_b: Signal | None = None,
    method: str = "dopri",
    step: float = DEFAULT_FIXED_STEP,
    rtol: float | None = None,
    x0: float = 0.0,
    v0: float = 0.0,
    z0: float = 0.0,
    strict: bool = False,
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
    method : {"dopri", "fixed", "scipy"}
        Integrator for the velocity-as-state drives: compiled adaptive Dormand-Prince 5(4)
        (default), the compiled fixed-step impulse scheme, or scipy Radau (reference). For
        PrescribedMotion, ``"scipy"`` gives the Radau reference and anything else the exact
        z update with mid-step velocity.
    step : float
        Internal step of ``"fixed"`` and of prescribed motion [s] (rounded to divide ``dt``).
    rtol : float, optional
        Relative tolerance of ``"dopri"`` (default 1e-6) and ``"scipy"`` (default 1e-9).
    x0, v0, z0 : float
        Initial position [m], velocity [m/s], bristle deflection [m].
    strict : bool
        Raise instead of warning (:class:`cylfric.model.ValidityWarning`) when the pressures
        leave the model's validity range or look like bar given as Pa.

    Returns
    -------
    SimulationResult
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; valid: {list(METHODS)}")
    if rtol is None:
        rtol = 1e-9 if method == "scipy" else DEFAULT_RTOL
    if not (0 < dt <= duration < math.inf):
        raise ValueError(f"need 0 < dt <= duration < inf; got dt = {dt} s, duration = {duration} s")
    if method == "fixed" and not (0 < step < math.inf):
        raise ValueError(f"step = {step} s is out of range; expected a finite step > 0 s")
    n = int(round(duration / dt)) + 1
    time = np.arange(n) * dt
    pa = _on_grid(pressure_a, time, "pressure_a")
    pb = pa if pressure_b is None else _on_grid(pressure_b, time, "pressure_b")
    for name, values in (("pressure_a", pa), ("pressure_b", pb)):
        if values.min() < 0:
            raise ValueError(
                f"{name} goes down to {values.min():.4g} Pa; expected pressures >= 0 Pa"
            )
    # warns outside the model's validity pressures, or for pressures that look like bar
    friction.check(None, friction.operating_pressure(pa, pb), strict=strict)
    if (
        np.ndim(pressure_a) == 0
        and (pressure_b is None or np.ndim(pressure_b) == 0)
        and not callable(pressure_a)
        and not callable(pressure_b)
    ):
        params = _friction_params(friction, float(pa[0]), float(pb[0]))  # constant pressures
    else:
        params = _friction_params(friction, pa, pb)
    _check_friction(friction, params)
    f_pressure = cylinder.area_a * pa - cylinder.area_b * pb
    info = {"method": method, "dt": dt}

    if isinstance(drive, PrescribedMotion):
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
    elif method == "fixed":
        substeps = max(1, int(math.ceil(dt / step - 1e-9)))
        pos, vel, z, force, mean_force, iterations = kernels.fixed_step(
            dt,
            substeps,
            *_plant_args(cylinder, friction, params, n, x0, v0, z0, k, c, ki, x_ref, v_ref, f_ext),
            1e-10,
        )
        states = {"position": pos, "velocity": vel, "z": z}
        info.update(step=dt / substeps, steps=(n - 1) * substeps, iterations=int(iterations))
    else:
        pos, vel, z, force, accepted, rejected, reached = kernels.dopri(
            dt,
            *_plant_args(cylinder, friction, params, n, x0, v0, z0, k, c, ki, x_ref, v_ref, f_ext),
            rtol,
            1e-12,
            1e-9,
            1e-13,
            50_000_000,
        )
        if reached < n:
            raise RuntimeError(
                f"dopri stopped at t = {(reached - 1) * dt} s after 5e7 steps; "
                "loosen rtol or use method='fixed'"
            )
        states = {"position": pos, "velocity": vel, "z": z}
        info.update(accepted=int(accepted), rejected=int(rejected))
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


def _check_friction(friction, params):
    """Clear errors for friction parameters the integrators cannot use (checked once)."""
    if friction.simulation_law != "lugre":
        return
    from ..friction import lugre_force

    shape = {name: np.asarray(params[name], dtype=float) for name in params}
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
    values = np.asarray(params[name], dtype=float)
    if values.ndim and not np.all(values == values.flat[0]):
        raise ValueError(f"{name} must not vary with pressure in the compiled integrators")
    return float(values.flat[0])


@dataclass(frozen=True)
class BatchResult:
    """Recorded signals of many simulated parameter sets.

    Attributes
    ----------
    time : ndarray
        Record times [s].
    position : ndarray
        (n_sets, n_records) rod positions [m].
    friction_force : ndarray
        (n_sets, n_records) friction forces [N] (eq. 2.5).
    pressure : ndarray
        Chamber pressure of each set [Pa].
    """

    time: np.ndarray
    position: np.ndarray
    friction_force: np.ndarray
    pressure: np.ndarray


def simulate_batch(
    cylinder: Cylinder,
    models,
    drive,
    duration: float,
    *,
    pressures,
    dt: float = 1e-3,
    record_every: int = 10,
    rtol: float = DEFAULT_RTOL,
    x0: float = 0.0,
    v0: float = 0.0,
) -> BatchResult:
    """Simulate many friction models and pressures at once on both cores (sweeps, Monte Carlo).

    Each set runs the compiled adaptive Dormand-Prince integrator of :func:`simulate`
    (LuGre friction, constant pressure per set); sets run in parallel with ``numba.prange``.

    Parameters
    ----------
    cylinder : Cylinder
        Shared plant.
    models : sequence of FrictionModel
        One LuGre model per set (or one model for all sets).
    drive : AppliedForce, SpringPull or PositionServo
        Shared drive.
    duration : float
        Simulated time [s].
    pressures : array_like
        Chamber pressure of each set [Pa] (both chambers; the models' reference applies).
    dt : float
        Input-grid interval [s]; signals are recorded every ``record_every`` intervals.
    rtol : float
        Relative tolerance of the integrator.

    Returns
    -------
    BatchResult
    """
    pressures = np.atleast_1d(np.asarray(pressures, dtype=float))
    if isinstance(models, FrictionModel):
        models = [models] * pressures.size
    models = list(models)
    if len(models) != pressures.size:
        raise ValueError(
            f"{len(models)} models for {pressures.size} pressures; expected one "
            "model per pressure (or a single model)"
        )
    if any(m.simulation_law != "lugre" for m in models):
        raise ValueError("simulate_batch needs LuGre models (simulation_law='lugre')")
    if isinstance(drive, PrescribedMotion):
        raise ValueError(
            "simulate_batch takes AppliedForce, SpringPull or PositionServo; "
            "prescribed motion needs no integration of the mechanics"
        )
    if not (duration > 0 and 0 < dt <= duration and record_every >= 1):
        raise ValueError("need 0 < dt <= duration and record_every >= 1")
    n = int(round(duration / dt)) + 1
    time = np.arange(n) * dt
    x_ref, v_ref, f_ext, k, c, ki = _drive_signals(drive, time, x0)
    # both chambers at the set's pressure: net pressure force (A_a - A_b) p per set
    f_offset = (cylinder.area_a - cylinder.area_b) * pressures
    table = {
        name: np.empty(pressures.size)
        for name in ("F_c", "F_s", "sigma_2", "v_r", "alpha", "sigma_0", "sigma_1")
    }
    for i, (model, p) in enumerate(zip(models, pressures, strict=True)):
        params = _friction_params(model, p)
        _check_friction(model, params)
        for name in table:
            table[name][i] = float(params[name])
    positions, frictions, reached = kernels.dopri_batch(
        dt,
        record_every,
        x0,
        v0,
        cylinder.mass,
        k,
        c,
        ki,
        x_ref,
        v_ref,
        f_ext,
        f_offset,
        table["F_c"],
        table["F_s"],
        table["sigma_2"],
        table["sigma_0"],
        table["sigma_1"],
        table["v_r"],
        table["alpha"],
        rtol,
        50_000_000,
    )
    if (reached < n).any():
        raise RuntimeError(
            f"{int((reached < n).sum())} set(s) stopped after 5e7 steps; loosen rtol"
        )
    return BatchResult(time[::record_every], positions, frictions, pressures)
