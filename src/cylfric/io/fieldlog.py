"""Readers of a working machine's own logs (``cylfric fit-field``) and their ``field.toml``.

A log holds time, rod position, the two pressures and optionally the valve command, as a
PLC or a Simulink logger writes them: delimited text with units in the header
(``position [mm]``; read by :func:`cylfric.io.text.read_bench_arrays`), MATLAB ``.mat`` v5
(scipy) or v7.3 (HDF5, h5py: ``pip install 'cylfric[field]'``). ``field.toml`` names the
cylinder and the columns::

    [cylinder]
    bore = "125 mm"
    rod = "70 mm"
    orientation = "A extends"     # pressure_a acts on the piston side; or "B extends"
    extension = "position increases"   # or "position decreases" (a sensor counting down)

    [columns]                     # role = column or variable name in the logs
    time = "time"
    position = "position"         # grows as the rod extends
    pressure_a = "p_A"
    pressure_b = "p_B"
    valve = "valve command"       # optional: finds valve steps

    [units]                       # for .mat logs (text logs carry units in their header)
    position = "mm"
    pressure_a = "bar"
    pressure_b = "bar"

    [sensors]                     # where each pressure is measured
    pressure_a = "chamber"        # or "valve side" (between the valve and a
    pressure_b = "chamber"        #  counter-balance / load-holding valve)

    [days]
    pattern = '(\\d{4}-\\d{2}-\\d{2})'   # the day of a log from its file name (else its stem)

    [fit]                         # all optional
    min_speed = "10 mm/s"
    load_degree = 6
    mass_degree = 2
    level = 0.95
    change_level = 0.99
    reproducibility = "0 %"       # between-day scatter of an unchanged machine, if known

Errors name the file, the line and the key (:class:`~cylfric.io.text.BenchFileError`).
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..units import UnitError, parse_quantity, to_si, unit_dimension
from .text import BenchFileError

if TYPE_CHECKING:
    from cylfric._typing import StrPath

__all__ = [
    "FieldConfig",
    "FieldRecord",
    "load_field_config",
    "read_field_log",
    "read_field_logs",
    "SENSOR_PLACES",
    "H5PY_HINT",
]

ROLES = {
    "time": "time",
    "position": "length",
    "pressure_a": "pressure",
    "pressure_b": "pressure",
    "valve": None,
}
"""Roles of [columns] and the dimension of each (the valve command: any unit, kept as read)."""
REQUIRED_ROLES = ("time", "position", "pressure_a", "pressure_b")
SENSOR_PLACES = ("chamber", "valve side")
ORIENTATIONS = ("A extends", "B extends")
EXTENSIONS = ("position increases", "position decreases")
H5PY_HINT = "pip install 'cylfric[field]' (or: pip install h5py)"
_TABLE_KEYS = {
    "cylinder": {"bore", "rod", "orientation", "extension"},
    "columns": set(ROLES),
    "units": set(ROLES) - {"valve"},
    "sensors": {"pressure_a", "pressure_b"},
    "days": {"pattern"},
    "fit": {
        "min_speed",
        "load_degree",
        "mass_degree",
        "level",
        "change_level",
        "reproducibility",
    },
}


@dataclass(frozen=True)
class FieldConfig:
    """The cylinder and the signals of a machine's logs (``field.toml``), in SI.

    Attributes
    ----------
    bore, rod : float
        Piston and rod diameters [m].
    orientation : str
        ``"A extends"`` (pressure_a on the piston side) or ``"B extends"``.
    extension : str
        ``"position increases"`` (default) or ``"position decreases"`` as the rod extends.
    columns : dict
        Role -> column or variable name.
    units : dict
        Role -> unit of a ``.mat`` variable (default SI).
    sensors : dict
        ``pressure_a``/``pressure_b`` -> ``"chamber"`` or ``"valve side"``.
    day_pattern : str
        Regular expression; its first group (or whole match) in a file name is the day.
    fit : dict
        ``min_speed`` [m/s], ``load_degree``, ``mass_degree`` [-], ``level``,
        ``change_level`` [-], ``reproducibility`` [-] (relative).
    source : str or None
        The file read.
    """

    bore: float
    rod: float
    orientation: str = "A extends"
    extension: str = "position increases"
    columns: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)
    sensors: dict = field(
        default_factory=lambda: dict.fromkeys(("pressure_a", "pressure_b"), "chamber")
    )
    day_pattern: str = r"(\d{4}-\d{2}-\d{2})"
    fit: dict = field(default_factory=dict)
    source: str | None = None

    @property
    def area_piston(self) -> float:
        """Piston-side area [m^2]."""
        return math.pi / 4 * self.bore**2

    @property
    def area_annulus(self) -> float:
        """Rod-side area [m^2]."""
        return math.pi / 4 * (self.bore**2 - self.rod**2)

    def areas(self) -> tuple[float, float]:
        """(area acted on by pressure_a, area acted on by pressure_b) [m^2]."""
        if self.orientation == "A extends":
            return self.area_piston, self.area_annulus
        return self.area_annulus, self.area_piston

    def error(self, table: str | None, key: str, message: str) -> BenchFileError:
        """A :class:`BenchFileError` naming this file and the line of ``[table] key``."""
        line = _line_of(self.source, key, table) if self.source else None
        where = f"{table}.{key}" if table else key
        return BenchFileError(self.source or "field config", f"{where}: {message}", line=line)


@dataclass
class FieldRecord:
    """One log in SI: ``time`` [s], ``position`` [m], ``pressure_a``/``pressure_b`` [Pa],
    ``valve`` (as logged, or None), with its ``name``, ``day`` and ``metadata``."""

    name: str
    day: str
    time: np.ndarray
    position: np.ndarray
    pressure_a: np.ndarray
    pressure_b: np.ndarray
    valve: np.ndarray | None
    metadata: dict[str, Any]


def _line_of(path, key, table=None) -> int | None:
    """1-based line of ``key = ...`` (or of the table ``[key]``), inside ``[table]`` if given."""
    pattern = re.compile(rf"^\s*(\[\s*{re.escape(key)}\s*\]|\"?{re.escape(key)}\"?\s*=)")
    current = None
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    for number, line in enumerate(text.splitlines(), 1):
        header = re.match(r"^\s*\[\s*([^\]]+?)\s*\]", line)
        if header and not pattern.match(line):
            current = header.group(1)
            continue
        if pattern.match(line) and (table is None or current == table):
            return number
    return None


def load_field_config(path: StrPath) -> FieldConfig:
    """Read and check ``field.toml`` (see the module docstring).

    Raises
    ------
    BenchFileError
        Invalid TOML, an unknown table or key, a missing required key, a value of the wrong
        kind or unit; the message names the file, the line and the key.
    """
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise BenchFileError(path, f"invalid TOML ({exc})") from None
    except OSError as exc:
        raise BenchFileError(path, f"cannot read the file ({exc.strerror})") from None

    def fail(table, key, message):
        line = _line_of(path, key, table)
        where = f"{table}.{key}" if table and key else (table or key)
        return BenchFileError(path, f"{where}: {message}", line=line)

    for table, content in doc.items():
        if table not in _TABLE_KEYS:
            raise fail(None, table, f"unknown table; valid: {sorted(_TABLE_KEYS)}")
        if not isinstance(content, dict):
            raise fail(None, table, "expected a table ([" + table + "])")
        for key in content:
            if key not in _TABLE_KEYS[table]:
                raise fail(table, key, f"unknown key; valid: {sorted(_TABLE_KEYS[table])}")
    cylinder = doc.get("cylinder", {})
    sizes = {}
    for key in ("bore", "rod"):
        if key not in cylinder:
            raise fail("cylinder", key, 'missing; expected a length such as "125 mm"')
        try:
            sizes[key] = parse_quantity(str(cylinder[key]), "length", default_unit="mm")
        except UnitError as exc:
            raise fail("cylinder", key, str(exc)) from None
    if not 0 < sizes["rod"] < sizes["bore"]:
        raise fail("cylinder", "rod", "expected 0 < rod < bore")
    orientation = cylinder.get("orientation", "A extends")
    if orientation not in ORIENTATIONS:
        raise fail("cylinder", "orientation", f"{orientation!r}; valid: {list(ORIENTATIONS)}")
    extension = cylinder.get("extension", "position increases")
    if extension not in EXTENSIONS:
        raise fail("cylinder", "extension", f"{extension!r}; valid: {list(EXTENSIONS)}")
    columns = doc.get("columns", {})
    for role in REQUIRED_ROLES:
        if role not in columns:
            raise fail("columns", role, "missing; name the log's column or variable")
    for role, name in columns.items():
        if not isinstance(name, str) or not name.strip():
            raise fail("columns", role, "expected a column name (text)")
    units = doc.get("units", {})
    for role, unit in units.items():
        try:
            dimension = unit_dimension(str(unit))
        except UnitError as exc:
            raise fail("units", role, str(exc)) from None
        if dimension != ROLES[role]:
            raise fail(
                "units", role, f"{unit!r} is a {dimension} unit; expected a {ROLES[role]} unit"
            )
    sensors = {"pressure_a": "chamber", "pressure_b": "chamber", **doc.get("sensors", {})}
    for key, place in sensors.items():
        if place not in SENSOR_PLACES:
            raise fail("sensors", key, f"{place!r}; valid: {list(SENSOR_PLACES)}")
    pattern = doc.get("days", {}).get("pattern", r"(\d{4}-\d{2}-\d{2})")
    try:
        re.compile(pattern)
    except (re.error, TypeError) as exc:
        raise fail("days", "pattern", f"not a regular expression ({exc})") from None
    fit = _fit_options(doc.get("fit", {}), fail)
    return FieldConfig(
        bore=sizes["bore"],
        rod=sizes["rod"],
        orientation=orientation,
        extension=extension,
        columns=dict(columns),
        units=dict(units),
        sensors=sensors,
        day_pattern=pattern,
        fit=fit,
        source=str(path),
    )


def _fit_options(table, fail) -> dict[str, Any]:
    options: dict[str, Any] = {}
    if "min_speed" in table:
        try:
            options["min_speed"] = parse_quantity(str(table["min_speed"]), "velocity", "mm/s")
        except UnitError as exc:
            raise fail("fit", "min_speed", str(exc)) from None
        if not options["min_speed"] > 0:
            raise fail("fit", "min_speed", "expected a speed > 0")
    for key, low, high in (("load_degree", 0, 12), ("mass_degree", 0, 4)):
        if key in table:
            value = table[key]
            if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
                raise fail("fit", key, f"{value!r}; expected an integer {low}..{high}")
            options[key] = value
    for key in ("level", "change_level"):
        if key in table:
            value = table[key]
            if not isinstance(value, float | int) or not 0.5 <= value < 1:
                raise fail("fit", key, f"{value!r}; expected a number 0.5 <= level < 1")
            options[key] = float(value)
    if "reproducibility" in table:
        text = str(table["reproducibility"]).strip()
        match = re.fullmatch(r"([0-9.eE+-]+)\s*%", text)
        if not match:
            raise fail("fit", "reproducibility", f'{text!r}; expected a percentage such as "3 %"')
        value = float(match.group(1))
        if not 0 <= value < 100:
            raise fail("fit", "reproducibility", "expected 0 % to 100 %")
        options["reproducibility"] = value / 100
    return options


def day_of(path: Path, pattern: str) -> str:
    """The day a log belongs to: ``pattern``'s first group in the file name, else its stem."""
    match = re.search(pattern, path.name)
    if match is None:
        return path.stem
    return match.group(1) if match.groups() else match.group(0)


def read_field_log(path: StrPath, config: FieldConfig) -> FieldRecord:
    """Read one log (text, ``.mat`` v5 or v7.3) into SI arrays.

    Raises
    ------
    BenchFileError
        Unreadable file, a missing column (named with its ``field.toml`` key and line),
        non-finite samples (the sample and, in a text log, the line), time not increasing.
    ImportError
        A v7.3 ``.mat`` file and h5py not installed (the message gives the install command).
    """
    path = Path(path)
    if not path.is_file():
        raise BenchFileError(path, "no such file")
    if path.suffix.lower() == ".mat":
        signals, metadata = _read_mat(path, config)
    else:
        signals, metadata = _read_text(path, config)
    time = signals["time"]
    for role, values in signals.items():
        if role == "valve" or values is None:
            continue
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            where = f"sample {bad[0] + 1}"
            line = None
            if metadata["kind"] == "text":
                from .text import data_row_line

                line = data_row_line(path, int(bad[0]))
            raise BenchFileError(
                path,
                f"{config.columns[role]!r} ({role}) is not finite at {where} "
                f"({bad.size} samples); expected numbers",
                line=line,
            )
    if time.size < 10:
        raise BenchFileError(path, f"{time.size} samples; expected a log of at least 10")
    steps = np.diff(time)
    if np.any(steps <= 0):
        first = int(np.flatnonzero(steps <= 0)[0]) + 1
        raise BenchFileError(
            path, f"time does not increase at sample {first + 1}; expected increasing time"
        )
    return FieldRecord(
        name=path.name,
        day=day_of(path, config.day_pattern),
        time=time,
        position=signals["position"],
        pressure_a=signals["pressure_a"],
        pressure_b=signals["pressure_b"],
        valve=signals.get("valve"),
        metadata=metadata,
    )


def read_field_logs(paths, config: FieldConfig) -> list[FieldRecord]:
    """Read several logs (files in the order given); see :func:`read_field_log`."""
    return [read_field_log(p, config) for p in paths]


def _missing(path, config, role, found) -> BenchFileError:
    line = _line_of(config.source, role, "columns") if config.source else None
    listed = ", ".join(
        f if isinstance(f, str) and f.startswith("[") else repr(f) for f in sorted(found)[:12]
    )
    return BenchFileError(
        path,
        f"no column {config.columns[role]!r} (columns.{role} in {config.source or 'field.toml'}"
        + (f", line {line}" if line else "")
        + f"); found {listed}",
    )


def _read_text(path: Path, config: FieldConfig):
    from .text import read_bench_arrays

    roles = {r: config.columns[r] for r in REQUIRED_ROLES}
    try:
        arrays, metadata = read_bench_arrays(path, roles=roles)
    except BenchFileError as exc:
        # the text reader words a missing role for campaign.toml: name field.toml instead
        named = re.search(
            r"\[columns\] (\w+) = .* names no column; the file has (.*)$", exc.message
        )
        if named is None:
            raise
        raise _missing(path, config, named.group(1), [named.group(2)]) from None
    names = metadata.get("columns", [])
    signals: dict[str, np.ndarray | None] = {}
    for role in REQUIRED_ROLES:
        if config.columns[role] not in names:
            raise _missing(path, config, role, names)
        key = f"{role} [{ {'time': 's', 'position': 'm'}.get(role, 'Pa') }]"
        signals[role] = np.asarray(arrays[key], dtype=float)
    if "valve" in config.columns:
        name = config.columns["valve"]
        keys = [k for k in arrays if k.startswith(f"{name} [")]
        if not keys:
            raise _missing(path, config, "valve", names)
        signals["valve"] = np.asarray(arrays[keys[0]], dtype=float)
    return signals, {"file": str(path), "kind": "text", "units": metadata.get("units", {})}


def _is_mat73(path: Path) -> bool:
    with open(path, "rb") as handle:
        head = handle.read(520)
    return (
        head.startswith(b"MATLAB 7.3")
        or head[512:520] == b"\x89HDF\r\n\x1a\n"
        or head[:8] == b"\x89HDF\r\n\x1a\n"
    )


def _read_mat(path: Path, config: FieldConfig):
    if _is_mat73(path):
        variables = _read_hdf5(path, config)
        kind = "mat v7.3"
    else:
        from scipy.io import loadmat
        from scipy.io.matlab import MatReadError

        try:
            content = loadmat(path, squeeze_me=True)
        except (MatReadError, ValueError, TypeError, OSError, NotImplementedError) as exc:
            raise BenchFileError(path, f"not a readable MATLAB .mat file ({exc})") from None
        variables = {k: v for k, v in content.items() if not k.startswith("__")}
        kind = "mat v5"
    signals: dict[str, np.ndarray | None] = {}
    for role, name in config.columns.items():
        if name not in variables:
            raise _missing(path, config, role, variables)
        values = np.asarray(variables[name])
        if (
            values.dtype.kind not in "fiu"
            or values.ndim > 2
            or (values.ndim == 2 and min(values.shape) != 1)
        ):
            raise BenchFileError(
                path, f"variable {name!r} ({role}) is not a numeric vector (shape {values.shape})"
            )
        values = values.astype(float).ravel()
        dimension = ROLES[role]
        if dimension is not None:
            unit = config.units.get(role, {"time": "s", "length": "m", "pressure": "Pa"}[dimension])
            values = to_si(values, unit, dimension)
        signals[role] = values
    sizes = {role: v.size for role, v in signals.items() if v is not None}
    if len(set(sizes.values())) > 1:
        raise BenchFileError(path, f"the variables differ in length ({sizes}); expected one length")
    return signals, {"file": str(path), "kind": kind, "units": dict(config.units)}


def _read_hdf5(path: Path, config: FieldConfig) -> dict[str, np.ndarray]:
    try:
        import h5py
    except ImportError:
        raise ImportError(
            f"{path}: a MATLAB v7.3 (HDF5) file needs h5py; install it: {H5PY_HINT}"
        ) from None
    variables = {}
    try:
        with h5py.File(path, "r") as handle:
            for name in config.columns.values():
                node = handle.get(name)
                if isinstance(node, h5py.Dataset):
                    variables[name] = np.asarray(node[()])
            found = [k for k, v in handle.items() if isinstance(v, h5py.Dataset)]
    except OSError as exc:
        raise BenchFileError(path, f"not a readable MATLAB v7.3 (HDF5) file ({exc})") from None
    for role, name in config.columns.items():
        if name not in variables:
            raise _missing(path, config, role, found)
    return variables
