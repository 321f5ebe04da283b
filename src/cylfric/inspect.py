"""What cylfric read: the facts behind one run file or a whole campaign (``cylfric inspect``).

For a run file (in its campaign folder, so that campaign.toml and manifest.csv apply) or a
campaign folder, :func:`inspect` gathers, with the readers and the extraction a fit uses
(:func:`cylfric.io.campaign.read_run`, :func:`cylfric.steady_state.extract_points`,
:func:`cylfric.quality.assess`) and nothing of its own:

- the columns found, each with its unit as read and as converted to SI (and the factor);
- the force balance applied (thesis eq. 3.1): which force (load cell or chamber
  pressures), the signs, the areas, the inertia term, the offset, the pressure reference,
  and whether each setting was written in campaign.toml or is a default;
- the nominal pressure and speed used and every source that gave one;
- the strokes found and the steady windows chosen (one row per window: the extraction's
  points of that file), with the traces to draw them (:mod:`cylfric.report.inspect`);
- what the data-quality gate says of the run(s), as in a fit (per seal when the campaign
  has several).

Draws nothing and writes nothing.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .io.campaign import CONFIG_NAME, MANIFEST_NAME, Campaign, CampaignConfig, RunInfo, read_run
from .io.text import QUANTITY_DIMENSIONS, SI_UNITS, BenchFileError
from .units import to_si

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "ColumnRead",
    "GateVerdicts",
    "Inspection",
    "RunInspection",
    "find_campaign",
    "force_balance",
    "gate_verdicts",
    "inspect",
    "inspect_run",
    "iter_runs",
]

WINDOW_COLUMNS = [
    "stroke",
    "direction [-]",
    "window_start [s]",
    "window_end [s]",
    "n [-]",
    "velocity [m/s]",
    "pressure [Pa]",
    "force [N]",
    "friction [N]",
    "offset [N]",
    "spikes [-]",
    "flag",
]
"""Columns of :attr:`RunInspection.windows` (those of the points table,
:data:`cylfric.steady_state.POINT_COLUMNS`)."""


@dataclass(frozen=True)
class ColumnRead:
    """One column of a run file as cylfric read it.

    Attributes
    ----------
    name : str
        The column's name in the file (or in campaign.toml ``[columns] names``).
    unit : str
        Its unit as read ("" when none).
    quantity : str or None
        What cylfric took it for (``time``, ``position``, ``force``, ``pressure_a``, ...);
        None: kept as read, not used.
    key : str
        The column's name after reading (``"force [N]"``): its SI unit in brackets.
    si_unit : str
        The unit it was converted to (the unit as read for a column not used).
    factor : float
        SI value = factor x value as read [-] (1 for a column not used).
    minimum, maximum : float
        Range of the column after conversion [si_unit].
    """

    name: str
    unit: str
    quantity: str | None
    key: str
    si_unit: str
    factor: float
    minimum: float
    maximum: float


@dataclass
class RunInspection:
    """The facts of one run file (:func:`inspect_run`).

    Attributes
    ----------
    file : Path
        The run file.
    name : str
        Its name relative to the campaign folder.
    test : str
        ``"constant-velocity"``, or the manifest's ``test`` (``presliding``, ``breakaway``:
        not read by the steady-state extraction).
    columns : list of ColumnRead
    reader : dict
        ``delimiter``, ``decimal``, ``rows``, ``segments``, ``header`` (key: value lines).
    pressure, velocity : float
        The nominal pressure [Pa] and speed [m/s] used (NaN: none).
    source : dict
        Where each was taken from (``manifest``, ``campaign.toml name_pattern``,
        ``header``, ``file name``).
    nominal : dict
        Every value found, ``{quantity: {source: (value [SI], where)}}``.
    pressure_measured : bool
        The file has a pressure column: the points' pressure is measured, not nominal.
    force_balance : list of dict
        The terms of eq. 3.1 as applied to this file (:func:`force_balance`).
    velocity_from : str
        How the velocity was obtained (a column, or the derivative of the position).
    windows : pandas.DataFrame
        One row per stroke: its extent (``stroke_start [s]``, ``stroke_end [s]``: the
        samples in motion), its steady window, means and flag (:data:`WINDOW_COLUMNS`);
        the points the extraction finds in this file.
    offset : float
        The load-cell weight offset removed [N] (NaN: none could be found).
    offset_from : str
        Where the offset comes from (this run's strokes, the campaign, none).
    gate : list of (str, str)
        The gate's (check, reason) for this file; empty when it passes.
    gate_note : str
        What the gate said of the campaign as a whole ("" when nothing).
    traces : dict or None
        ``time [s]``, ``position [m]`` (or None), ``velocity [m/s]``, ``force [N]`` (the
        force-balance signal with the offset) and ``stroke [-]`` (stroke index per sample,
        -1 at rest); None when not kept.
    error : str
        Why the file could not be read, naming the file (or manifest.csv) and the line
        ("" when it was read).
    error_line : int or None
        The line the error names.
    """

    file: Path
    name: str
    test: str = "constant-velocity"
    columns: list[ColumnRead] = field(default_factory=list)
    reader: dict = field(default_factory=dict)
    pressure: float = math.nan
    velocity: float = math.nan
    source: dict = field(default_factory=dict)
    nominal: dict = field(default_factory=dict)
    pressure_measured: bool = False
    force_balance: list[dict] = field(default_factory=list)
    velocity_from: str = ""
    windows: pd.DataFrame | None = None
    offset: float = math.nan
    offset_from: str = ""
    gate: list[tuple[str, str]] = field(default_factory=list)
    gate_note: str = ""
    traces: dict | None = None
    error: str = ""
    error_line: int | None = None

    @property
    def strokes(self) -> int:
        """Strokes found (one window each, ok or flagged) [-]."""
        return 0 if self.windows is None else len(self.windows)

    @property
    def usable(self) -> int:
        """Windows flagged ``"ok"`` (the points a fit uses unless the gate excludes the run)."""
        return 0 if self.windows is None else int(self.windows["flag"].eq("ok").sum())

    @property
    def verdict(self) -> str:
        """The gate's verdict in one line."""
        if self.error:
            return "unreadable: " + self.error
        if self.test != "constant-velocity":
            return f"{self.test} test: identified by the dynamic identification, not gated"
        if self.gate:
            return "excluded: " + "; ".join(f"{check}: {reason}" for check, reason in self.gate)
        return self.gate_note or "passes"

    def document(self) -> dict:
        """The facts as plain data (``--json``): SI numbers, no traces."""
        windows = [] if self.windows is None else self.windows.to_dict("records")
        return {
            "file": str(self.file),
            "name": self.name,
            "test": self.test,
            "error": self.error or None,
            "error_line": self.error_line,
            "columns": [vars(c) for c in self.columns],
            "reader": self.reader,
            "pressure [Pa]": self.pressure,
            "velocity [m/s]": self.velocity,
            "source": self.source,
            "nominal": {
                q: {s: {"value": v, "where": w} for s, (v, w) in found.items()}
                for q, found in self.nominal.items()
            },
            "pressure measured": self.pressure_measured,
            "force_balance": self.force_balance,
            "velocity_from": self.velocity_from,
            "strokes": self.strokes,
            "windows ok": self.usable,
            "windows": windows,
            "offset [N]": self.offset,
            "offset_from": self.offset_from,
            "gate": [{"check": c, "reason": r} for c, r in self.gate],
            "verdict": self.verdict,
        }


@dataclass
class GateVerdicts:
    """What the data-quality gate says of a campaign's runs, as in a fit (:func:`gate_verdicts`).

    Attributes
    ----------
    excluded : dict
        File name (relative to the campaign folder) -> [(check, reason)].
    notes : list of str
        The gate's summary line (per seal) and its refusal, if it refuses the campaign.
    refused : dict
        File name -> the refusal text of the gate for the campaign (or seal) it belongs to.
    offsets : dict
        Seal (None: the campaign) -> the campaign weight offset [N] (median of the runs').
    points : dict
        File name -> the number of points (windows) the campaign's extraction found in it.
    skipped : dict
        File name -> why the extraction could not read it.
    """

    excluded: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    refused: dict = field(default_factory=dict)
    offsets: dict = field(default_factory=dict)
    points: dict = field(default_factory=dict)
    skipped: dict = field(default_factory=dict)


@dataclass
class Inspection:
    """The facts of a campaign, or of one file in it (:func:`inspect`).

    Attributes
    ----------
    campaign : Campaign
    target : Path
        What was asked for (a file or the campaign folder).
    config_source : str
        The campaign.toml (or recipe) read, or a sentence saying none was.
    runs : list of RunInspection
        The file asked for, or every run of the campaign.
    gate : GateVerdicts
    """

    campaign: Campaign
    target: Path
    config_source: str
    runs: list[RunInspection]
    gate: GateVerdicts

    @property
    def unreadable(self) -> list[RunInspection]:
        """The runs that could not be read."""
        return [run for run in self.runs if run.error]

    def document(self) -> dict:
        """Everything as plain data (``--json``)."""
        basis = dict(self.campaign.config.pressure_basis)
        return {
            "target": str(self.target),
            "campaign": str(self.campaign.folder),
            "config": self.config_source,
            "glob": self.campaign.config.glob,
            "pressure_reference": basis,
            "unlisted": list(self.campaign.unlisted),
            "duplicates": [d._asdict() for d in self.campaign.duplicates],
            "gate_notes": list(self.gate.notes),
            "runs": [run.document() for run in self.runs],
        }


def _has_campaign_files(folder: Path) -> bool:
    return (folder / CONFIG_NAME).is_file() or (folder / MANIFEST_NAME).is_file()


def find_campaign(
    path: str | os.PathLike[str],
    *,
    config: str | os.PathLike[str] | None = None,
    glob: str | None = None,
) -> tuple[Campaign, RunInfo | None]:
    """The campaign of ``path`` and, for a file, its run.

    A folder is the campaign itself (campaign.toml and manifest.csv optional, as for
    ``cylfric fit``). A file belongs to the nearest folder at or above it that holds a
    campaign.toml or a manifest.csv (or, with a recipe ``config``, its own folder first)
    and lists it as a run (its glob, its manifest).

    Raises
    ------
    BenchFileError
        A file outside any campaign, or not a run of the campaign it lies in (naming it,
        the campaign folder and why).
    """
    path = Path(path)
    if path.is_dir():
        return Campaign.open(path, glob, config=config), None
    if not path.is_file():
        raise BenchFileError(
            path, "no such file or folder; expected a run file or a campaign folder"
        )
    resolved = path.resolve()
    folders = [p for p in resolved.parents if _has_campaign_files(p)]
    if config is not None and resolved.parent not in folders:
        folders.insert(0, resolved.parent)
    if not folders:
        raise BenchFileError(
            path,
            f"is outside any campaign: no {CONFIG_NAME} or {MANIFEST_NAME} in its folder or "
            "above; put the file in a campaign folder, give the rig's recipe with --config "
            "FILE, or inspect its folder as a campaign (cylfric inspect FOLDER)",
        )
    reasons = []
    for folder in folders:
        campaign = Campaign.open(folder, glob, config=config)
        for info in campaign.runs:
            if info.path.resolve() == resolved:
                return campaign, info
        copy = [d for d in campaign.duplicates if (folder / d.file).resolve() == resolved]
        if copy:
            raise BenchFileError(path, copy[0].reason)
        reasons.append(_not_listed(campaign, resolved))
    raise BenchFileError(path, f"is not a run of the campaign in {folders[0]}: {reasons[0]}")


def _not_listed(campaign: Campaign, file: Path) -> str:
    """Why ``campaign`` does not count ``file`` among its runs."""
    relative = file.relative_to(campaign.folder).as_posix()
    if relative in campaign.unlisted:
        return f"{MANIFEST_NAME} does not list it (only the files it lists are read)"
    return (
        f"it does not match the glob {campaign.config.glob!r} "
        f"({campaign.config.source or 'the default'})"
    )


def _stated_keys(config: CampaignConfig) -> dict[str, set[str]]:
    """Table -> keys written in the campaign.toml the config came from (empty: defaults)."""
    if not config.source:
        return {}
    try:
        doc = tomllib.loads(Path(config.source).read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError):
        return {}
    return {table: set(keys) for table, keys in doc.items() if isinstance(keys, dict)}


def _config_source(campaign: Campaign) -> str:
    source = campaign.config.source
    if source is None:
        return f"no {CONFIG_NAME}: every setting is a default"
    return str(source)


def force_balance(config: CampaignConfig, data: dict, velocity_from: str = "") -> list[dict]:
    """The terms of eq. 3.1 as :func:`cylfric.steady_state.friction_signal` applies them
    to a file with the columns of ``data``.

    Each term is ``{"term", "value", "applied", "set_in"}``: ``value`` text in engineering
    units, ``applied`` whether it enters this file's force signal, ``set_in`` where the
    setting comes from (campaign.toml's table.key, or "default").
    """
    stated = _stated_keys(config)

    def where(table: str, *keys: str) -> str:
        found = [f"[{table}] {k}" for k in keys if k in stated.get(table, set())]
        return ", ".join(found) if found else "default"

    force_key = where("force_balance", "force")
    terms: list[dict] = []
    pa = "pressure_a [Pa]" if "pressure_a [Pa]" in data else "pressure [Pa]"
    pb = "pressure_b [Pa]" if "pressure_b [Pa]" in data else "pressure [Pa]"
    if config.force_source == "pressures":
        terms.append(
            {
                "term": "force",
                "value": "the chamber pressures times the areas (no load cell)",
                "applied": True,
                "set_in": force_key,
            }
        )
    else:
        has = "force [N]" in data
        sign = "+" if config.load_cell_sign > 0 else "-"
        terms.append(
            {
                "term": "force",
                "value": f"load cell: {sign}1 x force [N]"
                + ("" if has else " (no force column: the file cannot be read)"),
                "applied": has,
                "set_in": f"{force_key}; sign: {where('force_balance', 'load_cell_sign')}",
            }
        )
    cylinder = where("cylinder", "bore", "rod", "kind")
    for chamber, area, column, sign in (
        ("A", config.area_a, pa, "+"),
        ("B", config.area_b, pb, "-"),
    ):
        if not area:
            kind = config.pressure_basis["kind"]
            terms.append(
                {
                    "term": f"chamber {chamber}",
                    "value": "none (no [cylinder] in campaign.toml: no areas)"
                    if cylinder == "default"
                    else f"none (a {kind} cylinder has no chamber {chamber})",
                    "applied": False,
                    "set_in": cylinder,
                }
            )
            continue
        present = column in data
        terms.append(
            {
                "term": f"chamber {chamber}",
                "value": f"{sign} {area * 1e6:.5g} mm^2 x {column}"
                + ("" if present else " (not applied: the file measures no pressure)"),
                "applied": present,
                "set_in": cylinder,
            }
        )
    mass = config.moving_mass
    terms.append(
        {
            "term": "inertia",
            "value": f"- {mass:g} kg x acceleration" if mass else "neglected (moving_mass = 0)",
            "applied": bool(mass),
            "set_in": where("force_balance", "moving_mass"),
        }
    )
    sign = (
        "+1 (position grows on extension)"
        if config.position_sign > 0
        else "-1 (position grows on retraction)"
    )
    terms.append(
        {
            "term": "position sign",
            "value": sign + (f"; velocity {velocity_from}" if velocity_from else ""),
            "applied": True,
            "set_in": where("force_balance", "position_sign"),
        }
    )
    basis = config.pressure_basis
    terms.append(
        {
            "term": "pressure the laws see",
            "value": str(basis["rule"]),
            "applied": True,
            "set_in": str(basis.get("stated_by", "default")),
        }
    )
    return terms


def _columns(data: dict, metadata: dict) -> list[ColumnRead]:
    """The columns of a file as read (:func:`cylfric.io.text.read_bench_arrays` keeps one
    data column per file column, in order, then ``segment [-]``)."""
    names = list(metadata.get("columns") or [])
    keys = [k for k in data if k != "segment [-]"]
    units = metadata.get("units") or {}
    out = []
    for name, key in zip(names, keys, strict=False):
        label, _, unit = key.rpartition(" [")
        unit = unit.rstrip("]")
        quantity = label if label in QUANTITY_DIMENSIONS else None
        values = np.asarray(data[key], dtype=float)
        low = float(np.nanmin(values)) if values.size else math.nan
        high = float(np.nanmax(values)) if values.size else math.nan
        if quantity is not None:
            dimension = QUANTITY_DIMENSIONS[quantity]
            read = str(units.get(quantity, ""))
            factor = float(to_si(1.0, read, dimension)) if read else 1.0
            out.append(
                ColumnRead(name, read, quantity, key, SI_UNITS[dimension], factor, low, high)
            )
        else:
            shown = "" if unit == "-" else unit
            out.append(ColumnRead(name, shown, None, key, shown, 1.0, low, high))
    return out


def _traces(data: dict, metadata: dict, config: CampaignConfig) -> tuple[dict, str]:
    """Time, position, velocity, force signal and stroke index of a run, as the extraction
    computes them (:func:`cylfric.steady_state.extract_points`), and how the velocity was
    obtained."""
    from .steady_state import extraction_options, find_windows, friction_signal, smoothed_velocity

    options = extraction_options(config, {})
    options.pop("spike_sigma", None)
    window = options.pop("velocity_window", 0.2)
    time = np.asarray(data["time [s]"], dtype=float)
    position = data.get("position [m]")
    if "velocity [m/s]" in data:
        velocity = config.position_sign * np.asarray(data["velocity [m/s]"], dtype=float)
        how = "from the velocity column"
    else:
        velocity = smoothed_velocity(
            time, np.asarray(position, dtype=float), window=window, sign=config.position_sign
        )
        how = f"the derivative of the position (Savitzky-Golay over {window:g} s)"
    force = friction_signal(data, config, velocity)
    nominal = abs(float(metadata.get("velocity", math.nan)))
    _, components = find_windows(
        time, velocity, force, nominal_speed=nominal, return_components=True, **options
    )
    stroke = components.get("stroke", np.full(time.size, -1))
    traces = {
        "time [s]": time,
        "position [m]": None
        if position is None
        else config.position_sign * np.asarray(position, dtype=float),
        "velocity [m/s]": velocity,
        "force [N]": force,
        "stroke [-]": stroke,
    }
    return traces, how


def inspect_run(
    campaign: Campaign,
    info: RunInfo,
    gate: GateVerdicts | None = None,
    *,
    traces: bool = True,
) -> RunInspection:
    """The facts of one run of ``campaign`` (a file that cannot be read: its ``error``).

    ``gate`` (from :func:`gate_verdicts`) gives the gate's verdict and, for a run without
    strokes in both directions, the campaign offset; ``traces`` keeps the signals for the
    figure.
    """
    from .steady_state import extract_points

    name = info.path.relative_to(campaign.folder).as_posix()
    run = RunInspection(file=info.path, name=name)
    test = str(info.extra.get("test", "") or "").strip().lower()
    if test in ("presliding", "breakaway"):
        run.test = test
    config = campaign.config
    try:
        data, metadata = read_run(info, config)
        run.columns = _columns(data, metadata)
        run.reader = {
            k: metadata.get(k) for k in ("delimiter", "decimal", "rows", "segments", "header")
        }
        run.pressure, run.velocity = metadata["pressure"], metadata["velocity"]
        run.source, run.nominal = dict(metadata["source"]), metadata["nominal"]
        run.pressure_measured = any(
            k in data for k in ("pressure [Pa]", "pressure_a [Pa]", "pressure_b [Pa]")
        )
        if run.test != "constant-velocity":
            run.force_balance = force_balance(config, data)
            return run
        points = extract_points(data, metadata, config)
        signals, run.velocity_from = _traces(data, metadata, config)
    except BenchFileError as exc:  # names the file (or manifest.csv) and the line
        run.error, run.error_line = str(exc), exc.line
        return run
    except ValueError as exc:  # the force balance cannot be made (friction_signal)
        run.error = f"{info.path}: {exc}"
        return run
    run.force_balance = force_balance(config, data, run.velocity_from)
    run.traces = signals if traces else None
    offsets = points["offset [N]"].dropna()
    if config.force_source == "pressures":
        run.offset, run.offset_from = 0.0, "none: the force is the chambers' (no load cell)"
    elif len(offsets):
        run.offset = float(offsets.iloc[0])
        run.offset_from = "this run: (F_up + F_down)/2 of its ok windows"
    else:
        offsets_found = gate.offsets if gate is not None else {}
        offset = offsets_found.get(info.seal, offsets_found.get(None, math.nan))
        if not math.isnan(offset):
            run.offset = offset
            run.offset_from = "the campaign: median of the other runs' offsets (one direction here)"
            ok = points["flag"].eq("no_offset")
            points.loc[ok, "flag"] = "ok"
            points["offset [N]"] = offset
            points["friction [N]"] = points["direction [-]"] * (points["force [N]"] - offset)
        else:
            run.offset_from = "none: no ok window in both directions, here or in the campaign"
    windows = points[WINDOW_COLUMNS].reset_index(drop=True)
    time, stroke = signals["time [s]"], np.asarray(signals["stroke [-]"])
    spans = [np.flatnonzero(stroke == k) for k in windows["stroke"]]
    windows.insert(2, "stroke_start [s]", [time[i[0]] if i.size else math.nan for i in spans])
    windows.insert(3, "stroke_end [s]", [time[i[-1]] if i.size else math.nan for i in spans])
    run.windows = windows
    if gate is not None:
        run.gate = list(gate.excluded.get(name, []))
        run.gate_note = gate.refused.get(name, "")
        if name in gate.skipped and not run.gate:
            run.gate_note = "skipped by the campaign's extraction: " + gate.skipped[name]
    return run


def gate_verdicts(campaign: Campaign, seal: str | None = None) -> GateVerdicts:
    """Extract the campaign (or ``seal``'s runs; every seal's apart when it has several,
    as ``cylfric fit`` does) and run the data-quality gate on it, as a fit would.

    Files the extraction cannot read are skipped (listed in ``skipped``); a gate that
    refuses the campaign (:class:`cylfric.quality.QualityError`) is recorded, not raised.
    """
    from .quality import QualityError, assess
    from .steady_state import extract_campaign

    parts: dict[str | None, Campaign]
    if seal is not None:
        parts = {seal: campaign.for_seal(seal)}
    elif len(campaign.seals) > 1:
        parts = {name: campaign.for_seal(name) for name in campaign.seals}
    else:
        parts = {None: campaign}
    verdicts = GateVerdicts()
    for label, part in parts.items():
        prefix = "" if label is None else f"seal {label}: "
        names = [i.path.relative_to(campaign.folder).as_posix() for i in part.steady_runs]
        if not names:
            continue
        try:
            extraction = extract_campaign(
                part,
                skip_bad=True,
                exclude=[i.path.name for i in part.dynamic_runs],
            )
        except BenchFileError as exc:
            verdicts.notes.append(prefix + f"the extraction reads none of the runs: {exc}")
            continue
        for item in extraction.skipped:
            name = Path(item["file"]).relative_to(campaign.folder).as_posix()
            verdicts.skipped[name] = item["reason"]
        files = extraction.points["file"].map(
            lambda f: Path(f).relative_to(campaign.folder).as_posix()
        )
        for file, count in files.value_counts().items():
            verdicts.points[str(file)] = int(count)
        verdicts.offsets[label] = extraction.offset
        try:
            report = assess(extraction, duplicates=part.duplicates)
        except QualityError as exc:
            whose = "" if label is None else f" of seal {label}"
            text = f"the gate refuses the campaign{whose}: {exc}"
            verdicts.notes.append(text)
            for name in names:
                verdicts.refused[name] = text
            continue
        verdicts.notes.append(prefix + report.summary().replace("; see excluded.csv", ""))
        for row in report.excluded.to_dict("records"):
            verdicts.excluded.setdefault(str(row["file"]), []).append(
                (str(row["check"]), str(row["reason"]))
            )
    return verdicts


def iter_runs(
    campaign: Campaign,
    runs: list[RunInfo] | tuple[RunInfo, ...],
    gate: GateVerdicts | None = None,
    *,
    traces: bool = True,
) -> Iterator[RunInspection]:
    """:func:`inspect_run` of each of ``runs``, one at a time (the traces of one file held
    at a time when the caller draws and drops them)."""
    for info in runs:
        yield inspect_run(campaign, info, gate, traces=traces)


def inspect(
    path: str | os.PathLike[str],
    *,
    config: str | os.PathLike[str] | None = None,
    glob: str | None = None,
    gate: bool = True,
    traces: bool = True,
    each: Callable[[RunInspection], object] | None = None,
) -> Inspection:
    """The facts of a run file (in its campaign) or of every run of a campaign folder.

    Parameters
    ----------
    path : path-like
        A run file or a campaign folder.
    config : path-like, optional
        A campaign.toml (recipe) to use instead of the folder's (as ``cylfric fit
        --config``).
    glob : str, optional
        Which files are runs (replaces campaign.toml's ``[files] glob``).
    gate : bool
        Run the data-quality gate (it reads the whole campaign, or the file's seal).
    traces : bool
        Keep each run's signals for :func:`cylfric.report.inspect.figure_run`.
    each : callable, optional
        Called with each run's facts as soon as they are gathered (e.g. to draw its figure
        and let its traces go: ``run.traces = None``).

    Raises
    ------
    BenchFileError
        ``path`` is not a campaign folder nor a run of one (:func:`find_campaign`), or the
        campaign cannot be opened. A run file that cannot be read is not raised: its
        :attr:`RunInspection.error` says why.
    """
    campaign, info = find_campaign(path, config=config, glob=glob)
    runs = list(campaign.runs) if info is None else [info]
    verdicts = GateVerdicts()
    if gate:
        seal = None if info is None or len(campaign.seals) < 2 else info.seal
        verdicts = gate_verdicts(campaign, seal=seal)
    found = []
    for run in iter_runs(campaign, runs, verdicts, traces=traces):
        if each is not None:
            each(run)
        found.append(run)
    return Inspection(campaign, Path(path), _config_source(campaign), found, verdicts)
