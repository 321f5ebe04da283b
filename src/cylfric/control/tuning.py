"""PI(D) tuning of the position loop from the critical gain, with a 6 dB gain margin.

The axis is linearised at rest (mid-stroke by default, valve at null, chamber pressures of
:meth:`Axis.rest_pressures`) with the datasheet's viscous friction only (the part of friction
a linear model can hold), discretised with a zero-order hold at the controller's sample time
(``scipy.linalg.expm`` of the augmented matrix), and the loop ``C(z) G(z)`` is evaluated on
the unit circle. The critical proportional gain ``K_u`` makes the loop gain one where its
phase is -180 deg (the Nyquist point); the tuning uses ``K_p = K_u / 2`` (6 dB gain margin,
the margin Jelali & Kroll 2003 sec. 6.2 and Merritt sec. 8.3 recommend for hydraulic
position loops, whose limit is ``K_v < 2 zeta_h omega_h``). The integral time is ``T_i =
10 / omega_c``, omega_c the gain crossover of the P loop at half its critical gain (the
integral's phase lag at the crossover is then 5.7 deg), and ``K_u`` is computed with that
integral action in the loop, so the margin holds for the controller used, not for a P
controller alone.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .axis import Axis

__all__ = ["Tuning", "tune", "linear_model", "feedforward_lead"]


@dataclass(frozen=True)
class Tuning:
    """The controller's gains and the margins they were chosen for.

    Attributes: ``kp`` [1/m] (valve opening per metre of error), ``ki`` [1/(m*s)], ``kd``
    [s/m], ``loop_gain_1_s`` (``K_v = k_p v_max``: the velocity gain [1/s]), ``critical_kp``
    [1/m], ``gain_margin_db``, ``phase_crossover_rad_s`` [rad/s], ``gain_crossover_rad_s``,
    ``phase_margin_deg``, ``omega_h_rad_s`` (hydraulic natural frequency), ``method``.
    """

    kp: float
    ki: float
    kd: float
    loop_gain_1_s: float
    critical_kp: float
    gain_margin_db: float
    phase_crossover_rad_s: float
    gain_crossover_rad_s: float
    phase_margin_deg: float
    omega_h_rad_s: float
    method: str

    def to_dict(self) -> dict:
        """The fields by name (JSON-ready)."""
        return asdict(self)


def feedforward_lead(axis: Axis) -> float:
    """Lead time [s] of the reference-velocity feedforward: the delay of the velocity path.

    The command reaches the piston speed through the zero-order hold (half a sample, ``T/2``)
    and the spool, whose low-frequency equivalent delay is ``tau`` for a first-order spool and
    ``2 zeta_v / omega_v`` for a second-order one (the phase slope of ``1/(tau s + 1)`` and of
    ``omega_v^2/(s^2 + 2 zeta_v omega_v s + omega_v^2)`` at omega -> 0). The feedforward sends
    ``v_ref + lead a_ref`` (velocity and acceleration feedforward; Jelali & Kroll 2003 sec.
    7.2), so the piston follows the reference velocity without that lag. The hydraulic mode's
    own delay ``2 zeta_h / omega_h`` is left out (tens of microseconds on the default axis).
    """
    if axis.spool_order == 1:
        spool = axis.spool_time_constant
    else:
        spool = 2.0 * axis.spool_damping / (2.0 * math.pi * axis.spool_frequency)
    return 0.5 * axis.sample_time + spool


def linear_model(axis: Axis, viscous: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the axis linearised at rest; states x, v, p_A, p_B, spool (and its rate).

    ``viscous`` [N*s/m] is the linear friction kept. The valve's flow gain at null is the
    mean of its two one-sided slopes [m^3/s per unit opening].
    """
    pa, pb = axis.rest_pressures()
    va, vb = axis.volumes(axis.start_position)
    k, ps, pt = axis.valve_coefficient, axis.supply_pressure, axis.tank_pressure
    kqa = k * 0.5 * (math.sqrt(ps - pa) + math.sqrt(max(pa - pt, 0.0)))
    kqb = k * 0.5 * (math.sqrt(max(pb - pt, 0.0)) + math.sqrt(ps - pb))
    b, c, m = axis.bulk_modulus, axis.leakage, axis.mass
    n = 5 if axis.spool_order == 1 else 6
    a = np.zeros((n, n))
    bb = np.zeros(n)
    a[0, 1] = 1.0
    a[1, 1], a[1, 2], a[1, 3] = -viscous / m, axis.area_a / m, -axis.area_b / m
    a[2, 1], a[2, 2], a[2, 3], a[2, 4] = (
        -b * axis.area_a / va,
        -b * c / va,
        b * c / va,
        b * kqa / va,
    )
    a[3, 1], a[3, 2], a[3, 3], a[3, 4] = (
        b * axis.area_b / vb,
        b * c / vb,
        -b * c / vb,
        -b * kqb / vb,
    )
    if axis.spool_order == 1:
        a[4, 4] = -1.0 / axis.spool_time_constant
        bb[4] = 1.0 / axis.spool_time_constant
    else:
        w = 2 * math.pi * axis.spool_frequency
        a[4, 5] = 1.0
        a[5, 4], a[5, 5] = -w * w, -2 * axis.spool_damping * w
        bb[5] = w * w
    return a, bb


def _frequency_response(axis: Axis, viscous: float, omega: np.ndarray) -> np.ndarray:
    from scipy.linalg import expm

    a, b = linear_model(axis, viscous)
    n = a.shape[0]
    t = axis.sample_time
    big = np.zeros((n + 1, n + 1))
    big[:n, :n], big[:n, n] = a, b
    phi = expm(big * t)
    ad, bd = phi[:n, :n], phi[:n, n]
    zs = np.exp(1j * omega * t)
    eye = np.eye(n)
    return np.array([np.linalg.solve(zz * eye - ad, bd)[0] for zz in zs])


def _gain_crossover(loop, omega) -> float:
    """The first frequency [rad/s] where the loop gain falls below one."""
    below = np.nonzero(np.abs(loop) < 1.0)[0]
    if below.size == 0 or below[0] == 0:
        raise ValueError("the linearised loop has no gain crossover in the frequency grid")
    return float(omega[below[0]])


def tune(axis: Axis, viscous: float = 0.0, *, points: int = 4000) -> Tuning:
    """Gains for ``axis`` by the critical gain with a 6 dB margin (see the module notes)."""
    t = axis.sample_time
    omega = np.geomspace(0.1, 0.999 * math.pi / t, points)
    g = _frequency_response(axis, viscous, omega)
    z = np.exp(1j * omega * t)

    def crossing(loop):
        phase = np.unwrap(np.angle(loop))
        below = np.nonzero(phase <= -math.pi)[0]
        if below.size == 0:
            raise ValueError("the linearised loop never reaches -180 deg: no critical gain")
        i = below[0]
        f = (-math.pi - phase[i - 1]) / (phase[i] - phase[i - 1])
        w180 = omega[i - 1] + f * (omega[i] - omega[i - 1])
        mag = abs(loop[i - 1]) + f * (abs(loop[i]) - abs(loop[i - 1]))
        return w180, 1.0 / mag

    _, ku_p = crossing(g)
    ti = 10.0 / _gain_crossover(0.5 * ku_p * g, omega)
    pi_shape = 1.0 + t / (ti * (z - 1.0))
    w180, ku = crossing(pi_shape * g)
    kp = ku / 2.0
    loop = kp * pi_shape * g
    wc = _gain_crossover(loop, omega)
    i = int(np.searchsorted(omega, wc))
    pm = 180.0 + math.degrees(np.unwrap(np.angle(loop))[i])
    v_gain = 0.5 * sum(axis.no_load_velocity_gain())
    return Tuning(
        kp=float(kp),
        ki=float(kp / ti),
        kd=0.0,
        loop_gain_1_s=float(kp * v_gain),
        critical_kp=float(ku),
        gain_margin_db=float(20 * math.log10(ku / kp)),
        phase_crossover_rad_s=float(w180),
        gain_crossover_rad_s=float(wc),
        phase_margin_deg=float(pm),
        omega_h_rad_s=axis.natural_frequency(),
        method="critical gain of the PI loop (T_i = 10/omega_c), K_p = K_u/2 (6 dB margin)",
    )
