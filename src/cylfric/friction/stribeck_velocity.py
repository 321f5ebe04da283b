"""Velocity of minimum steady-state friction (the thesis' v_Stribeck, Table 4.1)."""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING

import numpy as np

from ._checks import check_parameters

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["stribeck_velocity", "NoStribeckMinimumWarning"]


class NoStribeckMinimumWarning(UserWarning):
    """The steady-state friction curve has no interior minimum (result is NaN)."""


def _slope(speed, dF, v_r, sigma_2, alpha):
    """dF_ss/dv for v > 0 of eq. 2.7 [N*s/m]."""
    u = speed / v_r
    return sigma_2 - dF * alpha / v_r * u ** (alpha - 1.0) * np.exp(-(u**alpha))


def _one(F_c, F_s, v_r, sigma_2, alpha) -> float:
    dF = F_s - F_c
    if dF <= 0 or sigma_2 <= 0:
        return np.nan  # no dip (dF <= 0) or friction falls for ever (sigma_2 = 0)
    # Past the peak of the Stribeck term's steepness, the slope only grows: one root at most.
    start = v_r * ((alpha - 1.0) / alpha) ** (1.0 / alpha) if alpha > 1 else 0.0
    if alpha < 1 and start == 0.0:
        start = v_r * 1e-12  # the slope tends to -inf at 0+
    if _slope(start, dF, v_r, sigma_2, alpha) >= 0:
        return np.nan
    upper = max(start, v_r)
    while _slope(upper, dF, v_r, sigma_2, alpha) <= 0:
        upper *= 2.0
        if upper > 1e9 * v_r:  # pragma: no cover - unreachable for finite inputs
            return np.nan
    from scipy.optimize import brentq  # imported here: importing cylfric stays quick

    return brentq(_slope, start, upper, args=(dF, v_r, sigma_2, alpha), xtol=1e-14 * v_r)


def stribeck_velocity(
    F_c: ArrayLike, F_s: ArrayLike, v_r: ArrayLike, sigma_2: ArrayLike, *, alpha: ArrayLike = 1.0
) -> np.ndarray | float:
    """Velocity of minimum steady-state friction of the Stribeck law (eq. 2.7).

    This is the thesis' v_Stribeck (Table 4.1), which differs from the curve parameter
    ``v_r``. It is the root of ``dF_ss/dv`` past the steepest point of the Stribeck term,
    found by bracketing and Brent's method (robust for any ``alpha > 0``).

    Parameters
    ----------
    F_c, F_s : float or array_like
        Coulomb and stiction levels [N].
    v_r : float or array_like
        Stribeck velocity parameter [m/s].
    sigma_2 : float or array_like
        Viscous coefficient [N*s/m].
    alpha : float or array_like, optional
        Stribeck exponent [-].

    Returns
    -------
    float or ndarray
        Velocity of minimum friction [m/s]; NaN where the curve has no minimum
        (``F_s <= F_c``, ``sigma_2 = 0`` or a viscous slope that dominates everywhere),
        with a :class:`NoStribeckMinimumWarning`.

    Notes
    -----
    For ``alpha = 1`` the closed form is ``v_r ln((F_s - F_c) / (v_r sigma_2))``.

    Examples
    --------
    Thesis Table 4.1, 0 bar, with alpha = 1 and v_r = 10 mm/s:

    >>> round(stribeck_velocity(70.2, 113.0, 0.010, 340.0) * 1000, 1)  # mm/s
    25.3
    """
    check_parameters(F_c=F_c, F_s=F_s, v_r=v_r, sigma_2=sigma_2, alpha=alpha)
    args = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (F_c, F_s, v_r, sigma_2, alpha))
    )
    out = np.array([_one(*vals) for vals in zip(*(a.ravel() for a in args), strict=True)])
    out = out.reshape(args[0].shape)
    if np.isnan(out).any():
        warnings.warn(
            "the steady-state friction curve has no minimum for some parameter sets "
            "(F_s <= F_c, sigma_2 = 0, or the viscous slope dominates); v_Stribeck is NaN there",
            NoStribeckMinimumWarning,
            stacklevel=2,
        )
    return float(out) if out.ndim == 0 else out
