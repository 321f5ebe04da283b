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
    if alpha == 2.0:  # Gaussian Stribeck curve: u*u is exact and avoids pow
        return F_c + (F_s - F_c) * math.exp(-(u * u))
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
    """DOPRI5's right-hand side: the plant (:func:`_plant`) without a ramp; returns the
    friction force (eq. 2.5) [N]."""
    return _plant(
        t,
        y,
        out,
        dt,
        0.0,
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
        s0,
        s1,
        v_r,
        alpha,
    )


@njit(cache=True)
def _record(
    out_y, friction, reached, accepted, rejected, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha
):
    """The integrators' result: states on the output grid (NaN past ``reached``), the friction
    force there (eq. 2.5; outputs lie on the input grid, no interpolation) [N], step counts."""
    n = out_y.shape[0]
    for i in range(reached, n):
        out_y[i] = np.nan
    for i in range(n):
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
        reached,
    )


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
    return _record(
        out_y,
        friction,
        next_out,
        accepted,
        rejected,
        sigma_0,
        sigma_1,
        sigma_2,
        F_c,
        F_s,
        v_r,
        alpha,
    )


# ------------------------------------------------ adaptive Rosenbrock (Rodas3 / Rodas4), L-stable
#
# A Rosenbrock method solves one linear system per stage with the exact Jacobian instead of
# Newton iterations: stiff bristles (sigma_0 up to 1e10 N/m) cost no smaller steps, because the
# methods are L-stable and stiffly accurate. KPP form (Sandu et al. 1997; Hairer & Wanner 1996,
# section IV.7), with G = 1/(h gamma) - J(t_n, y_n):
#     Y_i = y_n + sum_j A_ij K_j,   G K_i = f(t_n + alpha_i h, Y_i) + sum_j C_ij / h K_j
#                                           + h gamma_i df/dt(t_n, y_n)
#     y_n+1 = y_n + sum_j M_j K_j,   error = sum_j E_j K_j
# Between steps the states are interpolated on the output grid by cubic Hermite polynomials
# through (y_n, f_n) and (y_n+1, f_n+1) (f_n+1 is the next step's first stage anyway), except
# velocity and z on stiff steps: their slopes carry the stiff error, so they go linearly.

RODAS3 = (  # Sandu et al. 1997, "Benchmarking stiff ODE solvers for atmospheric chemistry II"
    0.5,
    np.array([[0, 0, 0, 0], [0, 0, 0, 0], [2, 0, 0, 0], [2, 0, 1, 0]], dtype=np.float64),
    np.array([[0, 0, 0, 0], [4, 0, 0, 0], [1, -1, 0, 0], [1, -1, -8 / 3, 0]], dtype=np.float64),
    np.array([2.0, 0.0, 1.0, 1.0]),
    np.array([0.0, 0.0, 0.0, 1.0]),
    np.array([0.0, 0.0, 1.0, 1.0]),
    np.array([0.5, 1.5, 0.0, 0.0]),
    3.0,
)
_R4A = (1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950)
RODAS4 = (  # Hairer & Wanner 1996, RODAS (order 4(3), 6 stages), in the KPP form
    0.25,
    np.array(
        [
            [0, 0, 0, 0, 0, 0],
            [1.544, 0, 0, 0, 0, 0],
            [0.9466785280815826, 0.2557011698983284, 0, 0, 0, 0],
            [3.314825187068521, 2.896124015972201, 0.9986419139977817, 0, 0, 0],
            [*_R4A, 0, 0],
            [*_R4A, 1.0, 0],
        ],
        dtype=np.float64,
    ),
    np.array(
        [
            [0, 0, 0, 0, 0, 0],
            [-5.6688, 0, 0, 0, 0, 0],
            [-2.430093356833875, -0.2063599157091915, 0, 0, 0, 0],
            [-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0, 0, 0],
            [7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0, 0],
            [
                8.083246795921522,
                -7.981132988064893,
                -31.52159432874371,
                16.31930543123136,
                -6.058818238834054,
                0,
            ],
        ],
        dtype=np.float64,
    ),
    np.array([*_R4A, 1.0, 1.0]),
    np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1.0]),
    np.array([0.0, 0.386, 0.21, 0.63, 1.0, 1.0]),
    np.array([0.25, -0.1043, 0.1035, -0.0362, 0.0, 0.0]),
    4.0,
)
ROSENBROCK_TABLES = {"rodas3": RODAS3, "rodas4": RODAS4}


@njit(cache=True, inline="always")
def lugre_partials(v, z, sigma_0, F_c, F_s, v_r, alpha):
    """Partial derivatives of dz/dt = v - sigma_0 |v| z / g(v) (eq. 2.5).

    Returns ``(d/dv, d/dz, d/dF_c, d/dF_s)`` of dz/dt, with dg/d|v| from eq. 2.5's
    g(v) = F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha). At v = 0 the one-sided slope for v > 0
    is used (the velocity term then vanishes for alpha > 1).
    """
    speed = abs(v)
    u = speed / v_r
    if u == 0.0:
        decay = 1.0
        slope_u = 1.0 if alpha == 1.0 else (0.0 if alpha > 1.0 else 1e300)
    elif alpha == 1.0:
        decay = math.exp(-u)
        slope_u = 1.0
    else:
        ua = u**alpha
        decay = math.exp(-ua)
        slope_u = alpha * ua / u
    g = F_c + (F_s - F_c) * decay
    dg = -(F_s - F_c) * decay * slope_u / v_r  # dg/d|v|
    sign = 1.0 if v >= 0.0 else -1.0
    d_v = 1.0 - sigma_0 * z * sign * (g - speed * dg) / (g * g)
    d_z = -sigma_0 * speed / g
    d_g = sigma_0 * speed * z / (g * g)  # d(dz/dt)/dg
    return d_v, d_z, d_g * (1.0 - decay), d_g * decay


@njit(cache=True, inline="always")
def _inputs(t, dt, ramp, x_ref, v_ref, f_ext, F_c, F_s, sigma_2):
    """Inputs at t (linear between grid points) and their slopes on that interval."""
    n = x_ref.shape[0]
    pos = t / dt
    if pos <= 0.0:
        i, w = 0, 0.0
    elif pos >= n - 1:
        i, w = n - 2, 1.0
    else:
        i = int(pos)
        w = pos - i
    dxr = x_ref[i + 1] - x_ref[i]
    dvr = v_ref[i + 1] - v_ref[i]
    dfe = f_ext[i + 1] - f_ext[i]
    dfc = F_c[i + 1] - F_c[i]
    dfs = F_s[i + 1] - F_s[i]
    ds2 = sigma_2[i + 1] - sigma_2[i]
    return (
        x_ref[i] + w * dxr + ramp * t,
        v_ref[i] + w * dvr + ramp,
        f_ext[i] + w * dfe,
        F_c[i] + w * dfc,
        F_s[i] + w * dfs,
        sigma_2[i] + w * ds2,
        dxr / dt + ramp,
        dvr / dt,
        dfe / dt,
        dfc / dt,
        dfs / dt,
        ds2 / dt,
    )


@njit(cache=True, inline="always")
def _plant(
    t, y, out, dt, ramp, mass, k, c, ki, x_ref, v_ref, f_ext, F_c, F_s, sigma_2, s0, s1, v_r, alpha
):
    """Right-hand side of the plant; returns the friction force (eq. 2.5) [N]."""
    xr, vr, fe, fc, fs, s2, _, _, _, _, _, _ = _inputs(
        t, dt, ramp, x_ref, v_ref, f_ext, F_c, F_s, sigma_2
    )
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
def rosenbrock_core(
    dt,
    ramp,
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
    s0,
    s1,
    v_r,
    alpha,
    rtol,
    atol_x,
    atol_v,
    atol_z,
    atol_f,
    max_steps,
    h_max,
    tables,
    out_y,
):
    """Adaptive Rosenbrock integration of the plant; states written to ``out_y`` (n, 4).

    ``ramp`` [m/s] adds ``ramp * t`` to ``x_ref`` and ``ramp`` to ``v_ref`` (a spring pulled
    at constant speed needs no signal arrays of its own). ``tables`` is :data:`RODAS3` or
    :data:`RODAS4`. Returns (accepted, rejected, grid points reached).
    """
    gamma, A, C, M, E, ALPHA, GAMMA, order = tables
    stages = M.shape[0]
    n = x_ref.shape[0]
    t_end = dt * (n - 1)
    y = np.array([x0, v0, z0, 0.0])
    atol = np.array([atol_x, atol_v, atol_z, atol_x * max(t_end, 1.0)])
    K = np.zeros((stages, 4))
    stage = np.empty(4)
    f_stage = np.empty(4)
    rhs_ = np.empty(4)
    y_new = np.empty(4)
    f0 = np.empty(4)
    f1 = np.empty(4)
    _plant(
        0.0,
        y,
        f0,
        dt,
        ramp,
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
        s0,
        s1,
        v_r,
        alpha,
    )
    out_y[0, :] = y
    t = 0.0
    h = min(dt, 1e-5)
    next_out = 1
    accepted = 0
    rejected = 0
    exponent = -1.0 / order
    reuse = np.zeros(stages, dtype=np.bool_)  # stage evaluates f(t_n, y_n) again: reuse f0
    for s in range(stages):
        reuse[s] = s == 0 or (ALPHA[s] == 0.0 and not np.any(A[s] != 0.0))
    while next_out < n and accepted + rejected < max_steps:
        h = min(h, h_max)
        if t + h > t_end:
            h = t_end - t
        # exact Jacobian and time derivative at (t_n, y_n)
        xr, vr, fe, fc, fs, s2, sxr, svr, sfe, sfc, sfs, ss2 = _inputs(
            t, dt, ramp, x_ref, v_ref, f_ext, F_c, F_s, sigma_2
        )
        v, z = y[1], y[2]
        d_v, d_z, d_fc, d_fs = lugre_partials(v, z, s0, fc, fs, v_r, alpha)
        f_v = s1 * d_v + s2  # dF/dv
        f_z = s0 + s1 * d_z  # dF/dz
        # Breakaway guards. An implicit step damps growing modes it steps over, and a stuck
        # contact shows no error until it breaks loose, so (1) while the drive loads the
        # contact towards the slip limit g(v), a step covers at most half the force margin at
        # the present loading rate (the threshold is approached geometrically, like an event
        # location); (2) a growing mode of the (v, z) block (breakaway under way) limits h to
        # 1/(its rate).
        load = k * (xr - y[0]) + c * (vr - v) + ki * y[3] + fe
        rate = k * (sxr - v) + c * svr + sfe + ki * (xr - y[0])
        if load * rate > 0.0:
            margin = g_function(abs(v), fc, fs, v_r, alpha) - abs(load)
            if margin > 0.0:
                h = min(h, max(0.5 * margin / abs(rate), 1e-3 * dt))
        # (3) a slip that decelerates towards v = 0 (where |v| makes the Jacobian jump) is
        # followed to the sticking instant geometrically too
        if v * f0[1] < 0.0 and abs(v) > 1e-3 * v_r:
            h = min(h, max(0.5 * abs(v / f0[1]), 1e-3 * dt))
        trace = -(c + f_v) / mass + d_z
        det = -(c + f_v) / mass * d_z + f_z * d_v / mass
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
        ft_v = (k * sxr + c * svr + sfe - s1 * dzdt_t - v * ss2) / mass
        # G = 1/(h gamma) I - J, solved in closed form (x, e eliminated; z by its own row)
        gi = 1.0 / (h * gamma)
        a_ = k / mass
        b_ = (c + f_v) / mass
        cz = f_z / mass
        d_ = ki / mass
        inv_g = 1.0 / gi
        inv_gz = 1.0 / (gi - d_z)
        inv_den = 1.0 / (a_ * inv_g + gi + b_ + cz * d_v * inv_gz + d_ * inv_g * inv_g)
        for s in range(stages):
            if reuse[s]:
                f_stage[:] = f0  # Rodas3's second stage re-uses f(t_n, y_n)
            else:
                for q in range(4):
                    acc = 0.0
                    for j in range(s):
                        acc += A[s, j] * K[j, q]
                    stage[q] = y[q] + acc
                _plant(
                    t + ALPHA[s] * h,
                    stage,
                    f_stage,
                    dt,
                    ramp,
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
                    s0,
                    s1,
                    v_r,
                    alpha,
                )
            for q in range(4):
                acc = 0.0
                for j in range(s):
                    acc += C[s, j] * K[j, q]
                rhs_[q] = f_stage[q] + acc / h
            hg = h * GAMMA[s]
            rx = rhs_[0]
            rv = rhs_[1] + hg * ft_v
            rz = rhs_[2] + hg * dzdt_t
            re = rhs_[3] + hg * sxr
            kv = (
                rv - a_ * rx * inv_g - cz * rz * inv_gz + d_ * re * inv_g - d_ * rx * inv_g * inv_g
            ) * inv_den
            kx = (rx + kv) * inv_g
            K[s, 0] = kx
            K[s, 1] = kv
            K[s, 2] = (rz + d_v * kv) * inv_gz
            K[s, 3] = (re - kx) * inv_g
        err = 0.0
        err_f = 0.0
        for q in range(4):
            acc_m = 0.0
            acc_e = 0.0
            for j in range(stages):
                acc_m += M[j] * K[j, q]
                acc_e += E[j] * K[j, q]
            y_new[q] = y[q] + acc_m
            scale = atol[q] + rtol * max(abs(y[q]), abs(y_new[q]))
            err += (acc_e / scale) ** 2
            if q == 1:
                err_f += f_v * acc_e
            elif q == 2:
                err_f += f_z * acc_e
        # the friction force is what users read: its error (linearised) is controlled too
        force_n = s0 * z + s1 * f0[2] + s2 * v
        err += (err_f / (atol_f + rtol * abs(force_n))) ** 2
        err = math.sqrt(err / 5)
        if err <= 1.0 and math.isfinite(err):
            t_new = t + h
            _plant(
                t_new,
                y_new,
                f1,
                dt,
                ramp,
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
                s0,
                s1,
                v_r,
                alpha,
            )
            while next_out < n and next_out * dt <= t_new + 1e-12 * dt:
                theta = (next_out * dt - t) / h
                t2 = theta * theta
                t3 = t2 * theta
                h00 = 2 * t3 - 3 * t2 + 1
                h10 = (t3 - 2 * t2 + theta) * h
                h01 = 3 * t2 - 2 * t3
                h11 = (t3 - t2) * h
                for q in range(4):
                    if stiff and (q == 1 or q == 2):  # slopes of stiff states carry their error
                        out_y[next_out, q] = y[q] + theta * (y_new[q] - y[q])
                    else:
                        out_y[next_out, q] = h00 * y[q] + h10 * f0[q] + h01 * y_new[q] + h11 * f1[q]
                next_out += 1
            t = t_new
            y[:] = y_new
            f0[:] = f1
            accepted += 1
            factor = min(6.0, 0.9 * max(err, 1e-10) ** exponent)
        else:
            rejected += 1
            factor = 0.2 if not math.isfinite(err) else max(0.2, 0.9 * err**exponent)
        h *= factor
    return accepted, rejected, next_out


@njit(cache=True)
def rosenbrock(
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
    atol_f,
    max_steps,
    h_max,
    tables,
):
    """Adaptive L-stable Rosenbrock integration with output on the input grid.

    Returns position [m], velocity [m/s], z [m], friction [N] (eq. 2.5) on the grid, the
    numbers of accepted and rejected steps, and how many grid points were reached.
    """
    n = x_ref.shape[0]
    out_y = np.empty((n, 4))
    accepted, rejected, reached = rosenbrock_core(
        dt,
        0.0,
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
        atol_f,
        max_steps,
        h_max,
        tables,
        out_y,
    )
    return _record(
        out_y,
        np.empty(n),
        reached,
        accepted,
        rejected,
        sigma_0,
        sigma_1,
        sigma_2,
        F_c,
        F_s,
        v_r,
        alpha,
    )


@njit(cache=True, parallel=True)
def rosenbrock_batch(
    dt,
    record_every,
    x0,
    v0,
    rows,
    ramp,
    mass,
    k,
    c,
    ki,
    f_offset,
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
    atol_f,
    max_steps,
    tables,
    chunks,
):
    """Many heterogeneous sets with the Rosenbrock kernel (``prange``: all cores).

    Per-set values are 1-D arrays of length ``n_sets``: drive (``ramp`` [m/s], ``mass`` [kg],
    ``k``, ``c``, ``ki``, ``f_offset`` [N] added to the drive force), friction and absolute
    tolerances. ``rows[s]`` picks the set's input signals from the (n_signals, n) arrays
    ``x_ref``, ``v_ref``, ``f_ext``. Returns the states (n_sets, n_records, 4) every
    ``record_every`` grid points, step counts (n_sets, 2) and grid points reached.
    ``chunks`` work packages share the sets (a few per thread).
    """
    n_sets = F_c.shape[0]
    n = x_ref.shape[1]
    n_rec = (n - 1) // record_every + 1
    states = np.empty((n_sets, n_rec, 4))
    steps = np.empty((n_sets, 2), dtype=np.int64)
    reached = np.empty(n_sets, dtype=np.int64)
    # sets go in chunks, each with its own work arrays allocated once (allocating per set
    # serialises the threads on the allocator)
    n_chunks = max(1, min(n_sets, chunks))
    for chunk in prange(n_chunks):
        out_y = np.empty((n, 4))
        fe = np.empty(n)
        fc = np.empty(n)
        fs = np.empty(n)
        s2 = np.empty(n)
        for s in range(chunk * n_sets // n_chunks, (chunk + 1) * n_sets // n_chunks):
            row = rows[s]
            for i in range(n):
                fe[i] = f_ext[row, i] + f_offset[s]
            fc[:] = F_c[s]
            fs[:] = F_s[s]
            s2[:] = sigma_2[s]
            accepted, rejected, got = rosenbrock_core(
                dt, ramp[s], x0, v0, 0.0, mass[s], k[s], c[s], ki[s], x_ref[row], v_ref[row],
                fe, fc, fs, s2, sigma_0[s], sigma_1[s], v_r[s], alpha[s], rtol, atol_x[s],
                atol_v[s], atol_z[s], atol_f[s], max_steps, math.inf, tables, out_y,
            )  # fmt: skip
            for r in range(n_rec):
                for q in range(4):
                    states[s, r, q] = (
                        out_y[r * record_every, q] if r * record_every < got else np.nan
                    )
            steps[s, 0] = accepted
            steps[s, 1] = rejected
            reached[s] = got
    return states, steps, reached


@njit(cache=True)
def lugre_instant_array(v, z, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha):
    """:func:`lugre_instant` over (n_sets, n) arrays; parameters are (n_sets, 1) columns [N]."""
    out = np.empty(v.shape)
    for s in range(v.shape[0]):
        for i in range(v.shape[1]):
            out[s, i] = lugre_instant(
                v[s, i],
                z[s, i],
                sigma_0[s, 0],
                sigma_1[s, 0],
                sigma_2[s, 0],
                F_c[s, 0],
                F_s[s, 0],
                v_r[s, 0],
                alpha[s, 0],
            )
    return out
