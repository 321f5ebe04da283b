"""Virtual servo-valve rig: a cylinder driven by a proportional valve, no load cell.

A single-rod (or double-rod) cylinder moves a mass; a 4/3 proportional valve meters oil
from a supply to chamber A and from chamber B to tank (or the reverse), so the chamber
pressures are set by the valve opening, the areas and the friction, not by the experimenter.
The files carry what such a rig measures: time, position, ``p_A``, ``p_B`` and the valve
voltage; the friction force has to be computed from the force balance (eq. 3.1 without a
load cell), ``F_f sign(v) = A_A p_A - A_B p_B - m x''``.

Model (gauge pressures, tank at 0 Pa), integrated with a fixed step (numba)::

    tau_v s' = u/u_max - s                                   spool, first-order lag
    Q_A = K a(s) q(p_s - p_A)  (s > 0),  -K a(s) q(p_A)      (s < 0)    orifice edges
    Q_B = -K a(s) q(p_B)       (s > 0),   K a(s) q(p_s - p_B) (s < 0)
    p_A' = beta / (V_A0 + A_A x) (Q_A - A_A v)               chamber compliance
    p_B' = beta / (V_B0 + A_B (L - x)) (Q_B + A_B v)
    m v' = A_A p_A - A_B p_B - F_f(v, p)                     no external load
    tau_s p_s' = p_n - p_s - c (Q_A^+ + Q_B^+)               supply droop and recovery

with ``a(s) = max(|s| - overlap, 0) / (1 - overlap)`` (spool overlap: a dead band),
``q(dp) = sign(dp) sqrt(|dp|)`` (laminar below ``transition_pressure``), ``F_f`` the
steady friction of a :class:`~cylfric.model.FrictionModel` regularised by
``tanh(v / v_eps)`` and the velocity step linearly implicit. Each run is one voltage step
out (extension) and one back (retraction), with rests between: after each step the speed
and the pressures pass through a start-up transient (spool lag, the hydraulic oscillation of
mass and oil column, the supply's droop) before they settle. In such a rig the chamber
pressures are tied to the direction of motion: with one supply pressure, extension and
retraction each run at their own p_A whatever the speed, so a pressure slope cannot be told
from a direction effect. Several supply pressures, drawn independently of the direction
(:attr:`ValveRigSettings.supply_pressures_bar`), untie them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..friction.pressure import operating_pressure
from ..io.writers import atomic_write_text, write_mts_text
from ..model import FrictionModel
from .kernels import g_function

if TYPE_CHECKING:
    from cylfric._typing import StrPath

__all__ = [
    "ValveRigSettings",
    "ValveRun",
    "ValveCampaign",
    "VALVE_RIG_FRICTION",
    "run_valve_test",
    "generate_valve_campaign",
]

VALVE_RIG_FRICTION = FrictionModel(
    {
        "F_c": {"intercept": 60.0, "slope": 2.0e-5},  # 60 N + 2 N/bar
        "F_s": {"intercept": 100.0, "slope": 2.5e-5},  # 100 N + 2.5 N/bar
        "sigma_2": {"intercept": 800.0, "slope": 1.0e-4},  # 800 N*s/m + 10 N*s/m per bar
        "v_r": 0.010,
        "alpha": 1.0,
    },
    reference="a",
)
"""Default friction of the virtual valve rig: a rod and piston seal set of a 40/25 mm
teaching-lab cylinder, of the order of 100-300 N, rising with the pressure of chamber A
(``reference="a"``, the chamber the points table reports)."""


@dataclass(frozen=True)
class ValveRigSettings:
    """The virtual valve rig (SI unless the name says otherwise).

    Defaults: a 40/25 mm single-rod cylinder of 300 mm stroke on a 20 kg carriage, a
    24 L/min (at 35 bar per edge) proportional valve with 10 V full scale, 15 ms spool lag
    and 3 % overlap, 1 L of hose per chamber with an effective bulk modulus of 0.9 GPa
    (oil with some air), a 100 bar supply that droops by up to about 6 % at full flow and
    recovers in 0.25 s, and sensors of a teaching lab: position 5 um quantisation and 3 um
    noise, pressures 0.05 bar quantisation, 0.08 bar noise and 0.15 bar pump ripple at 120 Hz,
    sampled at 1 kHz.

    ``start_transients`` injects start transients: the runs it names (their index in
    :meth:`runs`' order) step for ``transient_step`` only, so each stroke ends while the
    spool, the oil column and the supply still settle (0.38 s: the force balance's level is
    off its steady value by 1-35 N, 0.5-18 %, with windows of 15-250 ms against 1.2 s; at
    0.3 s the strokes are too short for a window). Their rows of the campaign's ``truth``
    say ``transient [-] = True``.
    """

    friction: FrictionModel = field(default_factory=lambda: VALVE_RIG_FRICTION)
    bore: float = 0.040  # [m]
    rod: float = 0.025  # [m]
    double_rod: bool = False
    stroke: float = 0.300  # [m]
    moving_mass: float = 20.0  # [kg]
    supply_pressures_bar: tuple = (100.0,)  # [bar], one per run in turn (seeded shuffle)
    voltages: tuple = (1.0, 1.2, 1.4, 1.7, 2.0, 2.3, 2.7, 3.1, 3.6, 4.2)  # [V]
    repeats: int = 2
    full_scale_voltage: float = 10.0  # [V]
    rated_flow: float = 24.0 / 60000  # [m^3/s] at full opening
    rated_drop: float = 35e5  # [Pa] per metering edge, for rated_flow
    spool_time_constant: float = 0.015  # [s]
    overlap: float = 0.03  # [-] of the spool travel
    transition_pressure: float = 0.5e5  # [Pa], laminar below
    bulk_modulus: float = 0.9e9  # [Pa], effective
    dead_volume: float = 1.0e-3  # [m^3] per chamber (hoses, valve block)
    supply_time_constant: float = 0.25  # [s]
    supply_droop: float = 0.06  # [-] of the supply pressure at rated flow
    regularisation_speed: float = 2e-4  # [m/s], v_eps of tanh(v / v_eps)
    rest: float = 0.4  # [s] before, between and after the two steps
    longest_step: float = 3.0  # [s] a step ends then or at the end of its travel
    travel_margin: float = 0.02  # [m] kept from each end of the stroke
    sample_interval: float = 1e-3  # [s]
    internal_step: float = 2e-5  # [s]
    position_noise: float = 3e-6  # [m], standard deviation
    position_resolution: float = 5e-6  # [m]
    pressure_noise: float = 0.08e5  # [Pa], standard deviation
    pressure_resolution: float = 0.05e5  # [Pa]
    pressure_ripple: float = 0.15e5  # [Pa], amplitude
    ripple_frequency: float = 120.0  # [Hz]
    seed: int = 0
    start_transients: tuple = ()  # runs (index in run order) whose steps end early
    transient_step: float = 0.38  # [s], their steps' length: still in the start transient

    @property
    def area_a(self) -> float:
        """Piston area of chamber A [m^2]."""
        bore = math.pi / 4 * self.bore**2
        return bore - math.pi / 4 * self.rod**2 if self.double_rod else bore

    @property
    def area_b(self) -> float:
        """Annulus area of chamber B [m^2]."""
        return math.pi / 4 * (self.bore**2 - self.rod**2)

    def runs(self) -> list[tuple[float, float]]:
        """(voltage [V], supply pressure [Pa]) of every run in run order (seeded)."""
        rng = np.random.default_rng(self.seed + 7)
        voltages = [u for _ in range(self.repeats) for u in self.voltages]
        order = rng.permutation(len(voltages))
        supply = np.asarray(self.supply_pressures_bar, dtype=float) * 1e5
        picks = rng.permutation(np.resize(supply, len(voltages)))
        return [(float(voltages[i]), float(picks[k])) for k, i in enumerate(order)]


@dataclass(frozen=True)
class ValveRun:
    """One simulated run and its truth.

    Arrays at the sample times: ``time`` [s], ``position`` [m], ``pressure_a``,
    ``pressure_b`` [Pa], ``voltage`` [V] (as measured), ``velocity`` [m/s] (true),
    ``friction`` [N] (true, signed). ``levels`` holds per direction (+1, -1) the true steady
    state at the end of the step: ``velocity [m/s]``, ``pressure_a [Pa]``, ``pressure_b
    [Pa]``, ``friction [N]`` (magnitude, from the friction model at that state).
    """

    time: np.ndarray
    position: np.ndarray
    pressure_a: np.ndarray
    pressure_b: np.ndarray
    voltage: np.ndarray
    velocity: np.ndarray
    friction: np.ndarray
    voltage_step: float
    supply_pressure: float
    levels: dict


@njit(cache=True, nogil=True)
def _flow(dp, transition):
    """Orifice flow function q(dp) [sqrt(Pa)]: sqrt law, laminar below ``transition``."""
    if abs(dp) >= transition:
        return math.copysign(math.sqrt(abs(dp)), dp)
    return dp / math.sqrt(transition)


@njit(cache=True, nogil=True)
def _valve_kernel(
    rig, friction, command, supply, stroke_limits, rest, longest, h, every, n_out, out
):
    """Fixed-step integration of one run; writes (t, x, v, pA, pB, u, F_f) rows of ``out``.

    ``rig`` = (A_A, A_B, m, L, K, tau_v, overlap, dp_tr, beta, V_0, tau_s, c, v_eps),
    ``friction`` = (F_c0, F_c1, F_s0, F_s1, s_0, s_1, v_r, alpha) (linear laws in p_A).
    Returns the number of rows written.
    """
    A_A, A_B, m, L, K, tau_v, overlap, dp_tr, beta, V0, tau_s, c, v_eps = rig
    F_c0, F_c1, F_s0, F_s1, s_0, s_1, v_r, alpha = friction
    x_lo, x_hi = stroke_limits
    x, v, s = x_lo, 0.0, 0.0
    p_s = supply
    # at rest both chambers hold the pressure the closed (overlapped) valve traps
    p_a = 0.3 * supply
    p_b = p_a * A_A / A_B
    phase, t_phase, t, k, row = 0, 0.0, 0.0, 0, 0
    while row < n_out and phase < 5:
        # valve command of the phase: rest, extend, rest, retract, rest
        u = command if phase == 1 else (-command if phase == 3 else 0.0)
        if (phase in (0, 2, 4) and t_phase >= rest) or (
            (phase == 1 and (x >= x_hi or t_phase >= longest))
            or (phase == 3 and (x <= x_lo or t_phase >= longest))
        ):
            phase += 1
            t_phase = 0.0
            continue
        open_ = max(abs(s) - overlap, 0.0) / (1.0 - overlap)
        if s >= 0:
            q_a = K * open_ * _flow(p_s - p_a, dp_tr)
            q_b = -K * open_ * _flow(p_b, dp_tr)
        else:
            q_a = -K * open_ * _flow(p_a, dp_tr)
            q_b = K * open_ * _flow(p_s - p_b, dp_tr)
        p_op = max(p_a, 0.0)
        F_c = F_c0 + F_c1 * p_op
        F_s = F_s0 + F_s1 * p_op
        s_2 = s_0 + s_1 * p_op
        speed = abs(v)
        g = g_function(speed, F_c, F_s, v_r, alpha)  # eq. 2.5
        th = math.tanh(v / v_eps)
        f = (g + s_2 * speed) * th
        if k % every == 0:
            out[row, 0] = t
            out[row, 1] = x
            out[row, 2] = v
            out[row, 3] = p_a
            out[row, 4] = p_b
            out[row, 5] = u
            out[row, 6] = f
            row += 1
        # linearly implicit velocity step (the regularised friction is stiff near v = 0)
        dfdv = (g + s_2 * speed) * (1.0 - th * th) / v_eps + s_2 * abs(th)
        drive = A_A * p_a - A_B * p_b
        v_new = v + h * (drive - f) / (m + h * dfdv)
        x_new = x + h * v_new
        va = V0 + A_A * (x - x_lo)
        vb = V0 + A_B * (x_hi - x)
        p_a = max(p_a + h * beta / va * (q_a - A_A * v_new), 0.0)
        p_b = max(p_b + h * beta / vb * (q_b + A_B * v_new), 0.0)
        supply_flow = max(q_a, 0.0) + max(q_b, 0.0)
        p_s = p_s + h * (supply - p_s - c * supply_flow) / tau_s
        s = s + h * (u - s) / tau_v
        x, v = x_new, v_new
        t += h
        t_phase += h
        k += 1
    return row


def _friction_vector(model: FrictionModel) -> np.ndarray:
    """(F_c0, F_c1, F_s0, F_s1, s_0, s_1, v_r, alpha) of a linear-law Stribeck model, in p_A."""
    if model.pressure_law != "linear" or model.friction_law != "stribeck":
        raise ValueError(
            "the valve rig takes a Stribeck model with linear pressure laws; got "
            f"{model.friction_law} with {model.pressure_law} laws"
        )
    if model.reference != "a":
        raise ValueError(
            f"the valve rig's friction sees chamber A (reference 'a'); got {model.reference!r}"
        )
    k = model.coefficients()
    values = []
    for name in ("F_c", "F_s", "sigma_2"):
        spec = k[name]
        if isinstance(spec, dict):
            values += [float(spec["intercept"]), float(spec.get("slope", 0.0))]
        else:
            values += [float(spec), 0.0]
    return np.array(values + [float(k["v_r"]), float(k["alpha"])])


def run_valve_test(settings: ValveRigSettings, voltage: float, supply_pressure: float, seed: int):
    """Simulate one run (a step of ``voltage`` [V] out and back) → :class:`ValveRun`."""
    s = settings
    flow_coefficient = s.rated_flow / math.sqrt(s.rated_drop)  # [m^3/s/sqrt(Pa)]
    droop = s.supply_droop * supply_pressure / s.rated_flow  # [Pa s/m^3]
    rig = np.array(
        [
            s.area_a,
            s.area_b,
            s.moving_mass,
            s.stroke,
            flow_coefficient,
            s.spool_time_constant,
            s.overlap,
            s.transition_pressure,
            s.bulk_modulus,
            s.dead_volume,
            s.supply_time_constant,
            droop,
            s.regularisation_speed,
        ]
    )
    every = max(1, int(round(s.sample_interval / s.internal_step)))
    n_out = int((3 * s.rest + 2 * s.longest_step) / s.sample_interval) + 10
    out = np.zeros((n_out, 7))
    limits = np.array([s.travel_margin, s.stroke - s.travel_margin])
    rows = _valve_kernel(
        rig,
        _friction_vector(s.friction),
        voltage / s.full_scale_voltage,
        supply_pressure,
        limits,
        s.rest,
        s.longest_step,
        s.internal_step,
        every,
        n_out,
        out,
    )
    t, x, v, pa, pb, u, f = out[:rows].T
    levels = {}
    for d in (1, -1):
        moving = np.flatnonzero(u * d > 0)
        if moving.size < 10:
            continue
        end = moving[-1] - 5  # the last samples of the step, before the valve closes
        sel = slice(max(moving[0], end - 50), end)
        state = {
            "velocity [m/s]": float(v[sel].mean()),
            "pressure_a [Pa]": float(pa[sel].mean()),
            "pressure_b [Pa]": float(pb[sel].mean()),
        }
        p = float(
            operating_pressure(state["pressure_a [Pa]"], state["pressure_b [Pa]"], reference="a")
        )
        state["friction [N]"] = float(
            abs(s.friction.friction(state["velocity [m/s]"], p, strict=False))
        )
        levels[d] = state
    rng = np.random.default_rng(seed)

    def measured(values, noise, resolution, ripple=0.0):
        phase = rng.uniform(0, 2 * math.pi)
        noisy = values + noise * rng.standard_normal(values.size)
        noisy = noisy + ripple * np.sin(2 * math.pi * s.ripple_frequency * t + phase)
        return np.round(noisy / resolution) * resolution

    return ValveRun(
        time=t,
        position=measured(x, s.position_noise, s.position_resolution),
        pressure_a=measured(pa, s.pressure_noise, s.pressure_resolution, s.pressure_ripple),
        pressure_b=measured(pb, s.pressure_noise, s.pressure_resolution, s.pressure_ripple),
        voltage=np.round(u * s.full_scale_voltage + 0.005 * rng.standard_normal(t.size), 3),
        velocity=v,
        friction=f,
        voltage_step=voltage,
        supply_pressure=supply_pressure,
        levels=levels,
    )


@dataclass(frozen=True)
class ValveCampaign:
    """What :func:`generate_valve_campaign` wrote, and the truth.

    ``truth`` is a table with one row per run and direction: ``file``, ``direction [-]``,
    ``voltage [V]``, ``supply [Pa]``, ``transient [-]`` (a step cut short by
    :attr:`ValveRigSettings.start_transients`: its state is not steady) and the true state at
    the end of the step ``velocity [m/s]``, ``pressure_a [Pa]``, ``pressure_b [Pa]`` and
    ``friction [N]``. ``friction`` is the true model.
    """

    folder: Path
    files: list
    truth: object  # pandas.DataFrame
    friction: FrictionModel
    settings: ValveRigSettings


CAMPAIGN_TOML = """\
# Virtual servo-valve rig (cylfric.simulate.valve_bench): no load cell, force from the
# chamber pressures times the areas, minus the inertia of the moving mass.
[files]
glob = "*.txt"

[cylinder]
bore = "{bore_mm:g} mm"
rod = "{rod_mm:g} mm"
kind = "{kind}"
pressure_reference = "a"  # the pressure the friction laws see: chamber A (the rig's truth)

[force_balance]
force = "pressures"
moving_mass = "{mass:g} kg"
"""


def generate_valve_campaign(
    out_dir: StrPath, settings: ValveRigSettings | None = None
) -> ValveCampaign:
    """Simulate every run of ``settings`` and write a campaign a user of such a rig would.

    Writes ``valve_NNN.txt`` (MTS-like text: Time [s], Position [mm], Pressure A [bar],
    Pressure B [bar], Valve voltage [V]), ``manifest.csv`` (``file`` and the step's
    ``valve_voltage_V`` and ``supply_bar`` as labels: no nominal speed or pressure, which
    such a rig does not set) and ``campaign.toml`` (``[force_balance] force = "pressures"``,
    the cylinder's bore and rod, the moving mass). Returns a :class:`ValveCampaign`.
    """
    import pandas as pd

    s = settings or ValveRigSettings()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files, truth, manifest = [], [], ["file,valve_voltage_V,supply_bar"]
    transients = set(s.start_transients)
    short = replace(s, longest_step=s.transient_step)
    for index, (voltage, supply) in enumerate(s.runs()):
        rig = short if index in transients else s
        run = run_valve_test(rig, voltage, supply, seed=s.seed * 100_003 + index)
        name = f"valve_{index:03d}.txt"
        units = {
            "Time": "s",
            "Position": "mm",
            "Pressure A": "bar",
            "Pressure B": "bar",
            "Valve voltage": "V",
        }
        columns = {
            "Time": run.time,
            "Position": run.position * 1e3,
            "Pressure A": run.pressure_a / 1e5,
            "Pressure B": run.pressure_b / 1e5,
            "Valve voltage": run.voltage,
        }
        write_mts_text(
            out / name,
            [columns],
            header={"Station Name": "teaching-lab valve rig (virtual)", "Test Run Name": name},
            units=units,
            decimals={
                "Time": 4,
                "Position": 4,
                "Pressure A": 3,
                "Pressure B": 3,
                "Valve voltage": 3,
            },
        )
        files.append(out / name)
        manifest.append(f"{name},{voltage:g},{supply / 1e5:g}")
        for direction, state in run.levels.items():
            truth.append(
                {
                    "file": name,
                    "direction [-]": direction,
                    "voltage [V]": voltage,
                    "supply [Pa]": supply,
                    "transient [-]": index in transients,
                    **state,
                }
            )
    atomic_write_text(out / "manifest.csv", "\n".join(manifest) + "\n")
    atomic_write_text(
        out / "campaign.toml",
        CAMPAIGN_TOML.format(
            bore_mm=s.bore * 1e3,
            rod_mm=s.rod * 1e3,
            kind="double-rod" if s.double_rod else "single-rod",
            mass=s.moving_mass,
        ),
    )
    return ValveCampaign(out, files, pd.DataFrame(truth), s.friction, s)
