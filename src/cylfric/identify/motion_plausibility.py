"""Plausibility gates of a motion identification: magnitudes the record cannot support.

IDIM-LS (:func:`cylfric.identify.motion.fit_motion`) returns numbers for any record: a
position in mm whose unit says m, a force channel in the wrong unit or a record that does
not excite the inertia all give parameters with small standard errors. The checks of
:data:`CHECKS` compare the identified values with what the record itself shows and return
:class:`PlausibilityFlag` items; ``cylfric fit-motion`` refuses (exit 2) when there is one,
unless ``--accept-implausible`` is given, and then writes them into ``motion_fit.json``.

Each check is a pure function ``check(fit, evidence, limits) -> list of flags`` registered
in :data:`CHECKS`; its threshold is a keyword of :data:`LIMITS` with its unit. The limits
are loose on purpose (they must never fire on a sound record such as the EMPS benchmark,
whose values are in the module tests) and fire on the same record with a unit off by 1000:

============================  =======  ====================================================
limit                         value    why
============================  =======  ====================================================
``max_stroke``                20 m     longest strokes of industrial cylinders are a few m;
                                       a position in mm read as m gives 50-1000 m
``max_speed``                 20 m/s   hydraulic cylinders move at most a few m/s; mm/s
                                       read as m/s gives 10-1000 m/s
``negative_mass_sigmas``      3 [-]    a mass below zero by more than 3 standard errors
                                       (closer to zero it is noise: the record barely
                                       accelerates and the mass is not identified)
``mass_force_ratio``          10 [-]   the inertial force mass * max|a| may not exceed
                                       10 x the largest force recorded
``coulomb_force_ratio``       1 [-]    the Coulomb level is a force of the record: at most
                                       the largest force magnitude recorded
``friction_force_ratio``      2 [-]    the friction at the fastest sample (Coulomb +
                                       viscous) at most 2 x the largest force recorded
============================  =======  ====================================================

Not caught: a position in m whose unit says mm (1000x too small) looks like a genuine small
motion. A force unit slip in either direction (kN exported as N read as N, or the reverse)
scales the identified mass, friction levels and offset alike, so every ratio the checks use
is unchanged and the fit passes: a force 1000x too large gave mass 95,114 kg and F_c
20,409 N on the EMPS record. No gate is set on absolute magnitudes, which would fire on
genuine large machines; check the force unit (motion.toml ``force_scale``, the record's
header) against the rig.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Mapping

    from numpy.typing import ArrayLike

    from cylfric.identify.motion import MotionFit

__all__ = ["PlausibilityFlag", "LIMITS", "CHECKS", "check_plausibility", "record_evidence"]

LIMITS = {
    "max_stroke": 20.0,  # [m]
    "max_speed": 20.0,  # [m/s]
    "negative_mass_sigmas": 3.0,  # [-]
    "mass_force_ratio": 10.0,  # [-]
    "coulomb_force_ratio": 1.0,  # [-]
    "friction_force_ratio": 2.0,  # [-]
}
"""Thresholds of the checks (units in the module docstring's table)."""


@dataclass(frozen=True)
class PlausibilityFlag:
    """One implausible magnitude of a motion identification.

    Attributes
    ----------
    code : str
        The check (a key of :data:`CHECKS`): ``position_unit``, ``velocity_unit``,
        ``mass_negative``, ``mass_magnitude``, ``coulomb_level``, ``friction_level``.
    quantity : str
        What was judged, with its SI unit (``"stroke [m]"``, ``"mass [kg]"``).
    value : float
        Its value [SI unit of ``quantity``].
    expected : str
        What a sound record gives, in words with the limit.
    hint : str
        The likely cause and what to do.
    """

    code: str
    quantity: str
    value: float
    expected: str
    hint: str

    def __str__(self) -> str:
        return f"{self.summary()}. {self.hint}"

    def summary(self) -> str:
        """``code: quantity = value; expected ...`` (without the hint)."""
        return f"{self.code}: {self.quantity} = {self.value:.4g}; expected {self.expected}"

    def to_dict(self) -> dict:
        """The JSON form (``motion_fit.json`` ``plausibility``)."""
        return asdict(self)


def record_evidence(signals: Mapping[str, np.ndarray], position: ArrayLike) -> dict[str, float]:
    """What the record shows: stroke [m], fastest speed [m/s], largest |acceleration|
    [m/s^2] and largest |force| [N] (the regression signals of a fit; the stroke of the
    full-rate position)."""
    position = np.asarray(position, dtype=float)
    return {
        "stroke": float(np.ptp(position)),
        "speed": float(np.max(np.abs(signals["velocity [m/s]"]))),
        "acceleration": float(np.max(np.abs(signals["acceleration [m/s^2]"]))),
        "force": float(np.max(np.abs(signals["force [N]"]))),
    }


_UNIT_HINT = (
    'A position in mm whose unit says m? Fix the unit: [units] position = "mm" in '
    "motion.toml for a .mat record, the unit in the header of a text record."
)


def _stroke(fit, evidence, limits):
    if evidence["stroke"] <= limits["max_stroke"]:
        return []
    return [
        PlausibilityFlag(
            "position_unit",
            "stroke [m]",
            evidence["stroke"],
            f"at most {limits['max_stroke']:g} m for a cylinder",
            _UNIT_HINT,
        )
    ]


def _speed(fit, evidence, limits):
    if evidence["speed"] <= limits["max_speed"]:
        return []
    return [
        PlausibilityFlag(
            "velocity_unit",
            "largest speed [m/s]",
            evidence["speed"],
            f"at most {limits['max_speed']:g} m/s for a cylinder",
            _UNIT_HINT,
        )
    ]


def _mass(fit, evidence, limits):
    mass, stderr = fit.parameters["mass"], fit.stderr["mass"]
    if mass < -limits["negative_mass_sigmas"] * stderr:
        return [
            PlausibilityFlag(
                "mass_negative",
                "mass [kg]",
                mass,
                f"a positive moving mass (this one is {-mass / stderr:.3g} standard errors of "
                f"{stderr:.3g} kg below zero; at most {limits['negative_mass_sigmas']:g})",
                "The record does not excite the inertia (too little acceleration) or force "
                "and position are not of the same axis or sign; check the signals.",
            )
        ]
    supported = (
        limits["mass_force_ratio"] * evidence["force"] / max(evidence["acceleration"], 1e-300)
    )
    if mass <= supported:
        return []
    return [
        PlausibilityFlag(
            "mass_magnitude",
            "mass [kg]",
            mass,
            f"at most {supported:.4g} kg: {limits['mass_force_ratio']:g} x the largest force "
            f"{evidence['force']:.4g} N over the largest acceleration "
            f"{evidence['acceleration']:.4g} m/s^2 of the record",
            "A force channel in the wrong unit or scale (force_scale), or a record that "
            "barely accelerates; check the force signal.",
        )
    ]


def _levels(fit):
    """(Coulomb, viscous) of the fit, per direction the larger of each."""
    p = fit.parameters
    if "F_c" in p:
        return p["F_c"], p["F_v"]
    return max(p["F_c_pos"], p["F_c_neg"]), max(p["F_v_pos"], p["F_v_neg"])


def _coulomb(fit, evidence, limits):
    coulomb, _ = _levels(fit)
    limit = limits["coulomb_force_ratio"] * evidence["force"]
    if abs(coulomb) <= limit:
        return []
    return [
        PlausibilityFlag(
            "coulomb_level",
            "Coulomb friction F_c [N]",
            coulomb,
            f"at most {limit:.4g} N (the largest force magnitude in the record)",
            "A friction level above every force recorded: a force or position unit is off, "
            "or the model does not fit the record; check the signals.",
        )
    ]


def _friction(fit, evidence, limits):
    coulomb, viscous = _levels(fit)
    friction = abs(coulomb) + abs(viscous) * evidence["speed"]
    limit = limits["friction_force_ratio"] * evidence["force"]
    if friction <= limit:
        return []
    return [
        PlausibilityFlag(
            "friction_level",
            "friction at the fastest sample |F_c| + |F_v| max|v| [N]",
            friction,
            f"at most {limit:.4g} N ({limits['friction_force_ratio']:g} x the largest force "
            "magnitude in the record)",
            "A friction force well above every force recorded: a force or position unit is "
            "off, or the model does not fit the record; check the signals.",
        )
    ]


CHECKS = {
    "position_unit": _stroke,
    "velocity_unit": _speed,
    "mass": _mass,
    "coulomb_level": _coulomb,
    "friction_level": _friction,
}
"""Check name -> ``check(fit, evidence, limits) -> list of PlausibilityFlag``."""


def check_plausibility(
    fit: MotionFit, position: ArrayLike, **limits: float
) -> tuple[PlausibilityFlag, ...]:
    """Flags of the implausible magnitudes of a motion fit.

    Parameters
    ----------
    fit : MotionFit
        The identification (:func:`cylfric.identify.motion.fit_motion`); its ``signals``
        are the regression signals.
    position : array_like
        The record's full-rate position [m].
    **limits
        Overrides of :data:`LIMITS` (``max_stroke`` [m], ``max_speed`` [m/s], the ratios
        [-]).

    Returns
    -------
    tuple of PlausibilityFlag
        Empty for a plausible fit.
    """
    unknown = sorted(set(limits) - set(LIMITS))
    if unknown:
        raise ValueError(f"unknown plausibility limit {unknown[0]!r}; valid: {sorted(LIMITS)}")
    limits = {**LIMITS, **limits}
    evidence = record_evidence(fit.signals, position)
    return tuple(flag for check in CHECKS.values() for flag in check(fit, evidence, limits))
