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
def g_function(speed, F_c, F_s, v_r, alpha):
    """g(v) of eq. 2.5 for ``speed = |v|`` [N]."""
    u = speed / v_r
    if alpha == 1.0:
        return F_c + (F_s - F_c) * math.exp(-u)
    return F_c + (F_s - F_c) * math.exp(-(u**alpha))


@njit(cache=True, inline="always")
def z_step(z0, v, h, sigma_0, F_c, F_s, v_r, alpha):
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
def lugre_instant(v, z, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha):
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


@njit(cache=True, inline="always")
def _rhs(t, y, out, dt, mass, k, c, ki, x_ref, v_ref, f_ext, F_c, F_s, sigma_2, s0, s1, v_r, alpha):
    n = x_ref.shape[0]
    pos = t / dt
    if pos <= 0.0:
        i, w = 0, 0.0
    elif pos >= n - 1:
        i, w = n - 2, 1.0
    else:
        i = int(pos)
        w = pos - i
    xr = x_ref[i] + w * (x_ref[i + 1] - x_ref[i])  # one index and weight for all inputs
    vr = v_ref[i] + w * (v_ref[i + 1] - v_ref[i])
    fe = f_ext[i] + w * (f_ext[i + 1] - f_ext[i])
    fc = F_c[i] + w * (F_c[i + 1] - F_c[i])
    fs = F_s[i] + w * (F_s[i + 1] - F_s[i])
    s2 = sigma_2[i] + w * (sigma_2[i + 1] - sigma_2[i])
    x, v, z, e = y[0], y[1], y[2], y[3]
    g = g_function(abs(v), fc, fs, v_r, alpha)
    dz = v - s0 * abs(v) * z / g
    friction = s0 * z + s1 * dz + s2 * v
    out[0] = v
    out[1] = (k * (xr - x) + c * (vr - v) + ki * e + fe - friction) / mass
    out[2] = dz
    out[3] = xr - x
    return friction


@njit(cache=True)
def dopri(
    dt,
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
    rtol,
    atol_x,
    atol_v,
    atol_z,
    max_steps,
):
    """Adaptive Dormand-Prince 5(4) with dense output on the input grid.

    Absolute tolerances per state: position [m], velocity [m/s], z [m]; the servo integral
    state shares the position tolerance times the duration. Returns position, velocity, z,
    friction [N] on the grid, the numbers of accepted and rejected steps, and how many grid
    points were reached (fewer than the grid when ``max_steps`` ran out).
    """
    n = x_ref.shape[0]
    t_end = dt * (n - 1)
    out_y = np.empty((n, 4))
    friction = np.empty(n)
    y = np.array([x0, v0, z0, 0.0])
    atol = np.array([atol_x, atol_v, atol_z, atol_x * max(t_end, 1.0)])
    K = np.empty((7, 4))
    Q = np.empty((4, 4))
    tmp = np.empty(4)
    y_new = np.empty(4)
    f0 = np.empty(4)
    _rhs(
        0.0,
        y,
        f0,
        dt,
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
    )
    out_y[0] = y
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
            _rhs(
                t + _C[s] * h,
                tmp,
                K[s],
                dt,
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
            )
        for q in range(4):
            acc = 0.0
            for r in range(6):
                acc += _B[r] * K[r, q]
            y_new[q] = y[q] + h * acc
        _rhs(
            t + h,
            y_new,
            K[6],
            dt,
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
                theta = (next_out * dt - t) / h
                for q in range(4):
                    out_y[next_out, q] = y[q] + h * theta * (
                        Q[q, 0] + theta * (Q[q, 1] + theta * (Q[q, 2] + theta * Q[q, 3]))
                    )
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
    for i in range(next_out, n):
        out_y[i] = np.nan
    for i in range(n):  # outputs lie on the input grid: no interpolation needed
        friction[i] = lugre_instant(
            out_y[i, 1], out_y[i, 2], sigma_0, sigma_1, sigma_2[i], F_c[i], F_s[i], v_r, alpha
        )
    return (
        out_y[:, 0].copy(),
        out_y[:, 1].copy(),
        out_y[:, 2].copy(),
        friction,
        accepted,
        rejected,
        next_out,
    )


@njit(cache=True, parallel=True)
def dopri_batch(
    dt,
    record_every,
    x0,
    v0,
    mass,
    k,
    c,
    ki,
    x_ref,
    v_ref,
    f_ext,
    f_offset,
    F_c,
    F_s,
    sigma_2,
    sigma_0,
    sigma_1,
    v_r,
    alpha,
    rtol,
    max_steps,
):
    """Many parameter sets with the adaptive Dormand-Prince kernel (``prange``, both cores).

    Per-set parameters are 1-D arrays of length ``n_sets``, ``f_offset`` a constant force
    added to the shared ``f_ext`` per set [N] (e.g. the net pressure force). Returns
    position [m] and friction force [N] every ``record_every`` grid points, as
    (n_sets, n_records) arrays, and the number of grid points each set reached (all of them
    unless ``max_steps`` ran out).
    """
    n_sets = F_c.shape[0]
    n = x_ref.shape[0]
    n_rec = (n - 1) // record_every + 1
    positions = np.empty((n_sets, n_rec))
    frictions = np.empty((n_sets, n_rec))
    reached = np.empty(n_sets, dtype=np.int64)
    for s in prange(n_sets):
        fc = np.full(n, F_c[s])
        fs = np.full(n, F_s[s])
        s2 = np.full(n, sigma_2[s])
        fe = f_ext + f_offset[s]
        pos, _, _, force, _, _, got = dopri(
            dt,
            x0,
            v0,
            0.0,
            mass,
            k,
            c,
            ki,
            x_ref,
            v_ref,
            fe,
            fc,
            fs,
            s2,
            sigma_0[s],
            sigma_1[s],
            v_r[s],
            alpha[s],
            rtol,
            1e-12,
            1e-9,
            1e-13,
            max_steps,
        )
        for r in range(n_rec):
            positions[s, r] = pos[r * record_every]
            frictions[s, r] = force[r * record_every]
        reached[s] = got
    return positions, frictions, reached
