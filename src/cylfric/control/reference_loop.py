"""A second, independent servo-axis loop: the check of :mod:`.kernel` and :mod:`.loop`.

Written apart from cylfric's loop (no code shared with :mod:`.kernel`, :mod:`.axis`,
:mod:`.loop` or :mod:`.tuning`; it reads an axis's parameters by attribute only), with
another integrator and another formulation of the valve:

- **state** ``y = (x, v, p_A, p_B, s, ds/dt, z)``, integrated by the classical fourth-order
  Runge-Kutta method at a fixed step (``STEPS_PER_SAMPLE`` per controller sample), every
  equation (friction included) inside the one right-hand side :func:`_rhs`;
- **valve**: four sharp-edged orifices, ``Q = C_d a sqrt(2/rho |dp|) sign(dp)`` (Merritt
  1967 eq. 2-4) with the opening ``a = w x_v + a_0`` of each landing; ``w`` from the rated
  flow at the rated drop per landing, ``a_0`` the leak opening that passes the valve's null
  leakage (Jelali & Kroll 2003 sec. 3.2.2: the leakage of a real critically lapped valve);
  the square root regularised as ``dp / (dp^2 + d_0^2)^(1/4)``, ``d_0`` = :data:`ROOT_SMOOTHING`
  (cylfric's kernel: a linear branch below a laminar drop);
- **chambers** (Jelali & Kroll 2003 eq. 3.8): ``dp_A/dt = beta/V_A (Q_A - A_A v - C_i (p_A -
  p_B))``, ``dp_B/dt = beta/V_B (Q_B + A_B v + C_i (p_A - p_B))``;
- **friction**: LuGre (Canudas de Wit et al. 1995) with F_c, F_s linear in the pressure sum
  ``p_A + p_B``, integrated with the other states (cylfric: the exact z update);
- **controller** at the sample rate, zero-order hold, the position measured with the axis's
  resolution (``round(x / q) q``): ``u = v_ff / K_v(p) + k_p e + k_i sum(e T) + u_c``, the
  feed-forward velocity ``v_ref + t_l a_ref`` led by the delay of the hold and the spool
  (``t_l = T/2 + 2 zeta_v / omega_v``), divided by the piston speed per unit opening at the
  measured pressures;
- **tuning** from the critical gain found by *eigenvalues*: the plant's Jacobian by central
  differences of :func:`_rhs` at the rest equilibrium (solved with the null-leakage flows),
  discretised with the zero-order hold (``scipy.signal.cont2discrete``), closed with the PI;
  ``K_u`` the proportional gain whose closed loop has spectral radius one (bisection),
  ``k_p = K_u/2``, ``T_i = 10/omega_c`` (omega_c from the discrete P loop's frequency
  response at ``K_u/2``); cylfric's :func:`.tuning.tune` reads the -180 deg crossing of a
  frequency response instead;
- **compensation**: a friction force ``F`` [N] goes through this loop's own force path, the
  opening that changes ``A_A p_A - A_B p_B`` by ``F_k - F_{k-1}`` over a sample and holds it
  against what the flows take away from a held force (the cross-piston leakage and the
  valve's own pressure-flow slope at the last command, the chamber pressures moved by
  ``+-F/(A_A + A_B)``), ``u_c = ((F_k - F_{k-1})/T + H(F)) / (beta (A_A dQ_A/dx_v / V_A +
  A_B |dQ_B/dx_v| / V_B))`` with the landing derivatives of the orifice equations at the
  measured pressures; a compensator may also return a valve command of its own (the
  exported step's ``command``), added as is.

:func:`run_reference` returns the tracking error; ``compensator`` is ``"none"``,
``"oracle"`` (the plant's friction at the sample), or a callable ``step(x, p_A, p_B,
x_ref, v_ref) -> (force [N], command [-])`` such as cylfric's exported compensator step.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numba import njit

__all__ = [
    "ReferenceAxis",
    "ReferenceSeal",
    "ReferenceRun",
    "reference_tuning",
    "rest_equilibrium",
    "run_reference",
    "STEPS_PER_SAMPLE",
    "ROOT_SMOOTHING",
    "OIL_DENSITY",
    "DISCHARGE_COEFFICIENT",
]

STEPS_PER_SAMPLE = 20
"""Runge-Kutta steps per controller sample [-] (50 us at 1 kHz)."""
ROOT_SMOOTHING = 1e4
"""d_0 of the regularised orifice root [Pa]."""
OIL_DENSITY = 870.0
"""rho [kg/m^3] (mineral oil, ISO VG 46)."""
DISCHARGE_COEFFICIENT = 0.61
"""C_d [-] of a sharp-edged orifice (Merritt 1967 sec. 2.5)."""


@dataclass(frozen=True)
class ReferenceAxis:
    """The axis of the reference loop (SI). ``null_leakage`` [m^3/s] is the valve's total
    leakage P -> T at null with the chambers blocked and at supply pressure ``p_s``;
    ``resolution`` [m] the position measurement's quantum (0: exact)."""

    area_a: float
    area_b: float
    stroke: float
    v0_a: float
    v0_b: float
    mass: float
    beta: float
    c_i: float
    p_s: float
    p_t: float
    q_n: float
    dp_n: float
    null_leakage: float
    spool_hz: float
    spool_zeta: float
    rate: float
    resolution: float
    start: float
    load: float = 0.0

    @classmethod
    def from_axis(cls, axis: Any, *, null_leakage: float = 0.0, resolution: float = 0.0):
        """From any object with cylfric's axis attribute names (bore, rod, rod_a, ...):
        the areas are recomputed here from the diameters."""
        bore, rod, rod_a = float(axis.bore), float(axis.rod), float(axis.rod_a)
        return cls(
            area_a=math.pi / 4 * (bore**2 - rod_a**2),
            area_b=math.pi / 4 * (bore**2 - rod**2),
            stroke=float(axis.stroke),
            v0_a=float(axis.dead_volume_a),
            v0_b=float(axis.dead_volume_b),
            mass=float(axis.mass),
            beta=float(axis.bulk_modulus),
            c_i=float(axis.leakage),
            p_s=float(axis.supply_pressure),
            p_t=float(axis.tank_pressure),
            q_n=float(axis.valve_nominal_flow),
            dp_n=float(axis.valve_nominal_drop),
            null_leakage=float(null_leakage),
            spool_hz=float(axis.spool_frequency),
            spool_zeta=float(axis.spool_damping),
            rate=float(axis.control_rate),
            resolution=float(resolution),
            start=float(axis.start_position),
            load=float(axis.load_force),
        )

    @property
    def gradient(self) -> float:
        """C_d w sqrt(2/rho) [m^3/(s sqrt(Pa))] per unit opening: the rated flow at the rated
        drop."""
        return self.q_n / math.sqrt(self.dp_n)

    @property
    def leak_opening(self) -> float:
        """The leak opening of each landing [-] (fraction of full opening): two paths P -> A
        -> T and P -> B -> T in series of two equal orifices, each across p_s / 2."""
        per_path = 0.5 * self.null_leakage
        return per_path / (self.gradient * math.sqrt(0.5 * (self.p_s - self.p_t)))

    def vector(self) -> np.ndarray:
        """The compiled right-hand side's parameter array."""
        return np.array(
            [
                self.area_a,
                self.area_b,
                self.stroke,
                self.v0_a,
                self.v0_b,
                self.mass,
                self.beta,
                self.c_i,
                self.p_s,
                self.p_t,
                self.gradient,
                self.leak_opening,
                2 * math.pi * self.spool_hz,
                self.spool_zeta,
                self.load,
                ROOT_SMOOTHING,
            ]
        )


@dataclass(frozen=True)
class ReferenceSeal:
    """LuGre friction with F_c, F_s linear in ``p_A + p_B`` [N, N/Pa]; ``level`` scales
    F_c, F_s and sigma_2 (a plant whose friction differs from the datasheet)."""

    fc0: float
    fc1: float
    fs0: float
    fs1: float
    sigma_2: float
    v_r: float
    alpha: float
    sigma_0: float
    sigma_1: float
    level: float = 1.0

    def vector(self) -> np.ndarray:
        """The compiled right-hand side's friction array."""
        k = self.level
        return np.array(
            [
                k * self.fc0,
                k * self.fc1,
                k * self.fs0,
                k * self.fs1,
                k * self.sigma_2,
                self.v_r,
                self.alpha,
                self.sigma_0,
                self.sigma_1,
            ]
        )

    def scaled(self, level: float) -> ReferenceSeal:
        """The same seal with its friction level times ``level``."""
        return replace(self, level=level)


@njit(cache=True)
def _orifice(gain, opening, dp, d0):
    # turbulent orifice, root regularised near dp = 0
    return gain * opening * dp / math.sqrt(math.sqrt(dp * dp + d0 * d0))


@njit(cache=True)
def _friction(v, z, pa, pb, fr):
    psum = pa + pb
    fc = fr[0] + fr[1] * psum
    fs = fr[2] + fr[3] * psum
    g = fc + (fs - fc) * math.exp(-((abs(v) / fr[5]) ** fr[6]))
    dz = v - fr[7] * abs(v) * z / g
    return fr[7] * z + fr[8] * dz + fr[4] * v, dz


@njit(cache=True)
def _rhs(y, u, p, fr, out):
    x, v, pa, pb, s, sd, z = y[0], y[1], y[2], y[3], y[4], y[5], y[6]
    aa, ab, L, va0, vb0, m, beta, ci = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    ps, pt, kw, a0, wv, zv, fl, d0 = p[8], p[9], p[10], p[11], p[12], p[13], p[14], p[15]
    open_p = max(s, 0.0) + a0  # P->A and B->T landings
    open_n = max(-s, 0.0) + a0  # A->T and P->B landings
    qa = _orifice(kw, open_p, ps - pa, d0) - _orifice(kw, open_n, pa - pt, d0)
    qb = _orifice(kw, open_n, ps - pb, d0) - _orifice(kw, open_p, pb - pt, d0)
    leak = ci * (pa - pb)
    friction, dz = _friction(v, z, pa, pb, fr)
    out[0] = v
    out[1] = (aa * pa - ab * pb - friction - fl) / m
    out[2] = beta / (va0 + aa * x) * (qa - aa * v - leak)
    out[3] = beta / (vb0 + ab * (L - x)) * (qb + ab * v + leak)
    out[4] = sd
    out[5] = wv * wv * (u - s) - 2.0 * zv * wv * sd
    out[6] = dz


@njit(cache=True)
def _advance(y, u, p, fr, h, steps):
    """``steps`` classical Runge-Kutta steps of ``h`` with the command u held."""
    n = y.shape[0]
    k1, k2, k3, k4, t = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for _ in range(steps):
        _rhs(y, u, p, fr, k1)
        for i in range(n):
            t[i] = y[i] + 0.5 * h * k1[i]
        _rhs(t, u, p, fr, k2)
        for i in range(n):
            t[i] = y[i] + 0.5 * h * k2[i]
        _rhs(t, u, p, fr, k3)
        for i in range(n):
            t[i] = y[i] + h * k3[i]
        _rhs(t, u, p, fr, k4)
        for i in range(n):
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        if y[4] > 1.0:
            y[4], y[5] = 1.0, 0.0
        elif y[4] < -1.0:
            y[4], y[5] = -1.0, 0.0


def rest_equilibrium(axis: ReferenceAxis, seal: ReferenceSeal) -> tuple[float, float, float]:
    """(p_A, p_B [Pa], spool opening [-]) of the axis at rest: the chambers' net flows zero
    and ``A_A p_A - A_B p_B = F_load`` (no friction at rest). Without null leakage the valve
    at null holds any pressures; then ``p_A + p_B = p_s + p_t``."""
    p, fr = axis.vector(), seal.vector()
    aa, ab = axis.area_a, axis.area_b
    if axis.null_leakage == 0.0:
        pb = (aa * (axis.p_s + axis.p_t) - axis.load) / (aa + ab)
        return axis.p_s + axis.p_t - pb, pb, 0.0
    from scipy.optimize import fsolve

    out = np.empty(7)
    pb0 = (aa * (axis.p_s + axis.p_t) - axis.load) / (aa + ab)
    scale = np.array([axis.p_s, axis.leak_opening])

    def balance(unknown: np.ndarray) -> np.ndarray:
        pa, s = unknown * scale
        pb = (aa * pa - axis.load) / ab
        _rhs(np.array([axis.start, 0, pa, pb, s, 0, 0.0]), s, p, fr, out)
        return np.array([out[2], out[3]]) / (axis.beta / axis.v0_a * axis.q_n * 1e-3)

    start = np.array([axis.p_s + axis.p_t - pb0, 0.0]) / scale
    solution, info, ok, message = fsolve(balance, start, full_output=True, xtol=1e-12)
    if ok != 1:
        raise ValueError(f"no rest equilibrium of the reference axis: {message}")
    pa, s = solution * scale
    return pa, (aa * pa - axis.load) / ab, s


def _jacobian(axis: ReferenceAxis, seal: ReferenceSeal, viscous: float):
    """(A, B) of the plant linearised at rest by central differences of :func:`_rhs`, the
    friction replaced by the viscous coefficient (states x, v, p_A, p_B, s, ds/dt)."""
    pa, pb, s0 = rest_equilibrium(axis, seal)
    p = axis.vector()
    fr = np.array([0.0, 0.0, 0.0, 0.0, viscous, 1.0, 1.0, 1.0, 0.0])  # viscous only
    fr[0] = fr[2] = 1e-12
    y0 = np.array([axis.start, 0.0, pa, pb, s0, 0.0, 0.0])
    out_p, out_m = np.empty(7), np.empty(7)
    steps = np.array([1e-7, 1e-6, 1e2, 1e2, 1e-7, 1e-4])
    a = np.zeros((6, 6))
    for j in range(6):
        yp, ym = y0.copy(), y0.copy()
        yp[j] += steps[j]
        ym[j] -= steps[j]
        _rhs(yp, s0, p, fr, out_p)
        _rhs(ym, s0, p, fr, out_m)
        a[:, j] = (out_p[:6] - out_m[:6]) / (2 * steps[j])
    _rhs(y0, s0 + 1e-6, p, fr, out_p)
    _rhs(y0, s0 - 1e-6, p, fr, out_m)
    b = (out_p[:6] - out_m[:6]) / 2e-6
    return a, b


def reference_tuning(axis: ReferenceAxis, seal: ReferenceSeal, viscous: float) -> dict:
    """PI gains from the critical gain by eigenvalues (see the module notes). The valve
    needs a null leakage > 0: without it the chambers' pressure level is a marginal mode
    (an eigenvalue at one for any gain)."""
    from scipy.signal import cont2discrete

    if not axis.null_leakage > 0:
        raise ValueError("reference_tuning needs a valve null leakage > 0 [m^3/s]")

    a, b = _jacobian(axis, seal, viscous)
    t = 1.0 / axis.rate
    ad, bd, *_ = cont2discrete((a, b[:, None], np.eye(6), np.zeros((6, 1))), t, method="zoh")
    n = 6

    def radius(kp: float, ti: float | None) -> float:
        # states: plant (6), integrator sum of e T; u = -kp x - kp/ti * sum
        if ti is None:
            closed = ad - kp * bd @ np.eye(1, n)
            return float(np.max(np.abs(np.linalg.eigvals(closed))))
        # u_k = kp e_k + (kp/ti) S_k, S_{k+1} = S_k + T e_k, e_k = -x_k (regulation)
        c = np.eye(1, n)
        big = np.zeros((n + 1, n + 1))
        big[:n, :n] = ad - kp * bd @ c
        big[:n, n] = (kp / ti) * bd[:, 0]
        big[n, :n] = -t * c[0]
        big[n, n] = 1.0
        return float(np.max(np.abs(np.linalg.eigvals(big))))

    def critical(ti: float | None) -> float:
        lo, hi = 1e-3, 1.0
        while radius(hi, ti) < 1.0:
            hi *= 2.0
        for _ in range(80):
            mid = math.sqrt(lo * hi)
            lo, hi = (mid, hi) if radius(mid, ti) < 1.0 else (lo, mid)
        return math.sqrt(lo * hi)

    ku_p = critical(None)
    omega = np.geomspace(0.1, 0.999 * math.pi / t, 8000)
    zs = np.exp(1j * omega * t)
    c = np.eye(1, n)[0]
    gain = np.array([c @ np.linalg.solve(z * np.eye(n) - ad, bd[:, 0]) for z in zs])
    below = np.nonzero(np.abs(0.5 * ku_p * gain) < 1.0)[0]
    wc = float(omega[below[0]])
    ti = 10.0 / wc
    ku = critical(ti)
    kp = 0.5 * ku
    return {"kp": kp, "ki": kp / ti, "critical_kp": ku, "crossover_rad_s": wc, "rest": (a, b)}


def _landing_gain(axis: ReferenceAxis, pa: float, pb: float, sign: float):
    """dQ_A/dx_v and -dQ_B/dx_v [m^3/s per unit opening] at the pressures, for the landings
    open in ``sign``'s direction."""
    k, d0 = axis.gradient, ROOT_SMOOTHING

    def root(dp: float) -> float:
        return max(dp, 0.0) / math.sqrt(math.sqrt(dp * dp + d0 * d0))

    if sign >= 0:
        return k * root(axis.p_s - pa), k * root(pb - axis.p_t)
    return k * root(pa - axis.p_t), k * root(axis.p_s - pb)


@dataclass
class ReferenceRun:
    """Samples of a reference-loop run: time, reference, measured and true position [m],
    friction [N], the compensation force [N] and the valve command [-]."""

    time: np.ndarray
    reference: np.ndarray
    position: np.ndarray
    friction: np.ndarray
    force: np.ndarray
    command: np.ndarray

    @property
    def rms_error(self) -> float:
        """RMS of reference - true position [m]."""
        return float(np.sqrt(np.mean((self.reference - self.position) ** 2)))


def run_reference(
    axis: ReferenceAxis,
    seal: ReferenceSeal,
    x_ref: np.ndarray,
    v_ref: np.ndarray,
    *,
    compensator: str | Callable[..., tuple[float, float]] = "none",
    path: str = "force",
    tuning: dict | None = None,
    viscous: float | None = None,
    force_filter: float = 0.0,
) -> ReferenceRun:
    """Run the loop along the reference samples ``x_ref`` [m], ``v_ref`` [m/s] at the axis's
    rate. ``path``: ``"force"`` turns the compensator's force into a command with this
    loop's force path; ``"command"`` adds the compensator's own command instead.
    ``force_filter`` [s]: time constant of a first-order filter (exact discretisation) on
    the force before the force path (0: none; the oracle's force goes through it too)."""
    if tuning is None:
        tuning = reference_tuning(axis, seal, seal.sigma_2 if viscous is None else viscous)
    kp, ki = tuning["kp"], tuning["ki"]
    t = 1.0 / axis.rate
    lead = 0.5 * t + 2.0 * axis.spool_zeta / (2 * math.pi * axis.spool_hz)
    p, fr = axis.vector(), seal.vector()
    pa, pb, s0 = rest_equilibrium(axis, seal)
    y = np.array([axis.start, 0.0, pa, pb, s0, 0.0, 0.0])
    n = len(x_ref)
    out = np.empty((n, 4))
    rhs = np.empty(7)
    integ = s0  # the integrator holds the valve's rest bias
    u_prev = s0
    f_prev = 0.0
    aa, ab = axis.area_a, axis.area_b
    q = axis.resolution
    for k in range(n):
        x, pa, pb = y[0], y[2], y[3]
        xm = round(x / q) * q if q > 0 else x
        e = x_ref[k] - xm
        a_ref = (v_ref[min(k + 1, n - 1)] - v_ref[max(k - 1, 0)]) / (2 * t)
        v_ff = v_ref[k] + lead * a_ref
        ga, gb = _landing_gain(axis, pa, pb, v_ff)
        speed = 0.5 * (ga / aa + gb / ab)
        u_ff = v_ff / speed if speed > 0 else 0.0
        force, command = 0.0, 0.0
        if compensator == "oracle":
            _rhs(y, y[4], p, fr, rhs)
            force = _friction(y[1], y[6], pa, pb, fr)[0]
        elif callable(compensator):
            force, command = compensator(xm, pa, pb, x_ref[k], v_ref[k])
        if force_filter > 0.0 and k > 0:
            force = f_prev + (1.0 - math.exp(-t / force_filter)) * (force - f_prev)
        u_c = 0.0
        if compensator != "none" and k > 0:
            if path == "command" and callable(compensator):
                u_c = command
            else:
                va, vb = axis.v0_a + aa * x, axis.v0_b + ab * (axis.stroke - x)
                hold = _hold(axis, force, pa, pb, u_prev, va, vb)
                rate = (force - f_prev) / t + hold
                ga, gb = _landing_gain(axis, pa, pb, rate)
                gain = axis.beta * (aa * ga / va + ab * gb / vb)
                u_c = rate / gain
        f_prev = force
        u = u_ff + kp * e + integ + u_c
        u_prev = min(max(u, -1.0), 1.0)
        if -1.0 < u < 1.0:
            integ += ki * e * t
        u = min(max(u, -1.0), 1.0)
        out[k] = (x, force, u, 0.0)
        _rhs(y, u, p, fr, rhs)
        out[k, 3] = _friction(y[1], y[6], y[2], y[3], fr)[0]
        if k < n - 1:
            _advance(y, u, p, fr, t / STEPS_PER_SAMPLE, STEPS_PER_SAMPLE)
    time = np.arange(n) * t
    return ReferenceRun(time, np.asarray(x_ref), out[:, 0], out[:, 3], out[:, 1], out[:, 2])


def _hold(axis: ReferenceAxis, force: float, pa: float, pb: float, u: float, va, vb) -> float:
    """The force rate [N/s] the flows take away from a held force F: the cross-piston leakage
    and the valve's own pressure-flow slope (orifice equations differentiated numerically at
    the measured pressures and the last command ``u``), the chamber pressures moved by
    ``+-F / (A_A + A_B)``."""
    dpa = force / (axis.area_a + axis.area_b)
    dpb = -dpa
    k, d0, a0 = axis.gradient, ROOT_SMOOTHING, axis.leak_opening
    op, on = max(u, 0.0) + a0, max(-u, 0.0) + a0

    def qa(p: float) -> float:
        return _orifice(k, op, axis.p_s - p, d0) - _orifice(k, on, p - axis.p_t, d0)

    def qb(p: float) -> float:
        return _orifice(k, on, axis.p_s - p, d0) - _orifice(k, op, p - axis.p_t, d0)

    step = 1e3
    slope_a = (qa(pa + step) - qa(pa - step)) / (2 * step)  # dQ_A/dp_A < 0
    slope_b = (qb(pb + step) - qb(pb - step)) / (2 * step)
    lost_a = -slope_a * dpa + axis.c_i * (dpa - dpb)  # flow out of A the force costs
    lost_b = -slope_b * dpb - axis.c_i * (dpa - dpb)
    return axis.beta * (axis.area_a * lost_a / va - axis.area_b * lost_b / vb)
