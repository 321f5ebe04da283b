"""Published friction parameter sets, as data with their citations (SI units).

Each set is a frozen :class:`ParameterSet`. ``params`` is a parameter dict for a friction law;
``coefficients`` a pressure-law coefficient set for
:func:`cylfric.friction.pressure.params_at_pressure`; ``table`` holds measured rows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType

BAR = 1e5  # [Pa/bar]
MM_S = 1e-3  # [(m/s)/(mm/s)]

__all__ = [
    "ParameterSet",
    "THESIS_2016",
    "THESIS_2016_REVISED",
    "THESIS_TABLE_4_1",
    "AALBORG_TABLE_2_1",
    "CANUDAS_DE_WIT_1995",
    "LITERATURE",
]

THESIS = (
    "A. Pérez Dorado, 'Friction, a Limiting Property in Controlled Motion', master thesis, "
    "Linköping University, 2016"
)


@dataclass(frozen=True)
class ParameterSet:
    """A published parameter set.

    Attributes
    ----------
    name : str
        Registry key.
    citation : str
        Source, with table or equation numbers.
    params : mapping
        Friction-law parameters (SI) when the set is pressure independent.
    coefficients : mapping
        Pressure-law coefficients (SI: N, N/Pa, N*s/m, N*s/(m*Pa), m/s, -).
    table : mapping
        Measured columns as tuples (SI), e.g. ``pressure`` [Pa], ``F_s`` [N].
    law : str
        Friction law the parameters belong to.
    notes : str
        Anything a user must know to use the set.
    """

    name: str
    citation: str
    params: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    coefficients: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    table: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    law: str = "stribeck"
    notes: str = ""


def _linear(intercept, slope_per_bar):
    return MappingProxyType({"intercept": intercept, "slope": slope_per_bar / BAR})


THESIS_2016 = ParameterSet(
    name="thesis_2016",
    citation=THESIS + ", eq. 4.1-4.3 (alpha = 1, v_r = 10 mm/s from sections 4.1.1-4.1.2)",
    coefficients=MappingProxyType(
        {
            "F_c": _linear(70.2, 0.5),  # eq. 4.1: 70.2 + 0.5 p[bar] N
            "F_s": _linear(112.9, 0.6),  # eq. 4.2: 112.9 + 0.6 p[bar] N
            "sigma_2": _linear(0.34e3, 8e-4 * 1e3),  # eq. 4.3: 0.34 + 8e-4 p[bar] N*s/mm
            "v_r": 10 * MM_S,
            "alpha": 1.0,
        }
    ),
    notes="Pressure is the common pressure of both chambers (reference='mean' of equal pressures).",
)

THESIS_2016_REVISED = ParameterSet(
    name="thesis_2016_revised",
    citation=THESIS + ", chapter 5, eq. 4.1rev-4.3rev",
    coefficients=MappingProxyType(
        {
            "F_c": _linear(73.5, 0.5),  # eq. 4.1 rev
            "F_s": _linear(117.0, 0.6),  # eq. 4.2 rev
            "sigma_2": _linear(0.34e3, 8e-4 * 1e3),  # eq. 4.3 rev
            "v_r": 10 * MM_S,
            "alpha": 1.0,
        }
    ),
    notes="Chapter 5 revises the intercepts of F_c and F_s; the slopes are unchanged.",
)

THESIS_TABLE_4_1 = ParameterSet(
    name="thesis_table_4_1",
    citation=THESIS + ", Table 4.1 (measured per-pressure parameters)",
    table=MappingProxyType(
        {
            "pressure": tuple(p * BAR for p in (0.0, 55.0, 83.0, 124.0, 159.0)),  # [Pa]
            "F_s": (113.0, 146.0, 162.6, 187.4, 208.1),  # [N]
            "F_c": (70.2, 99.5, 114.1, 136.0, 158.6),  # [N]
            "sigma_2": tuple(s * 1e3 for s in (0.340, 0.386, 0.398, 0.409, 0.472)),  # [N*s/m]
            "stribeck_velocity": tuple(v * MM_S for v in (25, 26, 24, 25, 23)),  # [m/s]
        }
    ),
    notes="The table's first column is the 0.1 bar level, printed as 0 bar.",
)

AALBORG_TABLE_2_1 = ParameterSet(
    name="aalborg_table_2_1",
    citation=(
        THESIS + ", Table 2.1, from the Aalborg University master thesis 'Friction Modelling and "
        "Parameter Estimation for Hydraulic Asymmetrical Cylinders' (asymmetric cylinder)"
    ),
    table=MappingProxyType(
        {
            "load": (500.0, 1000.0, 2000.0, 5000.0),  # [N]
            "F_s": (616.0, 647.0, 634.0, 651.0),  # [N]
            "F_c": (341.0, 379.0, 387.0, 541.0),  # [N]
            "stribeck_velocity": (0.10, 0.11, 0.10, 0.13),  # [m/s]
        }
    ),
    notes="Indexed by external load [N], not chamber pressure.",
)

CANUDAS_DE_WIT_1995 = ParameterSet(
    name="canudas_de_wit_1995",
    citation=(
        "C. Canudas de Wit, H. Olsson, K. J. Åström, P. Lischinsky, 'A new model for control of "
        "systems with friction', IEEE Trans. Automatic Control 40(3):419-425, 1995, "
        "simulation parameters"
    ),
    law="lugre",
    params=MappingProxyType(
        {
            "sigma_0": 1e5,  # [N/m]
            "sigma_1": math.sqrt(1e5),  # [N*s/m]
            "sigma_2": 0.4,  # [N*s/m]
            "F_c": 1.0,  # [N]
            "F_s": 1.5,  # [N]
            "v_r": 1e-3,  # [m/s], v_s in the paper
            "alpha": 2.0,  # [-]
        }
    ),
    table=MappingProxyType({"mass": (1.0,)}),  # [kg], unit mass
)

LITERATURE = MappingProxyType(
    {
        s.name: s
        for s in (
            THESIS_2016,
            THESIS_2016_REVISED,
            THESIS_TABLE_4_1,
            AALBORG_TABLE_2_1,
            CANUDAS_DE_WIT_1995,
        )
    }
)
"""All literature sets by name."""
