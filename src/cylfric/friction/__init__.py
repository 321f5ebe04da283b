"""Friction laws, pressure laws and literature parameter sets (numpy/scipy only).

The registry :data:`LAWS` names every friction law; :func:`get_law` looks one up and
:func:`law_params` picks, from a larger parameter dict, the keywords a law takes.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import TYPE_CHECKING

from . import literature, pressure
from .laws import (
    barus_viscosity,
    coulomb,
    dahl_derivative,
    hersey_number,
    lugre_force,
    lugre_g,
    lugre_state_derivative,
    lugre_steady_state,
    lugre_unchecked,
    lugre_z_update,
    stiction,
    stribeck,
    stribeck_jacobian,
    stribeck_shape,
    stribeck_unchecked,
    viscous,
)
from .pressure import operating_pressure, params_at_pressure, simscape_cylinder_friction
from .stribeck_velocity import NoStribeckMinimumWarning, stribeck_velocity

if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

__all__ = [
    "LAWS",
    "Law",
    "get_law",
    "law_params",
    "coulomb",
    "viscous",
    "stiction",
    "stribeck",
    "stribeck_shape",
    "stribeck_jacobian",
    "stribeck_unchecked",
    "dahl_derivative",
    "lugre_g",
    "lugre_state_derivative",
    "lugre_force",
    "lugre_unchecked",
    "lugre_steady_state",
    "lugre_z_update",
    "stribeck_velocity",
    "NoStribeckMinimumWarning",
    "barus_viscosity",
    "hersey_number",
    "operating_pressure",
    "params_at_pressure",
    "simscape_cylinder_friction",
    "literature",
    "pressure",
]


@dataclass(frozen=True)
class Law:
    """A registered friction law.

    Attributes
    ----------
    name : str
        Registry key.
    function : callable
        The law; velocity [m/s] first.
    kind : str
        ``"force"`` (returns a force [N]) or ``"derivative"`` (returns a state derivative).
    state : str or None
        Name of the state argument (``"z"`` [m], ``"force"`` [N]) for dynamic laws.
    example : dict
        A valid parameter set (SI), used in documentation and property tests.
    equation : str
        Equation number in the thesis.
    """

    name: str
    function: Callable[..., Any]
    kind: str
    state: str | None
    example: dict[str, float]
    equation: str

    @property
    def parameters(self) -> tuple[str, ...]:
        """Keyword parameters of the law, in signature order."""
        sig = inspect.signature(self.function)
        skip = {"velocity", self.state}
        return tuple(p for p in sig.parameters if p not in skip)


_THESIS_0BAR = {"F_c": 70.2, "F_s": 112.9, "v_r": 0.010, "sigma_2": 340.0, "alpha": 1.0}

LAWS: dict[str, Law] = {
    law.name: law
    for law in (
        Law("coulomb", coulomb, "force", None, {"F_c": 70.2}, "2.1"),
        Law("viscous", viscous, "force", None, {"sigma_2": 340.0}, "2.2"),
        Law(
            "stiction",
            stiction,
            "force",
            None,
            {"F_c": 70.2, "F_s": 112.9, "velocity_tolerance": 1e-4},
            "2.3",
        ),
        Law("stribeck", stribeck, "force", None, dict(_THESIS_0BAR), "2.7"),
        Law("lugre_steady_state", lugre_steady_state, "force", None, dict(_THESIS_0BAR), "2.6"),
        Law(
            "dahl",
            dahl_derivative,
            "derivative",
            "force",
            {"F_c": 70.2, "sigma": 1e6, "exponent": 1.0},
            "2.4",
        ),
        Law(
            "lugre_state",
            lugre_state_derivative,
            "derivative",
            "z",
            {"sigma_0": 1e6, "F_c": 70.2, "F_s": 112.9, "v_r": 0.010, "alpha": 1.0},
            "2.5",
        ),
        Law(
            "lugre",
            lugre_force,
            "force",
            "z",
            {
                "sigma_0": 1e6,
                "sigma_1": 3e3,
                "sigma_2": 340.0,
                "F_c": 70.2,
                "F_s": 112.9,
                "v_r": 0.010,
                "alpha": 1.0,
            },
            "2.5",
        ),
    )
}
"""Every friction law by name."""


def get_law(name: str) -> Law:
    """Return the registered law ``name``; unknown names list the valid ones."""
    try:
        return LAWS[name]
    except KeyError:
        raise ValueError(f"unknown friction law {name!r}; valid: {sorted(LAWS)}") from None


def law_params(name: str, params: dict) -> dict:
    """Pick from ``params`` the keywords law ``name`` takes (e.g. LuGre set -> stribeck).

    Raises ValueError if a required keyword is missing.
    """
    law = get_law(name)
    sig = inspect.signature(law.function)
    picked = {k: params[k] for k in law.parameters if k in params}
    missing = [
        k
        for k in law.parameters
        if k not in params and sig.parameters[k].default is inspect.Parameter.empty
    ]
    if missing:
        raise ValueError(f"law {name!r} needs parameters {missing}; got {sorted(params)}")
    return picked
