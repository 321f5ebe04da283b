"""Units at the edges: engineering units in, SI inside.

cylfric computes in SI (N, m, s, kg, Pa, N*s/m). Users, bench files and the command
line speak bar, mm, mm/s, kN, ms and N*s/mm; this module is the one place that converts.
It imports nothing of cylfric, so every layer may use it.

Examples
--------
>>> parse_quantity("10mm/s", "velocity")
0.01
>>> parse_quantity("55 bar", "pressure")
5500000.0
>>> parse_quantity("7", "pressure", default_unit="bar")
700000.0
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import numpy as np

    _Value = TypeVar("_Value", float, np.ndarray)
    """A value converted as it is: a float gives a float, an array an array."""

__all__ = [
    "UNITS",
    "UnitError",
    "to_si",
    "from_si",
    "parse_quantity",
    "parse_temperature",
    "unit_dimension",
    "BAR",
    "MM",
    "MM_S",
]

BAR = 1e5
"""One bar in pascal [Pa/bar]."""
MM = 1e-3
"""One millimetre in metre [m/mm]."""
MM_S = 1e-3
"""One mm/s in m/s [(m/s)/(mm/s)]."""

# unit symbol (lower-cased, spaces removed) -> (dimension, factor to SI)
UNITS: dict[str, tuple[str, float]] = {
    # time
    "s": ("time", 1.0),
    "sec": ("time", 1.0),
    "secs": ("time", 1.0),
    "second": ("time", 1.0),
    "seconds": ("time", 1.0),
    "ms": ("time", 1e-3),
    "msec": ("time", 1e-3),
    "min": ("time", 60.0),
    "h": ("time", 3600.0),
    # length
    "m": ("length", 1.0),
    "mm": ("length", 1e-3),
    "cm": ("length", 1e-2),
    "um": ("length", 1e-6),
    "µm": ("length", 1e-6),
    "in": ("length", 0.0254),
    "inch": ("length", 0.0254),
    # force
    "n": ("force", 1.0),
    "kn": ("force", 1e3),
    "dan": ("force", 10.0),
    "lbf": ("force", 4.4482216152605),
    "kgf": ("force", 9.80665),
    # pressure
    "pa": ("pressure", 1.0),
    "kpa": ("pressure", 1e3),
    "bar": ("pressure", 1e5),
    "mbar": ("pressure", 1e2),
    "psi": ("pressure", 6894.757293168),
    "barg": ("pressure", 1e5),
    # velocity
    "m/s": ("velocity", 1.0),
    "mm/s": ("velocity", 1e-3),
    "mms": ("velocity", 1e-3),
    "mm_s": ("velocity", 1e-3),
    "cm/s": ("velocity", 1e-2),
    "mm/min": ("velocity", 1e-3 / 60),
    "in/s": ("velocity", 0.0254),
    # viscous friction coefficient
    "ns/m": ("damping", 1.0),
    "n*s/m": ("damping", 1.0),
    "n.s/m": ("damping", 1.0),
    "ns/mm": ("damping", 1e3),
    "n*s/mm": ("damping", 1e3),
    "n.s/mm": ("damping", 1e3),
    # stiffness
    "n/m": ("stiffness", 1.0),
    "n/mm": ("stiffness", 1e3),
    # mass
    "kg": ("mass", 1.0),
    "g": ("mass", 1e-3),
    # kinematic viscosity (oil data sheets: mm^2/s = cSt)
    "mm2/s": ("kinematic viscosity", 1e-6),
    "mm^2/s": ("kinematic viscosity", 1e-6),
    "mm²/s": ("kinematic viscosity", 1e-6),
    "cst": ("kinematic viscosity", 1e-6),
    "m2/s": ("kinematic viscosity", 1.0),
    "m^2/s": ("kinematic viscosity", 1.0),
    "m²/s": ("kinematic viscosity", 1.0),
    # electric (raw sensor channels)
    "v": ("voltage", 1.0),
    # dimensionless
    "-": ("dimensionless", 1.0),
    "1": ("dimensionless", 1.0),
    "": ("dimensionless", 1.0),
}


# Symbols whose case carries the prefix (m milli, M mega): matched exactly as written, or
# all upper-case as bench exports write them (MN, MPA, MV: mega). Lower-case "mn", "mpa",
# "mv" are ambiguous and refused.
CASED_UNITS: dict[str, tuple[str, float]] = {
    "mN": ("force", 1e-3),
    "MN": ("force", 1e6),
    "mPa": ("pressure", 1e-3),
    "MPa": ("pressure", 1e6),
    "MPA": ("pressure", 1e6),
    "mV": ("voltage", 1e-3),
    "MV": ("voltage", 1e6),
}
_AMBIGUOUS = {"mn": ("mN", "MN"), "mpa": ("mPa", "MPa"), "mv": ("mV", "MV")}


# Where the case-insensitive symbols of UNITS carry the milli prefix m: an upper-case M
# there is mega (Mm/s, Ms, Mbar, N*s/Mm), which cylfric does not read, so it is refused
# rather than read as milli. (The m of metre and of min is no prefix: M/S, MIN are read.)
_MILLI_AT: dict[str, tuple[int, ...]] = {
    "ms": (0,),
    "msec": (0,),
    "mm": (0,),
    "mbar": (0,),
    "mm/s": (0,),
    "mms": (0,),
    "mm_s": (0,),
    "mm/min": (0,),
    "n/mm": (2,),
    "ns/mm": (3,),
    "n*s/mm": (4,),
    "n.s/mm": (4,),
    "mm2/s": (0,),
    "mm^2/s": (0,),
    "mm²/s": (0,),
}

# In a unit of _MILLI_AT the case of m and s carries the meaning (m milli or metre, M mega;
# s second, S siemens): a spelling that is neither all capitals nor lower-case in them
# ('mM/s', 'mm/S', 'mS') is refused, not guessed. The words sec and min are no symbols (Sec,
# mSec, mm/Min are read), and N (newton) may be written n.
_CASED_LETTERS = re.compile(r"[MS]")
_WORDS = re.compile(r"sec|min", re.IGNORECASE)


class UnitError(ValueError):
    """A unit symbol is unknown or of the wrong dimension."""


def _key(unit: str) -> str:
    return unit.strip().replace(" ", "").replace("·", "*").lower()


def _written(key: str) -> str:
    """The spelling of a unit of _MILLI_AT to suggest: lower case, N for newton."""
    return "N" + key[1:] if key.startswith("n") else key


@lru_cache(maxsize=256)
def _lookup(unit: str) -> tuple[str, float]:
    """(dimension, factor to SI) of a unit symbol; prefixes m and M by their case.

    Memoised per spelling (a bench file's few units are looked up for every run file;
    errors are not cached: they raise again)."""
    exact = unit.strip().replace(" ", "")
    if exact in CASED_UNITS:
        return CASED_UNITS[exact]
    key = _key(unit)
    mega = [i for i in _MILLI_AT.get(key, ()) if exact[i : i + 1] == "M"]
    # all capitals (an export's 'SEC MM KN' units row) carry no case: a unit whose only
    # prefixed form is milli is read as that (MM is mm, MBAR mbar); mixed case is not guessed
    if mega and len(exact) == len(key) and not exact.isupper():
        milli = "".join("m" if i in mega else c for i, c in enumerate(exact))
        if _CASED_LETTERS.search(_WORDS.sub("", milli)):  # 'Mm/S': an S left, write mm/s
            milli = _written(key)
        raise UnitError(
            f"unit {unit!r}: M is the mega prefix (m is milli), and cylfric reads no mega "
            f"{UNITS[key][0]} unit; write {milli} for the milli unit. Unit prefixes are "
            "case-sensitive"
        )
    if key in _MILLI_AT and not exact.isupper() and _CASED_LETTERS.search(_WORDS.sub("", exact)):
        written = _written(key)
        raise UnitError(
            f"unit {unit!r} is ambiguous: in a unit the case of m and s carries the meaning "
            "(m milli or metre, M mega; s second, S siemens), and this spelling mixes them; "
            f"write {written} (or {written.upper()} in all capitals, as bench exports do)"
        )
    if key in _AMBIGUOUS:
        milli_unit, mega_unit = _AMBIGUOUS[key]
        raise UnitError(
            f"unit {unit!r} is ambiguous: write {milli_unit} (milli) or {mega_unit} (mega); "
            "unit prefixes are case-sensitive"
        )
    return UNITS[key]


def unit_dimension(unit: str) -> str:
    """Return the dimension name of a unit symbol (``"time"``, ``"force"``, ...).

    Raises
    ------
    UnitError
        If the unit is unknown; the message lists the known symbols.
    """
    try:
        return _lookup(unit)[0]
    except KeyError:
        known = sorted([k for k in UNITS if k] + list(CASED_UNITS))
        raise UnitError(f"unknown unit {unit!r}; known units: {', '.join(known)}") from None


def _factor(unit: str, dimension: str | None) -> float:
    dim = unit_dimension(unit)
    if dimension is not None and dim != dimension:
        raise UnitError(f"unit {unit!r} is a {dim} unit, expected a {dimension} unit")
    return _lookup(unit)[1]


def to_si(value: _Value, unit: str, dimension: str | None = None) -> _Value:
    """Convert ``value`` given in ``unit`` to SI (scalar or ndarray).

    Parameters
    ----------
    value : float or array_like
        Value in ``unit``.
    unit : str
        Unit symbol, e.g. ``"bar"``, ``"mm/s"``, ``"kN"``, ``"N*s/mm"``.
    dimension : str, optional
        If given, the unit must be of this dimension.
    """
    return value * _factor(unit, dimension)


def from_si(value: _Value, unit: str, dimension: str | None = None) -> _Value:
    """Convert an SI ``value`` to ``unit`` (inverse of :func:`to_si`)."""
    return value / _factor(unit, dimension)


_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([^\d\s].*)?$")


def parse_quantity(text: str, dimension: str, default_unit: str | None = None) -> float:
    """Parse ``"10mm/s"``, ``"55 bar"`` or ``"5MPa"`` into an SI float.

    Parameters
    ----------
    text : str
        A number with an optional unit. A bare number is read in ``default_unit``.
    dimension : str
        Expected dimension (``"pressure"``, ``"velocity"``, ...).
    default_unit : str, optional
        Unit of a bare number; without it a bare number is taken as SI.

    Raises
    ------
    UnitError
        If the text is not a number with a known unit of ``dimension``.
    """
    match = _QUANTITY.match(str(text).replace(",", "."))
    if not match:
        raise UnitError(
            f"cannot read {text!r} as a {dimension} (expected e.g. a number and a unit)"
        )
    number = float(match.group(1))
    unit = match.group(2)
    if unit is None:
        if default_unit is None:
            return number
        unit = default_unit
    return float(to_si(number, unit, dimension))


ZERO_CELSIUS = 273.15
"""0 degC in kelvin [K]."""
_TEMPERATURE_UNITS = {"k": 0.0, "degc": ZERO_CELSIUS, "°c": ZERO_CELSIUS, "c": ZERO_CELSIUS}


def parse_temperature(text: str | float, default_unit: str = "degC") -> float:
    """Parse ``"40 degC"``, ``"40°C"`` or ``"313.15 K"`` into kelvin [K].

    Temperatures are affine (0 degC = 273.15 K), so they are not in :data:`UNITS`.

    Parameters
    ----------
    text : str or float
        A number with an optional unit (``degC``, ``°C``, ``C`` or ``K``).
    default_unit : str
        Unit of a bare number (``"degC"`` or ``"K"``).

    Raises
    ------
    UnitError
        If the text is not a temperature or lies at or below absolute zero.

    Examples
    --------
    >>> parse_temperature("40 degC")
    313.15
    >>> parse_temperature("300K")
    300.0
    """
    match = _QUANTITY.match(str(text).replace(",", "."))
    unit = (match.group(2) if match else None) or default_unit
    offset = _TEMPERATURE_UNITS.get(_key(unit))
    if not match or offset is None:
        raise UnitError(
            f"cannot read {text!r} as a temperature (expected e.g. '40 degC' or '313.15 K')"
        )
    kelvin = float(match.group(1)) + offset
    if not kelvin > 0:
        raise UnitError(f"temperature {text!r} is at or below absolute zero")
    return kelvin
