"""scipy ``solve_ivp`` backend: the validation reference, and the path for non-LuGre laws."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.integrate import solve_ivp

from ..friction import get_law, law_params, lugre_force, lugre_unchecked

if TYPE_CHECKING:
    from collections.abc import Mapping
    from typing import Any


def solve_reference(
    time,
    mass,
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
    *,
    rtol: float = 1e-9,
    method: str = "Radau",
):
    """Integrate the plant of :mod:`cylfric.simulate.kernels` with scipy.

    LuGre (eq. 2.5) and Dahl (eq. 2.4) carry their state; static laws (Coulomb, Stribeck,
    stiction with its Karnopp band) are evaluated at the velocity. Returns (states dict,
    friction force on ``time``, info dict).
    """
    law = friction.simulation_law
    dt = time[1] - time[0]

    def at(signal, t):
        return np.interp(t, time, signal)

    def drive(t, x, v, e):
        return k * (at(x_ref, t) - x) + c * (at(v_ref, t) - v) + ki * e + at(f_ext, t)

    def param(name, t):
        value = params[name]
        return at(value, t) if np.ndim(value) else value

    if law == "lugre":
        s0, s1 = params["sigma_0"], params["sigma_1"]

        v_r, alpha = params_const(params, "v_r"), params_const(params, "alpha")
        given = (params["sigma_2"], params["F_c"], params["F_s"])
        lugre_force(0.0, 0.0, s0, s1, *given, v_r, alpha=alpha)  # checks them all once

        def force_of(t, v, z):
            return lugre_unchecked(
                v, z, s0, s1, param("sigma_2", t), param("F_c", t), param("F_s", t), v_r, alpha
            )  # eq. 2.5: (force, dz/dt)
    elif law == "dahl":

        def force_of(t, v, z):
            p = {n: param(n, t) for n in ("F_c", "sigma")}
            return z, get_law("dahl").function(
                v, z, p["F_c"], p["sigma"], exponent=params.get("exponent", 1.0)
            )
    else:
        fn = get_law(law).function

        def force_of(t, v, z):
            p = law_params(law, {n: param(n, t) for n in params})
            if law == "stiction":
                p["external_force"] = drive(t, current[0], v, current[2])
            return fn(v, **p), 0.0

    current = [x0, v0, 0.0]

    # The servo-integral state is carried only when it acts (ki != 0): a state that the
    # right-hand side ignores breaks the finite-difference Jacobian of the implicit solvers.
    with_integral = ki != 0

    def rhs(t, y):
        x, v, z = y[0], y[1], y[2]
        e = y[3] if with_integral else 0.0
        current[:] = [x, v, e]
        force, dz = force_of(t, v, z)
        out = [v, (drive(t, x, v, e) - force) / mass, dz]
        return out + [at(x_ref, t) - x] if with_integral else out

    y0 = [x0, v0, z0] + ([0.0] if with_integral else [])
    atol = [1e-12, 1e-9, 1e-13] + ([1e-12] if with_integral else [])
    sol = solve_ivp(
        rhs,
        (time[0], time[-1]),
        y0,
        method=method,
        t_eval=time,
        rtol=rtol,
        atol=atol,
        max_step=dt * 10,
    )
    if not sol.success:
        raise RuntimeError(f"solve_ivp ({method}) failed: {sol.message}")
    x, v, z = sol.y[:3]
    force = np.array([force_of(t, vi, zi)[0] for t, vi, zi in zip(time, v, z, strict=True)])
    return (
        {"position": x, "velocity": v, "z": z},
        force,
        {"nfev": int(sol.nfev), "backend": f"scipy {method}"},
    )


def params_const(params: Mapping[str, Any], name: str) -> float | np.ndarray:
    value = np.asarray(params[name], dtype=float)
    return float(value.flat[0])


def solve_prescribed_reference(time, velocity, z0, params, *, rtol: float = 1e-10):
    """Radau solution of the LuGre bristle equation along a prescribed velocity record."""
    v_r, alpha = params_const(params, "v_r"), params_const(params, "alpha")
    # every pressure-dependent parameter may vary along the record (a pressure signal)
    sigma_0 = np.broadcast_to(params["sigma_0"], time.shape)
    sigma_1 = np.broadcast_to(params["sigma_1"], time.shape)
    F_c = np.broadcast_to(params["F_c"], time.shape)
    F_s = np.broadcast_to(params["F_s"], time.shape)
    sigma_2 = np.broadcast_to(params["sigma_2"], time.shape)

    dt = time[1] - time[0]

    def decay(t):
        i = min(int(t / dt), time.size - 2)
        w = (t - time[i]) / dt
        v = velocity[i] * (1 - w) + velocity[i + 1] * w
        fc = F_c[i] * (1 - w) + F_c[i + 1] * w
        fs = F_s[i] * (1 - w) + F_s[i + 1] * w
        s0 = sigma_0[i] * (1 - w) + sigma_0[i + 1] * w
        # decay rate s0 |v| / g(v) of eq. 2.5 = v - dz/dt at z = 1 (the unchecked core)
        return v, v - lugre_unchecked(v, 1.0, s0, 0.0, 0.0, fc, fs, v_r, alpha)[1]

    def rhs(t, y):
        v, lam = decay(t)
        return [v - lam * y[0]]

    def jac(t, y):
        return [[-decay(t)[1]]]

    sol = solve_ivp(
        rhs, (time[0], time[-1]), [z0], method="Radau", t_eval=time, rtol=rtol, atol=1e-14, jac=jac
    )
    if not sol.success:
        raise RuntimeError(f"solve_ivp (Radau) failed: {sol.message}")
    z = sol.y[0]
    force = lugre_force(velocity, z, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha=alpha)
    return z, force
