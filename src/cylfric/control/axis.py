"""The servo-hydraulic axis: a double-acting cylinder driven by a 4/3 servo valve.

Equations (SI; Merritt 1967, ch. 5 and 6; Jelali & Kroll 2003, ch. 3):

- chamber volumes ``V_A = V_A0 + A_A x``, ``V_B = V_B0 + A_B (L - x)`` (x from the cap end);
- pressure build-up ``dp_A/dt = beta / V_A (Q_A - A_A v - C_i (p_A - p_B))`` and
  ``dp_B/dt = beta / V_B (Q_B + A_B v + C_i (p_A - p_B))`` (Jelali & Kroll eq. 3.8);
- valve (critically lapped, symmetric, sharp-edged orifices; Merritt eq. 2-4): for a spool
  opening ``s >= 0`` ``Q_A = K s r(p_S - p_A)``, ``Q_B = -K s r(p_B - p_T)``; for ``s < 0``
  ``Q_A = K s r(p_A - p_T)``, ``Q_B = -K s r(p_S - p_B)``, with ``K = Q_N / sqrt(dp_N)``
  (the valve's nominal flow ``Q_N`` at ``dp_N`` per landing) and ``r(dp) = sign(dp)
  sqrt(|dp|)``, linear below ``dp_lam`` (laminar transition, as Hopsan's and Simscape's
  orifices) so that the flow is Lipschitz in the pressures;
- spool: first order ``tau ds/dt = u - s`` or second order ``s'' = w_v^2 (u - s) - 2 zeta_v
  w_v s'`` (Jelali & Kroll sec. 3.2.4), the command ``u`` and the opening saturated at +-1;
- the load ``m dv/dt = A_A p_A - A_B p_B - F_friction - F_load`` (gauge pressures) with the
  datasheet's LuGre friction (thesis eq. 2.5) at the operating pressure of (p_A, p_B).

The hydraulic natural frequency (Merritt eq. 6-41, symmetric cylinder at mid-stroke):
``omega_h = sqrt(4 beta A^2 / (V_t m))``; in general ``omega_h = sqrt(beta (A_A^2 / V_A +
A_B^2 / V_B) / m)`` (Jelali & Kroll eq. 3.39), which :meth:`Axis.natural_frequency` returns.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..units import UnitError, parse_quantity

if TYPE_CHECKING:
    from cylfric._typing import StrPath

__all__ = ["Axis", "AxisError", "load_axis", "DEFAULT_AXIS", "AXIS_KEYS"]


class AxisError(ValueError):
    """A bad ``axis.toml`` or axis parameter (names the file, key and line)."""


# key -> (dimension, SI unit written in docs, lower bound (exclusive unless 0 allowed))
AXIS_KEYS: dict[str, tuple[str, str]] = {
    "bore": ("length", "m"),
    "rod": ("length", "m"),
    "rod_a": ("length", "m"),
    "stroke": ("length", "m"),
    "dead_volume_a": ("volume", "m^3"),
    "dead_volume_b": ("volume", "m^3"),
    "mass": ("mass", "kg"),
    "bulk_modulus": ("pressure", "Pa"),
    "leakage": ("conductance", "m^3/(s*Pa)"),
    "supply_pressure": ("pressure", "Pa"),
    "tank_pressure": ("pressure", "Pa"),
    "valve_nominal_flow": ("flow", "m^3/s"),
    "valve_nominal_drop": ("pressure", "Pa"),
    "valve_laminar_drop": ("pressure", "Pa"),
    "spool_order": ("dimensionless", "-"),
    "spool_time_constant": ("time", "s"),
    "spool_frequency": ("frequency", "Hz"),
    "spool_damping": ("dimensionless", "-"),
    "load_force": ("force", "N"),
    "start_position": ("length", "m"),
    "control_rate": ("frequency", "Hz"),
    "substeps": ("dimensionless", "-"),
    "position_resolution": ("length", "m"),
}
"""``axis.toml`` keys (table ``[axis]``): dimension and SI unit."""

# units the shared table (cylfric.units) has no dimension for
_LOCAL_UNITS = {
    "volume": {"m3": 1.0, "l": 1e-3, "L": 1e-3, "dm3": 1e-3, "cm3": 1e-6, "mm3": 1e-9},
    "flow": {
        "m3/s": 1.0,
        "l/min": 1e-3 / 60,
        "L/min": 1e-3 / 60,
        "l/s": 1e-3,
        "L/s": 1e-3,
        "cm3/s": 1e-6,
    },
    "conductance": {
        "m3/(s*Pa)": 1.0,
        "m3/s/Pa": 1.0,
        "l/min/bar": 1e-3 / 60 / 1e5,
        "L/min/bar": 1e-3 / 60 / 1e5,
    },
    "frequency": {"Hz": 1.0, "hz": 1.0, "kHz": 1e3, "khz": 1e3},
    "dimensionless": {"": 1.0, "-": 1.0},
}
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def _quantity(value: Any, dimension: str) -> float:
    """A number (SI) or a string with a unit -> SI float."""
    if isinstance(value, bool):
        raise UnitError(f"expected a number or a quantity, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value)
    if not isinstance(value, str):
        raise UnitError(f"expected a number or a quantity string, got {type(value).__name__}")
    if dimension in _LOCAL_UNITS:
        match = _NUMBER.match(value.replace(" ", ""))
        table = _LOCAL_UNITS[dimension]
        if not match or match.group(2) not in table:
            raise UnitError(
                f"cannot read {value!r} as a {dimension} (units: {sorted(k for k in table if k)})"
            )
        return float(match.group(1)) * table[match.group(2)]
    return parse_quantity(value, dimension)


@dataclass(frozen=True)
class Axis:
    """Parameters of a servo-hydraulic axis (SI). The defaults are :data:`DEFAULT_AXIS`.

    The default is an industrial double-rod servo cylinder 40/28 x 200 mm (ISO 6020-1 sizes;
    the synchronous cylinder of servo axes, Jelali & Kroll 2003 sec. 3.3) on a
    servo valve of 10 L/min at 35 bar per landing (the D633 size of Moog's catalogue) with
    100 Hz spool bandwidth, 100 bar supply, 0.1 L of hose and manifold per chamber and a
    50 kg moving load. The effective bulk modulus 1.2e9 Pa is Jelali & Kroll's (2003, sec.
    3.3) typical value for mineral oil with hoses and some entrained air; the internal
    leakage of a servo cylinder is small (1e-13 m^3/(s Pa), 0.06 L/min at 100 bar).
    """

    bore: float = 0.040
    """Piston diameter [m]."""
    rod: float = 0.028
    """Rod diameter on the B side [m]."""
    rod_a: float = 0.028
    """Rod diameter on the A side [m]: equal to ``rod`` for a double-rod (synchronous)
    cylinder, the usual servo-axis actuator; 0 for a single-rod (differential) cylinder."""
    stroke: float = 0.200
    """Stroke L [m]."""
    dead_volume_a: float = 1.0e-4
    """Volume of chamber A at x = 0 (hoses, manifold) [m^3]."""
    dead_volume_b: float = 1.0e-4
    """Volume of chamber B at x = L [m^3]."""
    mass: float = 50.0
    """Moving mass (piston, rod and load) [kg]."""
    bulk_modulus: float = 1.2e9
    """Effective bulk modulus of the oil [Pa]."""
    leakage: float = 1.0e-13
    """Internal (cross-piston) leakage coefficient C_i [m^3/(s*Pa)]."""
    supply_pressure: float = 100e5
    """Supply pressure p_S [Pa]."""
    tank_pressure: float = 0.0
    """Tank pressure p_T [Pa]."""
    valve_nominal_flow: float = 10.0e-3 / 60
    """Valve flow Q_N at full opening and ``valve_nominal_drop`` per landing [m^3/s]."""
    valve_nominal_drop: float = 35e5
    """Pressure drop per landing at which Q_N is rated [Pa]."""
    valve_laminar_drop: float = 1e5
    """Pressure drop below which an orifice flow is taken as linear [Pa]."""
    spool_order: int = 2
    """1 (first order, ``spool_time_constant``) or 2 (``spool_frequency``, ``spool_damping``)."""
    spool_time_constant: float = 2e-3
    """Time constant of a first-order spool [s]."""
    spool_frequency: float = 100.0
    """Natural frequency of a second-order spool [Hz]."""
    spool_damping: float = 0.7
    """Damping ratio of a second-order spool [-]."""
    load_force: float = 0.0
    """Constant external force against extension [N]."""
    start_position: float = 0.100
    """Position x at t = 0 [m] (mid-stroke by default)."""
    control_rate: float = 1000.0
    """Controller sample rate [Hz]."""
    substeps: int = 10
    """Integration steps of the plant per controller sample [-] (10 at 1 kHz: 100 us, where
    the demo loop's PI-alone RMS error agrees with 100 substeps to 1e-4 relative, the LuGre
    loop's 0.1 um residual to 1.5 %)."""

    position_resolution: float = 0.0
    """Quantum of the position measurement the controller reads [m] (``round(x / q) q``;
    0: exact). A 1 um encoder or transducer: ``position_resolution = "0.001 mm"``."""

    def __post_init__(self) -> None:
        self._check_positive()
        self._check_ranges()

    def _check_positive(self) -> None:
        """Every size, rate and valve value must be finite and > 0."""
        positive = (
            "bore",
            "stroke",
            "dead_volume_a",
            "dead_volume_b",
            "mass",
            "bulk_modulus",
            "supply_pressure",
            "valve_nominal_flow",
            "valve_nominal_drop",
            "valve_laminar_drop",
            "spool_time_constant",
            "spool_frequency",
            "spool_damping",
            "control_rate",
        )
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise AxisError(f"axis {name} = {value!r} is out of range; expected > 0")

    def _check_ranges(self) -> None:
        """Rods inside the bore, leakage, pressures, spool order, start, substeps, load."""
        for name in ("rod", "rod_a"):
            value = getattr(self, name)
            if not (0 <= value < self.bore):
                raise AxisError(
                    f"axis {name} = {value!r} m; expected 0 <= {name} < bore {self.bore} m"
                )
        if not (0 <= self.leakage < 1e-6):
            raise AxisError(f"axis leakage = {self.leakage!r}; expected 0 <= C_i < 1e-6 m^3/(s*Pa)")
        if not (0 <= self.tank_pressure < self.supply_pressure):
            raise AxisError("axis tank_pressure must be >= 0 and below supply_pressure")
        if self.spool_order not in (1, 2):
            raise AxisError(f"axis spool_order = {self.spool_order!r}; expected 1 or 2")
        if not (0 < self.start_position < self.stroke):
            raise AxisError(
                f"axis start_position = {self.start_position!r} m; expected inside "
                f"(0, stroke = {self.stroke} m)"
            )
        if not (isinstance(self.substeps, int) and 1 <= self.substeps <= 10000):
            raise AxisError(f"axis substeps = {self.substeps!r}; expected an integer 1..10000")
        if not (math.isfinite(self.position_resolution) and 0 <= self.position_resolution < 1e-3):
            raise AxisError(
                f"axis position_resolution = {self.position_resolution!r} m; expected 0 <= q < 1 mm"
            )
        if not math.isfinite(self.load_force):
            raise AxisError("axis load_force must be finite")

    # ------------------------------------------------------------------ derived
    @property
    def area_a(self) -> float:
        """Piston area on the A side A_A [m^2]."""
        return math.pi / 4 * (self.bore**2 - self.rod_a**2)

    @property
    def area_b(self) -> float:
        """Annulus area A_B [m^2]."""
        return math.pi / 4 * (self.bore**2 - self.rod**2)

    @property
    def valve_coefficient(self) -> float:
        """Orifice coefficient K = Q_N / sqrt(dp_N) [m^3/(s*sqrt(Pa))]."""
        return self.valve_nominal_flow / math.sqrt(self.valve_nominal_drop)

    @property
    def sample_time(self) -> float:
        """Controller sample time T [s]."""
        return 1.0 / self.control_rate

    def volumes(self, position: float) -> tuple[float, float]:
        """Chamber volumes (V_A, V_B) [m^3] at ``position`` x [m]."""
        return (
            self.dead_volume_a + self.area_a * position,
            self.dead_volume_b + self.area_b * (self.stroke - position),
        )

    def hydraulic_stiffness(self, position: float | None = None) -> float:
        """Oil-spring stiffness ``beta (A_A^2/V_A + A_B^2/V_B)`` [N/m] at ``position`` [m]."""
        va, vb = self.volumes(self.start_position if position is None else position)
        return self.bulk_modulus * (self.area_a**2 / va + self.area_b**2 / vb)

    def natural_frequency(self, position: float | None = None) -> float:
        """Hydraulic natural frequency omega_h [rad/s] (Jelali & Kroll eq. 3.39).

        For a symmetric cylinder at mid-stroke it is Merritt's ``sqrt(4 beta A^2/(V_t m))``.
        """
        return math.sqrt(self.hydraulic_stiffness(position) / self.mass)

    def rest_pressures(self) -> tuple[float, float]:
        """Chamber pressures (p_A, p_B) [Pa] of the axis at rest with the valve at null.

        The critically lapped valve at null holds both chambers at the pressure its leakage
        paths would share; here: force balance ``A_A p_A - A_B p_B = F_load`` with the
        chambers as far from supply and tank as the areas allow (``p_A + p_B = p_S + p_T``
        for a symmetric cylinder).
        """
        ps, pt = self.supply_pressure, self.tank_pressure
        aa, ab = self.area_a, self.area_b
        # A_A p_A - A_B p_B = F and p_A + p_B = p_S + p_T
        pb = (aa * (ps + pt) - self.load_force) / (aa + ab)
        return ps + pt - pb, pb

    def no_load_velocity_gain(self) -> tuple[float, float]:
        """Steady piston speed per unit valve opening [m/s] (extension, retraction).

        Closed form of the orifice equations with ``A_A p_A = A_B p_B`` (no load, no
        friction, no leakage, turbulent orifices): extension ``p_B = (p_S + p_T/a^2) /
        (a + 1/a^2)``, ``v = K sqrt(p_B - p_T) / A_B``; retraction ``p_B = (p_S + a^2 p_T) /
        (1 + a^3)``, ``v = K sqrt(p_S - p_B) / A_B``, with ``a = A_B / A_A``.
        """
        a = self.area_b / self.area_a
        ps, pt, k = self.supply_pressure, self.tank_pressure, self.valve_coefficient
        pb_out = (ps + pt / a**2) / (a + 1 / a**2)
        pb_in = (ps + a**2 * pt) / (1 + a**3)
        return k * math.sqrt(pb_out - pt) / self.area_b, k * math.sqrt(ps - pb_in) / self.area_b

    def vector(self) -> np.ndarray:
        """The parameters as the compiled loop's array (order of :data:`_VECTOR`)."""
        values = {
            **asdict(self),
            "area_a": self.area_a,
            "area_b": self.area_b,
            "valve_coefficient": self.valve_coefficient,
        }
        values["spool_omega"] = 2 * math.pi * self.spool_frequency
        return np.array([float(values[k]) for k in _VECTOR])

    def replace(self, **changes: Any) -> Axis:
        """A copy with some parameters changed."""
        return replace(self, **changes)

    def to_dict(self) -> dict[str, float]:
        """The parameters (SI) by name."""
        return asdict(self)


_VECTOR = (
    "area_a",
    "area_b",
    "stroke",
    "dead_volume_a",
    "dead_volume_b",
    "mass",
    "bulk_modulus",
    "leakage",
    "supply_pressure",
    "tank_pressure",
    "valve_coefficient",
    "valve_laminar_drop",
    "spool_order",
    "spool_time_constant",
    "spool_omega",
    "spool_damping",
    "load_force",
    "position_resolution",
)
"""Order of :meth:`Axis.vector` (the compiled loop reads it by index)."""

DEFAULT_AXIS = Axis()
"""The documented default axis (see :class:`Axis`)."""

_INTEGER_KEYS = ("spool_order", "substeps")


def _line_of(text: str, key: str) -> int | None:
    pattern = re.compile(rf"^\s*{re.escape(key)}\s*=")
    for number, line in enumerate(text.splitlines(), 1):
        if pattern.match(line):
            return number
    return None


def load_axis(path: StrPath) -> Axis:
    """Read an ``axis.toml``: table ``[axis]`` with any of :data:`AXIS_KEYS` (others default).

    Values are numbers in SI or strings with units (``bore = "40 mm"``, ``dead_volume_a =
    "0.1 L"``, ``valve_nominal_flow = "10 L/min"``, ``leakage = "0.001 L/min/bar"``,
    ``spool_frequency = "100 Hz"``). Errors (:class:`AxisError`) name the file, key and line.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        doc = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise AxisError(f"{path}: not a readable TOML file ({exc})") from None
    unknown = sorted(set(doc) - {"axis"})
    if unknown:
        raise AxisError(f"{path}: unknown table or key {unknown[0]!r}; expected only [axis]")
    table = doc.get("axis", {})
    if not isinstance(table, dict):
        raise AxisError(f"{path}: 'axis' must be a table [axis]")
    values: dict[str, Any] = {}
    for key, raw in table.items():
        where = f"{path}, line {_line_of(text, key)}"
        if key not in AXIS_KEYS:
            raise AxisError(f"{where}: unknown key axis.{key}; valid: {sorted(AXIS_KEYS)}")
        dimension, unit = AXIS_KEYS[key]
        try:
            value = _quantity(raw, dimension)
        except UnitError as exc:
            raise AxisError(f"{where}: axis.{key}: {exc} (SI unit {unit})") from None
        if key in _INTEGER_KEYS:
            if value != int(value):
                raise AxisError(f"{where}: axis.{key} = {raw!r}; expected an integer")
            value = int(value)
        values[key] = value
    try:
        return Axis(**values)
    except AxisError as exc:
        bad = next((k for k in values if f" {k} " in f"{exc} "), None)
        line = f", line {_line_of(text, bad)}" if bad else ""
        raise AxisError(f"{path}{line}: {exc}") from None


assert set(AXIS_KEYS) == {f.name for f in fields(Axis)}
