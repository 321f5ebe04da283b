"""Friction laws as pure, vectorised functions (SI units throughout).

Every law takes the velocity first (scalar or ndarray [m/s]) and its parameters as
keywords, so that ``law(v, **params)`` works with a parameter dict. Scalars in give a
float out; arrays broadcast. Velocity > 0 is extension; the returned force is the force
the seals exert *against* the motion, counted positive in the direction of motion, so every
law is odd in velocity and ``F * v >= 0`` (dissipative).

References
----------
.. [1] Pérez Dorado, "Friction, a Limiting Property in Controlled Motion", master thesis,
   Linköping University, 2016, chapter 2 (equation numbers below refer to it).
.. [2] C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, "A new model for control
   of systems with friction", IEEE Trans. Automatic Control 40(3), 1995.
.. [3] P. R. Dahl, "A solid friction model", Aerospace Corp. TOR-0158(3107-18)-1, 1968.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ._checks import as_output, check_parameters, check_signal

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = [
    "coulomb",
    "viscous",
    "stiction",
    "stribeck",
    "stribeck_unchecked",
    "stribeck_shape",
    "stribeck_jacobian",
    "dahl_derivative",
    "lugre_g",
    "lugre_state_derivative",
    "lugre_force",
    "lugre_unchecked",
    "lugre_steady_state",
    "lugre_z_update",
    "barus_viscosity",
    "hersey_number",
]


def coulomb(velocity: ArrayLike, F_c: float | np.ndarray) -> np.ndarray | float:
    """Coulomb (dry) friction, thesis eq. 2.1.

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    F_c : float or array_like
        Coulomb friction level, ``mu * F_N`` [N].

    Returns
    -------
    float or ndarray
        Friction force ``F_c * sign(v)`` [N]; 0 at v = 0.

    Examples
    --------
    >>> coulomb(-0.01, F_c=70.2)
    -70.2
    """
    check_parameters(F_c=F_c)
    v = check_signal("velocity", velocity)
    return as_output(np.sign(v) * F_c, velocity, F_c)  # eq. 2.1


def viscous(velocity: ArrayLike, sigma_2: float | np.ndarray) -> np.ndarray | float:
    """Viscous friction, thesis eq. 2.2 (``gamma`` there, ``sigma_2`` in LuGre).

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    sigma_2 : float or array_like
        Viscous coefficient [N*s/m] (the thesis quotes N*s/mm: multiply by 1000).

    Returns
    -------
    float or ndarray
        ``sigma_2 * v`` [N].
    """
    check_parameters(sigma_2=sigma_2)
    v = check_signal("velocity", velocity)
    return as_output(sigma_2 * v, velocity, sigma_2)  # eq. 2.2


def stiction(
    velocity: ArrayLike,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    *,
    external_force: ArrayLike = 0.0,
    velocity_tolerance: float = 1e-4,
) -> np.ndarray | float:
    """Coulomb friction with stiction and breakaway, thesis eq. 2.3 (Karnopp switch).

    Within the band ``|v| < velocity_tolerance`` the contact is taken as stuck: friction
    balances the external force up to the breakaway level ``F_s``, beyond which it saturates
    at ``F_s * sign(F_e)``. Outside the band it is Coulomb friction ``F_c * sign(v)``.
    The band is the regularisation that makes eq. 2.3 usable in a time-stepping
    simulation (Karnopp 1985): an exact ``v == 0`` is never met by a numerical integrator.

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    F_c : float or array_like
        Coulomb (sliding) friction level [N].
    F_s : float or array_like
        Stiction (breakaway) force [N].
    external_force : float or array_like, optional
        Net external force on the contact ``F_e`` [N] (used only while stuck).
    velocity_tolerance : float, optional
        Half-width of the stuck band [m/s]; default 0.1 mm/s.

    Returns
    -------
    float or ndarray
        Friction force [N], positive in the direction of motion (or of ``F_e`` while stuck).
    """
    check_parameters(F_c=F_c, F_s=F_s, velocity_tolerance=velocity_tolerance)
    v = check_signal("velocity", velocity)
    fe = check_signal("external_force", external_force)
    stuck = np.abs(v) < velocity_tolerance
    held = np.where(np.abs(fe) < F_s, fe, F_s * np.sign(fe))  # eq. 2.3
    force = np.where(stuck, held, np.sign(v) * F_c)
    return as_output(force, velocity, F_c, F_s, external_force)


def stribeck(
    velocity: ArrayLike,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    sigma_2: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """Steady-state friction of the LuGre model with Stribeck effect, thesis eq. 2.7.

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    F_c : float or array_like
        Coulomb friction level [N].
    F_s : float or array_like
        Stiction (breakaway) level, the force at v -> 0 [N].
    v_r : float or array_like
        Stribeck curve velocity parameter [m/s] (not the velocity of minimum friction:
        see :func:`cylfric.friction.stribeck_velocity`).
    sigma_2 : float or array_like
        Viscous coefficient [N*s/m].
    alpha : float or array_like, optional
        Stribeck exponent [-]; the thesis recommends 1.

    Returns
    -------
    float or ndarray
        ``sign(v) * (F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha) + sigma_2 |v|)`` [N].

    Notes
    -----
    At ``v = 0`` the sign makes the force 0; its limit from either side is ``+-F_s``.

    Examples
    --------
    Thesis model at 0 bar (eq. 4.1-4.3) at 25 mm/s:

    >>> round(stribeck(0.025, F_c=70.2, F_s=112.9, v_r=0.010, sigma_2=340.0), 2)
    82.21
    """
    check_parameters(F_c=F_c, F_s=F_s, v_r=v_r, sigma_2=sigma_2, alpha=alpha)
    v = check_signal("velocity", velocity)
    force = stribeck_unchecked(v, F_c, F_s, v_r, sigma_2, alpha=alpha)
    return as_output(force, velocity, F_c, F_s, v_r, sigma_2, alpha)


def stribeck_shape(
    speed: float | np.ndarray, v_r: float | np.ndarray, alpha: float | np.ndarray = 1.0
) -> np.ndarray | float:
    """The Stribeck decay ``exp(-(|v|/v_r)^alpha)`` of g(v), thesis eq. 2.5 [-].

    ``g(v) = F_c + (F_s - F_c) * stribeck_shape(v)``; no parameter checks (callers check).
    """
    return np.exp(-((np.abs(speed) / v_r) ** alpha))


def stribeck_unchecked(
    velocity: ArrayLike,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    sigma_2: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """Eq. 2.7 as :func:`stribeck`, without parameter checks and always as an array.

    For optimisers, whose trial steps may leave the physical range (F_c < 0, ...); every
    other caller uses :func:`stribeck`. Velocity [m/s], forces [N], ``v_r`` [m/s],
    ``sigma_2`` [N*s/m], ``alpha`` [-].
    """
    v = np.asarray(velocity, dtype=float)
    speed = np.abs(v)
    g = F_c + (F_s - F_c) * stribeck_shape(speed, v_r, alpha)  # eq. 2.5, g(v)
    return np.sign(v) * (g + sigma_2 * speed)  # eq. 2.7


def stribeck_jacobian(
    speed: float | np.ndarray,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    sigma_2: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> dict[str, np.ndarray]:
    """Partial derivatives of the friction magnitude of eq. 2.7 at ``speed`` >= 0 [m/s].

    Returns a dict of arrays d|F|/d(parameter): ``F_c`` and ``F_s`` [-], ``v_r`` [N*s/m],
    ``sigma_2`` [m/s], ``alpha`` [N]. For least-squares fits; no parameter checks.
    With ``e`` = :func:`stribeck_shape` and ``r = (speed / v_r) ** alpha``:
    dF/dF_c = 1 - e, dF/dF_s = e, dF/dv_r = (F_s - F_c) e r alpha / v_r,
    dF/dsigma_2 = speed, dF/dalpha = -(F_s - F_c) e r ln(speed / v_r).
    """
    speed = np.abs(np.asarray(speed, dtype=float))
    ratio = speed / v_r
    r = ratio**alpha
    e = np.exp(-r)
    amplitude = (F_s - F_c) * e * r
    with np.errstate(divide="ignore", invalid="ignore"):
        log_ratio = np.where(speed > 0, np.log(np.where(speed > 0, ratio, 1.0)), 0.0)
    return {
        "F_c": 1.0 - e,
        "F_s": e,
        "v_r": amplitude * alpha / v_r,
        "sigma_2": np.asarray(speed),  # already an array: for the type checker
        "alpha": -amplitude * log_ratio,
    }


def dahl_derivative(
    velocity: ArrayLike,
    force: ArrayLike,
    F_c: ArrayLike,
    sigma: float | np.ndarray,
    *,
    exponent: float = 1.0,
) -> np.ndarray | float:
    """Time derivative of the Dahl friction force, thesis eq. 2.4.

    Dahl writes ``dF/dx = sigma (1 - F/F_c sign(v))^i``; along a motion ``dF/dt = dF/dx * v``.
    The power is taken sign-preserving (``|u|^i sign(u)``) so that a force beyond ``F_c``
    relaxes back for any exponent.

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    force : float or array_like
        Current Dahl friction force (the state) [N].
    F_c : float or array_like
        Coulomb friction level, the asymptote of the force [N]; must be > 0.
    sigma : float or array_like
        Rest stiffness, slope of the force-deflection curve at F = 0 [N/m].
    exponent : float, optional
        Shape exponent ``i`` [-] (0 <= i <= 1 brittle, i >= 1 ductile).

    Returns
    -------
    float or ndarray
        ``dF/dt`` [N/s].
    """
    check_parameters(F_c=F_c, sigma=sigma, exponent=exponent)
    if np.any(np.asarray(F_c) == 0):
        raise ValueError("parameter F_c = 0.0 is out of range; expected > 0 N for the Dahl model")
    v = check_signal("velocity", velocity)
    f = check_signal("force", force)
    u = 1.0 - f / F_c * np.sign(v)
    slope = sigma * np.abs(u) ** exponent * np.sign(u)  # eq. 2.4, dF/dx
    return as_output(slope * v, velocity, force, F_c, sigma, exponent)


def lugre_g(
    velocity: ArrayLike,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """LuGre velocity function ``g(v) = F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha)``, eq. 2.5.

    Returns the (even) bristle saturation level [N] at ``velocity`` [m/s].
    """
    check_parameters(F_c=F_c, F_s=F_s, v_r=v_r, alpha=alpha)
    v = check_signal("velocity", velocity)
    g = F_c + (F_s - F_c) * stribeck_shape(v, v_r, alpha)  # eq. 2.5
    return as_output(g, velocity, F_c, F_s, v_r, alpha)


def _check_g_positive(F_c, F_s) -> None:
    if np.any(np.minimum(np.asarray(F_c), np.asarray(F_s)) <= 0):
        raise ValueError(
            "parameters F_c and F_s must both be > 0 N for the dynamic LuGre model "
            "(g(v) divides the bristle deflection)"
        )


def lugre_state_derivative(
    velocity: ArrayLike,
    z: ArrayLike,
    sigma_0: float | np.ndarray,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """Bristle-state derivative of the LuGre model, thesis eq. 2.5.

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    z : float or array_like
        Mean bristle deflection [m].
    sigma_0 : float or array_like
        Bristle stiffness [N/m].
    F_c, F_s : float or array_like
        Coulomb and stiction levels [N] (> 0).
    v_r : float or array_like
        Stribeck velocity parameter [m/s].
    alpha : float, optional
        Stribeck exponent [-].

    Returns
    -------
    float or ndarray
        ``dz/dt = v - sigma_0 |v| z / g(v)`` [m/s].
    """
    check_parameters(sigma_0=sigma_0, F_c=F_c, F_s=F_s, v_r=v_r, alpha=alpha)
    _check_g_positive(F_c, F_s)
    v = check_signal("velocity", velocity)
    zz = check_signal("z", z)
    _, dz = lugre_unchecked(v, zz, sigma_0, 0.0, 0.0, F_c, F_s, v_r, alpha)
    return as_output(dz, velocity, z, sigma_0, F_c, F_s, v_r, alpha)


def lugre_unchecked(
    velocity: float | np.ndarray,
    z: float | np.ndarray,
    sigma_0: float | np.ndarray,
    sigma_1: float | np.ndarray,
    sigma_2: float | np.ndarray,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    alpha: float | np.ndarray = 1.0,
) -> tuple[np.ndarray | float, np.ndarray | float]:
    """LuGre force and bristle rate (eq. 2.5) without parameter checks: (force [N], dz/dt [m/s]).

    For integrators that call it at every step after checking the parameters once; every
    other caller uses :func:`lugre_force` or :func:`lugre_state_derivative`. Works on
    scalars (Python floats) and arrays alike.
    """
    g = F_c + (F_s - F_c) * stribeck_shape(velocity, v_r, alpha)  # eq. 2.5, g(v)
    dz = velocity - sigma_0 * abs(velocity) * z / g  # type: ignore[operator]  # eq. 2.5
    return sigma_0 * z + sigma_1 * dz + sigma_2 * velocity, dz


def lugre_force(
    velocity: ArrayLike,
    z: ArrayLike,
    sigma_0: float | np.ndarray,
    sigma_1: float | np.ndarray,
    sigma_2: float | np.ndarray,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """LuGre friction force ``sigma_0 z + sigma_1 dz/dt + sigma_2 v``, thesis eq. 2.5.

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    z : float or array_like
        Mean bristle deflection [m].
    sigma_0 : float or array_like
        Bristle stiffness [N/m].
    sigma_1 : float or array_like
        Bristle damping [N*s/m].
    sigma_2 : float or array_like
        Viscous coefficient [N*s/m].
    F_c, F_s : float or array_like
        Coulomb and stiction levels [N].
    v_r : float or array_like
        Stribeck velocity parameter [m/s].
    alpha : float, optional
        Stribeck exponent [-].

    Returns
    -------
    float or ndarray
        Friction force [N], positive in the direction of motion.
    """
    check_parameters(sigma_0=sigma_0, sigma_1=sigma_1, sigma_2=sigma_2, F_c=F_c, F_s=F_s)
    check_parameters(v_r=v_r, alpha=alpha)
    _check_g_positive(F_c, F_s)
    v = check_signal("velocity", velocity)
    zz = check_signal("z", z)
    force, _ = lugre_unchecked(v, zz, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha)
    return as_output(force, velocity, z, sigma_0, sigma_1, sigma_2, F_c, F_s, v_r, alpha)


def lugre_steady_state(
    velocity: float | np.ndarray,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    sigma_2: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """Steady-state LuGre force, thesis eq. 2.6/2.7 (identical to :func:`stribeck`).

    At constant velocity ``dz/dt = 0`` gives ``z_ss = sign(v) g(v) / sigma_0`` and the
    force ``g(v) sign(v) + sigma_2 v``; sigma_0 and sigma_1 drop out.
    """
    return stribeck(velocity, F_c, F_s, v_r, sigma_2, alpha=alpha)


def lugre_z_update(
    z: ArrayLike,
    velocity: ArrayLike,
    step: float | np.ndarray,
    sigma_0: float | np.ndarray,
    F_c: float | np.ndarray,
    F_s: float | np.ndarray,
    v_r: float | np.ndarray,
    *,
    alpha: float | np.ndarray = 1.0,
) -> np.ndarray | float:
    """Exact LuGre bristle update over a step at constant velocity.

    For constant ``v`` over a step ``h`` the bristle equation (eq. 2.5) is linear in z:

        z(h) = z_ss + (z(0) - z_ss) exp(-sigma_0 |v| h / g(v)),  z_ss = sign(v) g(v) / sigma_0

    The decay factor lies in [0, 1] for any ``sigma_0`` and ``h``, so the update is
    unconditionally stable and keeps ``|z| <= max(F_s, F_c) / sigma_0`` when it starts there.

    Parameters
    ----------
    z : float or array_like
        Bristle deflection at the start of the step [m].
    velocity : float or array_like
        Velocity held over the step [m/s].
    step : float or array_like
        Step length ``h`` [s], >= 0.
    sigma_0 : float or array_like
        Bristle stiffness [N/m].
    F_c, F_s : float or array_like
        Coulomb and stiction levels [N] (> 0).
    v_r : float or array_like
        Stribeck velocity parameter [m/s].
    alpha : float, optional
        Stribeck exponent [-].

    Returns
    -------
    float or ndarray
        Bristle deflection at the end of the step [m].
    """
    check_parameters(sigma_0=sigma_0, step=step)
    _check_g_positive(F_c, F_s)
    g = lugre_g(velocity, F_c, F_s, v_r, alpha=alpha)
    v = np.asarray(velocity, dtype=float)
    z0 = check_signal("z", z)
    z_ss = np.sign(v) * g / sigma_0
    decay = np.exp(-sigma_0 * np.abs(v) * step / g)
    return as_output(z_ss + (z0 - z_ss) * decay, z, velocity, step, sigma_0, F_c, F_s, v_r)


def barus_viscosity(
    pressure: ArrayLike, viscosity_0: float, pressure_coefficient: float
) -> np.ndarray | float:
    """Barus isothermal pressure-viscosity law ``mu = mu_0 exp(alpha_p p)``, thesis eq. 2.9.

    Parameters
    ----------
    pressure : float or array_like
        Pressure [Pa].
    viscosity_0 : float
        Dynamic viscosity at p = 0 [Pa*s].
    pressure_coefficient : float
        Pressure-viscosity coefficient [1/Pa] (m^2/N); mineral oils 18e-9 to 28e-9.

    Returns
    -------
    float or ndarray
        Dynamic viscosity [Pa*s].

    Examples
    --------
    >>> round(barus_viscosity(159e5, 0.046, 20e-9) / 0.046, 3)  # +37 % at 159 bar
    1.374
    """
    check_parameters(viscosity_0=viscosity_0, pressure_coefficient=pressure_coefficient)
    p = check_signal("pressure", pressure)
    return as_output(viscosity_0 * np.exp(pressure_coefficient * p), pressure)  # eq. 2.9


def hersey_number(
    velocity: ArrayLike, viscosity: float | np.ndarray, load_per_length: float | np.ndarray
) -> np.ndarray | float:
    """Hersey number ``|v| mu / (F_N / L)``, thesis eq. 2.8 (dimensionless).

    Parameters
    ----------
    velocity : float or array_like
        Sliding velocity [m/s].
    viscosity : float or array_like
        Dynamic viscosity of the lubricant [Pa*s].
    load_per_length : float or array_like
        Normal load per unit length of the contact [N/m].

    Returns
    -------
    float or ndarray
        Hersey number [-].
    """
    check_parameters(load_per_length=load_per_length, viscosity=viscosity)
    v = check_signal("velocity", velocity)
    return as_output(np.abs(v) * viscosity / load_per_length, velocity, viscosity)  # eq. 2.8
