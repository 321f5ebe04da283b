"""The table-driven Rosenbrock kernel that chose the scheme (benchmarks only): Rodas3 and
Rodas4 from their coefficient tables, with the step guards and output of
``cylfric.simulate.kernels.rodas3_core`` (which is Rodas3 written out for speed).

Used by ``python benchmarks/run.py candidates`` (bench_stiff.bench_candidates). Input signals are
arrays on the output grid. Not compiled into the package: numba compiles it on first use.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cylfric.simulate.kernels import g_function, lugre_instant, lugre_partials


@njit(cache=False)
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


@njit(cache=False, inline="always")
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


@njit(cache=False, inline="always")
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


@njit(cache=False)
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


@njit(cache=False)
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
