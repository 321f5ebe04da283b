"""Names, units and bounds of a friction model's parameters (the vocabulary the model's
modules share: :mod:`~cylfric.model.core`, :mod:`~cylfric.model.serialize`,
:mod:`~cylfric.model.text`), and their engineering units. Imports nothing of cylfric."""

from __future__ import annotations

import math

__all__ = [
    "IDENTIFY_ADVICE",
    "STEADY_PARAMETERS",
    "DYNAMIC_PARAMETERS",
    "PRESSURE_DEPENDENT",
    "PARAMETER_UNITS",
    "PARAMETER_BOUNDS",
    "FRICTION_LAWS",
    "DYNAMIC_STATUS",
    "ValidityWarning",
    "engineering_unit",
]

STEADY_PARAMETERS = ("F_c", "F_s", "sigma_2", "v_r", "alpha")
"""Parameters of the steady-state law (eq. 2.7), in the order of vectors and tables."""
DYNAMIC_PARAMETERS = ("sigma_0", "sigma_1")
PRESSURE_DEPENDENT = ("F_c", "F_s", "sigma_2")
"""Parameters the datasheet always writes as pressure laws (a constant as ``"constant"``)."""
"""LuGre bristle stiffness and damping (eq. 2.5); they do not act in steady state."""

PARAMETER_UNITS = {
    "F_c": "N",
    "F_s": "N",
    "sigma_2": "N*s/m",
    "v_r": "m/s",
    "alpha": "-",
    "sigma_0": "N/m",
    "sigma_1": "N*s/m",
}
"""SI unit of each friction parameter."""

PARAMETER_BOUNDS = {
    "F_c": (0.0, math.inf),
    "F_s": (0.0, math.inf),
    "sigma_2": (0.0, math.inf),
    "v_r": (1e-5, 10.0),
    "alpha": (0.2, 5.0),
    "sigma_0": (0.0, math.inf),
    "sigma_1": (0.0, math.inf),
}
"""Physical bounds of each friction parameter (SI); fits use them for the shape parameters
``v_r`` [m/s] and ``alpha`` [-] and for the parameters of a single-pressure fit."""

FRICTION_LAWS = {
    "stribeck": (
        STEADY_PARAMETERS,
        "F = F_c + (F_s - F_c) exp(-(|v|/v_r)^alpha) + sigma_2 |v| (thesis eq. 2.7), times sign(v)",
    ),
    "coulomb_viscous": (
        ("F_c", "sigma_2"),
        "F = F_c + sigma_2 |v| (thesis eq. 2.1 + 2.2), times sign(v)",
    ),
    "coulomb": (("F_c",), "F = F_c (thesis eq. 2.1), times sign(v)"),
}
"""Steady-state laws a model can carry: name -> (identified parameters, equation). The
reduced laws are eq. 2.7 with ``F_s = F_c`` (no Stribeck term) and, for ``coulomb``,
``sigma_2 = 0``; the parameters they lack are not identified (null in the datasheet)."""

DYNAMIC_STATUS = ("identified", "assumed")
"""Status of ``sigma_0`` and ``sigma_1``: identified from data, or assumed (a default)."""

IDENTIFY_ADVICE = (
    "identify them from presliding runs in the campaign (cylfric fit with presliding tests) "
    "or on the axis itself from a 10 s logged motion, a small sine around a reversal and a "
    "slow ramp (cylfric identify-axis; docs/dynamic_parameters.md)"
)
"""How to identify an assumed sigma_0 / sigma_1: said wherever they are used (the model's
:meth:`~cylfric.model.FrictionModel.assumptions`, ``cylfric control`` and its exports)."""

_DEFAULT_DYNAMIC = {
    "sigma_0": (1e6, "typical of hydraulic seals (presliding F_s/sigma_0 of about 0.1 mm)"),
    "sigma_1": (
        1.58e3,
        "critically damped bristles for a 2.5 kg moving mass, sqrt(sigma_0 m)",
    ),
}

_PRESSURE_UNIT = {
    "intercept": ("", 1.0),
    "slope": ("/Pa", 1.0),
    "curvature": ("/Pa^2", 1.0),
    "amplitude": ("", 1.0),
    "rate": ("/Pa", 1.0),
}

_ENGINEERING = {
    "N": ("N", 1.0),
    "N*s/m": ("N*s/mm", 1e-3),
    "m/s": ("mm/s", 1e3),
    "-": ("-", 1.0),
    "N/m": ("N/mm", 1e-3),
}


class ValidityWarning(UserWarning):
    """A model was evaluated outside the range its data cover, or with suspect units."""


def engineering_unit(name: str) -> tuple[str, float]:
    """Engineering unit of a coefficient and the factor from SI: ``("N/bar", 1e5)``.

    ``name`` is a :class:`Parameter` name (``"F_c.slope"``, ``"sigma_2.intercept"``, ``"v_r"``).
    Forces stay in N, velocities go to mm/s, viscous coefficients to N*s/mm, pressures to bar.
    """
    parameter, _, coefficient = name.partition(".")
    unit, factor = _ENGINEERING[PARAMETER_UNITS[parameter]]
    if coefficient == "rate":
        return "1/bar", 1e5
    power = {"slope": 1, "curvature": 2}.get(coefficient, 0)
    if power:
        return f"{unit}/bar" + ("^2" if power == 2 else ""), factor * 1e5**power
    return unit, factor


def _si_unit(parameter: str, coefficient: str | None) -> str:
    unit = PARAMETER_UNITS[parameter]
    if coefficient == "rate":
        return "1/Pa"
    suffix = _PRESSURE_UNIT[coefficient][0] if coefficient else ""
    if not suffix:
        return unit
    return f"{unit}{suffix}" if unit != "-" else f"1{suffix}"
