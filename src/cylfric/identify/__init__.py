"""Identification of the pressure-dependent friction model from steady-state points (ch. 4).

:func:`identify` runs the thesis method and more on a points table (from
:func:`cylfric.steady_state.extract_campaign`): per-pressure Stribeck fits (Table 4.1), the
pressure laws two ways (regression of the per-pressure parameters, and one global surface
fit), information criteria across laws, the alpha / v_r sensitivity study (Tables 4.2-4.4),
and per-direction fits on request.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from typing import Any

__all__ = [
    "identify",
    "add_sensitivity",
    "Identification",
    "sensitivity_refits",
    "fit_stribeck",
    "StribeckFit",
    "fit_surface",
    "SurfaceFit",
    "regress_parameters",
    "PressureLawFit",
    "sensitivity_grid",
    "thesis_tables",
    "pressure_levels",
    "UnphysicalFrictionError",
    "validity_of",
    "point_errors",
    "unphysical",
    "fit_linear_surface",
    "IdentificationWarning",
    "PARAMETERS",
]

_SUBMODULES = (
    "dynamic",
    "lack_of_fit",
    "linear_fit",
    "motion",
    "motion_validation",
    "pressure_fit",
    "scatter",
    "sensitivity",
    "steady",
    "stribeck_fit",
)


def __getattr__(name: str) -> Any:
    """Load the steady-state identification (scipy.optimize) only when a name is used.

    ``import cylfric.identify.motion`` or ``.dynamic`` then does not pay for it.
    """
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    module = importlib.import_module(f"{__name__}.steady")
    try:
        value = getattr(module, name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
