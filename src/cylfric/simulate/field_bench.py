"""Virtual field bench: a loader crane's boom cylinder logged in service (docs/field.md).

A boom turns about a pivot; the cylinder's base is fixed to the crane column, its rod eye
to the boom. Gravity on the boom and the payload, seen through the linkage, is a load on
the rod that changes with the rod's position; the boom's inertia about the pivot is a mass
at the rod that changes with it too. A proportional valve under position control moves the
boom (ramps, trapezoids, stops, occasional valve steps); a PLC logs rod position, the two
pressures and the valve command at 100 Hz with sensor noise and quantisation; several days
carry a friction level that may drift. The truth is returned (and saved) beside the logs.

Equations (docs/field.md, with sources):

* linkage: cylinder length ``l(theta) = |d e(theta) - b|`` (rod eye at distance ``d`` along
  the boom, base at ``b``), rod position ``x = l - l_min``; moment arm
  ``dl/dtheta = d (e_perp . (d e - b)) / l`` (virtual work).
* load and reflected mass (Lagrange, coordinate x): ``m(x) = J / (dl/dtheta)^2 + m_rod``,
  ``F_load(x) = g (m_boom r_g + m_payload L) cos(theta) / (dl/dtheta)``,
  ``m(x) a + 1/2 m'(x) v^2 + F_load(x) + F_friction(v, p) = p_A A_A - p_B A_B``.
* chambers (Merritt 1967, eq. 6-5): ``dp/dt = beta / V (Q -/+ A v)``; valve orifices
  ``Q = K u sqrt(dp)`` (turbulent, laminar below ``dp_laminar``, as Simscape's orifice);
  spool first order; P position control with velocity feed-forward.
* friction: ``(F_c + k_p p_mean) tanh(v / v_s) + F_v v`` (Coulomb + viscous, regularised).
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numba import njit

from .._atomic import atomic_write_text

if TYPE_CHECKING:
    from cylfric._typing import StrPath

__all__ = [
    "Crane",
    "FieldSettings",
    "FieldLog",
    "crane_geometry",
    "simulate_log",
    "field_records",
    "generate_field",
    "GRAVITY",
    "write_log",
    "write_mat73",
    "field_toml",
]

GRAVITY = 9.81
"""Standard gravity [m/s^2]."""


@dataclass(frozen=True)
class Crane:
    """A knuckle-boom loader crane's main boom and its lift cylinder (SI units).

    Attributes
    ----------
    boom_length : float
        Pivot to tip, where the payload hangs [m].
    boom_mass : float
        Boom mass, uniform along its length [kg].
    rod_eye : float
        Distance of the rod eye from the pivot along the boom [m].
    base : tuple of float
        Cylinder base relative to the pivot (forward, up) [m].
    angles : tuple of float
        Boom angles at the retracted and the extended end of the stroke [rad].
    bore, rod : float
        Piston and rod diameters [m].
    rod_mass : float
        Piston and rod mass, moving with x [kg].
    """

    boom_length: float = 5.0
    boom_mass: float = 900.0
    rod_eye: float = 1.4
    base: tuple[float, float] = (0.3, -1.0)
    angles: tuple[float, float] = (math.radians(-25.0), math.radians(35.0))
    bore: float = 0.125
    rod: float = 0.070
    rod_mass: float = 40.0

    @property
    def area_a(self) -> float:
        """Piston area [m^2]."""
        return math.pi / 4 * self.bore**2

    @property
    def area_b(self) -> float:
        """Annulus area [m^2]."""
        return math.pi / 4 * (self.bore**2 - self.rod**2)


def crane_geometry(crane: Crane, theta: np.ndarray, payload: float) -> dict[str, np.ndarray]:
    """Rod position, moment arm, gravity load and reflected mass at boom angles ``theta``.

    Returns a dict of arrays: ``length`` [m], ``arm`` (dl/dtheta) [m], ``load`` [N] (the
    force the rod must push to hold the boom), ``mass`` [kg] (reflected to the rod, with
    the rod's own mass) and ``theta`` [rad].
    """
    theta = np.asarray(theta, dtype=float)
    d, (bx, by), length_boom = crane.rod_eye, crane.base, crane.boom_length
    ex, ey = np.cos(theta), np.sin(theta)
    rx, ry = d * ex - bx, d * ey - by  # cylinder vector, base -> rod eye
    length = np.hypot(rx, ry)
    arm = d * (-ey * rx + ex * ry) / length  # dl/dtheta
    moment = GRAVITY * (crane.boom_mass * length_boom / 2 + payload * length_boom) * ex
    inertia = crane.boom_mass * length_boom**2 / 3 + payload * length_boom**2
    return {
        "theta": theta,
        "length": length,
        "arm": arm,
        "load": moment / arm,
        "mass": inertia / arm**2 + crane.rod_mass,
    }


def _position_tables(crane: Crane, payload: float, n: int = 2001) -> dict[str, np.ndarray]:
    """Geometry tabulated against the rod position x = l - l_min (monotonic in theta)."""
    theta = np.linspace(crane.angles[0], crane.angles[1], n)
    g = crane_geometry(crane, theta, payload)
    x = g["length"] - g["length"][0]
    if np.any(np.diff(x) <= 0):
        raise ValueError("the crane's cylinder length must grow with the boom angle")
    dmass = np.gradient(g["mass"], x)
    return {"x": x, "load": g["load"], "mass": g["mass"], "dmass": dmass, "theta": theta}


@dataclass(frozen=True)
class FieldSettings:
    """How the virtual machine works and is logged (SI units).

    Friction: ``F_c`` [N], ``F_v`` [N*s/m], ``k_p`` [N/Pa] (slope of the Coulomb level with
    the mean chamber pressure), ``v_s`` [m/s] (regularisation of sign(v)).
    Moves: ``speeds`` [m/s] of the trapezoids, ``acceleration`` [m/s^2], ``dwell`` (min,
    max) [s], ``step_share`` [-] share of moves that are valve steps (the reference jumps).
    Logging: ``rate`` [Hz], noise standard deviations and quantisation steps of position
    [m] and pressure [Pa].
    """

    crane: Crane = field(default_factory=Crane)
    payloads: tuple[float, ...] = (500.0, 900.0)
    F_c: float = 1400.0
    F_v: float = 6000.0
    k_p: float = 0.0
    v_s: float = 0.002
    supply: float = 210e5
    tank: float = 2e5
    bulk_modulus: float = 1.2e9
    dead_volume: float = 1.5e-3
    valve_flow: float = 1.2e-3  # m^3/s at full opening and 35 bar drop
    valve_time: float = 0.02
    dp_laminar: float = 2e5
    gain: float = 2.0
    speeds: tuple[float, ...] = (0.03, 0.06, 0.10)
    acceleration: float = 0.25
    dwell: tuple[float, float] = (0.5, 3.0)
    step_share: float = 0.08
    margin: float = 0.05
    rate: float = 100.0
    step: float = 5e-4
    position_noise: float = 5e-5
    position_quantum: float = 1e-5
    pressure_noise: float = 0.3e5
    pressure_quantum: float = 0.05e5
    counterbalance: bool = False
    check_drop: float = 3e5
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("F_c", "F_v", "k_p", "rate", "step", "supply", "bulk_modulus"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"FieldSettings.{name} = {value}; expected a finite value >= 0")
        if not self.speeds or min(self.speeds) <= 0:
            raise ValueError(f"FieldSettings.speeds = {self.speeds}; expected speeds > 0 [m/s]")
        if (
            self.rate * self.step > 1
            or abs(round(1 / (self.rate * self.step)) * self.rate * self.step - 1) > 1e-9
        ):
            raise ValueError("FieldSettings.step must divide the logging period 1/rate")


@dataclass
class FieldLog:
    """One simulated log: the signals as logged (SI) and the truth behind them."""

    time: np.ndarray
    position: np.ndarray
    pressure_a: np.ndarray
    pressure_b: np.ndarray
    valve: np.ndarray
    truth: dict[str, Any]
    chamber_a: np.ndarray | None = None  # the true chamber pressure when the sensor is valve-side


def _moves(
    settings: FieldSettings, stroke: float, duration: float, rng, start: float | None = None
) -> np.ndarray:
    """Reference position and velocity sampled at the integrator step: (n, 2); from rest at
    ``start`` [m] (default mid-stroke)."""
    dt = settings.step
    n = int(round(duration / dt))
    ref = np.empty((n, 2))
    lo, hi = settings.margin * stroke, (1 - settings.margin) * stroke
    x = 0.5 * (lo + hi) if start is None else float(start)
    i = 0
    acc = settings.acceleration
    while i < n:
        dwell = int(rng.uniform(*settings.dwell) / dt)
        ref[i : i + dwell] = (x, 0.0)
        i += dwell
        if i >= n:
            break
        target = rng.uniform(lo, hi)
        while abs(target - x) < 0.1 * stroke:
            target = rng.uniform(lo, hi)
        sign = math.copysign(1.0, target - x)
        distance = abs(target - x)
        if rng.random() < settings.step_share:  # an operator's valve step: the reference jumps
            k = int(1.5 * distance / max(settings.speeds) / dt) + 1
            ref[i : i + k] = (target, 0.0)
            i += k
            x = target
            continue
        vmax = min(rng.choice(settings.speeds), math.sqrt(distance * acc))
        t_acc = vmax / acc
        t_total = distance / vmax + t_acc
        k = int(t_total / dt) + 1
        t = np.arange(k) * dt
        v = np.minimum.reduce([acc * t, np.full(k, vmax), np.maximum(acc * (t_total - t), 0)])
        s = np.cumsum(v) * dt
        s *= distance / s[-1] if s[-1] > 0 else 1.0
        m = min(k, n - i)
        ref[i : i + m, 0] = x + sign * s[:m]
        ref[i : i + m, 1] = sign * v[:m]
        i += m
        x = target
    return ref


def _integrate(ref, table_x, table_load, table_mass, table_dmass, p, fric, x0):
    """Fixed-step semi-implicit Euler (velocity first, then position and pressures).

    ``p``: (A_A, A_B, stroke, supply, tank, beta, V0, K, dp_lam, tau_valve, gain, v_full,
    every) ; ``fric``: (F_c, F_v, k_p, v_s). Returns logged (x, v, p_A, p_B, u, a) every
    ``every`` steps.
    """
    return _kernel(ref, table_x, table_load, table_mass, table_dmass, p, fric, x0)


@njit(cache=True, nogil=True)
def _kernel(ref, tx, tload, tmass, tdmass, p, fric, x0):  # pragma: no cover - compiled
    area_a, area_b, stroke, supply, tank, beta, v0, kv, dp_lam, tau, gain, v_full, every, dt = (
        p[0],
        p[1],
        p[2],
        p[3],
        p[4],
        p[5],
        p[6],
        p[7],
        p[8],
        p[9],
        p[10],
        p[11],
        int(p[12]),
        p[13],
    )
    f_c, f_v, k_p, v_s = fric[0], fric[1], fric[2], fric[3]
    n = ref.shape[0]
    m = n // every
    out = np.empty((m, 6))
    x = x0
    v = 0.0
    h = tx[1] - tx[0]
    nt = tx.size
    j0 = min(max(int(x / h), 0), nt - 2)
    w = (x - tx[j0]) / h
    load0 = tload[j0] * (1 - w) + tload[j0 + 1] * w
    pb = 20e5
    pa = (load0 + pb * area_b) / area_a
    u = 0.0
    acc = 0.0
    for i in range(n):
        # geometry by linear interpolation on the uniform table of x
        j = min(max(int(x / h), 0), nt - 2)
        w = (x - tx[j]) / h
        load = tload[j] * (1 - w) + tload[j + 1] * w
        mass = tmass[j] * (1 - w) + tmass[j + 1] * w
        dmass = tdmass[j] * (1 - w) + tdmass[j + 1] * w
        # position control with velocity feed-forward, first-order spool
        command = (ref[i, 1] + gain * (ref[i, 0] - x)) / v_full
        command = min(max(command, -1.0), 1.0)
        u += dt / tau * (command - u)
        # orifices: turbulent, laminar below dp_lam
        if u >= 0:
            d1 = supply - pa
            d2 = pb - tank
            q_a = kv * u * _root(d1, dp_lam)
            q_b = -kv * u * _root(d2, dp_lam) * area_b / area_a
        else:
            d1 = pa - tank
            d2 = supply - pb
            q_a = kv * u * _root(d1, dp_lam)
            q_b = -kv * u * _root(d2, dp_lam) * area_b / area_a
        force = pa * area_a - pb * area_b
        level = f_c + k_p * 0.5 * (pa + pb)
        friction = level * math.tanh(v / v_s) + f_v * v
        acc = (force - load - friction - 0.5 * dmass * v * v) / mass
        # stiff regularised friction: implicit in v for the tanh slope
        slope = level / v_s * (1 - math.tanh(v / v_s) ** 2) + f_v
        v_new = v + dt * acc / (1 + dt * slope / mass)
        acc = (v_new - v) / dt
        v = v_new
        x += dt * v
        if x < 0:
            x, v = 0.0, 0.0
        elif x > stroke:
            x, v = stroke, 0.0
        va = v0 + area_a * x
        vb = v0 + area_b * (stroke - x)
        pa += dt * beta / va * (q_a - area_a * v)
        pb += dt * beta / vb * (q_b + area_b * v)
        pa = max(pa, 0.3e5)
        pb = max(pb, 0.3e5)
        if (i + 1) % every == 0:
            k = (i + 1) // every - 1
            out[k, 0] = x
            out[k, 1] = v
            out[k, 2] = pa
            out[k, 3] = pb
            out[k, 4] = u
            out[k, 5] = acc
    return out


@njit(cache=True, inline="always")
def _root(dp, dp_lam):  # pragma: no cover - compiled with the kernel
    """sqrt(|dp|) sign(dp), linear below dp_lam (laminar), continuous at dp_lam."""
    if dp >= dp_lam:
        return math.sqrt(dp)
    if dp <= -dp_lam:
        return -math.sqrt(-dp)
    return dp / math.sqrt(dp_lam)


def _quantise(values, noise, quantum, rng):
    noisy = values + rng.normal(0.0, noise, values.shape) if noise > 0 else values.copy()
    return np.round(noisy / quantum) * quantum if quantum > 0 else noisy


def simulate_log(
    settings: FieldSettings,
    *,
    duration: float,
    payload: float,
    friction_scale: float = 1.0,
    seed: int | None = None,
    start: float | None = None,
) -> FieldLog:
    """Simulate one log of ``duration`` seconds with ``payload`` [kg] at the boom tip.

    The boom starts at rest at ``start`` [m] of rod position (default mid-stroke), its
    chambers at the pressures that hold the load there.

    ``friction_scale`` multiplies F_c, F_v and k_p (a day's friction level). Returns the
    logged signals (noise and quantisation applied) and the truth: friction parameters,
    the load and reflected mass against position, the logged samples' true velocity.
    """
    rng = np.random.default_rng(settings.seed if seed is None else seed)
    crane = settings.crane
    tables = _position_tables(crane, payload)
    stroke = float(tables["x"][-1])
    grid = np.linspace(0.0, stroke, 1001)  # uniform table for the kernel
    load = np.interp(grid, tables["x"], tables["load"])
    mass = np.interp(grid, tables["x"], tables["mass"])
    dmass = np.interp(grid, tables["x"], tables["dmass"])
    ref = _moves(settings, stroke, duration, rng, start)
    every = int(round(1 / (settings.rate * settings.step)))
    v_full = settings.valve_flow / crane.area_a  # speed at full opening, 35 bar drop
    kv = settings.valve_flow / math.sqrt(35e5)
    params = np.array(
        [
            crane.area_a,
            crane.area_b,
            stroke,
            settings.supply,
            settings.tank,
            settings.bulk_modulus,
            settings.dead_volume,
            kv,
            settings.dp_laminar,
            settings.valve_time,
            settings.gain,
            v_full,
            every,
            settings.step,
        ]
    )
    s = friction_scale
    fric = np.array([s * settings.F_c, s * settings.F_v, s * settings.k_p, settings.v_s])
    out = _integrate(ref, grid, load, mass, dmass, params, fric, float(ref[0, 0]))
    n = out.shape[0]
    time = np.arange(1, n + 1) / settings.rate
    chamber_a = out[:, 2]
    sensor_a = chamber_a
    if settings.counterbalance:
        sensor_a = _valve_side_pressure(chamber_a, out[:, 1], out[:, 4], settings)
    truth = {
        "payload [kg]": payload,
        "friction_scale [-]": friction_scale,
        "F_c [N]": s * settings.F_c,
        "F_v [N*s/m]": s * settings.F_v,
        "k_p [N/Pa]": s * settings.k_p,
        "v_s [m/s]": settings.v_s,
        "stroke [m]": stroke,
        "area_a [m^2]": crane.area_a,
        "area_b [m^2]": crane.area_b,
        "position [m]": grid,
        "load [N]": load,
        "mass [kg]": mass,
        "velocity [m/s]": out[:, 1],
        "acceleration [m/s^2]": out[:, 5],
        "counterbalance": settings.counterbalance,
    }
    return FieldLog(
        time=time,
        position=_quantise(out[:, 0], settings.position_noise, settings.position_quantum, rng),
        pressure_a=_quantise(sensor_a, settings.pressure_noise, settings.pressure_quantum, rng),
        pressure_b=_quantise(out[:, 3], settings.pressure_noise, settings.pressure_quantum, rng),
        valve=np.round(out[:, 4] * 1000) / 1000,
        truth=truth,
        chamber_a=chamber_a if settings.counterbalance else None,
    )


def _valve_side_pressure(chamber, velocity, valve, settings: FieldSettings) -> np.ndarray:
    """Pressure between the directional valve and a counter-balance valve on side A.

    Simplified (docs/field.md): lifting, the flow passes the CBV's check valve, the line
    reads the chamber plus the check's cracking drop; lowering and holding, the CBV throttles
    or closes and the line is at tank pressure plus the directional valve's own drop (lowering)
    or decays to tank pressure with a 0.3 s time constant (holding). The chamber itself is
    simulated as metered by the directional valve.
    """
    line = np.empty_like(chamber)
    alpha = 1 - math.exp(-1 / (settings.rate * 0.3))
    value = chamber[0]
    for i in range(chamber.size):
        if valve[i] > 0.01:
            target = chamber[i] + settings.check_drop
        elif valve[i] < -0.01:
            target = settings.tank + 4e5 * abs(valve[i])
        else:
            target = settings.tank
        value += alpha * (target - value) if valve[i] <= 0.01 else target - value
        line[i] = value
    return line


def field_records(
    settings: FieldSettings,
    day_scales,
    *,
    duration: float = 300.0,
    seed: int = 0,
    logs_per_day: int = 2,
) -> tuple[list, list]:
    """Simulated logs in memory, as :func:`cylfric.io.fieldlog.read_field_logs` returns
    them: ``logs_per_day`` logs [s of ``duration``] per day, day ``d`` at friction scale
    ``day_scales[d]`` [-], payloads in turn, seeds ``seed + 10 d + j``. Returns
    (:class:`~cylfric.io.fieldlog.FieldRecord` list, their truths)."""
    from ..io.fieldlog import FieldRecord

    records, truths = [], []
    for d, scale in enumerate(day_scales):
        for j in range(logs_per_day):
            log = simulate_log(
                settings,
                duration=duration,
                payload=settings.payloads[j % len(settings.payloads)],
                friction_scale=scale,
                seed=seed + 10 * d + j,
            )
            records.append(
                FieldRecord(
                    f"d{d}l{j}",
                    f"day{d}",
                    log.time,
                    log.position,
                    log.pressure_a,
                    log.pressure_b,
                    log.valve,
                    {"kind": "memory"},
                )
            )
            truths.append(log.truth)
    return records, truths


def generate_field(
    out: StrPath,
    settings: FieldSettings | None = None,
    *,
    days: int = 2,
    logs_per_day: int = 2,
    duration: float = 600.0,
    friction_scales: tuple[float, ...] | None = None,
    fmt: str = "csv",
) -> dict[str, Any]:
    """Write a field campaign: ``day<k>_log<j>.csv`` (or ``.mat``), field.toml, truth.json.

    Each day has ``logs_per_day`` logs of ``duration`` [s], the payloads cycling through
    ``settings.payloads``; ``friction_scales`` (one per day, default all 1) scales the
    friction. ``fmt``: ``"csv"`` (units in the header), ``"mat"`` (v5, scipy) or
    ``"mat73"`` (v7.3/HDF5, h5py). Returns the truth (as written to truth.json).
    """
    settings = settings or FieldSettings()
    if fmt not in ("csv", "mat", "mat73"):
        raise ValueError(f"fmt = {fmt!r}; valid: 'csv', 'mat', 'mat73'")
    scales = tuple(friction_scales) if friction_scales is not None else (1.0,) * days
    if len(scales) != days:
        raise ValueError(f"friction_scales has {len(scales)} values; expected one per day ({days})")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    truth: dict[str, Any] = {"settings": _settings_record(settings), "logs": {}}
    k = 0
    for day in range(days):
        for j in range(logs_per_day):
            payload = settings.payloads[k % len(settings.payloads)]
            log = simulate_log(
                settings,
                duration=duration,
                payload=payload,
                friction_scale=scales[day],
                seed=settings.seed * 1000 + k,
            )
            name = f"2026-03-{day + 1:02d}_log{j + 1}.{'csv' if fmt == 'csv' else 'mat'}"
            write_log(out / name, log, fmt)
            record = {
                key: (value.tolist() if key in ("position [m]", "load [N]", "mass [kg]") else value)
                for key, value in log.truth.items()
                if not isinstance(value, np.ndarray)
                or key in ("position [m]", "load [N]", "mass [kg]")
            }
            record["day"] = day + 1
            truth["logs"][name] = record
            k += 1
    atomic_write_text(out / "truth.json", json.dumps(truth, indent=1) + "\n")
    atomic_write_text(out / "field.toml", field_toml(settings, fmt))
    return truth


def _settings_record(settings: FieldSettings) -> dict[str, Any]:
    record = asdict(settings)
    record["crane"]["area_a [m^2]"] = settings.crane.area_a
    record["crane"]["area_b [m^2]"] = settings.crane.area_b
    return record


def field_toml(settings: FieldSettings, fmt: str = "csv") -> str:
    """The field.toml that describes the bench's logs."""
    crane = settings.crane
    units = ""
    if fmt != "csv":
        units = '\n[units]\ntime = "s"\nposition = "mm"\npressure_a = "bar"\npressure_b = "bar"\n'
    sensor = "valve side" if settings.counterbalance else "chamber"
    return (
        "# written by cylfric's virtual field bench\n"
        "[cylinder]\n"
        f'bore = "{crane.bore * 1e3:g} mm"\n'
        f'rod = "{crane.rod * 1e3:g} mm"\n'
        'orientation = "A extends"\n\n'
        "[columns]\n"
        'time = "time"\nposition = "position"\npressure_a = "p_A"\npressure_b = "p_B"\n'
        f'valve = "{"valve command" if fmt == "csv" else "valve_command"}"\n'
        f"{units}\n"
        "[sensors]\n"
        f'pressure_a = "{sensor}"\npressure_b = "chamber"\n'
    )


def write_log(path: Path, log: FieldLog, fmt: str = "csv") -> None:
    """Write one log as a PLC would: engineering units (mm, bar, %)."""
    columns = {
        "time": log.time,
        "position": log.position * 1e3,
        "p_A": log.pressure_a / 1e5,
        "p_B": log.pressure_b / 1e5,
        "valve command": log.valve * 100,
    }
    if fmt == "csv":
        import io

        units = {"time": "s", "position": "mm", "p_A": "bar", "p_B": "bar", "valve command": "%"}
        buffer = io.StringIO()
        buffer.write(",".join(f"{k} [{units[k]}]" for k in columns) + "\n")
        np.savetxt(buffer, np.column_stack(list(columns.values())), delimiter=",", fmt="%.6g")
        atomic_write_text(path, buffer.getvalue())
    elif fmt == "mat":
        from scipy.io import savemat

        savemat(str(path), {k.replace(" ", "_"): v for k, v in columns.items()})
    else:
        write_mat73(path, {k.replace(" ", "_"): v for k, v in columns.items()})


def write_mat73(path: Path, variables: dict[str, np.ndarray]) -> None:
    """A MATLAB v7.3 file (HDF5 with the 512-byte MATLAB header), as MATLAB lays it out:
    column vectors stored as (1, n) datasets with the ``MATLAB_class`` attribute."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as handle:
        for name, values in variables.items():
            data = handle.create_dataset(name, data=np.asarray(values, dtype=float)[None, :])
            data.attrs["MATLAB_class"] = np.bytes_("double")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created by: cylfric field bench"
    with open(path, "r+b") as handle:
        handle.write(header.ljust(116, b" ") + b"\x00" * 8 + b"\x00\x02IM")


def with_settings(settings: FieldSettings, **changes: Any) -> FieldSettings:
    """``settings`` with ``changes`` (dataclasses.replace, re-checked)."""
    return replace(settings, **changes)
