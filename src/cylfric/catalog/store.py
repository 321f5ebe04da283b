"""The seal catalogue: friction datasheets with their seal metadata in one SQLite file.

One row per catalogued seal (a name, the datasheet as JSON text, and the metadata: seal,
manufacturer, bore [m], rod [m], fluid, temperature [K]). The file is opened in WAL mode
with a busy timeout, and every write is one ``BEGIN IMMEDIATE`` transaction, so several
processes may add to the same catalogue at once (``cylfric fit-many --catalog DB``). The
schema is versioned with ``PRAGMA user_version`` and migrated forward when an older file is
opened; a file written by a newer cylfric is refused.

Where the catalogue lives: an explicit path, else the ``CYLFRIC_CATALOG`` environment
variable, else ``$XDG_DATA_HOME/cylfric/catalog.sqlite`` (``~/.local/share/cylfric`` when
``XDG_DATA_HOME`` is unset; ``%LOCALAPPDATA%\\cylfric`` on Windows).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sqlite3
import sys
import unicodedata
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from collections.abc import Mapping, Sequence

    import pandas as pd

    from cylfric._typing import StrPath
    from cylfric.model import FrictionModel

__all__ = [
    "Catalog",
    "CatalogError",
    "default_path",
    "SCHEMA_VERSION",
    "MIGRATIONS",
    "EXPORT_FORMAT",
    "METADATA",
]

ENV_VARIABLE = "CYLFRIC_CATALOG"
EXPORT_FORMAT = "cylfric-catalog/1"
BUSY_TIMEOUT = 60.0
"""Seconds a writer waits for another process's transaction before giving up."""

MIGRATIONS = (
    # version 1: the first layout, a name and its datasheet
    """
    CREATE TABLE seals (
        name TEXT PRIMARY KEY,
        datasheet TEXT NOT NULL,
        added TEXT NOT NULL
    );
    """,
    # version 2: seal metadata as columns (SI: bore and rod [m], temperature [K])
    """
    ALTER TABLE seals ADD COLUMN seal TEXT;
    ALTER TABLE seals ADD COLUMN manufacturer TEXT;
    ALTER TABLE seals ADD COLUMN bore REAL;
    ALTER TABLE seals ADD COLUMN rod REAL;
    ALTER TABLE seals ADD COLUMN fluid TEXT;
    ALTER TABLE seals ADD COLUMN temperature REAL;
    """,
)
"""SQL that takes a catalogue from version ``i`` to ``i + 1`` (index ``i``)."""
SCHEMA_VERSION = len(MIGRATIONS)
_COLUMNS = (
    ["name", "datasheet", "added"],
    ["name", "datasheet", "added", "seal", "manufacturer", "bore", "rod", "fluid", "temperature"],
)
"""The columns of the table ``seals`` at each schema version (index: version - 1)."""

METADATA = {
    "seal": ("seal", None),
    "manufacturer": ("manufacturer", None),
    "bore": ("bore [m]", "m"),
    "rod": ("rod [m]", "m"),
    "fluid": ("fluid", None),
    "temperature": ("temperature [K]", "K"),
}
"""Metadata keyword -> (column name of :meth:`Catalog.list`, SI unit or None for text)."""


class CatalogError(ValueError):
    """Bad input to the catalogue (unknown name, duplicate, bad metadata, bad file)."""


def default_path() -> Path:
    """The catalogue file used when no path is given (see the module docstring)."""
    env = os.environ.get(ENV_VARIABLE)
    if env:
        return Path(env).expanduser()
    if sys.platform == "win32" and os.environ.get("LOCALAPPDATA"):
        base = Path(os.environ["LOCALAPPDATA"])
    elif os.environ.get("XDG_DATA_HOME"):
        base = Path(os.environ["XDG_DATA_HOME"])
    elif os.environ.get("HOME") or sys.platform == "win32":
        base = Path.home() / ".local" / "share"
    else:  # a service or container: not the home the password database names
        raise CatalogError(
            f"no catalogue file given and HOME is not set; give --db FILE or set {ENV_VARIABLE}"
            " (or XDG_DATA_HOME) to say where the catalogue is"
        )
    return base / "cylfric" / "catalog.sqlite"


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def _check_name(name) -> str:
    """A catalogue name, normalised (Unicode NFKC): look-alike spellings (composed and
    decomposed accents, full-width letters) are one name, so they cannot coexist and print
    the same."""
    if not isinstance(name, str) or not name.strip() or name != name.strip():
        raise CatalogError(
            f"catalogue name {name!r}: expected a non-empty text without leading or trailing spaces"
        )
    return unicodedata.normalize("NFKC", name)


def _key(name: object) -> object:
    """A name as looked up: NFKC-normalised text (anything else as it is)."""
    return unicodedata.normalize("NFKC", name) if isinstance(name, str) else name


def _check_metadata(values: dict) -> dict:
    """Metadata keywords checked (SI numbers, text) -> column values."""
    out: dict[str, Any] = {}
    for key, value in values.items():
        if key not in METADATA:
            raise CatalogError(f"unknown metadata {key!r}; valid: {sorted(METADATA)}")
        unit = METADATA[key][1]
        if value is None:
            out[key] = None
        elif unit is None:
            if not isinstance(value, str):
                raise CatalogError(f"{key} = {value!r}: expected a text")
            out[key] = value
        else:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise CatalogError(f"{key} = {value!r}: expected a number in {unit}")
            try:
                number = float(value)
            except OverflowError:
                raise CatalogError(f"{key} = {value!r}: expected a number in {unit}") from None
            if not math.isfinite(number) or number <= 0:
                raise CatalogError(f"{key} = {value!r}: expected a positive number in {unit}")
            out[key] = number
    bore, rod = out.get("bore"), out.get("rod")
    if bore is not None and bore > 2.0:
        raise CatalogError(f"bore = {bore} m: larger than 2 m; bore is in m (40 mm = 0.04)")
    if bore is not None and rod is not None and rod >= bore:
        raise CatalogError(f"rod = {rod} m must be smaller than the bore {bore} m")
    temperature = out.get("temperature")
    if temperature is not None and not 150.0 <= temperature <= 700.0:
        raise CatalogError(
            f"temperature = {temperature} K: outside 150-700 K; the temperature is in kelvin "
            "(40 degC = 313.15 K)"
        )
    return out


def _load_datasheet(source, where=None) -> dict:
    """A validated datasheet dict from a path (a file, or a fit folder) or a dict, checked
    by ``cylfric show``'s rules: the schema, and a model that can be built from it
    (covariance shapes, numbers where numbers belong)."""
    from ..datasheet import DatasheetError, read_datasheet, validate
    from ..model import FrictionModel

    if isinstance(source, str | os.PathLike):
        path = Path(source)
        if path.is_dir():
            path = path / "datasheet.json"
        sheet, where = read_datasheet(path), str(path)
    elif isinstance(source, dict):
        try:
            copy = json.loads(json.dumps(source))
        except (ValueError, TypeError, RecursionError) as exc:
            raise CatalogError(f"{where or 'datasheet'}: not a JSON datasheet ({exc})") from None
        sheet = validate(copy, source=where or "datasheet")
    else:
        raise CatalogError(
            f"{type(source).__name__}: expected a datasheet path, a fit output folder or a dict"
        )
    try:
        FrictionModel.from_datasheet(sheet)
    except DatasheetError as exc:
        message = str(exc).removeprefix("datasheet: ")
        raise DatasheetError(f"{where or 'datasheet'}: {message}") from None
    return sheet


class Catalog:
    """A catalogue of seal friction datasheets in an SQLite file.

    Parameters
    ----------
    path : path-like, optional
        The catalogue file (created with its folder when absent). Default: the
        ``CYLFRIC_CATALOG`` environment variable, else the per-user data folder
        (:func:`default_path`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from cylfric.model import FrictionModel
    >>> db = Catalog(pathlib.Path(tempfile.mkdtemp()) / "seals.sqlite")
    >>> db.add(FrictionModel().to_datasheet(), "thesis", bore=0.040, rod=0.028)
    >>> db.names()
    ['thesis']
    >>> round(db.model("thesis").friction(0.025, 55e5), 2)   # [N] at 25 mm/s, 55 bar
    111.26
    """

    def __init__(self, path: StrPath | None = None) -> None:
        self.path = Path(path).expanduser() if path is not None else default_path()
        if self.path.is_dir():
            raise CatalogError(f"{self.path}: is a folder; expected a catalogue file (.sqlite)")
        for parent in self.path.parents:
            if parent.exists() or parent.is_symlink():
                if not parent.is_dir():
                    raise CatalogError(
                        f"{self.path}: {parent} is a file, not a folder; expected the "
                        f"catalogue file's path (--db, {ENV_VARIABLE}) to lie in a folder"
                    )
                break
        self._inspect()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self._connect() as db:
            self._migrate(db)

    def __repr__(self) -> str:
        return f"Catalog({str(self.path)!r})"

    # ------------------------------------------------------------------ connection
    @contextlib.contextmanager
    def _connect(self):
        try:
            db = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT, isolation_level=None)
        except sqlite3.Error as exc:
            raise CatalogError(f"{self.path}: cannot open the catalogue ({exc})") from None
        try:
            db.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT * 1000)}")
            mode = db.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            if mode.lower() != "wal":  # pragma: no cover - file systems without shared memory
                db.execute("PRAGMA journal_mode = DELETE")
            yield db
        except sqlite3.OperationalError as exc:
            raise CatalogError(f"{self.path}: catalogue not usable now ({exc})") from None
        except sqlite3.DatabaseError as exc:
            raise CatalogError(f"{self.path}: not a usable catalogue ({exc})") from None
        finally:
            db.close()

    @contextlib.contextmanager
    def _write(self):
        """One write transaction (BEGIN IMMEDIATE: writers queue on the busy timeout)."""
        with self._connect() as db:
            db.execute("BEGIN IMMEDIATE")
            try:
                yield db
            except BaseException:
                db.execute("ROLLBACK")
                raise
            db.execute("COMMIT")

    def _inspect(self) -> None:
        """Look at an existing file read-only before anything writes to it: an SQLite file
        that is not a cylfric catalogue (other tables, views, indexes or triggers: a
        trigger would run on :meth:`add`) or is not SQLite at all is refused, unchanged
        (no WAL switch, no migration)."""
        if not self.path.exists() or self.path.stat().st_size == 0:
            return
        uri = self.path.resolve().as_uri() + "?mode=ro"
        refused = f"{self.path}: not a cylfric catalogue"
        try:
            db = sqlite3.connect(uri, uri=True, timeout=BUSY_TIMEOUT, isolation_level=None)
        except sqlite3.Error as exc:
            raise CatalogError(f"{self.path}: cannot open the catalogue ({exc})") from None
        try:
            version = db.execute("PRAGMA user_version").fetchone()[0]
            objects = db.execute("SELECT type, name FROM sqlite_master").fetchall()
            columns = [row[1] for row in db.execute("PRAGMA table_info(seals)")]
        except sqlite3.DatabaseError as exc:
            raise CatalogError(
                f"{self.path}: not a usable catalogue ({exc}); the file is left as it is"
            ) from None
        finally:
            db.close()
        if version > SCHEMA_VERSION:
            raise CatalogError(
                f"{self.path}: catalogue schema version {version} is newer than this cylfric "
                f"knows ({SCHEMA_VERSION}); update cylfric"
            )
        known = {("table", "seals"), ("index", "sqlite_autoindex_seals_1")}
        unknown = [f"{kind} {name!r}" for kind, name in objects if (kind, name) not in known]
        if version == 0 and objects:
            raise CatalogError(
                f"{refused} (tables but no schema version); the file is left as it is"
            )
        if version and (unknown or columns != _COLUMNS[version - 1]):
            found = ", ".join(unknown) if unknown else f"the columns {columns}"
            raise CatalogError(
                f"{refused}: it holds {found}, which a cylfric catalogue of schema version "
                f"{version} does not (a trigger would run on every add); the file is left as "
                "it is: use another --db, or export the entries you trust from it"
            )

    def _migrate(self, db) -> None:
        version = db.execute("PRAGMA user_version").fetchone()[0]
        if version > SCHEMA_VERSION:
            raise CatalogError(
                f"{self.path}: catalogue schema version {version} is newer than this cylfric "
                f"knows ({SCHEMA_VERSION}); update cylfric"
            )
        if version == SCHEMA_VERSION:
            return
        db.execute("BEGIN IMMEDIATE")
        try:
            version = db.execute("PRAGMA user_version").fetchone()[0]  # another process?
            if (
                version == 0
                and db.execute(
                    "SELECT count(*) FROM sqlite_master WHERE type = 'table'"
                ).fetchone()[0]
            ):
                raise CatalogError(
                    f"{self.path}: an SQLite file that is not a cylfric catalogue "
                    "(tables but no schema version)"
                )
            for step in range(version, SCHEMA_VERSION):
                for statement in MIGRATIONS[step].split(";"):
                    if statement.strip():
                        db.execute(statement)
            db.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
        except BaseException:
            db.execute("ROLLBACK")
            raise
        db.execute("COMMIT")

    @property
    def schema_version(self) -> int:
        """The file's schema version (``PRAGMA user_version``)."""
        with self._connect() as db:
            return db.execute("PRAGMA user_version").fetchone()[0]

    # ------------------------------------------------------------------ entries
    def add(
        self,
        datasheet: StrPath | Mapping[str, Any],
        name: str,
        *,
        seal: str | None = None,
        manufacturer: str | None = None,
        bore: float | None = None,
        rod: float | None = None,
        fluid: str | None = None,
        temperature: float | None = None,
        replace: bool = False,
    ) -> None:
        """Add a datasheet under ``name`` (validated first; SI metadata).

        Parameters
        ----------
        datasheet : path-like or dict
            A ``datasheet.json``, a fit output folder that holds one, or the dict.
        name : str
            Catalogue name (unique).
        seal, manufacturer, fluid : str, optional
            Seal type or designation, maker, working fluid (text).
        bore, rod : float, optional
            Bore and rod diameters of the tested cylinder [m]; :meth:`predict` needs them.
            Default: the datasheet's ``cylinder`` (campaign.toml's [cylinder]); a value that
            contradicts it by more than 1 % is refused.
        temperature : float, optional
            Oil or seal temperature of the test [K].
        replace : bool
            Replace an entry of the same name instead of refusing.
        """
        name = _check_name(name)
        sheet = _load_datasheet(datasheet, where=f"datasheet of {name!r}")
        bore, rod = _stated_geometry(sheet, name, bore=bore, rod=rod)
        metadata = _check_metadata(
            {
                "seal": seal,
                "manufacturer": manufacturer,
                "bore": bore,
                "rod": rod,
                "fluid": fluid,
                "temperature": temperature,
            }
        )
        self._insert([(name, sheet, metadata, _now())], replace=replace)

    def _insert(self, rows, *, replace) -> None:
        columns = ("name", "datasheet", "added", *METADATA)
        verb = "INSERT OR REPLACE" if replace else "INSERT"
        sql = f"{verb} INTO seals ({', '.join(columns)}) VALUES ({', '.join('?' * len(columns))})"
        with self._write() as db:
            for name, sheet, metadata, added in rows:
                values = (name, json.dumps(sheet), added, *(metadata.get(k) for k in METADATA))
                try:
                    db.execute(sql, values)
                except sqlite3.IntegrityError:
                    raise CatalogError(
                        f"{name!r} is already in the catalogue {self.path}; "
                        "choose another name or replace it (replace=True, --replace)"
                    ) from None

    def names(self) -> list[str]:
        """Catalogue names, sorted."""
        with self._connect() as db:
            return [row[0] for row in db.execute("SELECT name FROM seals ORDER BY name")]

    def __contains__(self, name: object) -> bool:
        with self._connect() as db:
            found = db.execute("SELECT 1 FROM seals WHERE name = ?", (_key(name),)).fetchone()
            return found is not None

    def __len__(self) -> int:
        with self._connect() as db:
            return db.execute("SELECT count(*) FROM seals").fetchone()[0]

    def _row(self, name) -> sqlite3.Row:
        with self._connect() as db:
            db.row_factory = sqlite3.Row
            row = db.execute("SELECT * FROM seals WHERE name = ?", (_key(name),)).fetchone()
        if row is None:
            known = self.names()
            shown = ", ".join(repr(n) for n in known[:20]) + (" ..." if len(known) > 20 else "")
            raise CatalogError(
                f"{name!r} is not in the catalogue {self.path}; "
                + (f"known: {shown}" if known else "the catalogue is empty")
            )
        return row

    def get(self, name: str) -> dict[str, Any]:
        """The datasheet dict of ``name`` (as it was added)."""
        return json.loads(self._row(name)["datasheet"])

    def metadata(self, name: str) -> dict[str, Any]:
        """The metadata of ``name`` (SI: bore and rod [m], temperature [K]; None if unknown)."""
        row = self._row(name)
        return {key: row[key] for key in METADATA} | {"added": row["added"]}

    def model(self, name: str) -> FrictionModel:
        """The :class:`~cylfric.model.FrictionModel` of ``name``."""
        from ..model import FrictionModel

        try:
            sheet = self.get(name)
            return FrictionModel.from_datasheet(sheet)
        except (ValueError, TypeError, KeyError, RecursionError) as exc:
            if isinstance(exc, CatalogError) and " is not in the catalogue " in str(exc):
                raise
            raise CatalogError(
                f"catalogue entry {name!r} of {self.path} cannot be read ({exc}); remove or "
                "replace it (catalog remove, catalog add --replace)"
            ) from None

    def remove(self, name: str) -> None:
        """Remove ``name`` (an unknown name raises :class:`CatalogError`)."""
        with self._write() as db:
            if not db.execute("DELETE FROM seals WHERE name = ?", (_key(name),)).rowcount:
                raise CatalogError(f"{name!r} is not in the catalogue {self.path}")

    def list(self) -> pd.DataFrame:
        """One row per entry: metadata (SI, units in the column names) and model summary.

        Returns
        -------
        pandas.DataFrame
            ``name``, ``seal``, ``manufacturer``, ``bore [m]``, ``rod [m]``, ``fluid``,
            ``temperature [K]``, ``friction law``, ``pressure min [Pa]``,
            ``pressure max [Pa]``, ``velocity min [m/s]``, ``velocity max [m/s]``,
            ``rmse [N]``, ``added``.
        """
        import pandas as pd

        with self._connect() as db:
            db.row_factory = sqlite3.Row
            rows = db.execute("SELECT * FROM seals ORDER BY name").fetchall()
        records = []
        for row in rows:
            try:
                sheet = json.loads(row["datasheet"])
                if not isinstance(sheet, dict):
                    raise ValueError("not a JSON object")
                law = sheet["model"]["friction_law"]
                rmse = sheet["fit"].get("rmse")
                validity = sheet.get("validity") or {}
            except (ValueError, TypeError, KeyError, AttributeError, RecursionError):
                sheet, law, rmse, validity = {}, "unreadable", None, {}
            if not isinstance(validity, dict):
                validity = {}
            record = {"name": row["name"]}
            record.update({column: row[key] for key, (column, _) in METADATA.items()})
            record.update(
                {
                    "friction law": law,
                    "pressure min [Pa]": validity.get("pressure_min", math.nan),
                    "pressure max [Pa]": validity.get("pressure_max", math.nan),
                    "velocity min [m/s]": validity.get("velocity_min", math.nan),
                    "velocity max [m/s]": validity.get("velocity_max", math.nan),
                    "rmse [N]": rmse,
                    "added": row["added"],
                }
            )
            records.append(record)
        columns = ["name", *(c for c, _ in METADATA.values())]
        columns += [
            "friction law",
            "pressure min [Pa]",
            "pressure max [Pa]",
            "velocity min [m/s]",
            "velocity max [m/s]",
            "rmse [N]",
            "added",
        ]
        return pd.DataFrame.from_records(records, columns=columns)

    # ------------------------------------------------------------------ use
    def select(
        self,
        pressure: float,
        velocity: float,
        max_friction: float | None = None,
        *,
        names: Sequence[str] | None = None,
        level: float = 0.95,
    ) -> pd.DataFrame:
        """Entries ranked by friction at an operating point, lowest first, with the band.

        Parameters
        ----------
        pressure : float
            Operating pressure [Pa] (the pressure each model's laws see).
        velocity : float
            Speed [m/s] (its sign does not matter).
        max_friction : float, optional
            Keep only entries whose upper band limit is at most this force [N] (a promise
            that the friction stays below it, not just its estimate).
        names : list of str, optional
            Rank only these entries (default: all).
        level : float
            Confidence level of the band [-].

        Returns
        -------
        pandas.DataFrame
            ``rank``, ``name``, ``seal``, ``friction [N]``, ``lower [N]``, ``upper [N]``,
            ``inside validity`` (False: the model is extrapolated there) and
            ``friction law``. Entries without covariance have NaN band limits and are
            dropped by ``max_friction``.
        """
        import pandas as pd

        from .compare import friction_with_band

        if not (math.isfinite(pressure) and math.isfinite(velocity)):
            raise CatalogError(f"pressure {pressure} Pa, velocity {velocity} m/s: not finite")
        if max_friction is not None and not max_friction > 0:
            raise CatalogError(f"max_friction = {max_friction} N: expected a positive force")
        records, unreadable = [], {}
        for name in names if names is not None else self.names():
            try:
                model = self.model(name)
            except CatalogError as exc:
                if names is not None:  # asked for by name: say so
                    raise
                unreadable[name] = str(exc)  # one bad entry does not hide the others
                continue
            friction, lower, upper, inside = friction_with_band(
                model, abs(velocity), pressure, level
            )
            records.append(
                {
                    "name": name,
                    "seal": self.metadata(name)["seal"],
                    "friction [N]": float(friction),
                    "lower [N]": float(lower),
                    "upper [N]": float(upper),
                    "inside validity": bool(inside),
                    "friction law": model.friction_law,
                }
            )
        table = pd.DataFrame.from_records(
            records,
            columns=[
                "name",
                "seal",
                "friction [N]",
                "lower [N]",
                "upper [N]",
                "inside validity",
                "friction law",
            ],
        )
        if max_friction is not None:
            table = table[table["upper [N]"] <= max_friction]
        table = table.sort_values(["friction [N]", "name"], kind="stable").reset_index(drop=True)
        table.insert(0, "rank", range(1, len(table) + 1))
        table.attrs["unreadable"] = unreadable
        return table

    def compare(
        self,
        names: Sequence[str],
        out: StrPath,
        pressures: Sequence[float],
        velocities: Sequence[float],
        *,
        level: float = 0.95,
    ) -> dict[str, Any]:
        """Figures and a table comparing entries; see :func:`cylfric.catalog.compare.compare`."""
        from .compare import compare

        if not names:
            raise CatalogError("compare: give at least one catalogue name")
        models = {name: self.model(name) for name in names}
        return compare(models, out, pressures, velocities, level=level)

    def predict(
        self, name: str, bore: float, rod: float | None = None, **options: Any
    ) -> dict[str, Any]:
        """Datasheet of ``name``'s seal on another cylinder size, scaled by contact length.

        See :func:`cylfric.catalog.scaling.predict_datasheet` for the rule, its
        uncertainty and the ``options`` (``contact``, ``rod_seals``, ``rule_stderr``).

        Parameters
        ----------
        name : str
            Catalogue entry (its metadata must give the tested bore, and rod for rod seals).
        bore : float
            Bore of the target cylinder [m].
        rod : float, optional
            Rod diameter of the target cylinder [m].
        """
        from .scaling import predict_datasheet

        meta = self.metadata(name)
        return predict_datasheet(
            self.get(name),
            source_name=name,
            source_bore=meta["bore"],
            source_rod=meta["rod"],
            bore=bore,
            rod=rod,
            **options,
        )

    # ------------------------------------------------------------------ exchange
    def export_json(self, path: StrPath) -> Path:
        """Write the whole catalogue as one JSON file (atomically); returns the path."""
        from ..io.writers import atomic_write_text

        with self._connect() as db:
            db.row_factory = sqlite3.Row
            rows = db.execute("SELECT * FROM seals ORDER BY name").fetchall()
        document = {
            "format": EXPORT_FORMAT,
            "schema_version": SCHEMA_VERSION,
            "exported": _now(),
            "units": {"bore": "m", "rod": "m", "temperature": "K"},
            "entries": [
                {
                    "name": row["name"],
                    "added": row["added"],
                    "metadata": {key: row[key] for key in METADATA},
                    "datasheet": json.loads(row["datasheet"]),
                }
                for row in rows
            ],
        }
        return atomic_write_text(path, json.dumps(document, indent=1) + "\n")

    def import_json(self, path: StrPath, *, replace: bool = False) -> int:
        """Add every entry of an :meth:`export_json` file (all or none); returns the count.

        Every datasheet is validated and every name checked before anything is written;
        a name already in the catalogue is refused unless ``replace``.
        """
        path = Path(path)
        try:
            document = json.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise CatalogError(f"{path}: cannot read ({exc.strerror})") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as exc:
            raise CatalogError(f"{path}: not a JSON file ({exc})") from None
        if not isinstance(document, dict) or document.get("format") != EXPORT_FORMAT:
            raise CatalogError(f"{path}: format: expected {EXPORT_FORMAT!r} (a catalogue export)")
        entries = document.get("entries")
        if not isinstance(entries, list):
            raise CatalogError(f"{path}: entries: expected a list")
        rows, seen = [], set()
        for i, entry in enumerate(entries):
            where = f"{path}: entries/{i}"
            if not isinstance(entry, dict) or not {"name", "datasheet"} <= set(entry):
                raise CatalogError(f"{where}: expected an object with name and datasheet")
            try:
                name = _check_name(entry["name"])
                metadata = _check_metadata(dict(entry.get("metadata") or {}))
            except CatalogError as exc:
                raise CatalogError(f"{where}: {exc}") from None
            if name in seen:
                raise CatalogError(f"{where}: {name!r} appears twice in the file")
            seen.add(name)
            sheet = _load_datasheet(entry["datasheet"], where=f"{where} ({name!r})/datasheet")
            rows.append((name, sheet, metadata, entry.get("added") or _now()))
        self._insert(rows, replace=replace)
        return len(rows)


def _stated_geometry(
    sheet: Mapping[str, Any], name: str, *, bore: float | None, rod: float | None
) -> tuple[float | None, float | None]:
    """(bore, rod) [m]: those given, else the datasheet's ``cylinder`` record; a given value
    that contradicts the record by more than 1 % is a CatalogError naming both."""
    from collections.abc import Mapping

    cylinder = sheet.get("cylinder")
    if not isinstance(cylinder, Mapping):
        return bore, rod
    chosen = []
    for key, given in (("bore", bore), ("rod", rod)):
        recorded = cylinder.get(key)
        if not isinstance(recorded, int | float) or isinstance(recorded, bool):
            chosen.append(given)
            continue
        if given is not None and abs(given - recorded) > 0.01 * max(abs(recorded), 1e-9):
            raise CatalogError(
                f"{name!r}: --{key} {given * 1e3:g} mm contradicts the datasheet's cylinder "
                f"({key} {recorded * 1e3:g} mm, from its campaign.toml); leave --{key} out "
                "to take the datasheet's"
            )
        chosen.append(recorded if given is None else given)
    return chosen[0], chosen[1]
