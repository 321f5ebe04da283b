"""The main job: a campaign folder -> one fit in memory -> datasheet, tables, figures, report.

``fit(folder)`` fits a campaign in memory and returns a :class:`FitResult` (the datasheet's
model, its points, the gate's exclusions, the dynamic identification, the notes);
``FitResult.write(out)`` writes the output folder. ``cylfric fit``, ``fit --seal``,
``fit-many`` and the catalogue all go through :func:`fit`, so the Python route and the
command line give the same datasheet. :func:`fit_campaign` is ``fit(...).write(out)``.
The output folder's transaction (lock, staging, marker, swap) is :mod:`cylfric._outfolder`.
"""

from __future__ import annotations

import io
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import _outfolder
from ._atomic import atomic_write_chunks
from ._outfolder import MARKER
from ._paths import make_folder
from .io.campaign import Campaign, read_run
from .options import FitOptions
from .steady_state import start_extraction

if TYPE_CHECKING:  # pandas and the gate are imported where they are first used
    from collections.abc import Callable, Sequence

    import pandas as pd

    from .identify.dynamic import DynamicIdentification
    from .identify.steady import Identification
    from .model import FrictionModel
    from .quality import QualityReport
    from .steady_state import Extraction
    from .viscosity import ViscosityCorrection

__all__ = [
    "fit",
    "fit_campaign",
    "fit_seals",
    "FitOptions",
    "FitResult",
    "FitOutputs",
    "SealOutputs",
    "SealFitError",
    "MARKER",
]


@dataclass
class FitOutputs:
    """What :meth:`FitResult.write` (and :func:`fit_campaign`) wrote and found.

    ``excluded`` lists the runs the data-quality gate left out (:mod:`cylfric.quality`).
    ``exports`` maps each export target to its :class:`~cylfric.export.ExportResult`.
    ``dynamic`` is the :class:`~cylfric.identify.dynamic.DynamicIdentification` of the
    campaign's presliding and breakaway tests (None without them).
    ``files`` maps each output to its path; ``timings`` holds the wall time of each stage
    [s]: ``extract``, ``identify`` (with the sensitivity study), ``datasheet`` (with the
    CSV tables) and, with the report, ``report`` (figures and report.html).
    ``result`` is the in-memory :class:`FitResult` that was written.
    """

    out: Path
    datasheet: dict
    identification: Identification
    extraction: Extraction
    files: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    excluded: pd.DataFrame | None = None
    exports: dict = field(default_factory=dict)
    dynamic: DynamicIdentification | None = None
    result: FitResult | None = None

    @property
    def model(self) -> FrictionModel:
        """The datasheet's model (its name, pressure reference, dynamic parameters, record)."""
        if self.result is not None:
            return self.result.model
        from .model import FrictionModel

        return FrictionModel.from_datasheet(self.datasheet)


@dataclass
class FitResult:
    """One campaign fitted in memory (:func:`fit`): what every path of cylfric writes.

    Attributes
    ----------
    model : FrictionModel
        The datasheet's model: the campaign's pressure reference
        (``model.pressure_reference_basis``), the sigma_0/sigma_1 of presliding tests when
        the campaign has them, and the record (``model.record``) the datasheet holds.
    datasheet : dict
        ``model.to_datasheet()`` with the fit's records: what ``datasheet.json`` holds.
    identification : Identification
        The steady-state identification (laws compared, per-pressure table, sensitivity).
    extraction : Extraction
        The points of every run as extracted (before the gate), the offset, skipped files.
    quality : QualityReport
        The data-quality gate: ``quality.points`` (the points fitted: excluded runs flagged)
        and ``quality.excluded`` (one row per excluded run, with its check and reason).
    correction : ViscosityCorrection
        The viscosity correction to the ``[oil]`` reference temperature (or why none).
    dynamic : DynamicIdentification or None
        sigma_0/sigma_1 from presliding tests, validated on breakaway ramps.
    campaign : Campaign
        The campaign read (folder, campaign.toml, manifest.csv).
    options : FitOptions
        How it was fitted (and, by default, how :meth:`write` writes it).
    timings : dict
        Wall time [s] of ``extract`` and ``identify``.
    """

    identification: Identification
    extraction: Extraction
    quality: QualityReport
    correction: ViscosityCorrection
    dynamic: DynamicIdentification | None
    campaign: Campaign
    options: FitOptions
    timings: dict = field(default_factory=dict)
    _built: tuple[dict, FrictionModel] | None = field(default=None, repr=False, compare=False)

    @property
    def model(self) -> FrictionModel:
        """The datasheet's model (see the class); built with :attr:`datasheet` on first use."""
        return self._build()[1]

    @property
    def datasheet(self) -> dict:
        """What ``datasheet.json`` holds: ``model.to_datasheet()`` with the fit's records."""
        return self._build()[0]

    def _build(self) -> tuple[dict, FrictionModel]:
        # on first use, not in fit(): write() starts points.csv's forked writer first, so
        # the two overlap (about 6 ms at 270 runs, growing with the runs)
        if self._built is None:
            self._built = _datasheet(
                self.campaign,
                self.options,
                self.identification,
                self.extraction,
                self.correction,
                self.dynamic,
            )
        return self._built

    @property
    def points(self) -> pd.DataFrame:
        """The points the model was fitted to (excluded runs flagged ``"excluded: ..."``)."""
        return self.quality.points

    @property
    def excluded(self) -> pd.DataFrame:
        """The runs the data-quality gate left out: ``file``, ``run``, ``check``, ``reason``."""
        return self.quality.excluded

    @property
    def notes(self) -> list[str]:
        """What the fit assumed, simplified or left out, one line each."""
        return list(self.identification.notes)

    def __repr__(self) -> str:
        folder = self.campaign.folder
        kept = int(self.points["flag"].eq("ok").sum()) if "flag" in self.points else 0
        return (
            f"<FitResult of {folder}: {self.model.friction_law} law, {kept} points, "
            f"{len(self.excluded)} run(s) excluded, {len(self.notes)} note(s)>"
        )

    def write(
        self,
        out: str | os.PathLike[str],
        *,
        report: bool | None = None,
        export: Sequence[str] | str | None = None,
        step: Callable[[str, int], Callable[[str], object]] | None = None,
    ) -> FitOutputs:
        """Write the output folder ``out`` (what ``cylfric fit --out OUT`` writes).

        ``datasheet.json``, ``points.csv``, ``per_pressure.csv``, ``sensitivity.csv``,
        ``law_comparison.csv``, ``dynamic.csv``/``breakaway.csv`` (with presliding tests),
        ``skipped.csv``/``excluded.csv`` (when files were skipped or left out), the exports
        (``export/<target>/``) and, with ``report``, the figures and ``report.html``.
        ``report`` and ``export`` default to the fit's options.

        The folder is written as one transaction (:mod:`cylfric._outfolder`): into a staging
        folder beside ``out``, swapped in whole when every output succeeded; an existing
        ``out`` is replaced only when it is a cylfric output folder holding nothing else
        (ValueError naming what it holds); an ``out`` inside the campaign folder or that is
        a symbolic link is refused. A failed export writes nothing (:class:`ExportFailed`).
        """
        out = Path(out)
        _outfolder.check_out(Path(self.campaign.folder), out)
        return self._write_checked(out, report=report, export=export, step=step)

    def _write_checked(self, out: Path, *, locked=False, **how) -> FitOutputs:
        folder = Path(self.campaign.folder)
        try:
            staging, outputs = _outfolder.staged(
                out, lambda staging: self._write_into(staging, **how), locked=locked
            )
        except ExportFailed as failure:
            raise failure.named(folder, out) from failure.__cause__
        return _moved(staging, outputs, out, out)

    def _write_into(
        self,
        out: Path,
        *,
        report: bool | None = None,
        export: Sequence[str] | str | None = None,
        step: Callable[[str, int], Callable[[str], object]] | None = None,
    ) -> FitOutputs:
        """The outputs in the folder ``out`` as it is (the staging folder); no transaction."""
        options = self.options
        if report is not None or export is not None:
            options = replace(
                options,
                report=options.report if report is None else report,
                export=options.export if export is None else export,  # type: ignore[arg-type]  # __post_init__ makes the tuple
            )
        timings = dict(self.timings)
        t0 = time.perf_counter()
        # points.csv (pandas writes each value by itself: 0.2 s at 10,000 points, 0.4 s at
        # 40,000) is written by a forked process while the datasheet is built and written here
        points_csv = _start_csv(out / "points.csv", self.extraction.points, options.workers)
        try:
            files = self._write_tables(out, points_csv)
        finally:
            points_csv.close()
        timings["datasheet"] = time.perf_counter() - t0
        exports = {}
        if options.export:
            from .export import export as export_to

            t0 = time.perf_counter()
            for target in options.export:
                try:
                    exports[target] = export_to(self.model, target, out / "export" / target)
                except (ValueError, RuntimeError, OSError) as exc:  # a compiler's: 1st line
                    lines = str(exc).strip().splitlines() or [type(exc).__name__]
                    first = lines[0].rstrip(":")
                    raise ExportFailed(f"--export {target} failed: {first}", target) from exc
            timings["export"] = time.perf_counter() - t0
        if options.report:
            files.update(self._write_report(out, exports, options, step))
            timings["report"] = time.perf_counter() - t0
        return FitOutputs(
            out,
            self.datasheet,
            self.identification,
            self.extraction,
            files,
            timings,
            self.excluded,
            exports,
            self.dynamic,
            self,
        )

    def _write_tables(self, out: Path, points_csv) -> dict[str, Path]:
        """The datasheet and the tables in ``out``; points.csv from ``points_csv``."""
        import pandas as pd

        from .datasheet import write_datasheet

        ident, extraction, dynamic = self.identification, self.extraction, self.dynamic
        files = {"datasheet": write_datasheet(out / "datasheet.json", self.datasheet)}
        if dynamic is not None:
            files["dynamic"] = _csv(out / "dynamic.csv", dynamic.per_pressure)
            files["breakaway"] = _csv(out / "breakaway.csv", dynamic.breakaway)
        files["points"] = points_csv.results()[0]
        files["per_pressure"] = _csv(out / "per_pressure.csv", ident.per_pressure)
        files["law_comparison"] = _csv(out / "law_comparison.csv", ident.comparison)
        if ident.sensitivity is not None:
            files["sensitivity"] = _csv(out / "sensitivity.csv", ident.sensitivity)
        if extraction.skipped:
            files["skipped"] = _csv(out / "skipped.csv", pd.DataFrame(extraction.skipped))
        if not self.excluded.empty:
            files["excluded"] = _csv(out / "excluded.csv", self.excluded)
        if ident.directions:
            frames = [r.per_pressure.assign(direction=d) for d, r in ident.directions.items()]
            files["per_direction"] = _csv(out / "per_direction.csv", pd.concat(frames))
        return files

    def _write_report(self, out: Path, exports: dict, options: FitOptions, step) -> dict:
        from .report import write_report_folder

        summaries = [_export_summary(out, result) for result in exports.values()]
        advance = None
        if step is not None:
            from .report import all_figures

            shown = len(all_figures(self.identification, self.extraction.offset))
            advance = step("drawing the figures", shown + (self.dynamic is not None))
        return write_report_folder(
            out,
            self.datasheet,
            self.identification,
            self.extraction,
            self.excluded,
            exports=summaries,
            dynamic=self.dynamic,
            workers=options.workers,
            progress=advance,
        )


def _csv(path, frame: pd.DataFrame, rows: int = 2048):
    """``frame`` as CSV at ``path``, ``rows`` at a time (the same text as one to_csv: pandas
    writes each value by itself; a large table is never held whole as text). 2,048 rows
    take as long as 8,192 and hold a quarter of the text and of pandas' formatted values
    (the forked writer's peak: about 13 MB less at 40,000 points). Text cells go through
    :func:`cylfric.escape.csv_frame` (control characters shown, a leading ``= + - @`` made
    text: a run named ``=HYPERLINK(...)`` is not a formula in a spreadsheet)."""
    from .escape import csv_frame

    frame = csv_frame(frame)

    def chunks():
        for start in range(0, max(len(frame), 1), rows):
            buffer = io.StringIO()
            frame.iloc[start : start + rows].to_csv(buffer, index=False, header=start == 0)
            yield buffer.getvalue().encode()

    return atomic_write_chunks(path, chunks())


def fit(
    folder: Campaign | str | os.PathLike[str],
    options: FitOptions | None = None,
    *,
    seal: str | None = None,
    progress: Callable[[str], object] | None = None,
    after_extraction: Callable[[], object] | None = None,
    step: Callable[[str, int], Callable[[str], object]] | None = None,
    **keywords: Any,
) -> FitResult:
    """Fit a campaign folder in memory: what ``cylfric fit`` fits, nothing written.

    The runs are read (campaign.toml and manifest.csv once), the steady windows extracted,
    the data-quality gate applied, the speeds corrected to the ``[oil]`` reference
    temperature (when campaign.toml gives it), the model identified in the campaign's
    pressure reference, sigma_0/sigma_1 identified from presliding tests (when the campaign
    has them) and the datasheet built. ``fit(folder).write(out)`` writes what
    ``cylfric fit folder --out out`` writes, the same datasheet.

    One model per seal: a campaign whose runs carry several seal labels (a ``seal`` group
    of ``name_pattern`` or a manifest.csv column ``seal``) is never pooled; it is refused
    (ValueError naming the seals) unless ``seal`` picks one, whose runs are then fitted as a
    campaign of their own (the datasheet named after the campaign and the seal).

    Parameters
    ----------
    folder : path-like or Campaign
        Campaign folder of raw bench files (never modified), or the
        :class:`~cylfric.io.campaign.Campaign` already opened from it (``options.glob``,
        when set, must be its glob).
    options : FitOptions, optional
        How to fit (:class:`~cylfric.options.FitOptions`: fixed parameters, pressure law,
        per direction, skip bad files, glob, strict, viscosity correction, workers; the
        report and export targets are what :meth:`FitResult.write` writes by default);
        default ``FitOptions(**keywords)``.
    seal : str, optional
        Fit only the runs of this seal (ValueError listing the seals for a name no run
        carries).
    progress : callable, optional
        Called with each file name as it is read.
    after_extraction : callable, optional
        Called once every file is read (e.g. to stop a progress display).
    step : callable, optional
        ``step(description, total)`` as a later step that can take seconds starts (the
        sigma_0/sigma_1 identification); it returns the callable the step then calls with
        each item's name as it is done, ``total`` times (a progress display).
    **keywords
        The fields of :class:`~cylfric.options.FitOptions` (``fixed=``,
        ``pressure_law=``, ...) when no ``options`` is given; both at once is a ValueError,
        and so is an unknown keyword.

    Returns
    -------
    FitResult

    Raises
    ------
    ValueError
        Bad input (named: the file, the line, what was expected), a campaign the gate
        refuses (:class:`cylfric.quality.QualityError`), an unphysical friction level.
    """
    options = FitOptions.from_keywords(options, **keywords)
    campaign, options = _open(folder, options, seal)
    return _fit(campaign, options, progress, after_extraction, step)


def _open(folder, options: FitOptions, seal: str | None) -> tuple[Campaign, FitOptions]:
    """The campaign to fit (one seal's runs with ``seal``) and the options naming it."""
    source, path = _source(folder, options)
    campaign = (
        source
        if isinstance(source, Campaign)
        else Campaign.open(path, options.glob, config=options.config)
    )
    if seal is not None:
        campaign = campaign.for_seal(seal)
        options = replace(options, name=_seal_name(options, path, seal))
    elif len(campaign.seals) > 1:
        raise ValueError(_several_seals(campaign))
    return campaign, options


def fit_campaign(
    folder: Campaign | str | os.PathLike[str],
    out: str | os.PathLike[str],
    options: FitOptions | None = None,
    *,
    seal: str | None = None,
    progress: Callable[[str], object] | None = None,
    after_extraction: Callable[[], object] | None = None,
    step: Callable[[str, int], Callable[[str], object]] | None = None,
    **keywords: Any,
) -> FitOutputs:
    """``fit(folder, options, seal=...).write(out)``: read, fit and write one campaign.

    The output folder is checked before anything is read (an ``out`` inside the campaign,
    a symbolic link, a folder holding files cylfric did not write: ValueError), and its
    lock is held from the start, so a second fit into the same ``out`` is refused at once.
    Parameters are those of :func:`fit` and :meth:`FitResult.write`; the report and the
    export targets are ``options.report`` and ``options.export``.
    """
    options = FitOptions.from_keywords(options, **keywords)
    _, path = _source(folder, options)
    out = Path(out)
    _outfolder.check_out(path, out)
    campaign, options = _open(folder, options, seal)
    make_folder(out.parent, f"--out {out}: its folder")
    with _outfolder.lock(out):
        result = _fit(campaign, options, progress, after_extraction, step)
        return result._write_checked(out, locked=True, step=step)


def _source(folder, options: FitOptions) -> tuple[Campaign | Path, Path]:
    """(the campaign or its folder, the folder); a Campaign's glob must be ``options.glob``."""
    if isinstance(folder, Campaign):
        if options.glob is not None and options.glob != folder.config.glob:
            raise ValueError(
                f"options.glob = {options.glob!r} but the campaign was opened with glob "
                f"{folder.config.glob!r}; open it with Campaign.open(folder, glob=...)"
            )
        return folder, Path(folder.folder)
    return Path(folder), Path(folder)


def _moved(staging: Path, result: FitOutputs, out: Path, result_out: Path) -> FitOutputs:
    """``result`` (written into ``staging``) with its paths moved from the staging folder to
    ``out`` (and ``result.out`` = ``result_out``)."""
    result.out = result_out
    result.files = {k: out / Path(v).relative_to(staging) for k, v in result.files.items()}
    result.exports = {
        target: replace(
            exported, files=tuple(out / Path(f).relative_to(staging) for f in exported.files)
        )
        for target, exported in result.exports.items()
    }
    return result


class ExportFailed(ValueError):
    """An export of :meth:`FitResult.write` failed, so nothing of the fit was written.

    The message names the campaign, the target, the first line of the cause (chained as
    ``__cause__``) and what became of the output folder; ``target`` is the export target.
    """

    def __init__(self, message, target):
        super().__init__(message, target)
        self.target = target

    def __str__(self):
        return self.args[0]

    def named(self, folder, out: Path) -> ExportFailed:
        """This failure naming the campaign ``folder`` and what became of ``out`` (nothing
        was written: it keeps its earlier contents, or was not created)."""
        kept = "keeps its earlier contents" if out.exists() else "was not created"
        return ExportFailed(
            f"{folder}: {self}. Nothing was written (--out {out} {kept}); fit without "
            f"--export {self.target} to get the datasheet and the other outputs",
            self.target,
        )


def _sign_settings(folder, config=None) -> str:
    """Where campaign.toml (or the ``--config`` recipe) sets the force-balance signs, for an
    unphysical-friction error."""
    from .io.campaign import CONFIG_NAME, _line_of

    source = getattr(config, "source", None)
    path = Path(source) if source else Path(folder) / CONFIG_NAME
    if not path.is_file():
        return "; no campaign.toml: the signs are the defaults (load_cell_sign = 1)"
    found = [
        f"{path}, line {line}: {key}"
        for key in ("load_cell_sign", "position_sign")
        if (line := _line_of(path, key)) is not None
    ]
    return f"; set in {'; '.join(found)}" if found else f"; {path} keeps the default signs"


def _fit(
    campaign: Campaign,
    options: FitOptions,
    progress: Callable[[str], object] | None = None,
    after_extraction: Callable[[], object] | None = None,
    step: Callable[[str, int], Callable[[str], object]] | None = None,
) -> FitResult:
    """The fit of :func:`fit`, in order: extraction, gate, viscosity, identification,
    dynamic parameters, the datasheet's model."""
    timings = {}
    t0 = time.perf_counter()
    folder, config = campaign.folder, campaign.config
    dynamic_runs = campaign.dynamic_runs
    reading = start_extraction(
        campaign,
        skip_bad=options.skip_bad,
        progress=progress,
        exclude=[info.path.name for info in dynamic_runs],
        workers=options.workers,
        scheduler=options.scheduler,
    )
    try:
        # while a pool reads the files, the libraries of the next steps load here (pandas,
        # scipy.optimize, jsonschema: about 0.7 s; benchmarks/bench_parallel.py), and the
        # datasheet's validator is compiled (0.1 s, 15 MB for a moment; not in the tail)
        from . import datasheet  # noqa: F401 (loaded here while the pool reads)
        from .identify import UnphysicalFrictionError, identify
        from .model.serialize import compile_schema
        from .quality import assess

        compile_schema()

        extraction = reading.result()
    finally:
        reading.close()
        if after_extraction is not None:
            after_extraction()
    del reading  # the workers' packed results (their points as arrays), now in extraction

    # the data as measured: the gate looks for data errors (and lists the duplicate files)
    quality = assess(
        extraction,
        duplicates=campaign.duplicates,
        accept_force_balance=options.accept_force_balance,
    )
    correction = _correct_viscosity(extraction, config, options.viscosity_correction)
    if correction.record is not None:  # the points the gate passed, at the reference temperature
        gated = _correct_viscosity(replace(extraction, points=quality.points), config, True)
        extraction = replace(extraction, points=correction.points, runs=correction.runs)
        quality = replace(quality, points=gated.points)
    if options.strict and not quality.excluded.empty:
        raise ValueError(_strict_message(quality.excluded))
    timings["extract"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    try:
        ident = identify(
            quality.points,
            fixed=options.fixed,
            pressure_law=options.pressure_law,
            per_direction=options.per_direction,
            workers=options.workers,
            pressure_reference=config.pressure_basis,
        )
    except UnphysicalFrictionError as exc:
        raise UnphysicalFrictionError(f"{exc}{_sign_settings(folder, config)}") from None
    ident.notes[0:0] = list(quality.notes)  # what the physical checks found, when accepted
    if not quality.excluded.empty:
        ident.notes.insert(0, quality.summary())
    if correction.note:
        ident.notes.insert(0, correction.note)
    dynamic = None
    if dynamic_runs:
        dynamic, notes = _identify_dynamic(dynamic_runs, config, ident.model, step)
        model = ident.model if dynamic is None else dynamic.model
        ident = replace(ident, model=model, notes=ident.notes + notes)
    timings["identify"] = time.perf_counter() - t0
    return FitResult(ident, extraction, quality, correction, dynamic, campaign, options, timings)


def _datasheet(campaign, options, ident, extraction, correction, dynamic):
    """(the datasheet, its model): the identified model with the campaign's record."""
    from .datasheet import datasheet_model

    folder, config = campaign.folder, campaign.config
    model = datasheet_model(
        ident,
        extraction=extraction,
        campaign=str(folder),
        name=options.name,
        recipe=_recipe(config, folder),
        cylinder=_cylinder(config),
    )
    sheet, record = model.to_datasheet(), dict(model.record)
    if correction.record is not None:
        sheet["fit"]["viscosity_correction"] = correction.record
        record["fit"] = {**record.get("fit", {}), "viscosity_correction": correction.record}
    if dynamic is not None:
        from .model.serialize import clean

        sheet["dynamic_fit"] = record["dynamic_fit"] = clean(dynamic.summary())
    return sheet, model.replace(record=record)  # the datasheet's model, for the exports


def _cylinder(config) -> dict | None:
    """The datasheet's ``cylinder``: campaign.toml's [cylinder] (kind, bore and rod [m]) and
    the chamber areas [m^2] the force balance used; None when campaign.toml gives none."""
    if config.cylinder is None:
        return None
    return {**config.cylinder, "area_a": config.area_a, "area_b": config.area_b}


def _start_csv(path: Path, frame: pd.DataFrame, workers: int | None):
    """``frame`` written as CSV at ``path`` by a forked process (:func:`_csv`), from
    :data:`BACKGROUND_CSV_MIN_ROWS` rows and with ``workers`` 2 or more (None: the cores
    this process may use); else when the result is asked for, here."""
    from ._parallel import start

    # start forks only where this process has a second core (else it writes here)
    background = workers != 1 and len(frame) >= BACKGROUND_CSV_MIN_ROWS
    return start(lambda _: _csv(path, frame), 1, min_items=1, background=background)


BACKGROUND_CSV_MIN_ROWS = 2000
"""Fewest points for which points.csv is written by a forked process (about 10 ms to fork
and wait for; pandas writes about 40 ms per 2,000 rows)."""


STRICT_SHOWN = 8
"""How many flagged runs the ``--strict`` error names (then a count of the rest)."""


def _strict_message(excluded: pd.DataFrame) -> str:
    """The ``--strict`` error: every flagged run with its reason (the first
    :data:`STRICT_SHOWN`, then a count); nothing is written, so no file is named."""
    counts = ", ".join(f"{n} by {check}" for check, n in excluded["check"].value_counts().items())
    shown = excluded.head(STRICT_SHOWN)
    runs = "; ".join(f"{row['file']}: {row['reason']}" for _, row in shown.iterrows())
    if len(excluded) > STRICT_SHOWN:
        runs += f"; and {len(excluded) - STRICT_SHOWN} more run(s)"
    return (
        f"--strict: the data-quality gate flags {len(excluded)} run(s) ({counts}): {runs}. "
        "Nothing was written (--strict stops before the fit); without --strict the fit "
        "leaves these runs out and lists them with their reasons"
    )


def _export_summary(out: Path, result) -> dict:
    """Plain data about one export for the report (the report never imports export)."""
    folder = Path(result.files[0]).parent if result.files else out / "export"
    return {
        "target": result.target,
        "folder": str(folder.relative_to(out)),
        "files": [Path(f).name for f in result.files],
        "loss": None
        if result.loss is None
        else [
            {
                "block": report.title,
                "rms [N]": report.rms,
                "max [N]": report.max_abs,
                "velocity [mm/s]": report.worst[0] * 1e3,
                "pressure [bar]": report.worst[1] / 1e5,
            }
            for report in result.loss
        ],
    }


def _correct_viscosity(extraction, config, enabled):
    """The points at the reference temperature of ``[oil]`` (or as they are, with a note)."""
    from .viscosity import correct_campaign

    return correct_campaign(extraction.points, extraction.runs, config.oil, enabled=enabled)


def _identify_dynamic(infos, config, model, step=None):
    """sigma_0 and sigma_1 from the presliding tests, validated on the breakaway ramps.

    Returns (DynamicIdentification or None, notes): without a presliding test the
    parameters stay assumed and a note says why.
    """
    from .identify.dynamic import dynamic_record, identify_dynamic

    records = []
    for info in infos:
        data, metadata = read_run(info, config)
        metadata["path"] = str(info.path)
        records.append(
            dynamic_record(
                data,
                metadata,
                mass=config.moving_mass or None,
                position_sign=config.position_sign,
                force_sign=config.load_cell_sign,
                reference=config.pressure_reference,
            )
        )
    if not any(record.test == "presliding" for record in records):
        return None, [
            f"{len(records)} breakaway test(s) but no presliding test: sigma_0 and sigma_1 "
            "stay assumed (they are identified from presliding tests)"
        ]
    tests = [r for r in records if r.test in ("presliding", "breakaway")]
    advance = None
    if step is not None:
        advance = step(f"sigma_0, sigma_1 from {len(tests)} presliding/breakaway tests", len(tests))
    dynamic = identify_dynamic(records, model, progress=advance)
    return dynamic, list(dynamic.notes)


# ---- one model per seal --------------------------------------------------------------------

SEALS_NAME = "seals.csv"
"""The summary table of :func:`fit_seals`: one row per seal (:data:`SEAL_COLUMNS`)."""

SEAL_COLUMNS = (
    "seal",
    "folder",
    "runs [-]",
    "points [-]",
    "excluded [-]",
    "friction law",
    "pressure min [bar]",
    "pressure max [bar]",
    "speed min [mm/s]",
    "speed max [mm/s]",
    "F_c at pressure min [N]",
    "F_c at pressure max [N]",
    "RMSE [N]",
)
"""Columns of ``seals.csv``: the seal label, its output folder (relative to ``out``), the
runs read, the points fitted, the files the data-quality gate left out, the friction law
of its datasheet, its validity range, its Coulomb level at both ends of the pressure range
and the RMS residual of its fit."""


class SealFitError(ValueError):
    """One seal of :func:`fit_seals` could not be fitted, so nothing was written; the
    message names the seal and the cause (chained as ``__cause__``)."""


@dataclass
class SealOutputs:
    """What :func:`fit_seals` wrote: one :class:`FitOutputs` per seal (``out/<seal>/``),
    the summary table (``summary``, :data:`SEAL_COLUMNS`; ``out/seals.csv``) and its path
    (``files["seals"]``)."""

    out: Path
    seals: dict[str, FitOutputs]
    summary: pd.DataFrame
    files: dict = field(default_factory=dict)


def _seal_name(options: FitOptions, folder: Path, seal: str) -> str:
    """The datasheet name of one seal's fit: the campaign's name (``options.name`` or the
    folder's) and the seal's."""
    base = options.name or Path(folder).resolve().name or "campaign"
    return f"{base}: {seal}"


def _several_seals(campaign: Campaign) -> str:
    seals = ", ".join(campaign.seals)
    return (
        f"{campaign.folder} holds {len(campaign.seals)} seals ({seals}); a model pools no "
        "seals: pick one with seal=NAME (cylfric fit --seal NAME), or fit each into its own "
        "folder with fit_seals (cylfric fit without --seal writes OUT/<seal>/)"
    )


def _seal_folders(campaign: Campaign, out: Path) -> dict[str, str]:
    """seal -> its folder name inside ``out``; ValueError for runs without a label beside
    labelled ones, and OutputPathError for a label that cannot name a folder of its own
    inside ``out`` (``..``, a ``/``, a leading ``.``, the summary's name, two labels that
    differ only in case)."""
    from ._paths import OutputPathError, inside

    unlabelled = [info.path.name for info in campaign.runs if info.seal is None]
    if unlabelled:
        shown = _outfolder.named(unlabelled, 3)
        raise ValueError(
            f"{campaign.folder}: {len(unlabelled)} run(s) carry no seal label ({shown}) "
            f"while the others name the seals {', '.join(campaign.seals)}; runs of different "
            "seals are never pooled: give every run a seal (the 'seal' group of "
            "campaign.toml's name_pattern, or manifest.csv's 'seal' column) or leave those "
            "files out (--glob)"
        )
    folders: dict[str, str] = {}
    seen: dict[str, str] = {}
    for name in campaign.seals:
        if "/" in name or name.startswith(".") or name.casefold() == SEALS_NAME:
            raise OutputPathError(
                f"seal {name!r} cannot name a folder of its own inside {out}: expected a "
                f"name without '/', not starting with '.' and other than {SEALS_NAME}; "
                "rename the files or the manifest.csv 'seal' cells"
            )
        inside(out, name, what="seal")  # no '..', '\', control characters; stays inside
        key = name.casefold()
        if key in seen:
            raise OutputPathError(
                f"seals {seen[key]!r} and {name!r} differ only in case: their folders would "
                "be one on some file systems; give them distinct names"
            )
        seen[key] = name
        folders[name] = name
    return folders


def fit_seals(
    folder: Campaign | str | os.PathLike[str],
    out: str | os.PathLike[str],
    options: FitOptions | None = None,
    *,
    progress: Callable[[str], object] | None = None,
    after_extraction: Callable[[], object] | None = None,
    step: Callable[[str, int], Callable[[str], object]] | None = None,
    **keywords: Any,
) -> SealOutputs:
    """Fit each seal of a campaign into ``out/<seal>/``, and the summary ``out/seals.csv``.

    The runs are split by their seal label (a ``seal`` group of ``name_pattern`` or the
    manifest.csv column ``seal``; :attr:`~cylfric.io.campaign.RunInfo.seal`) and each seal
    is fitted as a campaign of its own (:func:`fit_campaign`'s outputs, the datasheet named
    after the campaign and the seal): no seal's runs enter another's model. The whole
    ``out`` is written as :func:`fit_campaign` writes it (one staging folder swapped in
    whole, the lock, the marker listing every file), so a seal that fails leaves ``out`` as
    it was (:class:`SealFitError` naming the seal).

    Seal labels come from file names and manifest cells: a label that would leave ``out``
    or collide with another output is refused (:class:`~cylfric._paths.OutputPathError`).
    Runs without a label beside labelled ones are refused (ValueError naming them), and so
    is a campaign without labels (fit it with :func:`fit_campaign`).

    Parameters are those of :func:`fit_campaign`; ``after_extraction`` is called once,
    after the last seal's files are read.
    """
    options = FitOptions.from_keywords(options, **keywords)
    source, folder = _source(folder, options)
    out = Path(out)
    _outfolder.check_out(folder, out)
    campaign = (
        source
        if isinstance(source, Campaign)
        else Campaign.open(folder, options.glob, config=options.config)
    )
    if not campaign.seals:
        raise ValueError(
            f"{folder}: no run carries a seal label (the 'seal' group of campaign.toml's "
            "name_pattern, or manifest.csv's 'seal' column); fit it as one campaign "
            "(fit_campaign)"
        )
    folders = _seal_folders(campaign, out)

    def write(staging: Path):
        from ._paths import inside

        results = {}
        for index, name in enumerate(campaign.seals):
            last = index == len(campaign.seals) - 1
            target = make_folder(inside(staging, folders[name], what="seal"))
            named = replace(options, name=_seal_name(options, folder, name))
            try:
                fitted = _fit(
                    campaign.for_seal(name),
                    named,
                    progress,
                    after_extraction if last else None,
                    step,
                )
                results[name] = fitted._write_into(target, step=step)
            except ExportFailed as failure:
                raise ExportFailed(f"seal {name}: {failure}", failure.target) from (
                    failure.__cause__
                )
            except ValueError as exc:
                raise SealFitError(
                    f"seal {name}: {exc} (the other seals alone: --seal NAME)"
                ) from exc
        summary = seal_summary(results, folders)
        _csv(staging / SEALS_NAME, summary)
        return results, summary

    try:
        staging, (results, summary) = _outfolder.staged(out, write)
    except ExportFailed as failure:
        raise failure.named(folder, out) from failure.__cause__
    fits = {
        name: _moved(staging, result, out, out / folders[name]) for name, result in results.items()
    }
    return SealOutputs(out, fits, summary, {"seals": out / SEALS_NAME})


def seal_summary(results: dict[str, FitOutputs], folders: dict[str, str]) -> pd.DataFrame:
    """The table of :func:`fit_seals`: one row per seal, :data:`SEAL_COLUMNS`."""
    import math

    import pandas as pd

    from .model import FrictionModel

    rows = []
    for name, result in results.items():
        sheet = result.datasheet
        validity = sheet.get("validity") or {}
        p_min, p_max = validity.get("pressure_min"), validity.get("pressure_max")
        levels = [math.nan, math.nan]
        if p_min is not None and p_max is not None:
            model = FrictionModel.from_datasheet(sheet)
            levels = [float(model.params_at(p)["F_c"]) for p in (p_min, p_max)]

        def scaled(value, scale):
            return math.nan if value is None else value / scale

        excluded = result.excluded
        rows.append(
            {
                "seal": name,
                "folder": folders[name],
                "runs [-]": len(result.extraction.runs),
                "points [-]": sheet["fit"].get("n_points"),
                "excluded [-]": 0 if excluded is None else len(excluded),
                "friction law": sheet["model"].get("friction_law"),
                "pressure min [bar]": scaled(p_min, 1e5),
                "pressure max [bar]": scaled(p_max, 1e5),
                "speed min [mm/s]": scaled(validity.get("velocity_min"), 1e-3),
                "speed max [mm/s]": scaled(validity.get("velocity_max"), 1e-3),
                "F_c at pressure min [N]": levels[0],
                "F_c at pressure max [N]": levels[1],
                "RMSE [N]": sheet["fit"].get("rmse"),
            }
        )
    return pd.DataFrame(rows, columns=list(SEAL_COLUMNS))


def _recipe(config, folder) -> str | None:
    """The campaign.toml read when it is not the folder's own (``--config``), else None."""
    from .io.campaign import CONFIG_NAME

    source = getattr(config, "source", None)
    if source is None or Path(source).resolve() == (Path(folder) / CONFIG_NAME).resolve():
        return None
    return str(source)
