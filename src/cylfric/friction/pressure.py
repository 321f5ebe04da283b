"""Pressure laws: operating point -> friction parameter dict (the calcparams pattern).

Friction laws know nothing about pressure. A pressure law maps the chamber pressure(s) to
the keyword parameters of a friction law, so the pressure-dependent model is a composition::

    stribeck(v, **params_at_pressure(p, THESIS_2016.coefficients))

A *coefficient set* is a dict whose keys are friction-parameter names; each value is either a
constant (float, SI) or a dict of the coefficients of a scalar pressure law, e.g.
``{"F_c": {"intercept": 70.2, "slope": 0.5e-5}, "v_r": 0.010, "alpha": 1.0}`` for the thesis'
linear law (eq. 2.10, 4.1-4.3). Which chamber pressure a law sees is the explicit
``reference`` argument of :func:`operating_pressure`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ._checks import check_signal

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = [
    "PRESSURE_LAWS",
    "PRESSURE_LAW_COEFFICIENTS",
    "constant",
    "PRESSURE_REFERENCES",
    "CYLINDER_ACTION",
    "DEFAULT_PRESSURE_REFERENCE",
    "REFERENCE_CHAMBERS",
    "pressure_reference_basis",
    "linear",
    "quadratic",
    "exponential",
    "operating_pressure",
    "params_at_pressure",
    "simscape_cylinder_friction",
]


def constant(pressure: ArrayLike, intercept: float) -> np.ndarray:
    """Pressure-independent value ``a`` (broadcast to the shape of ``pressure``).

    Parameters
    ----------
    pressure : float or array_like
        Operating pressure [Pa] (sets only the shape of the result).
    intercept : float
        The value [unit of the parameter].
    """
    return intercept + 0.0 * np.asarray(pressure, dtype=float)


def linear(pressure: ArrayLike, intercept: float, slope: float) -> np.ndarray:
    """Linear pressure law ``a + b p`` (thesis eq. 2.10 and 4.1-4.3).

    Parameters
    ----------
    pressure : float or array_like
        Operating pressure [Pa].
    intercept : float
        Value at p = 0 [unit of the parameter].
    slope : float
        Rise per pascal [unit/Pa] (thesis N/bar: divide by 1e5).
    """
    return intercept + slope * np.asarray(pressure, dtype=float)


def quadratic(pressure: ArrayLike, intercept: float, slope: float, curvature: float) -> np.ndarray:
    """Quadratic pressure law ``a + b p + c p^2``; ``curvature`` in [unit/Pa^2]."""
    p = np.asarray(pressure, dtype=float)
    return intercept + slope * p + curvature * p * p


def exponential(pressure: ArrayLike, intercept: float, amplitude: float, rate: float) -> np.ndarray:
    """Exponential pressure law ``a + b (exp(c p) - 1)``.

    The form the composite-seal (Bosch Rexroth) data of thesis ch. 2 suggested. The value at
    p = 0 is ``intercept``, the initial slope ``amplitude * rate``; it tends to the linear law
    as ``rate -> 0``. ``rate`` in [1/Pa], ``amplitude`` in the unit of the parameter.
    """
    return exponential_by_slope(pressure, intercept, amplitude * rate, rate)


MIN_RATE = 1e-14
"""Smallest ``|rate|`` [1/Pa] of the exponential law; below it the law is the linear law."""


def exponential_by_slope(
    pressure: ArrayLike, intercept: float, initial_slope: float, rate: float
) -> np.ndarray:
    """The exponential law by its initial slope: ``a + s (exp(c p) - 1) / c``.

    The same law as :func:`exponential` with ``amplitude = s / c``, written so that it stays
    well posed as ``rate -> 0`` (where it becomes the linear law ``a + s p``): the form fits
    use. ``initial_slope`` in [unit/Pa], ``rate`` in [1/Pa].
    """
    p = np.asarray(pressure, dtype=float)
    c = np.where(np.abs(rate) < MIN_RATE, MIN_RATE, rate)
    return intercept + initial_slope * np.expm1(c * p) / c


PRESSURE_LAWS: dict[str, Callable[..., np.ndarray]] = {
    "constant": constant,
    "linear": linear,
    "quadratic": quadratic,
    "exponential": exponential,
}
"""Scalar pressure laws by name; each maps (pressure [Pa], coefficients) to a value."""

PRESSURE_LAW_COEFFICIENTS = {
    "constant": ("intercept",),
    "linear": ("intercept", "slope"),
    "quadratic": ("intercept", "slope", "curvature"),
    "exponential": ("intercept", "amplitude", "rate"),
}
"""Coefficient names of each pressure law, in order. Units: the parameter's unit
(``intercept``, ``amplitude``), per Pa (``slope``, ``rate`` [1/Pa]), per Pa^2 (``curvature``)."""

PRESSURE_REFERENCES: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    "a": lambda pa, pb: pa,
    "b": lambda pa, pb: pb,
    "sum": lambda pa, pb: pa + pb,
    "mean": lambda pa, pb: 0.5 * (pa + pb),
    "max": lambda pa, pb: np.maximum(pa, pb),
}
"""How two chamber pressures combine into the pressure a law sees."""


def operating_pressure(
    pressure_a: ArrayLike,
    pressure_b: ArrayLike | None = None,
    *,
    reference: str = "mean",
) -> np.ndarray:
    """Combine chamber pressures into the pressure a pressure law uses [Pa].

    Parameters
    ----------
    pressure_a : float or array_like
        Pressure in chamber A (cap side) [Pa].
    pressure_b : float or array_like, optional
        Pressure in chamber B (rod side) [Pa]; defaults to ``pressure_a`` (both chambers at
        the same pressure, as in the thesis rig).
    reference : {"a", "b", "sum", "mean", "max"}
        Which pressure the law sees. The thesis law uses the common chamber pressure
        (``"mean"`` of two equal pressures); Simscape's Cylinder Friction uses ``"sum"``.
    """
    if reference not in PRESSURE_REFERENCES:
        raise ValueError(
            f"unknown pressure reference {reference!r}; valid: {sorted(PRESSURE_REFERENCES)}"
        )
    pa = check_signal("pressure_a", pressure_a)
    pb = pa if pressure_b is None else check_signal("pressure_b", pressure_b)
    return PRESSURE_REFERENCES[reference](pa, pb)


CYLINDER_ACTION = {
    "single-acting": "single-acting",
    "single-rod": "double-acting",
    "double-rod": "double-acting",
}
"""How each ``[cylinder] kind`` of campaign.toml acts: one working chamber or two."""

DEFAULT_PRESSURE_REFERENCE = "mean"
"""The reference of a double-acting cylinder whose campaign states none: the mean of the
chamber pressures, which is the common pressure when both chambers are held at one pressure
(the thesis rig, ch. 3)."""

WORKING_CHAMBER = "a"
"""The working chamber of a single-acting cylinder: A, the cap side, whose area is the bore's
(campaign.toml's single-acting kind gives chamber A the piston area and chamber B none)."""

REFERENCE_CHAMBERS = {
    "a": ("a",),
    "b": ("b",),
    "sum": ("a", "b"),
    "mean": ("a", "b"),
    "max": ("a", "b"),
}
"""The chambers whose pressure each reference needs."""


def pressure_reference_basis(
    kind: str | None, stated: str | None = None, *, where: str = "campaign.toml"
) -> dict[str, Any]:
    """The pressure reference a cylinder's laws are fitted and evaluated in, and why.

    A single-acting cylinder has one working chamber (:data:`WORKING_CHAMBER`, A); its laws
    see that chamber's gauge pressure (rule ``"a"``), so that a simulation fed the working
    pressure and an atmospheric other chamber (0 bar gauge) gives the datasheet's friction.
    A double-acting cylinder (``single-rod``, ``double-rod``) uses the rule the campaign
    states, else :data:`DEFAULT_PRESSURE_REFERENCE` (``"mean"``), recorded as a default.

    Parameters
    ----------
    kind : {"single-acting", "single-rod", "double-rod"} or None
        ``[cylinder] kind`` of campaign.toml; None when the campaign states none (a
        double-acting cylinder is assumed, as campaign.toml's default kind is ``double-rod``).
    stated : {"a", "b", "sum", "mean", "max"} or None
        ``[cylinder] pressure_reference`` when the campaign states one.
    where : str
        The file that states them, for the record and the errors.

    Returns
    -------
    dict
        ``kind`` (``"single-acting"``, ``"double-acting"``), ``rule`` (a key of
        :data:`PRESSURE_REFERENCES`), ``chamber`` (``"a"``, ``"b"`` or None when the rule
        combines both) and ``stated_by`` (who decided it, in words): the datasheet's
        ``model.pressure_reference_basis``.

    Raises
    ------
    ValueError
        An unknown kind or rule, or a recipe that contradicts itself (a single-acting
        cylinder with a rule other than its working chamber's).

    Examples
    --------
    >>> pressure_reference_basis("single-acting")["rule"]
    'a'
    >>> pressure_reference_basis("single-rod", "sum")["chamber"] is None
    True
    """
    if kind is not None and kind not in CYLINDER_ACTION:
        raise ValueError(f"unknown cylinder kind {kind!r}; valid: {sorted(CYLINDER_ACTION)}")
    if stated is not None and stated not in PRESSURE_REFERENCES:
        raise ValueError(
            f"unknown pressure reference {stated!r}; valid: {sorted(PRESSURE_REFERENCES)}"
        )
    action = CYLINDER_ACTION[kind] if kind is not None else "double-acting"
    said = f'[cylinder] kind = "{kind}"' if kind is not None else "no [cylinder] kind"
    if action == "single-acting":
        if stated not in (None, WORKING_CHAMBER):
            raise ValueError(
                f'pressure_reference = "{stated}" contradicts kind = "single-acting": a '
                f"single-acting cylinder has one working chamber, "
                f"{WORKING_CHAMBER.upper()} (the bore's area; the other chamber is at "
                f'atmosphere, 0 bar gauge), so its laws see that chamber (rule "'
                f'{WORKING_CHAMBER}"); remove pressure_reference or write "{WORKING_CHAMBER}"'
            )
        return {
            "kind": action,
            "rule": WORKING_CHAMBER,
            "chamber": WORKING_CHAMBER,
            "stated_by": (
                f"{where}: {said}"
                + (f' and pressure_reference = "{stated}"' if stated else "")
                + f": the working chamber {WORKING_CHAMBER.upper()}'s gauge pressure"
            ),
        }
    rule = stated or DEFAULT_PRESSURE_REFERENCE
    stated_by = (
        f'{where}: {said} and pressure_reference = "{stated}"'
        if stated
        else (
            f"default: {where} states "
            + (
                f"{said} and "
                if kind is not None
                else "no [cylinder] kind (double-acting assumed) and "
            )
            + f'no pressure_reference, so the laws see the "{rule}" of the chamber pressures '
            "(the common pressure when both chambers are held at one pressure)"
        )
    )
    chamber = rule if rule in ("a", "b") else None
    return {"kind": action, "rule": rule, "chamber": chamber, "stated_by": stated_by}


def params_at_pressure(
    pressure: ArrayLike,
    coefficients: Mapping[str, Any],
    *,
    law: str = "linear",
) -> dict[str, Any]:
    """Evaluate a coefficient set at an operating pressure -> friction parameter dict.

    Parameters
    ----------
    pressure : float or array_like
        Operating pressure [Pa] (see :func:`operating_pressure`).
    coefficients : dict
        Friction-parameter name -> constant (SI) or dict of coefficients of ``law``
        (e.g. ``{"intercept": 70.2, "slope": 5e-6}`` for ``linear``). A nested dict may carry
        its own ``"law"`` key to mix laws.
    law : {"constant", "linear", "quadratic", "exponential"}
        Default scalar pressure law for the nested dicts.

    Returns
    -------
    dict
        Parameter name -> value at ``pressure`` (float for scalar pressure, else ndarray),
        ready for ``stribeck(v, **params)``.

    Examples
    --------
    >>> from cylfric.friction.literature import THESIS_2016
    >>> p = params_at_pressure(55e5, THESIS_2016.coefficients)
    >>> round(p["F_c"], 2), round(p["sigma_2"], 1)
    (97.7, 384.0)
    """
    check_signal("pressure", pressure)
    scalar = np.ndim(pressure) == 0
    out: dict[str, float | np.ndarray] = {}
    for name, spec in coefficients.items():
        if scalar and type(spec) is float:  # a constant at one pressure: nothing to evaluate
            out[name] = spec
            continue
        if isinstance(spec, Mapping):
            spec = dict(spec)
            law_name = spec.pop("law", law)
            if law_name not in PRESSURE_LAWS:
                raise ValueError(
                    f"unknown pressure law {law_name!r}; valid: {sorted(PRESSURE_LAWS)}"
                )
            try:
                value = PRESSURE_LAWS[law_name](pressure, **spec)
            except TypeError as exc:
                raise ValueError(
                    f"coefficients of {name} do not fit the {law_name} pressure law: {exc}"
                ) from None
        else:
            value = np.broadcast_to(np.asarray(spec, dtype=float), np.shape(pressure))
        out[name] = float(value) if np.ndim(value) == 0 else np.asarray(value)
    return out


def simscape_cylinder_friction(
    pressure_a: ArrayLike,
    pressure_b: ArrayLike,
    *,
    preload_force: float,
    coulomb_friction_coefficient: float,
    breakaway_ratio: float,
    viscous_coefficient: float,
    transition_coefficient: float,
) -> dict[str, Any]:
    """Parameters of Simscape's "Cylinder Friction" block as a Stribeck parameter dict.

    Simscape Fluids models ``F_C = F_pr + f_cfr (p_A + p_B)`` (reference fixed to the *sum*
    of the chamber pressures), breakaway ``F_brk = K_brk F_C`` (constant ratio), a constant
    viscous coefficient ``f_vfr`` and the transition ``exp(-c_v |v|)``. That is eq. 2.7 with
    ``alpha = 1`` and ``v_r = 1 / c_v``.

    Parameters
    ----------
    pressure_a, pressure_b : float or array_like
        Chamber pressures [Pa].
    preload_force : float
        Seal preload force ``F_pr`` [N].
    coulomb_friction_coefficient : float
        ``f_cfr`` [N/Pa].
    breakaway_ratio : float
        ``K_brk = F_brk / F_C`` [-], >= 1.
    viscous_coefficient : float
        ``f_vfr`` [N*s/m].
    transition_coefficient : float
        ``c_v`` [s/m], > 0.

    Returns
    -------
    dict
        ``F_c``, ``F_s``, ``sigma_2``, ``v_r``, ``alpha`` for :func:`~cylfric.friction.stribeck`.
    """
    if breakaway_ratio < 1:
        raise ValueError(f"breakaway_ratio = {breakaway_ratio} is out of range; expected >= 1")
    if transition_coefficient <= 0:
        raise ValueError(
            f"transition_coefficient = {transition_coefficient} is out of range; expected > 0 s/m"
        )
    p = operating_pressure(pressure_a, pressure_b, reference="sum")
    F_c = preload_force + coulomb_friction_coefficient * p
    out: dict[str, float | np.ndarray] = {
        "F_c": F_c,
        "F_s": breakaway_ratio * F_c,
        "sigma_2": viscous_coefficient,
        "v_r": 1.0 / transition_coefficient,
        "alpha": 1.0,
    }
    return {k: (float(v) if np.ndim(v) == 0 else v) for k, v in out.items()}
