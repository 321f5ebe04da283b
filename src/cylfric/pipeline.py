"""The main job as one Python function: a campaign folder -> datasheet, tables, figures, report.

``fit_campaign(folder, out)`` is what ``cylfric fit`` runs; notebooks can call it too.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ._atomic import atomic_write_chunks
from ._paths import failed, make_folder, refuse_link
from .io.campaign import Campaign, read_run
from .io.writers import atomic_write_text
from .options import FitOptions
from .steady_state import start_extraction

if TYPE_CHECKING:  # pandas and the gate are imported where they are first used
    from collections.abc import Callable

    import pandas as pd

    from .identify.dynamic import DynamicIdentification
    from .identify.steady import Identification
    from .model import FrictionModel
    from .steady_state import Extraction

__all__ = ["fit_campaign", "fit_seals", "FitOptions", "FitOutputs", "SealOutputs", "SealFitError"]


@dataclass
class FitOutputs:
    """What :func:`fit_campaign` wrote and found.

    ``excluded`` lists the runs the data-quality gate left out (:mod:`cylfric.quality`).
    ``exports`` maps each export target to its :class:`~cylfric.export.ExportResult`.
    ``dynamic`` is the :class:`~cylfric.identify.dynamic.DynamicIdentification` of the
    campaign's presliding and breakaway tests (None without them).
    ``files`` maps each output to its path; ``timings`` holds the wall time of each stage
    [s]: ``extract``, ``identify`` (with the sensitivity study), ``datasheet`` (with the
    CSV tables) and, with the report, ``report`` (figures and report.html).
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


def _csv(path, frame: pd.DataFrame, rows: int = 2048):
    """``frame`` as CSV at ``path``, ``rows`` at a time (the same text as one to_csv: pandas
    writes each value by itself; a large table is never held whole as text). 2,048 rows
    take as long as 8,192 and hold a quarter of the text and of pandas' formatted values
    (the forked writer's peak: about 13 MB less at 40,000 points)."""

    def chunks():
        for start in range(0, max(len(frame), 1), rows):
            buffer = io.StringIO()
            frame.iloc[start : start + rows].to_csv(buffer, index=False, header=start == 0)
            yield buffer.getvalue().encode()

    return atomic_write_chunks(path, chunks())


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
    """Read a campaign, extract the points, identify the model, write the outputs.

    One model per seal: a campaign whose runs carry several seal labels (a ``seal`` group
    of ``name_pattern`` or a manifest.csv column ``seal``) is never pooled; it is refused
    (ValueError naming the seals) unless ``seal`` picks one, whose runs are then fitted
    into ``out`` as a campaign of their own. :func:`fit_seals` fits every seal.

    Every output is written into a staging folder beside ``out`` and swapped in only when
    all succeeded: an earlier ``out`` is replaced whole (no stale files of another campaign)
    or, on failure, left as it was. An existing ``out`` is re-used only when it is a cylfric
    output folder whose marker (:data:`MARKER`) lists everything in it: a folder without
    the marker, or holding any file or folder cylfric did not write, is refused
    (ValueError naming those files), so nothing of the user's is ever deleted. A lock file
    beside ``out`` refuses a second concurrent fit into it; an ``out`` inside the campaign
    folder is refused (it would be read back as runs), and so is an ``out`` that is a
    symbolic link (:func:`cylfric._paths.refuse_link`: the message names its target, which
    can be passed instead). An OSError (full disk, read-only folder) names the file or
    folder and the action.

    Parameters
    ----------
    folder : path-like or Campaign
        Campaign folder of raw bench files (never modified), or the
        :class:`~cylfric.io.campaign.Campaign` already opened from it (its campaign.toml
        and manifest.csv are not read again; ``options.glob``, when set, must be its glob).
    out : path-like
        Output folder: ``datasheet.json``, ``points.csv``, ``per_pressure.csv``,
        ``sensitivity.csv``, ``law_comparison.csv``, ``dynamic.csv`` and ``breakaway.csv``
        (with presliding/breakaway tests), ``skipped.csv`` (when files were
        skipped), ``excluded.csv`` (when the data-quality gate left runs out), and with
        ``report`` the figures (PNG, SVG) and ``report.html``.
    options : FitOptions, optional
        How to fit (:class:`~cylfric.options.FitOptions`: fixed parameters, pressure law,
        per direction, skip bad files, report, name, glob, strict, export targets, workers,
        viscosity correction); default ``FitOptions(**keywords)``.
    seal : str, optional
        Fit only the runs of this seal (ValueError listing the seals for a name no run
        carries); the datasheet's name is the campaign's followed by the seal's.
    progress : callable, optional
        Called with each file name as it is read.
    after_extraction : callable, optional
        Called once every file is read (e.g. to stop a progress display).
    step : callable, optional
        ``step(description, total)`` as each later step that can take seconds starts (the
        sigma_0/sigma_1 identification, the report); it returns the callable the step then
        calls with each item's name as it is done, ``total`` times (a progress display).
    **keywords
        The fields of :class:`~cylfric.options.FitOptions` (``fixed=``,
        ``pressure_law=``, ``report=``, ...) when no ``options`` is given; both at once is
        a ValueError, and so is an unknown keyword.
    """
    options = FitOptions.from_keywords(options, **keywords)
    source, folder = _source(folder, options)
    out = Path(out)
    _check_out(folder, out)
    campaign = (
        source
        if isinstance(source, Campaign)
        else Campaign.open(folder, options.glob, config=options.config)
    )
    if seal is not None:
        campaign = campaign.for_seal(seal)
        options = replace(options, name=_seal_name(options, folder, seal))
    elif len(campaign.seals) > 1:
        raise ValueError(_several_seals(campaign))
    staged = _staged(
        folder,
        out,
        lambda staging: _fit(campaign, staging, options, progress, after_extraction, step),
    )
    return _moved(staged, out, out)


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


def _staged(folder: Path, out: Path, write: Callable[[Path], Any]):
    """``write(staging)`` into a staging folder beside ``out``, swapped in whole under the
    lock (see :func:`fit_campaign`); returns what ``write`` returned, its paths still in the
    staging folder (:func:`_moved` maps them)."""
    make_folder(out.parent, f"--out {out}: its folder")
    with _lock(out):
        _remove_leftovers(out)
        try:
            staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
        except OSError as exc:
            action = f"writing --out {out}: creating a staging folder in"
            raise failed(exc, action, out.parent) from exc
        mask = os.umask(0)
        os.umask(mask)
        staging.chmod(0o777 & ~mask)  # mkdtemp makes it private; the output is not
        try:
            result = write(staging)
            _write_marker(staging)
            _check_reusable(out)  # again: a file may have been added during the fit
            _swap_in(staging, out)
        except ExportFailed as failure:  # name the campaign and the (untouched) output folder
            shutil.rmtree(staging, ignore_errors=True)
            kept = "keeps its earlier contents" if out.exists() else "was not created"
            raise ExportFailed(
                f"{folder}: {failure}. Nothing was written (--out {out} {kept}); fit without "
                f"--export {failure.target} to get the datasheet and the other outputs",
                failure.target,
            ) from failure.__cause__
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
    return staging, result


def _moved(staged, out: Path, result_out: Path) -> FitOutputs:
    """The :class:`FitOutputs` of ``staged`` = (staging folder, result) with its paths
    moved from the staging folder to ``out`` (and ``result.out`` = ``result_out``)."""
    staging, result = staged
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
    """An export of :func:`fit_campaign` failed, so nothing of the fit was written.

    The message names the campaign, the target, the first line of the cause (chained as
    ``__cause__``) and what became of the output folder; ``target`` is the export target.
    """

    def __init__(self, message, target):
        super().__init__(message, target)
        self.target = target

    def __str__(self):
        return self.args[0]


MARKER = ".cylfric-output"
"""File that marks a folder written by :func:`fit_campaign` and lists every file and folder
cylfric wrote into it (one path a line, relative, folders ending in ``/``). The next fit
replaces such a folder whole only when it holds nothing else."""

_MARKER_HEADER = (
    "# Written by cylfric fit. The next cylfric fit into this folder replaces it whole, but\n"
    "# only while it holds nothing but the files listed here (anything else: it refuses).\n"
)


def _write_marker(folder: Path):
    """List everything in ``folder`` (the finished staging folder) in its marker file."""
    entries = sorted(
        path.relative_to(folder).as_posix() + ("/" if path.is_dir() else "")
        for path in folder.rglob("*")
    )
    listed = [e for e in entries if e != MARKER]
    atomic_write_text(folder / MARKER, _MARKER_HEADER + "".join(f"{e}\n" for e in listed))


def _listed(out: Path) -> set[str]:
    """Paths the marker of ``out`` lists (empty for a marker of an older cylfric)."""
    try:
        text = (out / MARKER).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return set()
    return {line.strip() for line in text.splitlines() if line.strip() and line[0] != "#"}


def _foreign(out: Path) -> list[str]:
    """Files and folders in ``out`` that its marker does not list (folders end in ``/``;
    a folder that is not listed is named once, without its contents)."""
    listed = _listed(out) | {MARKER}
    foreign = []

    def walk(folder: Path):
        for path in sorted(folder.iterdir()):
            name = path.relative_to(out).as_posix()
            if path.is_dir() and not path.is_symlink():
                if name + "/" in listed:
                    walk(path)
                else:
                    foreign.append(name + "/")
            elif name not in listed:
                foreign.append(name)

    walk(out)
    return foreign


def _named(paths: list[str], limit: int = 4) -> str:
    shown = ", ".join(paths[:limit])
    return shown + (f" and {len(paths) - limit} more" if len(paths) > limit else "")


def _check_reusable(out: Path):
    """Refuse an existing ``out`` that holds anything cylfric did not write there."""
    if not out.exists() and not out.is_symlink():
        return
    if not out.is_dir():
        raise ValueError(f"--out {out} is a file; expected a folder")
    if not any(out.iterdir()):
        return
    if not (out / MARKER).is_file():
        held = sorted(p.name + ("/" if p.is_dir() else "") for p in out.iterdir())
        raise ValueError(
            f"--out {out} exists and is not a cylfric output folder (no {MARKER} marker); "
            f"it holds {_named(held)}. "
            "The output folder is replaced whole: choose a new or empty --out, or move "
            "those files"
        )
    foreign = _foreign(out)
    if foreign:
        raise ValueError(
            f"--out {out} holds files cylfric did not write ({_named(foreign)}; not listed in "
            f"its {MARKER}). The output folder is replaced whole and they would be lost: "
            "choose another --out, or move them out of it"
        )


def _check_out(folder: Path, out: Path):
    """Refuse an output folder that would read back as runs or whose files would be lost,
    or that is a symbolic link."""
    refuse_link(out)
    campaign, target = folder.resolve(), out.resolve()
    if target == campaign or campaign in target.parents or target in campaign.parents:
        sibling = campaign.parent / f"{campaign.name or 'campaign'}-fit"
        if not folder.is_absolute():  # as the user would type it: 'fit .' -> ../NAME-fit
            with contextlib.suppress(ValueError):  # (another drive on Windows)
                sibling = Path(os.path.relpath(sibling))
        unnamed = folder.name in ("", ".", "..")  # 'fit .': which folder that is
        where = f"{folder}" + (f" ({campaign})" if unnamed else "")
        if target in campaign.parents:
            problem = (
                f"--out {out} contains the campaign folder {where}; the output folder is "
                "replaced whole, so choose one that does not hold the raw files"
            )
        else:
            problem = (
                f"--out {out} is inside the campaign folder {where}: its files would be read "
                "back as runs; choose an output folder outside the campaign"
            )
        import shlex

        raise ValueError(f"{problem}, e.g. --out {shlex.quote(str(sibling))}")
    _check_reusable(out)


@contextlib.contextmanager
def _lock(out: Path):
    """Hold ``.OUT.lock`` beside ``out`` (with this process id); refuse a live holder."""
    lock = out.parent / f".{out.name}.lock"
    for _ in range(2):
        try:
            handle = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            break
        except FileExistsError:
            try:
                holder = int(lock.read_text().strip() or 0)
            except (OSError, ValueError):
                holder = 0
            if holder and _alive(holder):
                raise ValueError(
                    f"another cylfric fit (process {holder}) is writing {out}; wait for it or "
                    f"choose another --out (lock file {lock})"
                ) from None
            lock.unlink(missing_ok=True)  # a stale lock of a process that is gone
        except OSError as exc:  # a read-only folder, a full disk
            raise failed(exc, f"writing --out {out}: creating the lock file", lock) from exc
    else:  # pragma: no cover - lost a race twice
        raise ValueError(f"cannot take the lock {lock}")
    try:
        os.write(handle, str(os.getpid()).encode())
        os.close(handle)
        yield
    finally:
        lock.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _swap_in(staging: Path, out: Path):
    """Replace ``out`` by ``staging`` (two renames on one file system); on a failed second
    rename the previous ``out`` is put back."""
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.old-{os.getpid()}"
        try:
            out.rename(old)
        except OSError as exc:
            raise failed(exc, "writing --out: moving the previous folder aside", out) from exc
    try:
        staging.rename(out)
    except OSError as exc:
        if old is not None:
            old.rename(out)
        raise failed(exc, "writing --out: renaming the finished folder to", out) from exc
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _remove_leftovers(out: Path):
    """Staging and old folders of fits into ``out`` that were killed (called under the lock)."""
    for pattern in (f".{out.name}.staging-*", f".{out.name}.old-*"):
        for path in out.parent.glob(pattern):
            shutil.rmtree(path, ignore_errors=True)


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
    source: Campaign | Path,
    out: Path,
    options: FitOptions,
    progress: Callable[[str], object] | None = None,
    after_extraction: Callable[[], object] | None = None,
    step: Callable[[str, int], Callable[[str], object]] | None = None,
) -> FitOutputs:
    """Fit the campaign (opened here from a folder) into ``out`` (the staging folder) as
    ``options`` say; campaign.toml and manifest.csv are read once, by :meth:`Campaign.open`."""
    timings = {}
    t0 = time.perf_counter()
    campaign = (
        source
        if isinstance(source, Campaign)
        else Campaign.open(source, options.glob, config=options.config)
    )
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
    quality = assess(extraction, duplicates=campaign.duplicates)
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
        )
    except UnphysicalFrictionError as exc:
        raise UnphysicalFrictionError(f"{exc}{_sign_settings(folder, config)}") from None
    ident = _with_pressure_reference(ident, config.pressure_basis)
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
    t0 = time.perf_counter()
    # points.csv (pandas writes each value by itself: 0.2 s at 10,000 points, 0.4 s at
    # 40,000) is written by a forked process while the datasheet is built and written here
    points_csv = _start_csv(out / "points.csv", extraction.points, options.workers)
    try:
        files, sheet, model = _write_outputs(
            out,
            folder,
            config,
            options,
            ident,
            extraction,
            quality,
            correction,
            dynamic,
            points_csv,
        )
    finally:
        points_csv.close()
    timings["datasheet"] = time.perf_counter() - t0
    exports = {}
    if options.export:
        from .export import export as export_to

        t0 = time.perf_counter()
        for target in options.export:
            try:
                exports[target] = export_to(model, target, out / "export" / target)
            except (ValueError, RuntimeError, OSError) as exc:  # a compiler's output: 1st line
                first = (str(exc).strip().splitlines() or [type(exc).__name__])[0].rstrip(":")
                raise ExportFailed(f"--export {target} failed: {first}", target) from exc
        timings["export"] = time.perf_counter() - t0
    if options.report:
        from .report import write_report_folder

        t0 = time.perf_counter()
        summaries = [_export_summary(out, result) for result in exports.values()]
        advance = None
        if step is not None:
            from .report import all_figures

            shown = len(all_figures(ident, extraction.offset)) + (dynamic is not None)
            advance = step("drawing the figures", shown)
        files.update(
            write_report_folder(
                out,
                sheet,
                ident,
                extraction,
                quality.excluded,
                exports=summaries,
                dynamic=dynamic,
                workers=options.workers,
                progress=advance,
            )
        )
        timings["report"] = time.perf_counter() - t0
    return FitOutputs(
        out, sheet, ident, extraction, files, timings, quality.excluded, exports, dynamic
    )


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


def _write_outputs(
    out, folder, config, options, ident, extraction, quality, correction, dynamic, points_csv
) -> tuple[dict[str, Path], dict, FrictionModel]:
    """The datasheet and the tables of one fit in ``out`` -> (their paths by name, the
    datasheet, its model); points.csv from ``points_csv`` (:func:`_start_csv`)."""
    from .datasheet import datasheet_model, write_datasheet

    model = datasheet_model(
        ident,
        extraction=extraction,
        campaign=str(folder),
        name=options.name,
        recipe=_recipe(config, folder),
    )
    sheet, record = model.to_datasheet(), dict(model.record)
    if correction.record is not None:
        sheet["fit"]["viscosity_correction"] = correction.record
        record["fit"] = {**record.get("fit", {}), "viscosity_correction": correction.record}
    if dynamic is not None:
        from .model.serialize import clean

        sheet["dynamic_fit"] = record["dynamic_fit"] = clean(dynamic.summary())
    model = model.replace(record=record)  # the datasheet's model, for the exports as it is
    files = {"datasheet": write_datasheet(out / "datasheet.json", sheet)}
    if dynamic is not None:
        files["dynamic"] = _csv(out / "dynamic.csv", dynamic.per_pressure)
        files["breakaway"] = _csv(out / "breakaway.csv", dynamic.breakaway)
    files["points"] = points_csv.results()[0]
    files["per_pressure"] = _csv(out / "per_pressure.csv", ident.per_pressure)
    files["law_comparison"] = _csv(out / "law_comparison.csv", ident.comparison)
    if ident.sensitivity is not None:
        files["sensitivity"] = _csv(out / "sensitivity.csv", ident.sensitivity)
    import pandas as pd

    if extraction.skipped:
        files["skipped"] = _csv(out / "skipped.csv", pd.DataFrame(extraction.skipped))
    if not quality.excluded.empty:
        files["excluded"] = _csv(out / "excluded.csv", quality.excluded)
    if ident.directions:
        frames = [r.per_pressure.assign(direction=d) for d, r in ident.directions.items()]
        files["per_direction"] = _csv(out / "per_direction.csv", pd.concat(frames))
    return files, sheet, model


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


def _with_pressure_reference(ident, basis):
    """The identification with the campaign's pressure reference recorded in its model (the
    points were formed in it, steady_state.operating_pressure_signal), and a note when the
    reference is a default rather than stated by campaign.toml."""
    model = ident.model.replace(reference=basis["rule"], pressure_reference_basis=basis)
    notes = list(ident.notes)
    if basis["stated_by"].startswith("default"):
        reason = basis["stated_by"].removeprefix("default: ")
        notes.append(
            f'pressure reference "{basis["rule"]}" is a default: {reason}; state [cylinder] '
            "pressure_reference in campaign.toml if the laws should see another pressure "
            '("a", "b", "sum", "mean" or "max")'
        )
    return replace(ident, model=model, notes=notes)


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
        shown = _named(unlabelled, 3)
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
    _check_out(folder, out)
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
                results[name] = _fit(
                    campaign.for_seal(name),
                    target,
                    named,
                    progress,
                    after_extraction if last else None,
                    step,
                )
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

    staging, (results, summary) = _staged(folder, out, write)
    fits = {
        name: _moved((staging, result), out, out / folders[name])
        for name, result in results.items()
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
