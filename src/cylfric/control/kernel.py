"""The compiled closed loop: axis (:mod:`.axis`), PID with feedforward, compensators.

One function, :func:`closed_loop`, runs a whole simulation: the plant integrated at a fixed
inner step ``h = T / substeps`` (semi-implicit Euler for the load: the velocity first, the
position and the pressures with the new velocity; the bristle deflection z by the exact
update of thesis eq. 2.5 at constant velocity (``simulate.kernels.z_step``), stable for any
sigma_0; the spool of a first-order valve by its exact step), the controller at the sample
instants ``k T`` with a zero-order hold on its command.

The friction parameters come as a (7, 4) table, one row per parameter of
:data:`FRICTION_ROWS`: ``[law code, c0, c1, c2]`` with the codes of :data:`LAW_CODES`
(constant c0; linear c0 + c1 p; quadratic c0 + c1 p + c2 p^2; exponential c0 + c1 (exp(c2 p)
- 1)), evaluated at the operating pressure of (p_A, p_B) by the rule code of
:data:`REFERENCE_CODES`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..simulate.kernels import g_function, lugre_instant, z_step

__all__ = [
    "closed_loop",
    "friction_table",
    "FRICTION_ROWS",
    "LAW_CODES",
    "REFERENCE_CODES",
    "COMPENSATOR_CODES",
    "OUTPUTS",
    "params_at",
    "operating_pressure",
    "force_rate_gain",
    "leakage_force_rate",
    "compensator_step",
    "run_compensator",
    "COMPENSATOR_STATE",
]

FRICTION_ROWS = ("F_c", "F_s", "sigma_2", "v_r", "alpha", "sigma_0", "sigma_1")
LAW_CODES = {"constant": 0, "linear": 1, "quadratic": 2, "exponential": 3}
_LAW_KEYS = {
    "constant": ("intercept",),
    "linear": ("intercept", "slope"),
    "quadratic": ("intercept", "slope", "curvature"),
    "exponential": ("intercept", "amplitude", "rate"),
}
REFERENCE_CODES = {"a": 0, "b": 1, "sum": 2, "mean": 3, "max": 4}
COMPENSATOR_CODES = {"none": 0, "coulomb": 1, "static": 2, "lugre": 3, "oracle": 4}
OUTPUTS = (
    "position [m]",
    "velocity [m/s]",
    "pressure_a [Pa]",
    "pressure_b [Pa]",
    "command [-]",
    "spool [-]",
    "friction [N]",
    "compensation [N]",
    "z [m]",
    "z_hat [m]",
)
"""Columns of the output array of :func:`closed_loop` (one row per controller sample)."""

# the controller vector: indices
CTRL = (
    "kp",
    "ki",
    "kd",
    "feedforward",
    "feedforward_lead",
    "smoothing_velocity",
    "observer_gain",
    "coulomb_force",
    "command_offset",
    "sample_time",
    "force_filter_gain",
    "velocity_input",
)
"""Order of the controller vector: gains [1/m], [1/(m*s)], [s/m], feedforward on (1) or off
(0), the feedforward's lead time [s] (the reference velocity fed forward is ``v_ref + lead
a_ref``), sign smoothing velocity [m/s], observer gain [1/s], Coulomb level [N], a
constant command offset [-] (valve null bias; open-loop tests), sample time [s], the gain
``a = 1 - exp(-T / tau_f)`` of the first-order filter on the compensator's force estimate
[-] (1: no filter; :func:`compensator_step`), velocity input on (1: the compensator
reads the measured velocity) or off (0: the backward difference of the position) [-]."""


def friction_table(
    model,
    *,
    level: float = 1.0,
    slope: float = 1.0,
    offset: float = 0.0,
    stiffness: float = 1.0,
) -> np.ndarray:
    """The (7, 4) table of a :class:`~cylfric.model.FrictionModel` (see the module notes).

    ``level`` scales F_c, F_s and sigma_2 at every pressure [-]; ``slope`` scales their
    pressure dependence only (the coefficients beyond the intercept) [-]; ``offset`` [N] is
    added to F_c and F_s at every pressure; ``stiffness`` scales sigma_0 [-] (and sigma_1 by
    its square root, which keeps the bristles' damping ratio).
    """
    coefficients = model.coefficients()
    table = np.zeros((len(FRICTION_ROWS), 4))
    defaults = {"F_s": coefficients.get("F_c"), "sigma_2": 0.0, "v_r": 1.0, "alpha": 1.0}
    for row, name in enumerate(FRICTION_ROWS):
        spec, source = coefficients.get(name), name
        if spec is None:  # not in the datasheet's law (Coulomb-only: F_s = F_c, sigma_2 = 0)
            spec, source = defaults[name], "F_c"
        if isinstance(spec, dict):
            law = spec.get("law") or model.laws.get(source) or model.pressure_law
            keys = _LAW_KEYS[law]
            values = [float(spec[k]) for k in keys]
        else:
            law, values = "constant", [float(spec)]
        scale = level if name in ("F_c", "F_s", "sigma_2") else 1.0
        if name == "sigma_0":
            scale = stiffness
        elif name == "sigma_1":
            scale = math.sqrt(stiffness)
        values = [v * scale for v in values]
        if name in ("F_c", "F_s", "sigma_2") and law in ("linear", "quadratic"):
            values[1:] = [v * slope for v in values[1:]]
        if name in ("F_c", "F_s", "sigma_2") and law == "exponential":
            values[1] *= slope
        if name in ("F_c", "F_s"):
            values[0] += offset
        table[row, 0] = LAW_CODES[law]
        table[row, 1 : 1 + len(values)] = values
    return table


@njit(cache=True, inline="always")
def _law(table, row, p):
    code = table[row, 0]
    c0, c1, c2 = table[row, 1], table[row, 2], table[row, 3]
    if code == 0:
        return c0
    if code == 1:
        return c0 + c1 * p
    if code == 2:
        return c0 + p * (c1 + c2 * p)
    return c0 + c1 * math.expm1(c2 * p)


@njit(cache=True, inline="always")
def operating_pressure(code, pa, pb):
    """The pressure the laws see [Pa] (rule code of REFERENCE_CODES)."""
    if code == 0:
        return pa
    if code == 1:
        return pb
    if code == 2:
        return pa + pb
    if code == 3:
        return 0.5 * (pa + pb)
    return max(pa, pb)


@njit(cache=True, inline="always")
def params_at(table, p):
    """(F_c, F_s, sigma_2, v_r, alpha, sigma_0, sigma_1) at pressure p, kept physical."""
    fc = max(_law(table, 0, p), 1e-9)
    fs = max(_law(table, 1, p), 1e-9)
    s2 = max(_law(table, 2, p), 0.0)
    vr = max(_law(table, 3, p), 1e-12)
    al = max(_law(table, 4, p), 1e-3)
    s0 = max(_law(table, 5, p), 1e-9)
    s1 = max(_law(table, 6, p), 0.0)
    return fc, fs, s2, vr, al, s0, s1


@njit(cache=True, inline="always")
def _root(dp, laminar):
    """sign(dp) sqrt(|dp|), linear below ``laminar`` [sqrt(Pa)]."""
    a = abs(dp)
    if a < laminar:
        return dp / math.sqrt(laminar)
    return math.sqrt(a) if dp > 0 else -math.sqrt(a)


@njit(cache=True, inline="always")
def valve_flows(s, pa, pb, ps, pt, k, laminar):
    """Flows (Q_A, Q_B) into the chambers [m^3/s] at spool opening s [-]."""
    if s >= 0.0:
        return k * s * _root(ps - pa, laminar), -k * s * _root(pb - pt, laminar)
    return k * s * _root(pa - pt, laminar), -k * s * _root(ps - pb, laminar)


@njit(cache=True, inline="always")
def force_rate_gain(direction, x, pa, pb, ax):
    """d(A_A p_A - A_B p_B)/dt per unit of spool opening [N/s] in ``direction`` (+-1)."""
    aa, ab, stroke, va0, vb0 = ax[0], ax[1], ax[2], ax[3], ax[4]
    beta, ps, pt, k, lam = ax[6], ax[8], ax[9], ax[10], ax[11]
    va = va0 + aa * x
    vb = vb0 + ab * (stroke - x)
    floor = math.sqrt(lam)
    if direction >= 0:
        ka = k * max(_root(ps - pa, lam), floor)
        kb = k * max(_root(pb - pt, lam), floor)
    else:
        ka = k * max(_root(pa - pt, lam), floor)
        kb = k * max(_root(ps - pb, lam), floor)
    return beta * (aa * ka / va + ab * kb / vb)


@njit(cache=True, inline="always")
def leakage_force_rate(force, x, ax):
    """Force rate [N/s] the valve must supply to hold a cylinder force ``force`` [N] against the
    cross-piston leakage: ``beta C_i dp (A_A/V_A + A_B/V_B)`` with the pressure difference
    ``dp = force / ((A_A + A_B)/2)`` (exact for a double-rod cylinder)."""
    aa, ab, stroke, va0, vb0 = ax[0], ax[1], ax[2], ax[3], ax[4]
    va = va0 + aa * x
    vb = vb0 + ab * (stroke - x)
    return ax[6] * ax[7] * force / (0.5 * (aa + ab)) * (aa / va + ab / vb)


@njit(cache=True, inline="always")
def velocity_gain(direction, pa, pb, ax):
    """Piston speed per unit opening [m/s] at the pressures: the mean of the two chambers'
    ``K r(dp) / A`` in ``direction`` (+-1)."""
    aa, ab, ps, pt, k, lam = ax[0], ax[1], ax[8], ax[9], ax[10], ax[11]
    floor = math.sqrt(lam)
    if direction >= 0:
        ra, rb = max(_root(ps - pa, lam), floor), max(_root(pb - pt, lam), floor)
    else:
        ra, rb = max(_root(pa - pt, lam), floor), max(_root(ps - pb, lam), floor)
    return 0.5 * k * (ra / aa + rb / ab)


COMPENSATOR_STATE = ("x_prev [m]", "z_hat [m]", "f_prev [N]", "started [-]")
"""The compensator's state vector (:func:`compensator_step`): the previous position sample,
the observer's bristle deflection, the previous force estimate, 1 after the first sample."""
COMPENSATOR_STATE_SIZE = len(COMPENSATOR_STATE)


@njit(cache=True, inline="always")
def compensator_step(
    kind, model, model_ref, ctrl, ax, state, x, pa, pb, x_ref, v_ref, oracle, velocity=0.0
):
    """One controller sample of a compensator: returns (force F [N], command u_c [-]).

    A pure function of the measurements (position ``x`` [m], chamber pressures ``pa``,
    ``pb`` [Pa], reference ``x_ref`` [m], ``v_ref`` [m/s]) and the state vector
    ``state`` (:data:`COMPENSATOR_STATE`, updated in place); ``kind`` a code of
    COMPENSATOR_CODES, ``model`` the datasheet's friction table, ``model_ref`` its pressure
    rule, ``ctrl`` the controller vector (CTRL), ``ax`` the axis vector; ``oracle`` the
    plant's friction [N] (used by kind 4 only); ``velocity`` the measured velocity [m/s],
    read only with the velocity input on (``ctrl[11]`` = 1; otherwise the velocity is the
    backward difference ``(x - x_prev) / T``, 0 at the first sample). From the second
    sample the force goes through a first-order filter, ``F_k = F_{k-1} + a (F_raw -
    F_{k-1})`` with ``a = 1 - exp(-T / tau_f)`` (``ctrl[10]``; 1 without filter), before
    the command ``u_c = ((F_k - F_{k-1})/T + R_L(F_k)) / G_F``. The C, FMU and MATLAB exports
    (:mod:`cylfric.control.export`) are this function, line by line.
    """
    T = ctrl[9]
    started = state[3] > 0.0
    if ctrl[11] > 0.0:
        v_meas = velocity
    else:
        v_meas = (x - state[0]) / T if started else 0.0
    state[0] = x
    comp = 0.0
    if kind == 1:
        comp = ctrl[7] * math.tanh(v_ref / ctrl[5])
    elif kind == 2:
        fc, fs, s2, v_r, al, s0, s1 = params_at(model, operating_pressure(model_ref, pa, pb))
        comp = g_function(abs(v_ref), fc, fs, v_r, al) * math.tanh(v_ref / ctrl[5]) + s2 * v_ref
    elif kind == 3:
        fc, fs, s2, v_r, al, s0, s1 = params_at(model, operating_pressure(model_ref, pa, pb))
        z_hat, _ = z_step(state[1], v_meas, T, s0, fc, fs, v_r, al)
        z_hat += ctrl[6] * (x_ref - x) * T
        state[1] = z_hat
        comp = lugre_instant(v_meas, z_hat, s0, s1, s2, fc, fs, v_r, al)
    elif kind == 4:
        comp = oracle
    if started and kind != 0:  # first-order filter on the force: F <- F_prev + a (F - F_prev)
        comp = state[2] + ctrl[10] * (comp - state[2])
    u_c = 0.0
    if started and kind != 0:  # the force's rate and its hold against leakage, through the valve
        rate = (comp - state[2]) / T + leakage_force_rate(comp, x, ax)
        u_c = rate / force_rate_gain(1.0 if rate >= 0 else -1.0, x, pa, pb, ax)
    state[2] = comp
    state[3] = 1.0
    return comp, u_c


@njit(cache=True)
def run_compensator(kind, model, model_ref, ctrl, ax, measurements):
    """:func:`compensator_step` along recorded measurements, from the zero state: rows
    (x [m], p_A [Pa], p_B [Pa], x_ref [m], v_ref [m/s][, v [m/s]]); returns rows (F [N],
    u_c [-])."""
    n = measurements.shape[0]
    out = np.empty((n, 2))
    state = np.zeros(COMPENSATOR_STATE_SIZE)
    for k in range(n):
        m = measurements[k]
        v = m[5] if measurements.shape[1] > 5 else 0.0
        out[k, 0], out[k, 1] = compensator_step(
            kind, model, model_ref, ctrl, ax, state, m[0], m[1], m[2], m[3], m[4], 0.0, v
        )
    return out


@njit(cache=True)
def closed_loop(
    ax, plant, plant_ref, model, model_ref, compensator, ctrl, x_ref, v_ref, substeps, state0
):
    """Simulate the loop over the reference samples; returns (n, len(OUTPUTS)) outputs.

    ``ax`` is :meth:`Axis.vector`, ``plant`` and ``model`` friction tables (the plant's
    friction and the compensator's datasheet), ``*_ref`` their pressure rule codes,
    ``compensator`` a code of COMPENSATOR_CODES, ``ctrl`` the controller vector (CTRL),
    ``x_ref``, ``v_ref`` the reference at the samples [m], [m/s], ``state0`` (x, v, p_A,
    p_B, z) [SI].
    """
    aa, ab, stroke, va0, vb0, mass = ax[0], ax[1], ax[2], ax[3], ax[4], ax[5]
    beta, leak, ps, pt, kv, lam = ax[6], ax[7], ax[8], ax[9], ax[10], ax[11]
    order, tau, wv, zv, fload = ax[12], ax[13], ax[14], ax[15], ax[16]
    kp, ki, kd, ff_ext = ctrl[0], ctrl[1], ctrl[2], ctrl[3]
    T = ctrl[9]
    n = x_ref.shape[0]
    out = np.empty((n, 10))
    h = T / substeps
    decay = math.exp(-h / tau)
    x, v, pa, pb, z = state0[0], state0[1], state0[2], state0[3], state0[4]
    s = 0.0
    sd = 0.0
    integ = 0.0
    x_prev = x if ax[17] <= 0.0 else round(x / ax[17]) * ax[17]
    cstate = np.zeros(COMPENSATOR_STATE_SIZE)
    z_hat = 0.0
    u = 0.0
    comp = 0.0
    friction = 0.0
    quantum = ax[17]
    for k in range(n):
        # ---------------------------------------------------------- the controller
        xm = x if quantum <= 0.0 else round(x / quantum) * quantum  # the measured position
        v_meas = (xm - x_prev) / T if k > 0 else 0.0
        x_prev = xm
        err = x_ref[k] - xm
        vr = v_ref[k]
        comp, u_c = compensator_step(
            compensator, model, model_ref, ctrl, ax, cstate, xm, pa, pb, x_ref[k], vr, friction, v
        )
        z_hat = cstate[1]
        ff = 0.0
        if ff_ext > 0.0:  # flow linearisation at the measured pressures
            ar = (v_ref[min(k + 1, n - 1)] - v_ref[max(k - 1, 0)]) / (2.0 * T)
            vl = vr + ctrl[4] * ar
            ff = vl / velocity_gain(1.0 if vl >= 0 else -1.0, pa, pb, ax)
        u_fb = kp * err + integ + kd * (vr - v_meas)
        u = ff + u_fb + u_c + ctrl[8]
        if u > 1.0:
            u = 1.0
        elif u < -1.0:
            u = -1.0
        else:
            integ += ki * err * T  # conditional integration: no wind-up in saturation
        out[k, 0] = x
        out[k, 1] = v
        out[k, 2] = pa
        out[k, 3] = pb
        out[k, 4] = u
        out[k, 5] = s
        out[k, 6] = friction
        out[k, 7] = comp
        out[k, 8] = z
        out[k, 9] = z_hat
        if k == n - 1:
            break
        # ---------------------------------------------------------- the plant, one sample
        for _ in range(substeps):
            po = operating_pressure(plant_ref, pa, pb)
            fc, fs, s2, v_r, al, s0, s1 = params_at(plant, po)
            friction = lugre_instant(v, z, s0, s1, s2, fc, fs, v_r, al)
            force = aa * pa - ab * pb - friction - fload
            v_new = v + h * force / mass
            z, _ = z_step(z, 0.5 * (v + v_new), h, s0, fc, fs, v_r, al)
            v = v_new
            x += h * v
            qa, qb = valve_flows(s, pa, pb, ps, pt, kv, lam)
            va = va0 + aa * min(max(x, 0.0), stroke)
            vb = vb0 + ab * (stroke - min(max(x, 0.0), stroke))
            q_leak = leak * (pa - pb)
            pa = max(pa + h * beta / va * (qa - aa * v - q_leak), 0.0)
            pb = max(pb + h * beta / vb * (qb + ab * v + q_leak), 0.0)
            if order == 1:
                s = u + (s - u) * decay
            else:
                sd += h * (wv * wv * (u - s) - 2.0 * zv * wv * sd)
                s += h * sd
            if s > 1.0:
                s, sd = 1.0, 0.0
            elif s < -1.0:
                s, sd = -1.0, 0.0
        po = operating_pressure(plant_ref, pa, pb)
        fc, fs, s2, v_r, al, s0, s1 = params_at(plant, po)
        friction = lugre_instant(v, z, s0, s1, s2, fc, fs, v_r, al)
    return out
