"""Compiled integration kernels (numba, ``cache=True``). SI units; no Python objects.

The plant is a rigid moving mass with LuGre friction (thesis eq. 2.5, 3.1):

    m x'' = k (x_ref - x) + c (v_ref - v) + k_i * integral(x_ref - x) + f_ext + f_p - F_f
    dz/dt = v - sigma_0 |v| z / g(v),     F_f = sigma_0 z + sigma_1 dz/dt + sigma_2 v

One linear drive law covers an applied force (k = c = k_i = 0, ``f_ext``), a spring pulled at
a given speed (``k``, ``x_ref = x_0 + v t``) and a PID position servo (``k``, ``k_i``, ``c``).
``f_p = A_a p_a - A_b p_b`` is the net pressure force. Input signals are sampled on a uniform
grid and interpolated linearly in time; F_c, F_s and sigma_2 are signals too (pressure laws
evaluated on the grid by the caller), sigma_0, sigma_1, v_r and alpha are constants.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

# ---------------------------------------------------------------------------- LuGre pieces


@njit(cache=True, inline="always")
def exp_neg(x: float) -> float:
    """exp(-x) for x >= 0, as math.exp to rounding (at most 1 ulp apart) but cheaper where it can.

    Below 1e-3 the Taylor series to x^5 (its truncation, < x^6/720 < 1.4e-21, is below double
    rounding): sticking contacts have |v| << v_r. Above 746 the result underflows to 0.0, which
    is what exp returns there too, only slowly. In between, ``math.exp``.
    """
    if x < 1e-3:
        return 1.0 - x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0)))))
    if x > 746.0:
        return 0.0
    return math.exp(-x)


@njit(cache=True, inline="always")
def stribeck_decay(speed: float, inv_v_r: float, alpha: float) -> float:
    """exp(-(|v|/v_r)^alpha) of g(v) (eq. 2.5) from ``speed = |v|`` and ``1 / v_r`` [-]."""
    u = speed * inv_v_r
    if alpha == 2.0:  # Gaussian Stribeck curve: u*u is exact and avoids pow
        return exp_neg(u * u)
    if alpha == 1.0:
        return exp_neg(u)
    return exp_neg(u**alpha)


@njit(cache=True, inline="always")
def g_function(speed: float, F_c: float, F_s: float, v_r: float, alpha: float) -> float:
    """g(v) of eq. 2.5 for ``speed = |v|`` [N]."""
    return F_c + (F_s - F_c) * stribeck_decay(speed, 1.0 / v_r, alpha)


@njit(cache=True, inline="always")
def z_step(
    z0: float, v: float, h: float, sigma_0: float, F_c: float, F_s: float, v_r: float, alpha: float
) -> tuple[float, float]:
    """Exact z over a step at constant v: returns (z(h), integral of z over the step)."""
    if v == 0.0:
        return z0, z0 * h
    g = g_function(abs(v), F_c, F_s, v_r, alpha)
    lam = sigma_0 * abs(v) / g
    x = lam * h
    z_ss = g / sigma_0 if v > 0 else -g / sigma_0
    if x < 1e-5:
        one_minus_e = x * (1.0 - x * (0.5 - x / 6.0))
        integral_factor = h * (1.0 - x * (0.5 - x / 6.0))  # (1 - e^-x) / lam
    else:
        one_minus_e = -math.expm1(-x)
        integral_factor = one_minus_e / lam
    z1 = z_ss + (z0 - z_ss) * (1.0 - one_minus_e)
    return z1, z_ss * h + (z0 - z_ss) * integral_factor


@njit(cache=True, inline="always")
def lugre_instant(
    v: float,
    z: float,
    sigma_0: float,
    sigma_1: float,
    sigma_2: float,
    F_c: float,
    F_s: float,
    v_r: float,
    alpha: float,
) -> float:
    """Instantaneous LuGre force (eq. 2.5) [N]."""
    g = g_function(abs(v), F_c, F_s, v_r, alpha)
    dz = v - sigma_0 * abs(v) * z / g
    return sigma_0 * z + sigma_1 * dz + sigma_2 * v


# -------------------------------------------------------------- prescribed-velocity kernel


@njit(cache=True)
def prescribed_velocity(
    time, velocity, z0, sigma_0, sigma_1, F_c, F_s, sigma_2, v_r, alpha, substeps
):
    """LuGre friction along a prescribed velocity record (exact z with mid-step velocity).

    Parameters are arrays on ``time`` for F_c, F_s, sigma_2 (pressure may vary) and scalars
    otherwise; ``substeps`` internal steps per sample interval, the velocity interpolated
    linearly. Returns ``(z, friction)`` at the samples [m], [N]. Stable for any sigma_0.
    """
    n = time.shape[0]
    z = np.empty(n)
    force = np.empty(n)
    z[0] = z0
    for k in range(n - 1):
        h = (time[k + 1] - time[k]) / substeps
        zk = z[k]
        for j in range(substeps):
            w = (j + 0.5) / substeps
            vm = velocity[k] * (1 - w) + velocity[k + 1] * w
            fc = F_c[k] * (1 - w) + F_c[k + 1] * w
            fs = F_s[k] * (1 - w) + F_s[k + 1] * w
            zk, _ = z_step(zk, vm, h, sigma_0, fc, fs, v_r, alpha)
        z[k + 1] = zk
    for k in range(n):
        force[k] = lugre_instant(
            velocity[k], z[k], sigma_0, sigma_1, sigma_2[k], F_c[k], F_s[k], v_r, alpha
        )
    return z, force


# ------------------------------------------------------------------- fixed-step plant kernel


@njit(cache=True, inline="always")
def _implicit_step(
    x0, v0, z0, e0, h, mass, k, c, ki, xr, vr, fext, fc, fs, s2, s0, s1, v_r, alpha, tol
):
    """One step of the impulse scheme; returns (x1, v1, z1, e1, mean friction, iterations).

    The velocity held over the step is the midpoint ``(v0 + v1)/2``; z is updated exactly for
    it and friction enters as its impulse ``sigma_0 int z + sigma_1 (z1 - z0) + sigma_2 v h``.
    ``v1`` solves the momentum balance by a quasi-Newton iteration with the stuck-contact
    Jacobian, which bounds the true one, so it converges for any sigma_0 and step.
    """
    jac = mass + 0.25 * k * h * h + 0.5 * c * h + 0.5 * (0.5 * s0 * h * h + s1 * h + s2 * h)
    v1 = v0
    iterations = 0
    while iterations < 60:
        iterations += 1
        vm = 0.5 * (v0 + v1)
        z1, zint = z_step(z0, vm, h, s0, fc, fs, v_r, alpha)
        impulse = s0 * zint + s1 * (z1 - z0) + s2 * vm * h
        em = xr - (x0 + 0.5 * h * vm)
        drive = (k * em + c * (vr - vm) + ki * (e0 + 0.5 * h * em) + fext) * h
        dv = (mass * (v1 - v0) - drive + impulse) / jac
        v1 -= dv
        if abs(dv) <= tol * (abs(v1) + 1e-9):
            break
    vm = 0.5 * (v0 + v1)
    z1, zint = z_step(z0, vm, h, s0, fc, fs, v_r, alpha)
    impulse = s0 * zint + s1 * (z1 - z0) + s2 * vm * h
    return x0 + h * vm, v1, z1, e0 + h * (xr - (x0 + 0.5 * h * vm)), impulse / h, iterations


@njit(cache=True)
def fixed_step(
    dt,
    substeps,
    x0,
    v0,
    z0,
    mass,
    k,
    c,
    ki,
    x_ref,
    v_ref,
    f_ext,
    F_c,
    F_s,
    sigma_2,
    sigma_0,
    sigma_1,
    v_r,
    alpha,
    tol,
):
    """Integrate the plant on the uniform grid of the inputs (``dt`` apart).

    ``substeps`` internal steps per grid interval. Returns arrays on the grid:
    position [m], velocity [m/s], z [m], friction force [N] (instantaneous, eq. 2.5),
    mean friction over each interval [N], and the total quasi-Newton iteration count.
    """
    n = x_ref.shape[0]
    pos = np.empty(n)
    vel = np.empty(n)
    zz = np.empty(n)
    force = np.empty(n)
    mean_force = np.empty(n)
    pos[0], vel[0], zz[0] = x0, v0, z0
    force[0] = lugre_instant(v0, z0, sigma_0, sigma_1, sigma_2[0], F_c[0], F_s[0], v_r, alpha)
    mean_force[0] = force[0]
    h = dt / substeps
    x, v, z, e = x0, v0, z0, 0.0
    iterations = 0
    for i in range(n - 1):
        acc = 0.0
        for j in range(substeps):
            w = (j + 0.5) / substeps
            xr = x_ref[i] * (1 - w) + x_ref[i + 1] * w
            vr = v_ref[i] * (1 - w) + v_ref[i + 1] * w
            fe = f_ext[i] * (1 - w) + f_ext[i + 1] * w
            fc = F_c[i] * (1 - w) + F_c[i + 1] * w
            fs = F_s[i] * (1 - w) + F_s[i + 1] * w
            s2 = sigma_2[i] * (1 - w) + sigma_2[i + 1] * w
            x, v, z, e, fmean, it = _implicit_step(
                x,
                v,
                z,
                e,
                h,
                mass,
                k,
                c,
                ki,
                xr,
                vr,
                fe,
                fc,
                fs,
                s2,
                sigma_0,
                sigma_1,
                v_r,
                alpha,
                tol,
            )
            acc += fmean
            iterations += it
        pos[i + 1], vel[i + 1], zz[i + 1] = x, v, z
        force[i + 1] = lugre_instant(
            v, z, sigma_0, sigma_1, sigma_2[i + 1], F_c[i + 1], F_s[i + 1], v_r, alpha
        )
        mean_force[i + 1] = acc / substeps
    return pos, vel, zz, force, mean_force, iterations


# ------------------------------------------------------------------- the plant and its inputs
#
# Input signals are one (m, 6) array ``sig`` with the columns x_ref [m], v_ref [m/s], f_ext [N],
# F_c [N], F_s [N], sigma_2 [N*s/m] on a uniform grid ``dt_s`` apart, interpolated linearly in
# time. ``ramp`` [m/s] adds ``ramp * t`` to x_ref and ``ramp`` to v_ref, so a spring pulled at
# constant speed with constant friction needs two rows only (m = 2, dt_s = the duration).


@njit(cache=True, inline="always")
def _signals(sig, inv_dt_s, ramp, t):
    """Inputs at t (linear between grid points) and their slopes on that interval."""
    m = sig.shape[0]
    pos = t * inv_dt_s
    if pos <= 0.0:
        i, w = 0, 0.0
    elif pos >= m - 1:
        i, w = m - 2, 1.0
    else:
        i = int(pos)
        w = pos - i
    dxr = sig[i + 1, 0] - sig[i, 0]
    dvr = sig[i + 1, 1] - sig[i, 1]
    dfe = sig[i + 1, 2] - sig[i, 2]
    dfc = sig[i + 1, 3] - sig[i, 3]
    dfs = sig[i + 1, 4] - sig[i, 4]
    ds2 = sig[i + 1, 5] - sig[i, 5]
    return (
        sig[i, 0] + w * dxr + ramp * t,
        sig[i, 1] + w * dvr + ramp,
        sig[i, 2] + w * dfe,
        sig[i, 3] + w * dfc,
        sig[i, 4] + w * dfs,
        sig[i, 5] + w * ds2,
        dxr * inv_dt_s + ramp,
        dvr * inv_dt_s,
        dfe * inv_dt_s,
        dfc * inv_dt_s,
        dfs * inv_dt_s,
        ds2 * inv_dt_s,
    )


@njit(cache=True, inline="always")
def _rhs_at(x, v, z, e, xr, vr, fe, fc, fs, s2, inv_m, k, c, ki, s0, s1, inv_v_r, alpha):
    """The plant at given inputs: (dv/dt [m/s^2], dz/dt [m/s], de/dt [m], friction force
    (eq. 2.5) [N], decay of g(v) [-]); dx/dt is v."""
    decay = stribeck_decay(abs(v), inv_v_r, alpha)
    g = fc + (fs - fc) * decay
    dz = v - s0 * abs(v) * z / g
    friction = s0 * z + s1 * dz + s2 * v
    acc = (k * (xr - x) + c * (vr - v) + ki * e + fe - friction) * inv_m
    return acc, dz, xr - x, friction, decay


@njit(cache=True, inline="always")
def _plant(t, y, out, sig, inv_dt_s, ramp, inv_m, k, c, ki, s0, s1, inv_v_r, alpha):
    """Right-hand side of the plant at t, y = (x, v, z, e) into ``out``; returns the friction
    force (eq. 2.5) [N]. ``inv_m`` = 1/mass, ``inv_v_r`` = 1/v_r."""
    xr, vr, fe, fc, fs, s2, _, _, _, _, _, _ = _signals(sig, inv_dt_s, ramp, t)
    acc, dz, de, friction, _ = _rhs_at(
        y[0], y[1], y[2], y[3], xr, vr, fe, fc, fs, s2, inv_m, k, c, ki, s0, s1, inv_v_r, alpha
    )
    out[0] = y[1]
    out[1] = acc
    out[2] = dz
    out[3] = de
    return friction


@njit(cache=True, inline="always")
def _signal_mode(sig, n_grid):
    """How outputs read the inputs: 0 on the output grid, 1 constant, 2 interpolated."""
    if sig.shape[0] == n_grid:
        return 0
    if sig.shape[0] == 2:
        for q in range(6):
            if sig[0, q] != sig[1, q]:
                return 2
        return 1
    return 2


@njit(cache=True, inline="always")
def _outputs(x, v, z, e, xr, vr, fe, fc, fs, s2, k, c, ki, params, offset):
    """Friction force (eq. 2.5) [N] and force of the drive on the rod (``offset`` added) [N]."""
    s0, s1, inv_v_r, alpha = params
    speed = abs(v)
    g = fc + (fs - fc) * stribeck_decay(speed, inv_v_r, alpha)
    friction = s0 * z + s1 * (v - s0 * speed * z / g) + s2 * v
    return friction, k * (xr - x) + c * (vr - v) + ki * e + fe + offset


@njit(cache=True, inline="always")
def _write(
    out, j, tj, i_grid, mode, sig, inv_dt_s, ramp, x, v, z, e, k, c, ki, params, offset
) -> None:
    """Output point j: position, velocity, z, friction force (eq. 2.5) [N] and the force of
    the drive on the rod [N] (``offset`` added) into ``out[:, j]``."""
    s0, s1, inv_v_r, alpha = params
    if mode == 0:
        xr = sig[i_grid, 0] + ramp * tj
        vr = sig[i_grid, 1] + ramp
        fe, fc, fs, s2 = sig[i_grid, 2], sig[i_grid, 3], sig[i_grid, 4], sig[i_grid, 5]
    elif mode == 1:
        xr = sig[0, 0] + ramp * tj
        vr = sig[0, 1] + ramp
        fe, fc, fs, s2 = sig[0, 2], sig[0, 3], sig[0, 4], sig[0, 5]
    else:
        xr, vr, fe, fc, fs, s2, _, _, _, _, _, _ = _signals(sig, inv_dt_s, ramp, tj)
    friction, drive = _outputs(x, v, z, e, xr, vr, fe, fc, fs, s2, k, c, ki, params, offset)
    out[0, j] = x
    out[1, j] = v
    out[2, j] = z
    out[3, j] = friction
    out[4, j] = drive


@njit(cache=True)
def _output_grid(out, reached, dt, every):
    """Times of the output grid [s]; outputs past the last reached point are NaN."""
    n_out = out.shape[1]
    for j in range(reached, n_out):
        for r in range(out.shape[0]):
            out[r, j] = np.nan
    step = dt * every if every != 1 else dt
    time = np.empty(n_out)  # one allocation (np.arange(n_out) * step takes two)
    for j in range(n_out):
        time[j] = j * step
    return time


# ------------------------------------------------------------ adaptive Dormand-Prince 5(4)

_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0])
_A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [1 / 5, 0.0, 0.0, 0.0, 0.0],
        [3 / 40, 9 / 40, 0.0, 0.0, 0.0],
        [44 / 45, -56 / 15, 32 / 9, 0.0, 0.0],
        [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0.0],
        [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
    ]
)
_B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
_E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
# Dense output of Dormand & Prince (Hairer, Norsett, Wanner; as in scipy's RK45).
_P = np.array(
    [
        [1.0, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
        [0.0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
        [0.0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
        [0.0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
        [0.0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
    ]
)


@njit(cache=True)
def dopri(
    sig, dt_s, ramp, dt, n, x0, v0, z0, mass, k, c, ki, sigma_0, sigma_1, v_r, alpha,
    rtol, atol_x, atol_v, atol_z, max_steps, offset,
):  # fmt: skip
    """Adaptive Dormand-Prince 5(4) with dense output on the grid ``dt`` apart (n points).

    Inputs as for :func:`rosenbrock`. Absolute tolerances per state: position [m], velocity
    [m/s], z [m]; the servo integral shares the position tolerance times the duration.
    Returns (time [s], out, accepted, rejected, reached) with ``out`` (5, n): position [m],
    velocity [m/s], z [m], friction [N] (eq. 2.5), drive force [N]; NaN past ``reached``
    (fewer than n points when ``max_steps`` ran out).
    """
    t_end = dt * (n - 1)
    out = np.empty((5, n))
    inv_dt_s, inv_m, inv_v_r = 1.0 / dt_s, 1.0 / mass, 1.0 / v_r
    params = (sigma_0, sigma_1, inv_v_r, alpha)
    mode = _signal_mode(sig, n)
    y = np.array([x0, v0, z0, 0.0])
    atol = np.array([atol_x, atol_v, atol_z, atol_x * max(t_end, 1.0)])
    K = np.empty((7, 4))
    Q = np.empty((4, 4))
    tmp = np.empty(4)
    y_new = np.empty(4)
    f0 = np.empty(4)
    _plant(0.0, y, f0, sig, inv_dt_s, ramp, inv_m, k, c, ki, sigma_0, sigma_1, inv_v_r, alpha)
    _write(out, 0, 0.0, 0, mode, sig, inv_dt_s, ramp, x0, v0, z0, 0.0, k, c, ki, params, offset)
    t = 0.0
    h = min(dt, 1e-4)
    next_out = 1
    accepted = 0
    rejected = 0
    err_old = 1e-4
    last_rejected = False
    while next_out < n and accepted + rejected < max_steps:
        if t + h > t_end:
            h = t_end - t
        K[0] = f0
        for s in range(1, 6):
            for q in range(4):
                acc = 0.0
                for r in range(s):
                    acc += _A[s, r] * K[r, q]
                tmp[q] = y[q] + h * acc
            _plant(
                t + _C[s] * h,
                tmp,
                K[s],
                sig,
                inv_dt_s,
                ramp,
                inv_m,
                k,
                c,
                ki,
                sigma_0,
                sigma_1,
                inv_v_r,
                alpha,
            )
        for q in range(4):
            acc = 0.0
            for r in range(6):
                acc += _B[r] * K[r, q]
            y_new[q] = y[q] + h * acc
        _plant(
            t + h,
            y_new,
            K[6],
            sig,
            inv_dt_s,
            ramp,
            inv_m,
            k,
            c,
            ki,
            sigma_0,
            sigma_1,
            inv_v_r,
            alpha,
        )
        err = 0.0
        for q in range(4):
            acc = 0.0
            for r in range(7):
                acc += _E[r] * K[r, q]
            scale = atol[q] + rtol * max(abs(y[q]), abs(y_new[q]))
            err += (h * acc / scale) ** 2
        err = math.sqrt(err / 4)
        if err <= 1.0:
            t_new = t + h
            if next_out < n and next_out * dt <= t_new + 1e-12 * dt:
                for q in range(4):  # dense-output coefficients once per step
                    for j in range(4):
                        coef = 0.0
                        for r in range(7):
                            coef += K[r, q] * _P[r, j]
                        Q[q, j] = coef
            while next_out < n and next_out * dt <= t_new + 1e-12 * dt:
                tj = next_out * dt
                theta = (tj - t) / h
                for q in range(4):
                    tmp[q] = y[q] + h * theta * (
                        Q[q, 0] + theta * (Q[q, 1] + theta * (Q[q, 2] + theta * Q[q, 3]))
                    )
                _write(
                    out, next_out, tj, next_out, mode, sig, inv_dt_s, ramp,
                    tmp[0], tmp[1], tmp[2], tmp[3], k, c, ki, params, offset,
                )  # fmt: skip
                next_out += 1
            t = t_new
            y[:] = y_new
            f0[:] = K[6]
            accepted += 1
            # PI step control (Gustafsson; Hairer & Wanner's DOPRI5: 0.17 and 0.04)
            err = max(err, 1e-10)
            factor = min(10.0, 0.9 * err**-0.17 * err_old**0.04)
            if last_rejected:
                factor = min(factor, 1.0)
            err_old = max(err, 1e-4)
            last_rejected = False
        else:
            rejected += 1
            factor = max(0.2, 0.9 * err**-0.2)
            last_rejected = True
        h *= factor
    return _output_grid(out, next_out, dt, 1), out, accepted, rejected, next_out


# ------------------------------------------------------- adaptive Rosenbrock (Rodas3), L-stable
#
# A Rosenbrock method solves one linear system per stage with the exact Jacobian instead of
# Newton iterations: stiff bristles (sigma_0 up to 1e10 N/m) cost no smaller steps, because the
# method is L-stable and stiffly accurate. Rodas3 (Sandu et al. 1997) in the KPP form (Hairer &
# Wanner 1996, section IV.7), with G = 1/(h gamma) - J(t_n, y_n), gamma = 1/2:
#     G K_1 = f(t_n, y_n) + h/2 f_t
#     G K_2 = f(t_n, y_n) + 4 K_1 / h + 3h/2 f_t
#     G K_3 = f(t_n + h, y_n + 2 K_1) + (K_1 - K_2) / h
#     G K_4 = f(t_n + h, y_n + 2 K_1 + K_3) + (K_1 - K_2 - 8/3 K_3) / h
#     y_n+1 = y_n + 2 K_1 + K_3 + K_4,   error = K_4
# written out for the four states (the coefficient tables are in benchmarks/rosenbrock_tables.py,
# which also has Rodas4). f(t_n+1, y_n+1) is evaluated on acceptance for the output and is the
# next step's f(t_n, y_n); the Jacobian re-uses its exp. So a step costs three exps.
# Between steps the states are interpolated on the output grid by cubic Hermite polynomials
# through (y_n, f_n) and (y_n+1, f_n+1), except velocity and z on stiff steps: their slopes
# carry the stiff error, so they go linearly. The output points of a step are written by one
# loop without calls or branches (_dense_block, in numpy's error model: a division cannot raise),
# which LLVM vectorises: it was 60 % of a Canudas run (10,001 points, 386 steps) as a scalar
# loop with one exp per point, and exp_neg needs math.exp at about 5 % of those points only
# (sticking |v| << v_r takes the series, sliding far above v_r underflows to 0); those few are
# recomputed after (_dense_fixup).


@njit(cache=True, inline="always")
def _partials(v, z, sigma_0, F_c, F_s, inv_v_r, alpha, decay):
    """:func:`lugre_partials` from the decay exp(-(|v|/v_r)^alpha) already computed."""
    speed = abs(v)
    u = speed * inv_v_r
    if u == 0.0:
        slope_u = 1.0 if alpha == 1.0 else (0.0 if alpha > 1.0 else 1e300)
    elif alpha == 1.0:
        slope_u = 1.0
    elif alpha == 2.0:
        slope_u = 2.0 * u
    else:
        slope_u = alpha * u**alpha / u
    g = F_c + (F_s - F_c) * decay
    inv_g2 = 1.0 / (g * g)
    dg = -(F_s - F_c) * decay * slope_u * inv_v_r  # dg/d|v|
    sign = 1.0 if v >= 0.0 else -1.0
    d_v = 1.0 - sigma_0 * z * sign * (g - speed * dg) * inv_g2
    d_z = -sigma_0 * speed * g * inv_g2
    d_g = sigma_0 * speed * z * inv_g2  # d(dz/dt)/dg
    return d_v, d_z, d_g * (1.0 - decay), d_g * decay


@njit(cache=True, inline="always")
def lugre_partials(
    v: float, z: float, sigma_0: float, F_c: float, F_s: float, v_r: float, alpha: float
) -> tuple[float, float, float, float]:
    """Partial derivatives of dz/dt = v - sigma_0 |v| z / g(v) (eq. 2.5).

    Returns ``(d/dv, d/dz, d/dF_c, d/dF_s)`` of dz/dt, with dg/d|v| from eq. 2.5's
    g(v) = F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha). At v = 0 the one-sided slope for v > 0
    is used (the velocity term then vanishes for alpha > 1).
    """
    inv_v_r = 1.0 / v_r
    decay = stribeck_decay(abs(v), inv_v_r, alpha)
    return _partials(v, z, sigma_0, F_c, F_s, inv_v_r, alpha, decay)


@njit(cache=True, inline="always")
def _solve(rx, rv, rz, re, a_, cz, d_, d_v, inv_gi, inv_gz, inv_den):
    """K = G^-1 r for G = 1/(h gamma) I - J in closed form (x and e eliminated, z by its row)."""
    kv = (
        rv - a_ * rx * inv_gi - cz * rz * inv_gz + d_ * re * inv_gi - d_ * rx * inv_gi * inv_gi
    ) * inv_den
    kx = (rx + kv) * inv_gi
    return kx, kv, (rz + d_v * kv) * inv_gz, (re - kx) * inv_gi


@njit(cache=True, inline="always")
def _decay_cheap(arg):
    """exp(-arg) where :func:`exp_neg` needs no math.exp (arg < 1e-3 or > 746), any value
    elsewhere: branch-free, so that the output loop vectorises."""
    taylor = 1.0 - arg * (
        1.0 - arg * (0.5 - arg * (1.0 / 6.0 - arg * (1.0 / 24.0 - arg * (1.0 / 120.0))))
    )
    return 0.0 if arg > 746.0 else taylor


@njit(cache=True, inline="always")
def _dense_block(
    out, sig, j0, j1, every, on_grid, dt, t, inv_h, y, cx, cv, cz, ce,
    ramp, k, c, ki, s0, s1, inv_v_r, alpha2, offset,
):  # fmt: skip
    """Output points j0..j1-1 of one step (cubic Hermite coefficients as in rodas3_core) for
    inputs constant (``on_grid`` False: row 0 and the ramp) or on the output grid, and
    alpha = 1 or 2 (``alpha2``). One loop without calls or branches, which LLVM vectorises;
    g(v) there is exact where :func:`exp_neg` takes no math.exp (sticking: |v| << v_r, or
    slipping far above v_r). Returns how many points need math.exp (see :func:`_dense_fixup`).
    """
    x, v, z, e = y
    cx1, cx2, cx3 = cx
    cv1, cv2, cv3 = cv
    cz1, cz2, cz3 = cz
    ce1, ce2, ce3 = ce
    m = j1 - j0
    pos, vel, zz, frc, drv = (
        out[0, j0:j1],
        out[1, j0:j1],
        out[2, j0:j1],
        out[3, j0:j1],
        out[4, j0:j1],
    )
    bad = 0
    if on_grid:
        rows = sig[j0 * every : (j1 - 1) * every + 1 : every]
        for i in range(m):
            tj = ((j0 + i) * every) * dt
            th = (tj - t) * inv_h
            xj = x + th * (cx1 + th * (cx2 + th * cx3))
            vj = v + th * (cv1 + th * (cv2 + th * cv3))
            zj = z + th * (cz1 + th * (cz2 + th * cz3))
            ej = e + th * (ce1 + th * (ce2 + th * ce3))
            speed = abs(vj)
            u = speed * inv_v_r
            arg = u * u if alpha2 else u
            bad += 1 if (arg >= 1e-3 and arg <= 746.0) else 0
            fc, fs = rows[i, 3], rows[i, 4]
            g = fc + (fs - fc) * _decay_cheap(arg)
            pos[i] = xj
            vel[i] = vj
            zz[i] = zj
            frc[i] = s0 * zj + s1 * (vj - s0 * speed * zj / g) + rows[i, 5] * vj
            drv[i] = (
                k * (rows[i, 0] + ramp * tj - xj) + c * (rows[i, 1] + ramp - vj)
                + (ki * ej if ki != 0.0 else 0.0) + rows[i, 2] + offset
            )  # fmt: skip
        return bad
    xr0, vr0, fe, fc, fs, s2 = (
        sig[0, 0],
        sig[0, 1] + ramp,
        sig[0, 2],
        sig[0, 3],
        sig[0, 4],
        sig[0, 5],
    )
    dfs = fs - fc
    for i in range(m):
        tj = ((j0 + i) * every) * dt
        th = (tj - t) * inv_h
        xj = x + th * (cx1 + th * (cx2 + th * cx3))
        vj = v + th * (cv1 + th * (cv2 + th * cv3))
        zj = z + th * (cz1 + th * (cz2 + th * cz3))
        ej = e + th * (ce1 + th * (ce2 + th * ce3))
        speed = abs(vj)
        u = speed * inv_v_r
        arg = u * u if alpha2 else u
        bad += 1 if (arg >= 1e-3 and arg <= 746.0) else 0
        g = fc + dfs * _decay_cheap(arg)
        pos[i] = xj
        vel[i] = vj
        zz[i] = zj
        frc[i] = s0 * zj + s1 * (vj - s0 * speed * zj / g) + s2 * vj
        drv[i] = (
            k * (xr0 + ramp * tj - xj) + c * (vr0 - vj) + (ki * ej if ki != 0.0 else 0.0)
            + fe + offset
        )  # fmt: skip
    return bad


@njit(cache=True, inline="always")
def _dense_fixup(out, sig, j0, j1, every, on_grid, s0, s1, inv_v_r, alpha):
    """Friction force [N] at the output points j0..j1-1 written by :func:`_dense_block` whose
    g(v) needs math.exp, recomputed with :func:`stribeck_decay` (the drive force there does not
    depend on g)."""
    for j in range(j0, j1):
        vj = out[1, j]
        speed = abs(vj)
        u = speed * inv_v_r
        arg = u * u if alpha == 2.0 else u
        if arg >= 1e-3 and arg <= 746.0:
            row = j * every if on_grid else 0
            fc, fs = sig[row, 3], sig[row, 4]
            g = fc + (fs - fc) * exp_neg(arg)
            zj = out[2, j]
            out[3, j] = s0 * zj + s1 * (vj - s0 * speed * zj / g) + sig[row, 5] * vj


# Floating-point contraction (FMA), reciprocals and reassociation are allowed in the Rodas3 kernel
# (not NaN/inf assumptions: a failed step is detected by a non-finite error). They change
# results at rounding level only; benchmarks/c/rodas3.c is compiled with the same freedoms.
FAST_MATH = {"contract", "arcp", "nsz", "afn", "reassoc"}


# Weight of the linearised friction-force term in the Rodas3 error norm. At full weight (1.0)
# it over-resolves slipping contacts, where sigma_1 dz/dt multiplies the bristle error by
# sigma_1 |dg/dz|: on the Canudas case at sigma_0 = 1e8 N/m it took 629 steps where 373 reach
# the same RMS(F - F_ref)/F_c (4.6e-6); without the term (the textbook norm of the states) the
# error at sigma_0 = 1e10 N/m grows tenfold (4.7e-5 at rtol 1e-6). At 0.1 the sweep 1e5..1e10
# takes 0.6-1.0x the steps of full weight at the same or better accuracy (issue 26;
# benchmarks/c/rodas3.c mirrors it).
FORCE_NORM = 0.1


@njit(cache=True, fastmath=FAST_MATH, error_model="numpy")
def rodas3_core(
    sig, dt_s, ramp, x0, v0, z0, mass, k, c, ki, sigma_0, sigma_1, v_r, alpha,
    rtol, atol_x, atol_v, atol_z, atol_f, max_steps, dt, every, n_grid, offset, out,
):  # fmt: skip
    """Adaptive Rodas3 integration of the plant; outputs into ``out`` (5, n_out).

    The grid has ``n_grid`` points ``dt`` apart; output j is grid point ``j * every`` (see
    :func:`_write` for the rows). Returns (accepted, rejected, output points reached).
    """
    n_out = out.shape[1]
    t_end = dt * (n_grid - 1)
    atol_e = atol_x * max(t_end, 1.0)
    inv_dt_s, inv_m, inv_v_r = 1.0 / dt_s, 1.0 / mass, 1.0 / v_r
    s0, s1 = sigma_0, sigma_1
    params = (s0, s1, inv_v_r, alpha)
    mode = _signal_mode(sig, n_grid)
    # outputs by the vectorised _dense_block (inputs constant or on the grid, alpha 1 or 2)
    fast_out = mode != 2 and (alpha == 2.0 or alpha == 1.0)
    x, v, z, e = x0, v0, z0, 0.0
    t = 0.0
    xr, vr, fe, fc, fs, s2, sxr, svr, sfe, sfc, sfs, ss2 = _signals(sig, inv_dt_s, ramp, 0.0)
    a0, dz0, de0, _, decay0 = _rhs_at(
        x, v, z, e, xr, vr, fe, fc, fs, s2, inv_m, k, c, ki, s0, s1, inv_v_r, alpha
    )
    _write(out, 0, 0.0, 0, mode, sig, inv_dt_s, ramp, x, v, z, e, k, c, ki, params, offset)
    h = min(dt, 1e-5)
    next_out = 1
    accepted = 0
    rejected = 0
    while next_out < n_out and accepted + rejected < max_steps:
        if t + h > t_end:
            h = t_end - t
        # exact Jacobian and time derivative at (t_n, y_n)
        d_v, d_z, d_fc, d_fs = _partials(v, z, s0, fc, fs, inv_v_r, alpha, decay0)
        f_v = s1 * d_v + s2  # dF/dv
        f_z = s0 + s1 * d_z  # dF/dz
        # Breakaway guards. An implicit step damps growing modes it steps over, and a stuck
        # contact shows no error until it breaks loose, so (1) while the drive loads the
        # contact towards the slip limit g(v), a step covers at most half the force margin at
        # the present loading rate (the threshold is approached geometrically, like an event
        # location); (2) a growing mode of the (v, z) block (breakaway under way) limits h to
        # 1/(its rate).
        load = k * (xr - x) + c * (vr - v) + ki * e + fe
        rate = k * (sxr - v) + c * svr + sfe + ki * (xr - x)
        if load * rate > 0.0:
            margin = (fc + (fs - fc) * decay0) - abs(load)
            if margin > 0.0:
                h = min(h, max(0.5 * margin / abs(rate), 1e-3 * dt))
        # (3) a slip that decelerates towards v = 0 (where |v| makes the Jacobian jump) is
        # followed to the sticking instant geometrically too
        if v * a0 < 0.0 and abs(v) > 1e-3 * v_r:
            h = min(h, max(0.5 * abs(v / a0), 1e-3 * dt))
        b_ = (c + f_v) * inv_m
        cz = f_z * inv_m
        trace = d_z - b_
        det = cz * d_v - b_ * d_z
        disc = 0.25 * trace * trace - det
        growth = 0.5 * trace + math.sqrt(disc) if disc > 0.0 else 0.5 * trace
        if growth > 0.0:
            h = min(h, 1.0 / growth)
        # stiff step: the (v, z) modes are faster than 1/h; then v and z are interpolated
        # linearly on the output grid, otherwise by cubic Hermite polynomials
        stiff = h * (abs(trace) + math.sqrt(abs(det))) > 1.0
        if t + h > t_end:
            h = t_end - t
        dzdt_t = d_fc * sfc + d_fs * sfs
        ft_v = (k * sxr + c * svr + sfe - s1 * dzdt_t - v * ss2) * inv_m
        # G = 1/(h gamma) I - J, solved in closed form (x, e eliminated; z by its own row)
        inv_h = 1.0 / h
        gi = 2.0 * inv_h
        inv_gi = 0.5 * h
        a_ = k * inv_m
        d_ = ki * inv_m
        inv_gz = 1.0 / (gi - d_z)
        inv_den = 1.0 / (a_ * inv_gi + gi + b_ + cz * d_v * inv_gz + d_ * inv_gi * inv_gi)
        # stage 1
        rx = v
        rv = a0 + 0.5 * h * ft_v
        rz = dz0 + 0.5 * h * dzdt_t
        re = de0 + 0.5 * h * sxr
        k1x, k1v, k1z, k1e = _solve(rx, rv, rz, re, a_, cz, d_, d_v, inv_gi, inv_gz, inv_den)
        # stage 2
        rx = v + 4.0 * inv_h * k1x
        rv = a0 + 4.0 * inv_h * k1v + 1.5 * h * ft_v
        rz = dz0 + 4.0 * inv_h * k1z + 1.5 * h * dzdt_t
        re = de0 + 4.0 * inv_h * k1e + 1.5 * h * sxr
        k2x, k2v, k2z, k2e = _solve(rx, rv, rz, re, a_, cz, d_, d_v, inv_gi, inv_gz, inv_den)
        # stages 3 and 4 at t_n + h (the inputs there are shared with f(t_n+1, y_n+1))
        t1 = t + h
        xr1, vr1, fe1, fc1, fs1, s21, sxr1, svr1, sfe1, sfc1, sfs1, ss21 = _signals(
            sig, inv_dt_s, ramp, t1
        )
        yv = v + 2.0 * k1v
        fa, fz_, fe_, _, _ = _rhs_at(
            x + 2.0 * k1x, yv, z + 2.0 * k1z, e + 2.0 * k1e,
            xr1, vr1, fe1, fc1, fs1, s21, inv_m, k, c, ki, s0, s1, inv_v_r, alpha,
        )  # fmt: skip
        rx = yv + (k1x - k2x) * inv_h
        rv = fa + (k1v - k2v) * inv_h
        rz = fz_ + (k1z - k2z) * inv_h
        re = fe_ + (k1e - k2e) * inv_h
        k3x, k3v, k3z, k3e = _solve(rx, rv, rz, re, a_, cz, d_, d_v, inv_gi, inv_gz, inv_den)
        sx = 2.0 * k1x + k3x
        sv = 2.0 * k1v + k3v
        sz = 2.0 * k1z + k3z
        se = 2.0 * k1e + k3e
        yv = v + sv
        fa, fz_, fe_, _, _ = _rhs_at(
            x + sx, yv, z + sz, e + se,
            xr1, vr1, fe1, fc1, fs1, s21, inv_m, k, c, ki, s0, s1, inv_v_r, alpha,
        )  # fmt: skip
        rx = yv + (k1x - k2x - 8.0 / 3.0 * k3x) * inv_h
        rv = fa + (k1v - k2v - 8.0 / 3.0 * k3v) * inv_h
        rz = fz_ + (k1z - k2z - 8.0 / 3.0 * k3z) * inv_h
        re = fe_ + (k1e - k2e - 8.0 / 3.0 * k3e) * inv_h
        k4x, k4v, k4z, k4e = _solve(rx, rv, rz, re, a_, cz, d_, d_v, inv_gi, inv_gz, inv_den)
        x1 = x + (sx + k4x)
        v1 = v + (sv + k4v)
        z1 = z + (sz + k4z)
        e1 = e + (se + k4e)
        # weighted RMS error of the states and of the friction force (linearised), which is
        # what users read; the force term at FORCE_NORM of its weight (see there)
        q = k4x / (atol_x + rtol * max(abs(x), abs(x1)))
        err = q * q
        q = k4v / (atol_v + rtol * max(abs(v), abs(v1)))
        err += q * q
        q = k4z / (atol_z + rtol * max(abs(z), abs(z1)))
        err += q * q
        q = k4e / (atol_e + rtol * max(abs(e), abs(e1)))
        err += q * q
        q = FORCE_NORM * (f_v * k4v + f_z * k4z) / (atol_f + rtol * abs(s0 * z + s1 * dz0 + s2 * v))
        err += q * q
        err = math.sqrt(err / 5)
        if err <= 1.0 and math.isfinite(err):
            a1, dz1, de1, _, decay1 = _rhs_at(
                x1, v1, z1, e1, xr1, vr1, fe1, fc1, fs1, s21, inv_m, k, c, ki, s0, s1,
                inv_v_r, alpha,
            )  # fmt: skip
            # cubic Hermite p(theta) = y_n + theta (c1 + theta (c2 + theta c3)) through
            # (y_n, f_n), (y_n+1, f_n+1), its coefficients once per step
            dx = x1 - x
            cx1, cx2, cx3 = h * v, 3.0 * dx - h * (2.0 * v + v1), h * (v + v1) - 2.0 * dx
            dv, dzz, dee = v1 - v, z1 - z, e1 - e
            if stiff:  # slopes of stiff states carry their error: v and z go linearly
                cv1, cv2, cv3 = dv, 0.0, 0.0
                cz1, cz2, cz3 = dzz, 0.0, 0.0
            else:
                cv1, cv2, cv3 = h * a0, 3.0 * dv - h * (2.0 * a0 + a1), h * (a0 + a1) - 2.0 * dv
                cz1 = h * dz0
                cz2 = 3.0 * dzz - h * (2.0 * dz0 + dz1)
                cz3 = h * (dz0 + dz1) - 2.0 * dzz
            ce1, ce2, ce3 = h * de0, 3.0 * dee - h * (2.0 * de0 + de1), h * (de0 + de1) - 2.0 * dee
            # output points of this step: j_end is the first one past t_n+1
            t_lim = t1 + 1e-12 * dt
            j_end = min(max(int(t_lim / (every * dt)), next_out - 1) + 1, n_out)
            while j_end < n_out and (j_end * every) * dt <= t_lim:  # rounding of the guess
                j_end += 1
            while j_end > next_out and ((j_end - 1) * every) * dt > t_lim:
                j_end -= 1
            if fast_out and j_end - next_out >= 4:  # (fewer: the call costs more than it saves)
                n_bad = _dense_block(
                    out, sig, next_out, j_end, every, mode == 0, dt, t, inv_h, (x, v, z, e),
                    (cx1, cx2, cx3), (cv1, cv2, cv3), (cz1, cz2, cz3), (ce1, ce2, ce3),
                    ramp, k, c, ki, s0, s1, inv_v_r, alpha == 2.0, offset,
                )  # fmt: skip
                if n_bad > 0:  # the few points whose g(v) needs math.exp
                    _dense_fixup(
                        out, sig, next_out, j_end, every, mode == 0, s0, s1, inv_v_r, alpha
                    )
                next_out = j_end
            while next_out < j_end:
                i_grid = next_out * every
                tj = i_grid * dt
                theta = (tj - t) * inv_h
                xj = x + theta * (cx1 + theta * (cx2 + theta * cx3))
                vj = v + theta * (cv1 + theta * (cv2 + theta * cv3))
                zj = z + theta * (cz1 + theta * (cz2 + theta * cz3))
                ej = e + theta * (ce1 + theta * (ce2 + theta * ce3)) if ki != 0.0 else 0.0
                # (written out rather than through _write: passing the arrays to a helper
                # here costs reference counting at every output point)
                if mode == 0:
                    xrj, vrj = sig[i_grid, 0] + ramp * tj, sig[i_grid, 1] + ramp
                    fej, fcj, fsj, s2j = (
                        sig[i_grid, 2],
                        sig[i_grid, 3],
                        sig[i_grid, 4],
                        sig[i_grid, 5],
                    )
                elif mode == 1:
                    xrj, vrj = sig[0, 0] + ramp * tj, sig[0, 1] + ramp
                    fej, fcj, fsj, s2j = sig[0, 2], sig[0, 3], sig[0, 4], sig[0, 5]
                else:
                    xrj, vrj, fej, fcj, fsj, s2j, _, _, _, _, _, _ = _signals(
                        sig, inv_dt_s, ramp, tj
                    )
                friction, drive = _outputs(
                    xj, vj, zj, ej, xrj, vrj, fej, fcj, fsj, s2j, k, c, ki, params, offset
                )
                out[0, next_out] = xj
                out[1, next_out] = vj
                out[2, next_out] = zj
                out[3, next_out] = friction
                out[4, next_out] = drive
                next_out += 1
            t = t1
            x, v, z, e = x1, v1, z1, e1
            a0, dz0, de0, decay0 = a1, dz1, de1, decay1
            xr, vr, fe, fc, fs, s2 = xr1, vr1, fe1, fc1, fs1, s21
            sxr, svr, sfe, sfc, sfs, ss2 = sxr1, svr1, sfe1, sfc1, sfs1, ss21
            accepted += 1
            factor = min(6.0, 0.9 / np.cbrt(max(err, 1e-10)))  # err^(-1/order)
        else:
            rejected += 1
            factor = 0.2 if not math.isfinite(err) else max(0.2, 0.9 / np.cbrt(err))
        h *= factor
    return accepted, rejected, next_out


@njit(cache=True)
def rosenbrock(
    sig, dt_s, ramp, dt, n, x0, v0, z0, mass, k, c, ki, sigma_0, sigma_1, v_r, alpha,
    rtol, atol_x, atol_v, atol_z, atol_f, max_steps, offset,
):  # fmt: skip
    """Adaptive L-stable Rosenbrock (Rodas3) integration with output on a grid ``dt`` apart.

    ``sig`` (m, 6): input signals x_ref [m], v_ref [m/s], f_ext [N] (pressure force included),
    F_c [N], F_s [N], sigma_2 [N*s/m] on a grid ``dt_s`` apart (m = n on the output grid, or
    2 rows over the duration for constants); ``ramp`` [m/s] adds ``ramp * t`` to x_ref and
    ``ramp`` to v_ref. Plant: mass [kg], spring ``k`` [N/m], damping ``c`` [N*s/m], integral
    gain ``ki`` [N/(m*s)]; sigma_0 [N/m], sigma_1 [N*s/m], v_r [m/s], alpha [-]. Absolute
    tolerances: position [m], velocity [m/s], z [m], friction force [N].

    Returns (time [s], out, accepted, rejected, reached) with ``out`` (5, n): position [m],
    velocity [m/s], z [m], friction [N] (eq. 2.5) and the force of the drive on the rod
    k (x_ref - x) + c (v_ref - v) + ki int(x_ref - x) + f_ext + ``offset`` [N]; NaN past
    ``reached``.
    """
    out = np.empty((5, n))
    accepted, rejected, reached = rodas3_core(
        sig, dt_s, ramp, x0, v0, z0, mass, k, c, ki, sigma_0, sigma_1, v_r, alpha,
        rtol, atol_x, atol_v, atol_z, atol_f, max_steps, dt, 1, n, offset, out,
    )  # fmt: skip
    return _output_grid(out, reached, dt, 1), out, accepted, rejected, reached


@njit(cache=True, parallel=True)
def rosenbrock_batch(
    dt, n, record_every, x0, v0, rows, ramp, mass, k, c, ki, f_offset, x_ref, v_ref, f_ext,
    F_c, F_s, sigma_2, sigma_0, sigma_1, v_r, alpha, rtol, atol_x, atol_v, atol_z, atol_f,
    max_steps, chunks, accuracy, min_rtol,
):  # fmt: skip
    """Many heterogeneous sets with the Rodas3 kernel (``prange``: all cores).

    Per-set values are 1-D arrays of length ``n_sets``: drive (``ramp`` [m/s], ``mass`` [kg],
    ``k``, ``c``, ``ki``, ``f_offset`` [N] added to the drive force), friction and absolute
    tolerances. ``rows[s]`` picks the set's input signals from the (n_signals, n) arrays
    ``x_ref``, ``v_ref``, ``f_ext``; row 0 must be the constant ``x0``, 0, 0 (springs pulled at
    ``ramp``), which needs no signal arrays. Returns ``out`` (n_sets, 5, n_records) as in
    :func:`rosenbrock` every ``record_every`` grid points (the drive force without
    ``f_offset``), step counts (n_sets, 2) and output points reached.
    ``chunks`` work packages share the sets (a few per thread).

    Per-set accuracy control (``accuracy`` > 0, RMS(F)/F_c [-]): each set runs at ``rtol``
    and again at ``rtol / 10``; the tighter run is kept when the two friction records differ
    by at most half of ``accuracy`` in RMS over F_c, otherwise the tolerance goes down
    another decade, to ``min_rtol`` at most. (The half: with the full ``accuracy`` as the
    bound, 2 of 5,000 Canudas-like sets kept a run at 1.8e-4 against 1e-4, where the error
    fell less than tenfold per decade; with half, the worst of the 5,000 was 3.7e-5.)
    Returns, after ``reached``, each set's final rtol and whether its check passed.
    """
    n_sets = F_c.shape[0]
    n_rec = (n - 1) // record_every + 1
    t_end = dt * (n - 1)
    out = np.empty((n_sets, 5, n_rec))
    steps = np.empty((n_sets, 2), dtype=np.int64)
    reached = np.empty(n_sets, dtype=np.int64)
    final_rtol = np.empty(n_sets)
    passed = np.empty(n_sets, dtype=np.bool_)
    # sets go in chunks, each with its own work arrays allocated once (allocating per set
    # serialises the threads on the allocator)
    n_chunks = max(1, min(n_sets, chunks))
    for chunk in prange(n_chunks):
        full = np.empty((n, 6))
        compact = np.empty((2, 6))
        previous = np.empty(n_rec)
        for s in range(chunk * n_sets // n_chunks, (chunk + 1) * n_sets // n_chunks):
            row = rows[s]
            if row == 0:
                for r in range(2):
                    compact[r, 0] = x_ref[0, 0]
                    compact[r, 1] = v_ref[0, 0]
                    compact[r, 2] = f_ext[0, 0] + f_offset[s]
                    compact[r, 3] = F_c[s]
                    compact[r, 4] = F_s[s]
                    compact[r, 5] = sigma_2[s]
                sig, dt_s = compact, max(t_end, dt)
            else:
                for i in range(n):
                    full[i, 0] = x_ref[row, i]
                    full[i, 1] = v_ref[row, i]
                    full[i, 2] = f_ext[row, i] + f_offset[s]
                    full[i, 3] = F_c[s]
                    full[i, 4] = F_s[s]
                    full[i, 5] = sigma_2[s]
                sig, dt_s = full, dt
            r_tol = rtol
            accepted, rejected, got = rodas3_core(
                sig, dt_s, ramp[s], x0, v0, 0.0, mass[s], k[s], c[s], ki[s], sigma_0[s],
                sigma_1[s], v_r[s], alpha[s], rtol, atol_x[s], atol_v[s], atol_z[s], atol_f[s],
                max_steps, dt, record_every, n, -f_offset[s], out[s],
            )  # fmt: skip
            ok = accuracy <= 0.0
            while not ok and got == n_rec and r_tol * 0.1 >= min_rtol * (1.0 - 1e-9):
                for j in range(n_rec):
                    previous[j] = out[s, 3, j]
                r_tol *= 0.1
                scale = r_tol / rtol  # absolute tolerances follow rtol (same scales)
                a2, r2, got = rodas3_core(
                    sig, dt_s, ramp[s], x0, v0, 0.0, mass[s], k[s], c[s], ki[s], sigma_0[s],
                    sigma_1[s], v_r[s], alpha[s], r_tol, atol_x[s] * scale, atol_v[s] * scale,
                    atol_z[s] * scale, atol_f[s] * scale, max_steps, dt, record_every, n,
                    -f_offset[s], out[s],
                )  # fmt: skip
                accepted += a2
                rejected += r2
                if got == n_rec:
                    acc = 0.0
                    for j in range(n_rec):
                        d = out[s, 3, j] - previous[j]
                        acc += d * d
                    ok = math.sqrt(acc / n_rec) <= 0.5 * accuracy * F_c[s]
            for j in range(got, n_rec):
                for r in range(5):
                    out[s, r, j] = np.nan
            steps[s, 0] = accepted
            steps[s, 1] = rejected
            reached[s] = got
            final_rtol[s] = r_tol
            passed[s] = ok
    return out, steps, reached, final_rtol, passed
