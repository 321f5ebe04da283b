"""Campaigns: a folder of runs, their per-run metadata and the rig configuration.

Per-run metadata (chamber pressure, nominal speed, temperature) comes from, in this order:
``manifest.csv`` in the folder (``file,pressure_bar,velocity_mm_s`` and optional columns;
an oil temperature column ``temperature_C`` or ``temperature [degC]`` (or in kelvin
``temperature_K``, ``temperature [K]``) becomes the points' ``temperature [K]``),
``campaign.toml`` (a file-name pattern with named groups), ``key: value`` header lines of the
file, and file-name tokens (``55bar``, ``p55bar``, ``55.5bar``, ``10mms``, ``v10mms``,
``10mm_s``). Measured pressure and velocity columns win over these nominal values.
"""

from __future__ import annotations

import codecs
import csv
import fnmatch
import functools
import io
import math
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple

from ..friction.pressure import PRESSURE_REFERENCES, pressure_reference_basis
from ..units import UnitError, parse_quantity, parse_temperature
from .matfile import read_mat
from .text import BenchFileError, read_bench_arrays, si_columns

__all__ = [
    "Campaign",
    "CampaignConfig",
    "Duplicate",
    "find_duplicates",
    "find_near_duplicates",
    "OilSettings",
    "RunInfo",
    "load_config",
    "discover_runs",
    "read_run",
    "name_tokens",
    "CONFIG_NAME",
    "DYNAMIC_TESTS",
    "MANIFEST_NAME",
]

CONFIG_NAME = "campaign.toml"
DYNAMIC_TESTS = ("presliding", "breakaway")
"""Test kinds of manifest.csv's ``test`` column that are not constant-velocity runs: they
go to :mod:`cylfric.identify.dynamic`, never to the steady-state extraction."""
MANIFEST_NAME = "manifest.csv"
TEMPERATURE_COLUMNS = {
    "temperature_c": 273.15,
    "temperature [degc]": 273.15,
    "temperature_k": 0.0,
    "temperature [k]": 0.0,
}
"""manifest.csv columns of the oil temperature of each run (lower-cased) -> offset to
kelvin; read into the points' ``temperature [K]`` column."""
_SKIP_NAMES = {CONFIG_NAME, MANIFEST_NAME, "points.csv", "datasheet.json", "README.md", "LICENSE"}
_PRESSURE_TOKEN = re.compile(
    r"(?:^|[^A-Za-z0-9.])p?(\d+(?:[.,]\d+)?)\s*(bar|mpa|kpa|psi)(?![a-z])", re.IGNORECASE
)
_VELOCITY_TOKEN = re.compile(
    r"(?:^|[^A-Za-z0-9.])v?(\d+(?:[.,]\d+)?)\s*(mms|mm_s|mm-s|mmps|mm/s)", re.IGNORECASE
)
_HEADER_KEYS = {
    "pressure": ("pressure", "chamber pressure", "druck", "tryck", "system pressure"),
    "velocity": ("nominal velocity", "velocity", "speed", "test speed", "geschwindigkeit"),
    "temperature": ("temperature", "oil temperature", "temp"),
}


@dataclass(frozen=True)
class OilSettings:
    """The oil of a campaign (``campaign.toml [oil]``), for the viscosity correction.

    Attributes
    ----------
    points : ((float, float), (float, float))
        Two (temperature [K], kinematic viscosity [m^2/s]) points of the oil's data sheet
        (``viscosity_40C``, ``viscosity_100C``), as :func:`cylfric.viscosity.walther_viscosity`
        takes them.
    reference_temperature : float
        Temperature the datasheet is identified at [K] (default 40 degC, where ISO 3448
        grades oils).
    temperature : float or None
        Oil temperature of every run without its own in ``manifest.csv`` [K].
    source : str
        The campaign.toml it came from.
    """

    points: tuple
    reference_temperature: float = 313.15
    temperature: float | None = None
    source: str = ""


@dataclass(frozen=True)
class CampaignConfig:
    """Rig and file configuration of a campaign (``campaign.toml``), SI units.

    Attributes
    ----------
    glob : str
        Which files of the folder are runs: a pattern relative to the campaign folder
        (``"*.txt"``, ``"runs/*.txt"``); an absolute pattern or one with a ``..`` part is
        refused (:func:`check_glob`), so runs are never read from outside the folder.
    name_pattern : str or None
        Regular expression with named groups (``pressure_bar``, ``velocity_mm_s`` and any
        others, e.g. ``seal``) matched against the file name.
    columns, units : list of str or None
        Column map of headerless files.
    delimiter, decimal : str
        As for :func:`cylfric.io.read_bench_text`.
    area_a, area_b : float
        Piston areas seen by chambers A and B [m^2] (from bore/rod diameters and ``kind``).
    cylinder : dict or None
        ``[cylinder]`` as stated: ``kind``, ``bore`` [m], ``rod`` [m] (None when not stated);
        None without the table; recorded in the datasheet.
    load_cell_sign : float
        +1 if the load cell reads positive when it pushes the rod towards extension.
    position_sign : float
        +1 if the position column grows on extension.
    moving_mass : float
        Rod, piston and load-cell mass for the inertia term [kg] (0: neglected).
    force_source : {"load_cell", "pressures"}
        Where the force balance takes the force from: ``"load_cell"`` (a force column,
        plus the chamber terms when areas are given) or ``"pressures"`` (a rig without a load
        cell: ``A_a p_a - A_b p_b - m x''`` only, no force column needed and no weight
        offset removed).
    extraction : dict
        Keyword options for :func:`cylfric.steady_state.extract_points`.
    roles : dict
        Quantity -> column name chosen in ``[columns]`` (``force = "Axial Force"``).
    oil : OilSettings or None
        The ``[oil]`` table (viscosity correction), None without it.
    pressure_basis : dict
        The pressure reference the laws are fitted and evaluated in and why
        (:func:`cylfric.friction.pressure.pressure_reference_basis`: ``kind``, ``rule``,
        ``chamber``, ``stated_by``), from ``[cylinder] kind`` and ``pressure_reference``.
    """

    glob: str = "*"
    name_pattern: str | None = None
    columns: list | None = None
    units: list | None = None
    delimiter: str = "auto"
    decimal: str = "auto"
    area_a: float = 0.0
    area_b: float = 0.0
    load_cell_sign: float = 1.0
    position_sign: float = 1.0
    moving_mass: float = 0.0
    force_source: str = "load_cell"
    extraction: dict = field(default_factory=dict)
    source: str | None = None
    roles: dict = field(default_factory=dict)
    oil: OilSettings | None = None
    pressure_basis: dict = field(default_factory=lambda: pressure_reference_basis(None))
    cylinder: dict | None = None

    @property
    def pressure_reference(self) -> str:
        """The rule the laws see the chamber pressures by (``"a"``, ``"mean"``, ...)."""
        return str(self.pressure_basis["rule"])


class RunInfo:
    """A run file with its nominal metadata (SI; NaN when unknown).

    ``source`` says where the pressure and velocity used came from; ``nominal`` holds every
    value found for them, ``{quantity: {source: (value [SI], where)}}``, so that the
    data-quality gate can compare the sources (:func:`cylfric.quality.assess`).

    Immutable. A run whose values all come from manifest.csv (the common case) keeps no
    dictionaries of its own: ``source`` and ``nominal`` are made from ``pressure``,
    ``velocity`` and ``manifest_line`` when asked for, and an empty ``extra`` is not kept
    (about 1 kB a run less: 20 MB at 20,000 runs, which a forked reader would copy too).
    """

    __slots__ = (
        "path",
        "pressure",
        "velocity",
        "manifest_line",
        "manifest",
        "session",
        "_extra",
        "_source",
        "_nominal",
    )
    path: Path
    pressure: float  # [Pa]
    velocity: float  # [m/s]
    manifest_line: int | None  # the run's row in manifest.csv (1 = the header)
    manifest: Path | None  # the manifest.csv that lists the run
    session: str | None  # the session the run belongs to (see session_of)
    _extra: dict | None  # None: no labels
    _source: dict | None  # None: made from the manifest's values (_from_manifest)
    _nominal: dict | None  # None: the same

    def __init__(
        self,
        path: Path,
        pressure: float = math.nan,
        velocity: float = math.nan,
        extra: dict | None = None,
        source: dict | None = None,
        nominal: dict | None = None,
        manifest_line: int | None = None,
        manifest: Path | None = None,
        session: str | None = None,
    ) -> None:
        kept = ("path", "pressure", "velocity", "manifest_line", "manifest", "session")
        values = (path, pressure, velocity, manifest_line, manifest, session)
        for name, value in zip(kept, values, strict=True):
            object.__setattr__(self, name, value)
        source, nominal = source or {}, nominal or {}
        derived = _from_manifest(self, source, nominal)
        object.__setattr__(self, "_extra", extra or None)
        object.__setattr__(self, "_source", None if derived else source)
        object.__setattr__(self, "_nominal", None if derived else nominal)

    @property
    def extra(self) -> dict:
        """The run's labels (manifest.csv's other columns, name_pattern's other groups, the
        session); not to be modified."""
        return self._extra if self._extra is not None else {}

    @property
    def source(self) -> dict[str, str]:
        """Where the pressure and velocity used come from, ``{quantity: source}``; not to
        be modified."""
        if self._source is not None:
            return self._source
        return _manifest_sources(self.pressure, self.velocity, self.manifest_line)[0]

    @property
    def nominal(self) -> dict[str, dict[str, tuple[float, str]]]:
        """Every value found for the pressure and velocity, ``{quantity: {source: (value
        [SI], where)}}``; not to be modified."""
        if self._nominal is not None:
            return self._nominal
        return _manifest_sources(self.pressure, self.velocity, self.manifest_line)[1]

    @property
    def seal(self) -> str | None:
        """The run's seal label: a ``seal`` group of ``name_pattern`` or the manifest.csv
        column ``seal`` (the manifest wins); None when the campaign does not say."""
        return _label(self._extra.get("seal")) if self._extra else None

    def replace(self, **changes: Any) -> RunInfo:
        """A copy with ``changes`` (the constructor's names: ``path=``, ``manifest=``, ...)."""
        return RunInfo(**{**dict(zip(_RUN_FIELDS, self._fields(), strict=True)), **changes})

    def _fields(self) -> tuple:
        return (
            self.path,
            self.pressure,
            self.velocity,
            self.extra,
            self.source,
            self.nominal,
            self.manifest_line,
            self.manifest,
            self.session,
        )

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"RunInfo is immutable: cannot set {name!r}")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"RunInfo is immutable: cannot delete {name!r}")

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._fields() == other._fields()

    __hash__ = None  # type: ignore[assignment]  # holds dicts, as it always did

    def __reduce__(self):
        return (RunInfo, self._fields())

    def __repr__(self) -> str:
        inner = ", ".join(f"{n}={v!r}" for n, v in zip(_RUN_FIELDS, self._fields(), strict=True))
        return f"RunInfo({inner})"


_RUN_FIELDS = (
    "path",
    "pressure",
    "velocity",
    "extra",
    "source",
    "nominal",
    "manifest_line",
    "manifest",
    "session",
)
"""RunInfo's constructor arguments, in order (its repr, replace and pickle)."""


def _nan(value: float) -> bool:
    return isinstance(value, float) and math.isnan(value)


def _from_manifest(info: RunInfo, source: Mapping, nominal: Mapping) -> bool:
    """Whether ``source`` and ``nominal`` are exactly what :func:`_manifest_nominal` makes
    from manifest.csv's row ``info.manifest_line`` for ``info`` (the same keys in the same
    order, ``info``'s own value objects), so that the properties give them back as given."""
    if type(source) is not dict or type(nominal) is not dict:
        return False
    if list(nominal) != ["pressure", "velocity"]:
        return False
    where = f"{MANIFEST_NAME} line {info.manifest_line}"
    used = []
    for quantity in ("pressure", "velocity"):
        value, found = getattr(info, quantity), nominal[quantity]
        if type(found) is not dict:
            return False
        if _nan(value):
            if found:
                return False
            continue
        entry = found.get("manifest")
        if (
            info.manifest_line is None
            or len(found) != 1
            or type(entry) is not tuple
            or len(entry) != 2
            or entry[0] is not value
            or entry[1] != where
        ):
            return False
        used.append(quantity)
    return list(source.items()) == [(quantity, "manifest") for quantity in used]


def _label(value) -> str | None:
    """A label cell or name group as text, None when empty or missing (NaN)."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return None
    text = str(value).strip()
    return text or None


class Duplicate(NamedTuple):
    """A run file whose bytes equal an earlier run's (same SHA-256), or whose samples do
    with other header lines (``same_header`` False: :func:`find_near_duplicates`): not
    read, counted once.

    ``file`` and ``original`` are relative to the campaign folder; ``seal`` is the label of
    ``file`` (None without one)."""

    file: str
    original: str
    seal: str | None = None
    same_header: bool = True

    @property
    def reason(self) -> str:
        """The line excluded.csv and the command line give for it."""
        if not self.same_header:
            return (
                f"duplicate of {self.original} (the same samples, SHA-256 of the data block; "
                "only the header lines differ): counted once, not read"
            )
        return f"duplicate of {self.original} (the same bytes, SHA-256): counted once, not read"


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's bytes (hex), read in blocks (also the datasheet's
    ``file_digest``)."""
    import hashlib

    with open(path, "rb") as handle:
        return hashlib.file_digest(handle, "sha256").hexdigest()


EDGE_BYTES = 4096
"""Bytes read at each end of a file to tell same-size files apart before hashing them
whole (:func:`find_duplicates`)."""


def _edges_digest(path: Path, size: int) -> int:
    """CRC-32 of a file's first and last :data:`EDGE_BYTES` bytes (all of a short one): one
    open, unbuffered, and two reads.

    Only a filter: files whose edges agree are then compared by their SHA-256, so a CRC
    collision costs a whole-file hash, never a wrong duplicate.
    """
    import zlib

    with open(path, "rb", buffering=0) as handle:
        checksum = zlib.crc32(handle.read(EDGE_BYTES))
        if size > 2 * EDGE_BYTES:
            handle.seek(size - EDGE_BYTES)
        return zlib.crc32(handle.read(EDGE_BYTES), checksum)


def find_duplicates(paths) -> dict[Path, Path]:
    """Files whose bytes equal an earlier file's of ``paths``, each -> that first file.

    Files are grouped by size, then by their first and last :data:`EDGE_BYTES` bytes (a
    CRC-32 of them); only files that share both are hashed whole (SHA-256). A campaign
    whose files all differ in size is not read here, and thousands of runs of one length (a
    bench's fixed sample count) cost one open and two short reads each, not a pass over
    every byte. Files that cannot be read are left to the reader (which names them).
    """
    by_size: dict[int, list[Path]] = {}
    for path in paths:
        try:
            size = os.stat(path).st_size
        except OSError:
            continue
        by_size.setdefault(size, []).append(path if isinstance(path, Path) else Path(path))
    by_edges: dict[tuple, list[Path]] = {}
    for size, group in by_size.items():
        if len(group) > 1:
            _group_by_edges(group, size, by_edges)
    copies: dict[Path, Path] = {}
    for group in by_edges.values():
        if len(group) > 1:
            copies.update(_copies_by_content(group))
    return copies


def _group_by_edges(group: list[Path], size: int, by_edges: dict[tuple, list[Path]]) -> None:
    """Add the files of ``group`` (all ``size`` bytes) to ``by_edges`` under (size, the
    digest of their first and last bytes); a file that cannot be read is left out."""
    for path in group:
        try:
            by_edges.setdefault((size, _edges_digest(path, size)), []).append(path)
        except OSError:
            continue


def _copies_by_content(group: list[Path]) -> dict[Path, Path]:
    """Each file of ``group`` whose SHA-256 equals an earlier one's -> that earlier file."""
    copies: dict[Path, Path] = {}
    first: dict[str, Path] = {}
    for path in group:
        try:
            digest = file_sha256(path)
        except OSError:
            continue
        if digest in first:
            copies[path] = first[digest]
        else:
            first[digest] = path
    return copies


HEAD_BYTES = 65536
"""Most bytes read from the start of a text run to find where its header ends
(:func:`find_near_duplicates`); a file whose header is longer is compared whole."""


def _mark(byte: int) -> int:
    """How :func:`_data_offset` sees a byte: ``0`` a digit, ``.`` a sign, separator or
    letter of a number (e, NaN, inf), a space, a newline, or ``x`` anything else."""
    char = chr(byte)
    if char.isascii() and char.isdigit():
        return ord("0")
    if char in " \t\r":
        return ord(" ")
    if char == "\n":
        return ord("\n")
    return ord(".") if char in ".,;:+-eEnNaAiIfF" else ord("x")


_MARKS = bytes(_mark(byte) for byte in range(256))
_FIRST_ROW = re.compile(rb"^[ .]*0[0 .]*$", re.MULTILINE)
"""A line of :data:`_MARKS` that is a row of numbers (at least one digit, nothing else)."""


def _data_offset(head: bytes, whole: bool) -> int | None:
    """Byte offset where the numeric block of a text run begins, from its first bytes
    ``head`` (``whole``: the entire file): the start of the first line that is only numbers;
    None for a binary file (NUL bytes) or a header longer than ``head``.

    Everything from there on is compared, segment markers included, so a header misread
    (a line of digits in it) can only make a near-duplicate go unfound, never make two
    different runs one. A translation and one regular-expression search in C."""
    if b"\x00" in head:
        return None
    if not whole:
        head = head[: head.rfind(b"\n") + 1]  # a line cut off by the read is not judged
    found = _FIRST_ROW.search(head.translate(_MARKS))
    return None if found is None else found.start()


def _data_key(path: Path, size: int) -> tuple[int, int, int] | None:
    """(offset of the numeric block, its size, CRC-32 of its part within the first
    :data:`EDGE_BYTES` bytes) of a text run, or None (binary, or no row of numbers within
    :data:`HEAD_BYTES`). One open and, for a usual header, one read."""
    import zlib

    with open(path, "rb", buffering=0) as handle:
        head = handle.read(min(size, EDGE_BYTES))
        offset = _data_offset(head, whole=len(head) == size)
        if offset is None and size > EDGE_BYTES:
            head += handle.read(HEAD_BYTES - len(head))
            offset = _data_offset(head, whole=len(head) == size)
    if offset is None:
        return None
    return offset, size - offset, zlib.crc32(head[offset:])


def _data_sha256(path: Path, offset: int) -> str:
    """SHA-256 of a file's bytes from ``offset`` on (its numeric block), read in blocks."""
    import hashlib

    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        handle.seek(offset)
        while block := handle.read(1 << 20):
            digest.update(block)
    return digest.hexdigest()


def _tail_crc(path: Path, size: int) -> int:
    """CRC-32 of a file's last :data:`EDGE_BYTES` bytes."""
    import zlib

    with open(path, "rb", buffering=0) as handle:
        handle.seek(max(size - EDGE_BYTES, 0))
        return zlib.crc32(handle.read(EDGE_BYTES))


def find_near_duplicates(paths) -> dict[Path, Path]:
    """Text runs whose numeric block equals an earlier file's of ``paths`` while the header
    lines may differ (a copy with a header line changed), each -> that first file.

    Only the numbers are compared, never the header: each file's first 4 KiB are read to
    find where its numbers begin (:func:`_data_offset`); files are grouped by the size of
    that block and a CRC-32 of its first bytes, then by a CRC-32 of their last
    :data:`EDGE_BYTES` bytes, and only files that share all three are hashed (SHA-256 of
    the block). ``.mat`` files, binary files and headers longer than :data:`HEAD_BYTES` are
    left to :func:`find_duplicates`. Byte-for-byte copies are found here too;
    :class:`Campaign` asks :func:`find_duplicates` first and tells them apart.
    """
    groups: dict[tuple[int, int], list[tuple[Path, int, int]]] = {}
    for path in paths:
        path = path if isinstance(path, Path) else Path(path)
        if path.suffix.lower() == ".mat":
            continue
        try:
            size = os.stat(path).st_size
            key = _data_key(path, size)
        except OSError:
            continue
        if key is not None and key[1] > 0:
            groups.setdefault(key[1:], []).append((path, key[0], size))
    copies: dict[Path, Path] = {}
    for group in groups.values():
        if len(group) < 2:
            continue
        by_tail: dict[int, list[tuple[Path, int]]] = {}
        for path, offset, size in group:
            try:
                by_tail.setdefault(_tail_crc(path, size), []).append((path, offset))
            except OSError:
                continue
        for same in by_tail.values():
            if len(same) > 1:
                copies.update(_same_data(same))
    return copies


def _same_data(group: list[tuple[Path, int]]) -> dict[Path, Path]:
    """Each file of ``group`` (path, offset of its numeric block) whose block's SHA-256
    equals an earlier one's -> that earlier file."""
    copies: dict[Path, Path] = {}
    first: dict[str, Path] = {}
    for path, offset in group:
        try:
            digest = _data_sha256(path, offset)
        except OSError:
            continue
        if digest in first:
            copies[path] = first[digest]
        else:
            first[digest] = path
    return copies


class _Manifest(dict):
    """Rows of manifest.csv, file -> (pressure [Pa], velocity [m/s], extra); ``lines``:
    file -> line number."""

    def __init__(self):
        super().__init__()
        self.lines = {}


def _quantity(value, dimension, default_unit, where):
    try:
        number = parse_quantity(str(value), dimension, default_unit=default_unit)
    except UnitError as exc:
        raise BenchFileError(where, f"{exc}") from None
    if not math.isfinite(number):  # '1e400 bar', 'inf bar': no law can be fitted to it
        raise BenchFileError(where, f"{value!r} is not a finite {dimension}")
    return number


def load_config(folder, file=None) -> CampaignConfig:
    """Read ``campaign.toml`` of ``folder`` (defaults when absent), or the recipe ``file``.

    ``file`` (a ``--config``): a campaign.toml kept outside the data folder, e.g. a shipped
    recipe for read-only data; it must exist, and its errors name it and their line. The
    config's ``source`` is the path read (None for the defaults).

    The file has the tables ``[files]`` (``glob``, ``name_pattern``), ``[columns]``
    (``names``, ``units``, ``delimiter``, ``decimal``), ``[cylinder]`` (``bore``, ``rod``,
    ``kind`` = ``"double-rod"``, ``"single-rod"`` or ``"single-acting"``,
    ``pressure_reference`` = ``"a"``, ``"b"``, ``"sum"``, ``"mean"`` or ``"max"``: the
    pressure the laws see; a single-acting cylinder's is its working chamber A, a
    double-acting one's defaults to ``"mean"``), ``[force_balance]``
    (``load_cell_sign``, ``position_sign``, ``moving_mass``, ``force`` = ``"load_cell"`` or
    ``"pressures"``), ``[extraction]`` and ``[oil]``
    (``viscosity_40C``, ``viscosity_100C``, ``reference_temperature``, ``temperature``).
    Values with units are strings such as ``"25 mm"``, ``"46 mm2/s"``, ``"40 degC"``.
    """
    if file is not None:
        path = Path(file)
        if not path.is_file():
            raise BenchFileError(
                path, "recipe not found; expected a campaign.toml file (--config FILE)"
            )
    else:
        path = Path(folder) / CONFIG_NAME
        if not path.is_file():
            return CampaignConfig()
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise BenchFileError(path, f"invalid TOML ({exc})") from None
    except RecursionError:
        raise BenchFileError(path, "invalid TOML (arrays or tables nested too deeply)") from None
    _validate_config(doc, path)
    files, cols = doc.get("files", {}), doc.get("columns", {})
    cyl, fb = doc.get("cylinder", {}), doc.get("force_balance", {})
    area_a = area_b = 0.0
    cylinder = None
    try:
        pressure_basis = pressure_reference_basis(
            cyl.get("kind"), cyl.get("pressure_reference"), where=CONFIG_NAME
        )
    except ValueError as exc:
        raise BenchFileError(path, str(exc), line=_line_of(path, "pressure_reference")) from None
    for table, key, example in _UNIT_REQUIRED:
        _check_unit_given(doc.get(table, {}), table, key, example, path)
    if cyl:
        bore = _quantity(cyl.get("bore", "0 mm"), "length", "mm", path)
        rod = _quantity(cyl.get("rod", "0 mm"), "length", "mm", path)
        kind = cyl.get("kind", "double-rod")
        for key, value in (("bore", bore), ("rod", rod)):
            if not (math.isfinite(value) and abs(value) <= MAX_DIAMETER):
                raise BenchFileError(
                    path,
                    f"cylinder.{key} = {value:g} m is not a cylinder's diameter; expected at "
                    f'most {MAX_DIAMETER:g} m, e.g. {key} = "40 mm"',
                    line=_line_of(path, key),
                )
        piston = math.pi / 4 * bore**2
        annulus = piston - math.pi / 4 * rod**2
        kinds = {
            "double-rod": (annulus, annulus),
            "single-rod": (piston, annulus),
            "single-acting": (piston, 0.0),
        }
        if kind not in kinds:
            raise BenchFileError(path, f"unknown cylinder kind {kind!r}; valid: {sorted(kinds)}")
        if bore < 0 or rod < 0:
            key, value = ("bore", bore) if bore < 0 else ("rod", rod)
            raise BenchFileError(
                path,
                f"cylinder.{key} is negative ({value * 1e3:g} mm); expected a diameter > 0, "
                'e.g. bore = "40 mm"',
                line=_line_of(path, key),
            )
        if not bore > 0:
            raise BenchFileError(
                path,
                'cylinder.bore is missing or 0; expected e.g. bore = "40 mm"',
                line=_line_of(path, "bore"),
            )
        if rod >= bore:
            raise BenchFileError(
                path,
                f"cylinder.rod ({rod * 1e3:g} mm) must be smaller than the bore "
                f"({bore * 1e3:g} mm)",
                line=_line_of(path, "rod"),
            )
        area_a, area_b = kinds[kind]
        cylinder = {"kind": kind, "bore": bore, "rod": rod if "rod" in cyl else None}
    names, units = cols.get("names"), cols.get("units")
    if (names is None) != (units is None) or (names and len(names) != len(units)):
        raise BenchFileError(path, "[columns] needs `names` and `units` of the same length")
    for key in ("load_cell_sign", "position_sign"):
        if fb.get(key, 1) not in (1, -1):
            raise BenchFileError(path, f"force_balance.{key} must be 1 or -1")
    moving_mass = _quantity(fb.get("moving_mass", "0 kg"), "mass", "kg", path)
    if not (math.isfinite(moving_mass) and moving_mass >= 0):
        raise BenchFileError(
            path,
            f"force_balance.moving_mass is {fb['moving_mass']!r}; expected a mass >= 0, "
            'e.g. moving_mass = "12 kg"',
            line=_line_of(path, "moving_mass"),
        )
    force_source = fb.get("force", "load_cell")
    if force_source == "pressures" and not (area_a or area_b):
        raise BenchFileError(
            path,
            'force_balance.force = "pressures" needs the piston areas: give [cylinder] bore, '
            'rod and kind (e.g. bore = "40 mm", rod = "25 mm", kind = "single-rod")',
            line=_line_of(path, "force"),
        )
    return CampaignConfig(
        glob=files.get("glob", "*"),
        name_pattern=files.get("name_pattern"),
        columns=names,
        units=units,
        delimiter=cols.get("delimiter", "auto"),
        decimal=cols.get("decimal", "auto"),
        area_a=area_a,
        area_b=area_b,
        load_cell_sign=float(fb.get("load_cell_sign", 1)),
        position_sign=float(fb.get("position_sign", 1)),
        moving_mass=moving_mass,
        force_source=force_source,
        extraction={
            key: int(value) if key in COUNT_KEYS else value
            for key, value in doc.get("extraction", {}).items()
        },
        source=str(path),
        roles={k: v for k, v in cols.items() if k in ROLES},
        oil=_oil(doc["oil"], path) if "oil" in doc else None,
        pressure_basis=pressure_basis,
        cylinder=cylinder,
    )


_UNIT_REQUIRED = (
    ("cylinder", "bore", "40 mm"),
    ("cylinder", "rod", "28 mm"),
    ("force_balance", "moving_mass", "12 kg"),
)
"""(table, key, example) of campaign.toml values that must carry their unit."""
_BARE_NUMBER = re.compile(r"^\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*$")


def _check_unit_given(table: dict, name: str, key: str, example: str, path: Path) -> None:
    """Refuse ``key = "25"`` (a number without its unit, other than 0) in ``[name]``: mm or
    m, kg or g cannot be guessed (a bore taken in the wrong one is 1000x off)."""
    text = table.get(key)
    if isinstance(text, str) and _BARE_NUMBER.match(text) and float(text) != 0:
        raise BenchFileError(
            path,
            f"{name}.{key} = {text!r} has no unit; write the value with its unit, e.g. "
            f'{key} = "{example}"',
            line=_line_of(path, key),
        )


def _oil(table: dict, path: Path) -> OilSettings:
    """``[oil]`` in SI, checked: two data-sheet viscosities falling with temperature, within
    the Walther equation's range, and temperatures in 200-450 K."""

    def quantity(key, parse):
        try:
            return parse(table[key])
        except UnitError as exc:
            raise BenchFileError(path, f"oil.{key}: {exc}", line=_line_of(path, key)) from None

    def viscosity(key):
        return quantity(key, lambda text: parse_quantity(text, "kinematic viscosity", "mm2/s"))

    def temperature(key):
        kelvin = quantity(key, parse_temperature)
        if not 200.0 <= kelvin <= 450.0:
            raise BenchFileError(
                path,
                f"oil.{key} = {table[key]!r} ({kelvin - 273.15:.4g} degC): expected an oil "
                "temperature between -73 and 177 degC (200-450 K)",
                line=_line_of(path, key),
            )
        return kelvin

    nu40, nu100 = viscosity("viscosity_40C"), viscosity("viscosity_100C")
    for key, nu in (("viscosity_40C", nu40), ("viscosity_100C", nu100)):
        if not 2e-6 <= nu <= 1e-2:
            raise BenchFileError(
                path,
                f"oil.{key} = {table[key]!r}: expected a kinematic viscosity of 2 to 10000 "
                "mm2/s (the Walther equation of ASTM D341 holds from 2 mm2/s)",
                line=_line_of(path, key),
            )
    if not nu40 > nu100:
        raise BenchFileError(
            path,
            f"oil.viscosity_40C ({nu40 * 1e6:g} mm2/s) must be larger than oil.viscosity_100C "
            f"({nu100 * 1e6:g} mm2/s): an oil thins as it warms",
            line=_line_of(path, "viscosity_100C"),
        )
    return OilSettings(
        points=((313.15, nu40), (373.15, nu100)),
        reference_temperature=(
            temperature("reference_temperature") if "reference_temperature" in table else 313.15
        ),
        temperature=temperature("temperature") if "temperature" in table else None,
        source=str(path),
    )


_QUANTITY_TEXT = {"type": "string", "minLength": 1}
MAX_COUNT = 1_000_000_000
"""Largest sample count ``[extraction]`` may give (a billion samples: hours of a 100 kHz
record)."""
COUNT_KEYS = ("min_samples", "median_window", "skip_start", "skip_end")
"""``[extraction]`` keys that are counts of samples, passed on as ``int``."""
FORCE_SOURCES = ("load_cell", "pressures")
"""Values of ``[force_balance] force``: a load-cell column, or the chamber pressures times the
areas (a rig without a load cell, such as a valve-driven axis)."""
ROLES = ("time", "position", "force", "pressure", "pressure_a", "pressure_b", "velocity")
"""Quantities a ``[columns]`` key can assign to a named column (``force = "Axial Force"``)."""
CONFIG_SCHEMA = {
    "type": "object",
    "additionalProperties": False,
    "properties": {
        "files": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "glob": {"type": "string", "minLength": 1},
                "name_pattern": {"type": "string"},
            },
        },
        "columns": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "names": {"type": "array", "items": {"type": "string"}, "minItems": 1},
                "units": {"type": "array", "items": {"type": "string"}, "minItems": 1},
                "delimiter": {"enum": ["auto", "tab", "semicolon", "comma", "whitespace"]},
                "decimal": {"enum": ["auto", ".", ","]},
                **{role: {"type": "string", "minLength": 1} for role in ROLES},
            },
        },
        "cylinder": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "bore": _QUANTITY_TEXT,
                "rod": _QUANTITY_TEXT,
                "kind": {"enum": ["double-rod", "single-rod", "single-acting"]},
                "pressure_reference": {"enum": sorted(PRESSURE_REFERENCES)},
            },
        },
        "force_balance": {
            "type": "object",
            "additionalProperties": False,
            "properties": {
                "load_cell_sign": {"enum": [1, -1]},
                "position_sign": {"enum": [1, -1]},
                "moving_mass": _QUANTITY_TEXT,
                "force": {"enum": list(FORCE_SOURCES)},
            },
        },
        "extraction": {
            "type": "object",
            "properties": {
                "method": {"type": "string"},
                # counts of samples: whole numbers (10.0 is accepted as 10), at most a
                # billion (1e12 is a float TOML calls a number, not a count of samples)
                "min_samples": {"type": "integer", "minimum": 1, "maximum": MAX_COUNT},
                "median_window": {"type": "integer", "minimum": 1, "maximum": MAX_COUNT},
                "skip_start": {"type": "integer", "minimum": 0, "maximum": MAX_COUNT},
                "skip_end": {"type": "integer", "minimum": 0, "maximum": MAX_COUNT},
                # thresholds [-] and the velocity window [s]: positive
                **{
                    key: {"type": "number", "exclusiveMinimum": 0}
                    for key in (
                        "moving_fraction",
                        "settle_tolerance",
                        "trim_sigma",
                        "spike_sigma",
                        "settle_sigma",
                        "settle_force_tolerance",
                        "velocity_window",
                    )
                },
                "trim_floor": {"type": "number", "minimum": 0},
            },
            "additionalProperties": {"type": "number"},
        },
        "oil": {
            "type": "object",
            "additionalProperties": False,
            "required": ["viscosity_40C", "viscosity_100C"],
            "properties": {
                "viscosity_40C": _QUANTITY_TEXT,
                "viscosity_100C": _QUANTITY_TEXT,
                "reference_temperature": _QUANTITY_TEXT,
                "temperature": _QUANTITY_TEXT,
            },
        },
    },
}
"""JSON Schema of campaign.toml (tables and keys; extraction keys are checked by name later)."""


def _line_of(path, key) -> int | None:
    """1-based line of ``key = ...`` (or ``[key]``) in a TOML file, for error messages."""
    name = re.escape(key)  # bare, or quoted as "bore " (a quoted key may hold spaces)
    pattern = re.compile(rf"""^\s*(\[\s*{name}\s*\]|{name}\s*=|(["']){name}\2\s*=)""")
    for number, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
        if pattern.match(line):
            return number
    return None


def _validate_config(doc, path):
    """Raise BenchFileError naming the key (and its line) of the first schema violation."""
    import jsonschema

    validator = jsonschema.Draft202012Validator(CONFIG_SCHEMA)
    errors = sorted(validator.iter_errors(doc), key=lambda e: (len(e.path), list(e.path)))
    if errors:
        error = errors[0]
        where = ".".join(str(p) for p in error.path)
        if error.validator == "additionalProperties":
            extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
            valid = sorted(error.schema.get("properties", {}))
            table = f"[{where}] " if where else ""
            raise BenchFileError(
                path,
                f"unknown key {extra[0]!r} in {table or 'the top level '}(valid: {valid})",
                line=_line_of(path, extra[0]),
            )
        key = str(error.path[-1]) if error.path else ""
        raise BenchFileError(
            path, f"{where}: {error.message}", line=_line_of(path, key) if key else None
        )
    glob = doc.get("files", {}).get("glob")
    if glob is not None:
        check_glob(glob, path, line=_line_of(path, "glob"))
    pattern = doc.get("files", {}).get("name_pattern")
    if pattern is not None:
        compile_name_pattern(pattern, path)


PATTERN_LIMIT = 500
"""Longest ``name_pattern`` [characters]: RE2's time is linear in the file name but grows
with the pattern (10,000 groups took 36 s and 4.6 GB for one file name)."""
PATTERN_GROUPS = 30
"""Most groups a ``name_pattern`` may have."""


@functools.lru_cache(maxsize=16)
def _re2(pattern: str) -> object:
    """``pattern`` compiled by RE2, once per process (load_config checks it, _discover uses
    it); an RE2 error is raised (and not cached)."""
    import re2

    options = re2.Options()
    options.log_errors = False  # the caller raises the error; RE2 prints nothing on stderr
    options.max_mem = 8 << 20  # RE2's own default: a larger program is refused, not built
    return re2.compile(pattern, options=options)


def compile_name_pattern(pattern: str, path=None):
    """``[files] name_pattern`` compiled by RE2, whose matching time is linear in the name.

    A user's pattern is matched with google-re2 rather than Python's backtracking ``re``, so
    that no pattern (``^(a+)+$`` against a long file name) can hang a fit. RE2 has no
    back-references and no look-around; such a pattern is refused naming campaign.toml, its
    line and what RE2 said.

    Parameters
    ----------
    pattern : str
        The regular expression (Python/RE2 syntax; named groups ``(?P<pressure>...)``).
    path : path-like, optional
        The campaign.toml it came from (for the error).

    Returns
    -------
    re2._Regexp
        A compiled pattern with ``search`` and ``groupdict`` as :mod:`re` has them.
    """
    import re2

    where = path if path is not None else "campaign.toml"
    line = _line_of(path, "name_pattern") if path is not None else None
    groups = pattern.count("(") - pattern.count(r"\(") - pattern.count("(?:")
    if len(pattern) > PATTERN_LIMIT or groups > PATTERN_GROUPS:
        raise BenchFileError(
            where,
            f"files.name_pattern is {len(pattern)} characters with {groups} groups; at most "
            f"{PATTERN_LIMIT} characters and {PATTERN_GROUPS} groups (a file name is short: "
            "name the few groups it carries, e.g. '^(?P<seal>.+)_(?P<pressure_bar>[0-9.]+)bar')",
            line=line,
        )
    try:
        return _re2(pattern)
    except re2.error as exc:
        reason = exc.args[0] if exc.args else exc
        if isinstance(reason, bytes):
            reason = reason.decode("utf-8", "replace")
        raise BenchFileError(
            where,
            f"files.name_pattern is not a regular expression RE2 accepts ({reason}); "
            "cylfric matches file names in linear time with RE2, which has no "
            "back-references (\\1) and no look-around ((?=...), (?<=...)): write the "
            "pattern without them",
            line=line,
        ) from None


MAX_DIAMETER = 10.0
"""Largest bore or rod diameter [m] campaign.toml may give (the largest presses' cylinders
are about 3 m)."""

GLOB_LIMIT = 200
"""Longest ``glob`` [characters] a campaign may give."""


def check_glob(glob: str, where, line=None, key="files.glob") -> str:
    """Refuse a glob that would reach outside the campaign folder: absolute (``/data/*.txt``,
    ``C:/...``) or with a ``..`` part; and one that could not end in time or names no files:
    more than one ``**`` (pathlib's search is combinatorial in them on deep folders: five took
    two minutes on a 40-level chain), ``**`` inside a component, longer than
    :data:`GLOB_LIMIT`, empty or ``.``. BenchFileError naming ``where`` (campaign.toml, with
    the line of the key, or the campaign folder for ``--glob``) and what to write."""
    text = glob.replace("\\", "/")
    parts = [p for p in text.split("/") if p]
    problem = None
    if len(glob) > GLOB_LIMIT:
        problem = f"is {len(glob)} characters long (at most {GLOB_LIMIT})"
    elif not parts or all(p == "." for p in parts):
        problem = "names no files"
    elif sum(p == "**" for p in parts) > 1:
        problem = "has more than one '**' (any depth is one '**')"
    elif any("**" in p and p != "**" for p in parts):
        problem = "has '**' inside a name ('**' stands alone between slashes)"
    if problem:
        raise BenchFileError(
            where,
            f"{key} = {glob[:80]!r}{'...' if len(glob) > 80 else ''} {problem}; write a "
            'pattern such as glob = "*.txt", "runs/*.txt" or "**/*.txt"',
            line=line,
        )
    absolute = text.startswith("/") or re.match(r"^[A-Za-z]:", text) is not None  # or C:
    if absolute or ".." in text.split("/"):
        problem = "is absolute" if absolute else "climbs out of the campaign folder with '..'"
        raise BenchFileError(
            where,
            f"{key} = {glob!r} {problem}; run files are searched in the campaign folder only: "
            'write a pattern relative to it, e.g. glob = "*.txt" or "runs/*.txt" (or fit the '
            "folder that holds the files)",
            line=line,
        )
    return glob


def name_tokens(name: str) -> dict:
    """Pressure [Pa] and velocity [m/s] from file-name tokens such as ``p55bar_v10mms``."""
    return {quantity: value for quantity, (value, _) in _tokens(name).items()}


def _tokens(name: str) -> dict:
    """Quantity -> (value [SI], the token as written) of the file-name tokens."""
    out = {}
    match = _PRESSURE_TOKEN.search(name)
    if match:
        value = parse_quantity(match.group(1) + match.group(2), "pressure")
        out["pressure"] = value, match.group(0).lstrip("_-. ")
    match = _VELOCITY_TOKEN.search(name)
    if match:
        value = float(match.group(1).replace(",", ".")) * 1e-3
        out["velocity"] = value, match.group(0).lstrip("_-. ")
    return out


_MANIFEST_COLUMNS = ("file", "pressure_bar", "velocity_mm_s")
# a column named like a pressure or a speed without the unit the manifest needs: refused, not
# kept as a label ('pressure' in bar or psi? 'velocity' in mm/s or m/s?)
_QUANTITY_COLUMN = re.compile(
    r"^(p|pressure|press|druck|tryck|v|vel|velocity|speed|geschwindigkeit|hastighet)"
    r"($|[\s_\[(/.-])"
)


def _utf16_byte_order(data: bytes) -> str | None:
    """``"little"`` or ``"big"`` when ``data`` is UTF-16 text without a byte-order mark.

    Excel and LabVIEW exports write it so: in the first line every other byte is NUL (the high
    byte of a Latin character) and the bytes between are not. UTF-8 text has no NUL bytes, so
    the test cannot take a UTF-8 manifest for UTF-16.
    """
    head = data[: 2 * 4096]
    for order, text_at, nul_at in (("little", 0, 1), ("big", 1, 0)):
        units = [(head[i + text_at], head[i + nul_at]) for i in range(0, len(head) - 1, 2)]
        first_line = []
        for unit in units:
            if unit == (0x0A, 0):
                break
            first_line.append(unit)
        if len(first_line) >= 2 and all(low and not high for low, high in first_line):
            return order
    return None


_BOMS = (
    ("utf-32", (codecs.BOM_UTF32_LE, codecs.BOM_UTF32_BE)),
    ("utf-16", (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)),
)
"""Byte-order marks of manifest.csv read as such, in the order they are tried."""


def _manifest_text(path: Path) -> str:
    """Text of manifest.csv: UTF-8 (with or without a BOM), UTF-16 (with or without one) or
    UTF-32 with a BOM."""
    data = path.read_bytes()
    for codec, boms in _BOMS:  # UTF-32 first: its little-endian mark begins like UTF-16's
        if data.startswith(boms):
            try:
                return data.decode(codec)
            except UnicodeDecodeError as exc:
                raise BenchFileError(
                    path, f"starts like {codec.upper()} text but does not decode ({exc.reason})"
                ) from None
    order = _utf16_byte_order(data)
    if order is not None:
        try:
            return data.decode("utf-16-le" if order == "little" else "utf-16-be")
        except UnicodeDecodeError as exc:
            raise BenchFileError(
                path,
                f"is UTF-16 ({order} endian) without a byte-order mark but does not decode "
                f"({exc.reason}); save it as UTF-8 or UTF-16 with a BOM",
            ) from None
    if b"\x00" in data:  # UTF-16 whose first line is not Latin text, or a binary file
        raise BenchFileError(
            path,
            "holds NUL bytes; expected a CSV file in UTF-8 (a UTF-16 file without a byte-order "
            "mark is read only when its first line is Latin text): save it as UTF-8 or UTF-16 "
            "with a BOM",
            line=data[: data.index(b"\x00")].count(b"\n") + 1,
        )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise BenchFileError(
            path,
            f"byte 0x{data[exc.start]:02x} is not UTF-8 text; expected a CSV file in UTF-8 "
            "(or UTF-16, as Excel's 'Unicode text' writes)",
            line=line,
        ) from None


def _manifest_delimiter(path: Path, header: str) -> str:
    """The separator of manifest.csv's header row: a comma, else a semicolon or a tab."""
    if "," in header:
        return ","
    for delimiter in (";", "\t"):
        if delimiter in header:
            return delimiter
    if header.strip().lower() == "file":
        return ","
    raise BenchFileError(
        path,
        f"header row {header.strip()!r} has no separator; expected comma-separated columns "
        "starting with 'file' (file,pressure_bar,velocity_mm_s)",
        line=1,
    )


def _number(text: str, delimiter: str) -> float:
    """A manifest cell as a float (a decimal comma where the separator is not a comma)."""
    return float(text.replace(",", ".") if delimiter != "," else text)


def _read_manifest(folder: Path) -> _Manifest:
    path = folder / MANIFEST_NAME
    rows = _Manifest()
    if not path.is_file():
        return rows
    text = _manifest_text(path)
    delimiter = _manifest_delimiter(path, text.split("\n", 1)[0])
    reader = csv.DictReader(  # lines end at \n, \r\n or \r only (not at U+2028, \x0c, ...)
        io.StringIO(text, newline=""), delimiter=delimiter, skipinitialspace=True
    )
    if reader.fieldnames:  # 'file, pressure_bar' or 'File' are the same columns
        reader.fieldnames = [name.strip().lower() for name in reader.fieldnames]
    expected = ",".join(_MANIFEST_COLUMNS)
    if not reader.fieldnames or "file" not in reader.fieldnames:
        raise BenchFileError(
            path,
            f"expected a header row starting with 'file' ({expected}); found "
            f"{reader.fieldnames or 'an empty first line'}",
            line=1,
        )
    unclear = [
        name
        for name in reader.fieldnames
        if name not in _MANIFEST_COLUMNS and _QUANTITY_COLUMN.match(name)
    ]
    if unclear:
        raise BenchFileError(
            path,
            f"column(s) {unclear} not understood (found {reader.fieldnames}); expected "
            f"{expected}: the pressure in bar as pressure_bar and the speed in mm/s as "
            "velocity_mm_s (other columns, such as seal or test, are kept as labels)",
            line=1,
        )
    known = {*_MANIFEST_COLUMNS, *TEMPERATURE_COLUMNS}  # the columns that are not labels
    for number, row in _manifest_rows(reader, path):
        row = {k: (v.strip() if isinstance(v, str) else v) for k, v in row.items()}
        if not any(v for k, v in row.items() if k):  # a blank line
            continue
        extra = {k: v for k, v in row.items() if k and k not in known}
        temperature = _manifest_temperature(row, path, number, delimiter)
        if temperature is not None:
            extra["temperature [K]"] = temperature
        try:
            pressure = (
                _number(row["pressure_bar"], delimiter) * 1e5
                if row.get("pressure_bar")
                else math.nan
            )
            velocity = (
                _number(row["velocity_mm_s"], delimiter) * 1e-3
                if row.get("velocity_mm_s")
                else math.nan
            )
        except ValueError:
            raise BenchFileError(
                path, "pressure_bar and velocity_mm_s must be numbers", line=number
            ) from None
        if not (math.isnan(pressure) or (math.isfinite(pressure) and pressure >= 0)):
            raise BenchFileError(
                path,
                f"pressure_bar = {row['pressure_bar']} of {row['file']}; expected a finite "
                "pressure >= 0 bar",
                line=number,
            )
        if not (math.isnan(velocity) or (math.isfinite(velocity) and velocity != 0)):
            raise BenchFileError(
                path,
                f"velocity_mm_s = {row['velocity_mm_s']} of {row['file']}; expected a "
                "finite speed other than 0 mm/s",
                line=number,
            )
        if not row.get("file"):
            raise BenchFileError(path, "no file name; expected one in the 'file' column", number)
        _check_row_path(row["file"], path, number)
        if row["file"] in rows:
            raise BenchFileError(
                path, f"{row['file']} is listed twice; expected one row per file", line=number
            )
        rows[row["file"]] = (pressure, velocity, extra)
        rows.lines[row["file"]] = number
    return rows


def _check_row_path(name: str, path: Path, number: int) -> None:
    """Refuse a manifest row whose file is absolute or climbs out of the campaign folder
    with ``..`` (the row and line named); links are checked when the runs are listed."""
    text = name.replace("\\", "/")
    absolute = text.startswith("/") or re.match(r"^[A-Za-z]:", text) is not None
    if absolute or ".." in text.split("/"):
        problem = "is absolute" if absolute else "climbs out of the campaign folder with '..'"
        raise BenchFileError(
            path,
            f"file {name!r} {problem}; a manifest row names a run file by its path relative "
            "to the campaign folder (run_01.txt, day1/run_01.txt): copy the file into the "
            "folder",
            line=number,
        )


MANIFEST_ROWS = 200_000
"""Most rows a manifest.csv may have (10x the largest campaign measured, 20,000 runs; a 25 MB
manifest of missing files had taken 72 s and 2.7 GB)."""


def _manifest_rows(reader: csv.DictReader, path: Path):
    """(line number, row) of manifest.csv's rows after the header; a cell beyond the csv
    module's field limit (128 KiB) or more than :data:`MANIFEST_ROWS` rows is a
    BenchFileError naming the line."""
    number = 1
    try:
        for number, row in enumerate(reader, start=2):
            if number > MANIFEST_ROWS + 1:
                raise BenchFileError(
                    path,
                    f"more than {MANIFEST_ROWS:,} rows; a manifest lists one run per row: "
                    "split the campaign into folders (fit-many fits them one by one)",
                    line=number,
                )
            yield number, row
    except csv.Error as exc:
        raise BenchFileError(
            path,
            f"not a CSV row cylfric reads ({exc}); expected short cells (file names, "
            "numbers, labels)",
            line=number + 1,
        ) from None


def _manifest_temperature(row: dict, path: Path, number: int, delimiter: str = ",") -> float | None:
    """The oil temperature [K] of a manifest row (NaN for an empty cell; None without a
    temperature column)."""
    columns = [name for name in TEMPERATURE_COLUMNS if name in row]
    if not columns:
        return None
    if len(columns) > 1:
        raise BenchFileError(path, f"two temperature columns {columns}; expected one", line=1)
    (name,) = columns
    text = row[name]
    if text is None or text == "":
        return math.nan
    try:
        value = _number(text, delimiter)
    except ValueError:
        value = math.nan
    kelvin = value + TEMPERATURE_COLUMNS[name]
    if not 200.0 <= kelvin <= 450.0:
        expected = "in degC, -73 to 177" if TEMPERATURE_COLUMNS[name] else "in K, 200 to 450"
        raise BenchFileError(
            path,
            f"{name} = {text!r} of {row['file']}: expected an oil temperature {expected} "
            "(or an empty cell)",
            line=number,
        )
    return kelvin


def discover_runs(folder, config: CampaignConfig | None = None) -> list[RunInfo]:
    """List the run files of a campaign folder with their nominal metadata (sorted by name).

    Reads ``campaign.toml`` (without ``config``) and ``manifest.csv``; a :class:`Campaign`
    holds the result with everything else a fit needs, read once.
    """
    folder = _campaign_folder(folder)
    config = config or load_config(folder)
    check_glob(config.glob, folder, key="glob")  # also a --glob of the command line
    return _discover(folder, config, _read_manifest(folder))


def _campaign_folder(folder) -> Path:
    folder = Path(folder)
    if not folder.is_dir():
        raise BenchFileError(folder, "not a folder; expected a campaign folder of run files")
    return folder


def _check_encodable(path: Path) -> None:
    """Refuse a file or folder name that is not valid UTF-8 (bytes the file system holds but
    no table or report can write), naming it with its bytes escaped."""
    try:
        str(path).encode("utf-8")
    except UnicodeEncodeError:
        raise BenchFileError(
            path,
            "the name is not valid UTF-8 (shown with its bytes escaped); the tables and the "
            "report cannot hold it: rename the file or folder",
        ) from None


def _discover(folder: Path, config: CampaignConfig, manifest: _Manifest) -> list[RunInfo]:
    """The runs of ``folder`` (its glob already checked) with their nominal metadata."""
    pattern = (
        compile_name_pattern(config.name_pattern, Path(config.source or folder / CONFIG_NAME))
        if config.name_pattern
        else None
    )
    runs = []
    manifest_path = folder / MANIFEST_NAME
    boundary = _Boundary(folder)
    for path, key in _candidates(folder, config, manifest):
        _check_encodable(path)
        name = path.name
        line = manifest.lines.get(key)
        boundary.check(path, manifest_path if line is not None else None, line)
        pressure, velocity, extra, source, nominal = _manifest_nominal(key, manifest)
        if pattern is not None:
            match = pattern.search(name)
            if match:
                pressure, velocity, extra = _name_pattern_nominal(
                    path, match, pressure, velocity, extra, source, nominal
                )
        listed = manifest_path if line is not None else None
        session = session_of(path, folder, config.glob, extra)
        if session is not None:
            extra = {**extra, "session": session}
        runs.append(
            RunInfo(path, pressure, velocity, extra, source, nominal, line, listed, session)
        )
    if not runs:
        raise BenchFileError(folder, f"no run files matching {config.glob!r}")
    return runs


def _candidates(
    folder: Path, config: CampaignConfig, manifest: _Manifest
) -> list[tuple[Path, str]]:
    """(path, key) of the manifest's files matching the glob, in its order (the key: the
    row's file as written, a path relative to the campaign folder); without a manifest, of
    the folder's files matching the glob, sorted (the key: the path relative to the folder,
    with ``/``; hidden files and cylfric's own left out)."""
    if manifest:  # a row for a missing file stops its run in read_run (skippable)
        return [(folder / name, name) for name in manifest if _glob_matches(name, config.glob)]
    found = sorted(
        p
        for p in folder.glob(config.glob)
        if p.is_file() and p.name not in _SKIP_NAMES and not p.name.startswith(".")
    )
    return [(p, _relative(p, folder)) for p in found]


def _glob_matches(name: str, glob: str) -> bool:
    """Whether a manifest row's file (relative to the folder) matches the campaign's glob as
    :meth:`pathlib.Path.glob` would find it: a leading ``**/`` also matches no folder."""
    if fnmatch.fnmatchcase(name, glob):
        return True
    return glob.startswith("**/") and fnmatch.fnmatchcase(name, glob[3:])


def _relative(path: Path, folder: Path) -> str:
    """``path`` (found below ``folder``) relative to it, with ``/`` between the parts."""
    text, prefix = str(path), os.path.join(str(folder), "")
    if text.startswith(prefix):  # the glob's own paths: no path arithmetic
        return text[len(prefix) :].replace(os.sep, "/")
    return path.relative_to(folder).as_posix()


class _Boundary:
    """The campaign folder as a boundary: :meth:`check` refuses a run file that resolves
    outside it (a symbolic link, a file in a linked subfolder, a manifest row that climbs
    out). Each folder is resolved once; a file costs one ``lstat`` unless it is a link."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.real = os.path.realpath(folder)
        self._parents: dict[str, str] = {}

    def _real(self, path: Path) -> str:
        if os.path.islink(path):
            return os.path.realpath(path)
        parent = os.path.dirname(path)
        real = self._parents.get(parent)
        if real is None:
            real = self._parents[parent] = os.path.realpath(parent)
        return os.path.join(real, os.path.basename(path))

    def check(self, path: Path, manifest: Path | None, line: int | None) -> None:
        """Raise BenchFileError when ``path`` resolves outside the campaign folder, naming
        the manifest row (``manifest``, ``line``) or the file and where it leads."""
        real = self._real(path)
        if real == self.real or real.startswith(os.path.join(self.real, "")):
            return
        shown = path.relative_to(self.folder) if path.is_relative_to(self.folder) else path
        what = f"lists {str(shown)!r}, which" if manifest is not None else f"run file {shown}"
        raise BenchFileError(
            manifest if manifest is not None else self.folder,
            f"{what} resolves to {real}, outside the campaign folder {self.real} (through "
            "a symbolic link or '..'); run files are read from the campaign folder only: "
            "copy the file into it",
            line=line,
        )


def _manifest_nominal(name: str, manifest: _Manifest):
    """(pressure [Pa], velocity [m/s], extra labels, source, nominal) of the file ``name``
    from manifest.csv; NaN, empty labels and no source when the manifest does not list it.

    ``source`` maps a quantity to where its value comes from; ``nominal`` maps each
    quantity to {origin: (value [SI], where)}.
    """
    if name not in manifest:
        return math.nan, math.nan, {}, {}, {"pressure": {}, "velocity": {}}
    pressure, velocity, extra = manifest[name]
    return (pressure, velocity, extra, *_manifest_sources(pressure, velocity, manifest.lines[name]))


def _manifest_sources(pressure: float, velocity: float, line: int | None) -> tuple[dict, dict]:
    """(source, nominal) of a run whose pressure [Pa] and velocity [m/s] are manifest.csv's
    row ``line`` (NaN: not given there), as new dictionaries; :class:`RunInfo` makes them
    again from its values when asked (:func:`_from_manifest`)."""
    source: dict[str, str] = {}
    nominal: dict[str, dict[str, tuple[float, str]]] = {"pressure": {}, "velocity": {}}
    where = f"{MANIFEST_NAME} line {line}"
    for quantity, value in (("pressure", pressure), ("velocity", velocity)):
        if not _nan(value):
            source[quantity] = "manifest"
            nominal[quantity]["manifest"] = (value, where)
    return source, nominal


_PATTERN_GROUPS = (("pressure", "pressure_bar", 1e5), ("velocity", "velocity_mm_s", 1e-3))
"""(quantity, name_pattern group, scale to SI) of the nominal values a file name can give."""


def _name_pattern_nominal(path: Path, match, pressure, velocity, extra, source, nominal):
    """Pressure [Pa], velocity [m/s] and labels after campaign.toml's name_pattern matched
    ``path``'s name: a value fills only what the manifest left NaN; every value given goes
    into ``nominal``, the origin of a value used into ``source`` (both updated in place)."""
    groups = {k: v for k, v in match.groupdict().items() if v is not None}
    for quantity, key, scale in _PATTERN_GROUPS:
        if key not in groups:
            continue
        text = groups.pop(key)
        try:
            value = float(text.replace(",", ".")) * scale
        except ValueError:
            value = math.nan
        if not math.isfinite(value) or (quantity == "pressure" and value < 0):
            raise BenchFileError(
                path,
                f"campaign.toml name_pattern gives {key} = {text!r}; expected a finite "
                + ("pressure >= 0 bar" if quantity == "pressure" else "speed in mm/s"),
            )
        nominal[quantity]["campaign.toml name_pattern"] = (value, f"{key} = {text}")
        if quantity == "pressure" and math.isnan(pressure):
            pressure = value
            source["pressure"] = "campaign.toml name_pattern"
        elif quantity == "velocity" and math.isnan(velocity):
            velocity = value
            source["velocity"] = "campaign.toml name_pattern"
    return pressure, velocity, {**groups, **extra}


def session_of(path: Path, folder: Path, glob: str, labels: Mapping[str, Any]) -> str | None:
    """The session a run belongs to, or None when the campaign does not say.

    In this order: ``manifest.csv``'s ``session`` column, a ``session`` group of
    ``campaign.toml [files] name_pattern`` (both already in ``labels``), else the run's
    subfolder when the runs are kept one subfolder per session: only when the glob's first
    part is a wildcard (``"*/*.csv"``, ``"**/*.csv"``, ``"day*/*.txt"``) and the run lies in
    a subfolder, the first subfolder below the campaign folder is the session. A literal
    first part (``"runs/*.txt"``) is a folder of runs, not sessions, and gives none.
    """
    value = labels.get("session")
    if value is not None and str(value).strip():
        return str(value).strip()
    first = glob.replace("\\", "/").split("/", 1)
    if len(first) < 2 or not any(c in first[0] for c in "*?["):
        return None  # a glob within the folder, or below a literal folder: no sessions
    parts = path.relative_to(folder).parts if path.is_relative_to(folder) else (path.name,)
    return parts[0] if len(parts) > 1 else None


def unlisted_files(folder, config: CampaignConfig | None = None) -> list[str]:
    """Names of files matching the glob that ``manifest.csv`` does not list (not read)."""
    folder = Path(folder)
    manifest = _read_manifest(folder)
    if not manifest:
        return []
    config = config or load_config(folder)
    check_glob(config.glob, folder, key="glob")
    return _unlisted(folder, config, manifest)


def _unlisted(folder: Path, config: CampaignConfig, manifest: _Manifest) -> list[str]:
    """Files matching the (checked) glob that a non-empty ``manifest`` does not list."""
    if not manifest:
        return []
    return sorted(
        relative
        for p in folder.glob(config.glob)
        if p.name not in _SKIP_NAMES
        and not p.name.startswith(".")
        and (relative := _relative(p, folder)) not in manifest  # by path, not base name
        and p.is_file()
    )


def _is_dynamic(info: RunInfo) -> bool:
    """Whether ``manifest.csv``'s ``test`` column marks the run a presliding or breakaway test."""
    return str(info.extra.get("test", "")).strip().lower() in DYNAMIC_TESTS


@dataclass(frozen=True)
class Campaign:
    """A campaign folder read once: its configuration, manifest rows and runs.

    :meth:`open` reads ``campaign.toml`` and ``manifest.csv`` once each and lists the runs;
    a fit passes the ``Campaign`` to every step (:func:`cylfric.pipeline.fit_campaign`,
    :func:`cylfric.steady_state.extract_campaign`), so none reads them again. The run files
    themselves are read by the steps (:func:`read_run`).

    Attributes
    ----------
    folder : Path
        The campaign folder.
    config : CampaignConfig
        ``campaign.toml`` (defaults without it), with the ``glob`` given to :meth:`open`.
    manifest : dict
        Rows of ``manifest.csv``: file -> (pressure [Pa], velocity [m/s], other columns);
        empty without a manifest.
    runs : tuple of RunInfo
        Every run (sorted by name; those of the manifest when there is one), with its
        nominal metadata (:func:`discover_runs`).
    unlisted : tuple of str
        Files matching the glob that ``manifest.csv`` does not list (not read;
        :func:`unlisted_files`).
    duplicates : tuple of Duplicate
        Run files whose bytes equal an earlier run's (:func:`find_duplicates`), or whose
        samples do under other header lines (:func:`find_near_duplicates`): left out of
        ``runs`` (counted once), each with the file it repeats.
    """

    folder: Path
    config: CampaignConfig
    manifest: Mapping[str, tuple[float, float, dict]]
    runs: tuple[RunInfo, ...]
    unlisted: tuple[str, ...]
    duplicates: tuple[Duplicate, ...] = ()

    @classmethod
    def open(
        cls,
        folder: str | os.PathLike[str],
        glob: str | None = None,
        *,
        config: CampaignConfig | str | os.PathLike[str] | None = None,
    ) -> Campaign:
        """Read the campaign in ``folder``: ``campaign.toml`` (unless ``config`` is given)
        and ``manifest.csv`` once each, and list its runs.

        ``config`` is a :class:`CampaignConfig`, or the path of a campaign.toml to read
        instead of the folder's (a recipe kept outside read-only data; the folder stays
        untouched; :func:`load_config`).

        ``glob`` (e.g. a ``--glob``) replaces ``campaign.toml [files] glob``; a glob that
        reaches outside the folder is refused (:func:`check_glob`). A run file with the
        same bytes as an earlier one is left out of ``runs`` and listed in ``duplicates``.
        Raises BenchFileError for a missing folder, a campaign without run files, or a bad
        campaign.toml or manifest.csv (naming the file and line).
        """
        path = _campaign_folder(folder)
        _check_encodable(path)
        if config is None or isinstance(config, str | os.PathLike):
            config = load_config(path, config)
        if glob is not None:
            config = replace(config, glob=glob)
        check_glob(config.glob, path, key="glob")
        manifest = _read_manifest(path)
        runs = _discover(path, config, manifest)
        copies = find_duplicates(info.path for info in runs)
        near = find_near_duplicates(info.path for info in runs if info.path not in copies)
        copies.update({copy: original for copy, original in near.items() if copy not in copies})

        def relative(file: Path) -> str:
            return file.relative_to(path).as_posix()

        duplicates = tuple(
            Duplicate(
                relative(info.path), relative(copies[info.path]), info.seal, info.path not in near
            )
            for info in runs
            if info.path in copies
        )
        if copies:
            runs = [info for info in runs if info.path not in copies]
        unlisted = tuple(_unlisted(path, config, manifest))
        return cls(path, config, manifest, tuple(runs), unlisted, duplicates)

    @property
    def seals(self) -> tuple[str, ...]:
        """The seal labels of the runs, sorted (a ``seal`` group of ``name_pattern`` or
        the manifest.csv column ``seal``; :attr:`RunInfo.seal`); empty when none says."""
        return tuple(sorted({info.seal for info in self.runs if info.seal is not None}))

    def for_seal(self, name: str) -> Campaign:
        """The campaign of one seal: its runs and its duplicates (the other attributes
        as they are). ValueError for a name no run carries, listing the seals found."""
        if name not in self.seals:
            found = ", ".join(self.seals) if self.seals else "none (no run has a seal label)"
            raise ValueError(
                f"no seal {name!r} in {self.folder}; the seals found: {found} (from the "
                "'seal' group of campaign.toml's name_pattern or manifest.csv's 'seal' column)"
            )
        return replace(
            self,
            runs=tuple(info for info in self.runs if info.seal == name),
            duplicates=tuple(d for d in self.duplicates if d.seal == name),
        )

    @property
    def dynamic_runs(self) -> tuple[RunInfo, ...]:
        """Runs that ``manifest.csv`` marks as presliding or breakaway tests
        (:data:`DYNAMIC_TESTS`): for :mod:`cylfric.identify.dynamic`."""
        return tuple(info for info in self.runs if _is_dynamic(info))

    @property
    def steady_runs(self) -> tuple[RunInfo, ...]:
        """The constant-velocity runs (every run but the :attr:`dynamic_runs`)."""
        return tuple(info for info in self.runs if not _is_dynamic(info))


def _read_mat_run(path: Path, config: CampaignConfig):
    """A ``.mat`` run: the variables ``[columns] names`` in the units ``[columns] units``
    (a .mat file has no units), converted to SI as a text file's columns are."""
    import hashlib

    if config.columns is None:
        _, found = read_mat(path)
        raise BenchFileError(
            path,
            "a .mat run carries no units; expected [columns] names = [...] and units = [...] "
            f"in campaign.toml, e.g. names = {found['variables'][:3]} with their units "
            "(found the vectors " + ", ".join(found["variables"]) + ")",
        )
    frame, metadata = read_mat(path, variables=list(config.columns))
    assert config.units is not None  # load_config gives [columns] names and units together
    data, col_units = si_columns(
        path, config.columns, config.units, frame.to_numpy(), roles=config.roles
    )
    metadata.update(
        header={},
        rows=len(frame),
        units=col_units,
        sha256=hashlib.sha256(path.read_bytes()).hexdigest(),
    )
    return data, metadata


def read_run(info: RunInfo, config: CampaignConfig):
    """Read one run and complete its nominal metadata from header lines and the file name.

    Returns ``(data, metadata)``: ``data`` a dict of SI arrays named with their units (the
    columns of :func:`cylfric.io.read_bench_text`), ``metadata`` with ``pressure`` [Pa],
    ``velocity`` [m/s], ``extra``, ``source`` (where each value came from) and ``nominal``
    (every value found, ``{quantity: {source: (value [SI], where)}}``) added.
    """
    if not info.path.is_file():
        raise BenchFileError(
            info.manifest or info.path,
            f"lists {info.path.name}, which is not in the campaign folder; expected an "
            "existing run file (correct or remove the row)",
            line=info.manifest_line,
        )
    if info.path.suffix.lower() == ".mat":
        data, metadata = _read_mat_run(info.path, config)
    else:
        data, metadata = read_bench_arrays(
            info.path,
            columns=config.columns,
            units=config.units,
            delimiter=config.delimiter,
            decimal=config.decimal,
            roles=config.roles,
        )
    pressure, velocity = info.pressure, info.velocity
    source = dict(info.source)
    nominal = {q: dict(info.nominal.get(q, {})) for q in ("pressure", "velocity")}
    header = {k.lower(): v for k, v in metadata.get("header", {}).items()}
    original = {k.lower(): k for k in metadata.get("header", {})}
    extra = dict(info.extra)
    defaults = {"pressure": "bar", "velocity": "mm/s"}
    for quantity, keys in _HEADER_KEYS.items():
        for key in keys:
            if key in header:
                if quantity == "temperature":
                    extra.setdefault("temperature", header[key])
                    break
                used = math.isnan(pressure if quantity == "pressure" else velocity)
                try:
                    value = _quantity(header[key], quantity, defaults[quantity], info.path)
                except BenchFileError:
                    if used:  # needed: a header value that does not parse stops the run
                        raise
                    break  # not needed: another source gives the value
                nominal[quantity]["header"] = (value, f"{original[key]}: {header[key]}")
                if used and quantity == "pressure":
                    pressure, source["pressure"] = value, "header"
                elif used:
                    velocity, source["velocity"] = value, "header"
                break
    tokens = _tokens(info.path.name)
    for quantity in ("pressure", "velocity"):
        # a campaign.toml name_pattern is the authority on the file name
        if quantity in tokens and "campaign.toml name_pattern" not in nominal[quantity]:
            nominal[quantity]["file name"] = tokens[quantity]
    if math.isnan(pressure) and "pressure" in tokens:
        pressure, source["pressure"] = tokens["pressure"][0], "file name"
    if math.isnan(velocity) and "velocity" in tokens:
        velocity, source["velocity"] = tokens["velocity"][0], "file name"
    metadata.update(
        pressure=pressure,
        velocity=velocity,
        extra=extra,
        source=source,
        nominal=nominal,
        manifest_line=info.manifest_line,
    )
    return data, metadata
