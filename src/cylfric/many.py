"""Many campaigns at once (end-of-line testing): every campaign folder under a root, in parallel.

``fit_many(root, out)`` finds the campaign folders under ``root`` (a folder with
``manifest.csv``, ``campaign.toml`` or run files; folders holding only folders are searched
further), fits each with :func:`cylfric.pipeline.fit_campaign` into ``out/<folder name>/``
on Dask, and writes ``out/fit_many.csv`` with the status and reason of every campaign. A
campaign that fails is reported there, not raised.

Schedulers (``scheduler=``):

- ``None`` (default): local worker processes, a standard
  :class:`concurrent.futures.ProcessPoolExecutor` (:func:`cylfric._parallel.starmap`);
  it starts in well under a second where a ``distributed.LocalCluster`` of two processes
  takes 1.8-6.9 s on a 2-core machine (measured for issue 15).
- ``"local-cluster"``: a ``dask.distributed.LocalCluster(n_workers, threads_per_worker=1,
  processes=True)`` (its dashboard, its resilience to a dying worker).
- ``"tcp://host:8786"`` (any scheduler address): a Dask distributed cluster; every worker
  must see ``root`` and ``out`` at the same paths (a shared file system) and have cylfric.
- ``"serial"``: one campaign after another in this process (no Dask).

With ``catalog=DB`` each fitted datasheet is added to the catalogue
(:class:`cylfric.catalog.Catalog`) from this process, one after another.
"""

from __future__ import annotations

import csv
import io
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any

from .options import FitOptions

__all__ = ["find_campaigns", "fit_many", "ManyResult", "SUMMARY_COLUMNS"]

SUMMARY_COLUMNS = (
    "campaign",
    "status",
    "reason",
    "out",
    "runs [-]",
    "excluded [-]",
    "seconds [s]",
    "cpu [s]",
    "catalog",
    "start [s]",
    "worker",
)
"""Columns of ``fit_many.csv``: ``status`` is ``ok`` or ``failed``; ``reason`` the error;
``seconds`` the wall time and ``cpu`` the processor time of the fit (``cpu`` well below
``seconds``: the machine was busy with other work); ``catalog`` is ``added``, empty
without a catalogue, or the catalogue's error; ``start`` is when the fit began, counted
from the start of :func:`fit_many` [s], and ``worker`` the id of the process that ran it
(together they show the workers running side by side)."""

_CAMPAIGN_MARKERS = ("manifest.csv", "campaign.toml")
_OUTPUT_MARKER = ".cylfric-output"


def find_campaigns(root, *, exclude=()) -> list[Path]:
    """Campaign folders under ``root``, sorted: a folder with ``manifest.csv``,
    ``campaign.toml`` or files (run files); a folder holding only folders is searched
    further. Hidden folders, cylfric output folders and the folders in ``exclude`` (and
    everything under them) are left out."""
    root = Path(root)
    if not root.is_dir():
        raise ValueError(f"{root}: not a folder; expected a folder of campaign folders")
    excluded = {Path(p).resolve() for p in exclude}
    found = []

    def walk(folder: Path):
        for child in sorted(folder.iterdir()):
            if not child.is_dir() or child.name.startswith(".") or child.resolve() in excluded:
                continue
            if (child / _OUTPUT_MARKER).exists():
                continue
            entries = [e for e in child.iterdir() if not e.name.startswith(".")]
            if any(m in {e.name for e in entries} for m in _CAMPAIGN_MARKERS) or any(
                e.is_file() for e in entries
            ):
                found.append(child)
            else:
                walk(child)

    walk(root)
    return found


@dataclass
class ManyResult:
    """What :func:`fit_many` did.

    Attributes
    ----------
    rows : list of dict
        One summary row per campaign (keys :data:`SUMMARY_COLUMNS`; a key left out has no
        value), in campaign order: what ``fit_many.csv`` holds.
    out : Path
        The output folder (``fit_many.csv`` and one folder per campaign).
    scheduler : str
        Which scheduler ran the fits.
    seconds : float
        Wall time of the whole run [s].
    """

    rows: list
    out: Path
    scheduler: str
    seconds: float

    @cached_property
    def summary(self):
        """The rows as a ``pandas.DataFrame`` (columns :data:`SUMMARY_COLUMNS`), built on
        first use: :func:`fit_many` itself does not import pandas (0.3 s of processor time
        in the process that waits for the workers)."""
        import pandas as pd

        return pd.DataFrame(self.rows, columns=list(SUMMARY_COLUMNS))

    @property
    def succeeded(self) -> int:
        """Number of campaigns fitted."""
        return sum(row.get("status") == "ok" for row in self.rows)

    @property
    def failed(self) -> int:
        """Number of campaigns that failed."""
        return len(self.rows) - self.succeeded


def _name(folder: Path, root: Path) -> str:
    return folder.relative_to(root).as_posix()


def fit_one(
    folder: Path, out: Path, name: str, options: FitOptions, started: float | None = None
) -> dict[str, Any]:
    """Fit one campaign (what each worker runs); never raises: returns a summary row.

    ``options`` are those of every campaign; the datasheet is named ``name``. ``started`` is
    the wall-clock time (``time.time()`` [s]) the ``start [s]`` column counts from (default:
    now)."""
    import warnings

    t0, cpu0 = time.perf_counter(), time.process_time()
    row = {
        "campaign": name,
        "out": str(out),
        "catalog": "",
        "start [s]": round(time.time() - (time.time() if started is None else started), 3),
        "worker": os.getpid(),
    }
    try:
        from .pipeline import fit_campaign

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit_campaign(folder, out, replace(options, name=name))
        excluded = result.excluded
        row.update(
            status="ok",
            reason="",
            **{
                "runs [-]": int(result.extraction.points["run"].nunique()),
                "excluded [-]": 0 if excluded is None else int(len(excluded)),
            },
        )
    except Exception as exc:  # noqa: BLE001 - a failing campaign is reported, not fatal
        if isinstance(exc, OSError):  # the file and the action, as the command line says it
            from ._paths import os_error_message

            reason = os_error_message(exc)
        else:
            reason = str(exc).replace("\n", " ")
        if not isinstance(exc, ValueError | OSError):
            reason = f"unexpected {type(exc).__name__}: {reason}"
        row.update(status="failed", reason=reason, **{"runs [-]": None, "excluded [-]": None})
    row["seconds [s]"] = round(time.perf_counter() - t0, 3)
    row["cpu [s]"] = round(time.process_time() - cpu0, 3)
    return row


_FIT_OPTIONS = (
    "fixed",
    "pressure_law",
    "per_direction",
    "skip_bad",
    "report",
    "glob",
    "strict",
    "viscosity_correction",
)


def fit_many(
    root: str | os.PathLike[str],
    out: str | os.PathLike[str],
    options: FitOptions | None = None,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    catalog: str | os.PathLike[str] | None = None,
    progress: Callable[[dict[str, Any]], object] | None = None,
    **fit_options: Any,
) -> ManyResult:
    """Fit every campaign folder under ``root`` in parallel; outputs in ``out/<folder>/``.

    Parameters
    ----------
    root : path-like
        Folder of campaign folders (see :func:`find_campaigns`); never modified.
    out : path-like
        Output folder: ``fit_many.csv`` and one :func:`~cylfric.pipeline.fit_campaign`
        output folder per campaign (named by the campaign's path under ``root``, which must
        stay inside ``out``: :func:`cylfric._paths.inside`). A symbolic link is refused.
    options : FitOptions, optional
        The options of every fit (:class:`~cylfric.options.FitOptions`; its ``name`` must
        be None: each datasheet is named after its campaign). Without ``options.workers``,
        fits that run side by side each read on one core.
    workers : int, optional
        Local worker processes (default: the cores this process may use). Ignored only by a
        distributed scheduler address, whose cluster has its own workers (then it must be
        None).
    scheduler : str, optional
        None (local processes), ``"local-cluster"``, ``"serial"`` or a Dask distributed
        scheduler address (``"tcp://10.0.0.5:8786"``); see the module docstring.
    catalog : path-like, optional
        SQLite catalogue: each fitted datasheet is added under the campaign's name.
    progress : callable, optional
        Called with each campaign's summary row (a dict) as it finishes.
    **fit_options
        Without ``options``: the fields of :class:`~cylfric.options.FitOptions` that
        build it: ``fixed``, ``pressure_law``, ``per_direction``, ``skip_bad``, ``report``,
        ``glob``, ``strict``, ``viscosity_correction``.

    Returns
    -------
    ManyResult

    Raises
    ------
    ValueError
        ``root`` is not a folder or holds no campaign, ``out`` lies inside a campaign,
        an unknown fit option, both ``options`` and fit keywords, ``options.name`` or
        ``options.scheduler`` set, workers < 1, a scheduler address where no scheduler
        with workers answers (:func:`cylfric._parallel.connect`).

    Notes
    -----
    The local workers are forked where the calling process can fork
    (:func:`cylfric._parallel.starmap`); elsewhere (a notebook, whose kernel runs threads;
    Windows, macOS) they start fresh, which, as Python's ``spawn`` and ``forkserver``
    start methods do, runs the calling script's main module again: call ``fit_many`` from
    a script under ``if __name__ == "__main__":`` (notebooks and the ``cylfric fit-many``
    command need nothing).
    """
    options = _checked_options(options, fit_options)
    from ._paths import make_folder, refuse_link

    root, out = Path(root), refuse_link(out)  # a symbolic link is refused, not written through
    campaigns = find_campaigns(root, exclude=[out])
    if not campaigns:
        raise ValueError(
            f"{root}: no campaign folder found (a folder with manifest.csv, campaign.toml or "
            "run files)"
        )
    fitted, refused = _sort_campaigns(campaigns, root, out)
    workers, distributed = _checked_workers(workers, scheduler)
    from ._atomic import atomic_write_text  # not cylfric.io: its readers load numba, scipy

    make_folder(out)
    side_by_side = distributed or (workers > 1 and len(fitted) > 1)
    if scheduler != "serial" and side_by_side and options.workers is None:
        # fits side by side: each on one core (a fit alone uses every core)
        options = replace(options, workers=1)
    t0, started = time.perf_counter(), time.time()
    jobs = [(folder, folder_out, name, options, started) for folder, folder_out, name in fitted]
    # largest first: a long fit started last would leave the other workers idle at the end
    order = sorted(range(len(jobs)), key=lambda i: -_size(jobs[i][0]))
    rows = {}

    def done(row):
        if catalog is not None and row["status"] == "ok":
            row["catalog"] = _add_to_catalog(catalog, out, row["campaign"])
        rows[row["campaign"]] = row
        if progress is not None:
            progress(row)

    used = _run_jobs(jobs, order, scheduler, workers, done)
    for job in jobs:  # a worker lost with its task: reported like any failure
        rows.setdefault(
            job[2],
            {
                "campaign": job[2],
                "status": "failed",
                "reason": "the worker running it was lost",
                "out": str(job[1]),
                "catalog": "",
            },
        )
    ordered = [refused.get(_name(f, root)) or rows[_name(f, root)] for f in campaigns]
    for row in refused.values():
        if progress is not None:
            progress(row)
    atomic_write_text(out / "fit_many.csv", _summary_csv(ordered))
    return ManyResult(ordered, out, used, time.perf_counter() - t0)


def _checked_options(options: FitOptions | None, fit_options: dict[str, Any]) -> FitOptions:
    """The options of every fit, from ``options`` or the fit keywords; no name of its own."""
    unknown = set(fit_options) - set(_FIT_OPTIONS)
    if unknown:
        raise ValueError(f"unknown fit options {sorted(unknown)}; valid: {list(_FIT_OPTIONS)}")
    options = FitOptions.from_keywords(options, **fit_options)
    if options.name is not None:
        raise ValueError(
            f"options.name = {options.name!r}: fit_many names each datasheet after its "
            "campaign folder; leave name None"
        )
    if options.scheduler is not None:
        raise ValueError(
            f"options.scheduler = {options.scheduler!r}: fit_many sends whole campaigns to "
            "a cluster with its own scheduler=; leave options.scheduler None"
        )
    return options


def _checked_workers(workers: int | None, scheduler: str | None) -> tuple[int, bool]:
    """(local workers, whether ``scheduler`` is a distributed address): ``workers`` or the
    cores this process may use (:func:`cylfric._parallel.cores`); at least 1, and not given
    with a scheduler address."""
    if workers is not None and workers < 1:
        raise ValueError(f"workers = {workers}; expected at least 1")
    distributed = scheduler not in (None, "local-cluster", "serial")
    if distributed and workers is not None:
        raise ValueError("workers is set by the cluster behind a scheduler address; leave it out")
    from ._parallel import cores

    return workers or cores(), distributed


def _sort_campaigns(
    campaigns: list[Path], root: Path, out: Path
) -> tuple[list[tuple[Path, Path, str]], dict[str, dict[str, Any]]]:
    """(campaign, its output folder, its name) of the campaigns to fit, and the failed
    summary rows of those refused (a link to a folder holding ``root`` or ``out``, a name
    leaving ``out``). An ``out`` inside a campaign under ``root`` raises ValueError."""
    from ._paths import inside

    target, top = out.resolve(), root.resolve()
    fitted: list[tuple[Path, Path, str]] = []  # (campaign, its output folder, its name)
    refused: dict[str, dict[str, Any]] = {}
    for folder in campaigns:  # one campaign that cannot be fitted is a failed row, not fatal
        name, real = _name(folder, root), folder.resolve()
        holds_out = real == target or real in target.parents
        if holds_out and (real == top or top in real.parents):
            raise ValueError(f"--out {out} is inside the campaign folder {folder}")
        try:  # a link to a campaign elsewhere is followed, a loop back up is not
            if holds_out or real == top or real in top.parents:
                raise ValueError(
                    f"{folder} leads to {real}, which holds {root} or --out {out}: not fitted"
                )
            fitted.append((folder, inside(out, name, "campaign"), name))
        except ValueError as exc:
            refused[name] = {"campaign": name, "status": "failed", "reason": str(exc)}
            refused[name].update({"out": "", "catalog": "", "runs [-]": None})
    return fitted, refused


def _run_jobs(jobs: list, order: list[int], scheduler: str | None, workers: int, done) -> str:
    """Run ``fit_one`` on every job (serially in the given order, else largest first) on
    the scheduler; ``done(row)`` for each summary row. Returns what ran them."""
    if scheduler == "serial":
        for job in jobs:
            done(fit_one(*job))
        return "serial"
    if scheduler is None:
        from ._parallel import starmap

        starmap(fit_one, [jobs[i] for i in order], workers=workers, done=lambda _, row: done(row))
        return f"local process pool, {workers} process(es)"
    return _run_distributed([jobs[i] for i in order], scheduler, workers, done)


def _summary_csv(rows) -> str:
    """``fit_many.csv``: a header of :data:`SUMMARY_COLUMNS`, one line per row; a missing
    value or None is an empty field (what pandas reads as missing); text through
    :func:`cylfric.escape.csv_text` (no formulas, no control characters)."""
    from .escape import csv_text

    buffer = io.StringIO()
    writer = csv.DictWriter(
        buffer, fieldnames=SUMMARY_COLUMNS, restval="", extrasaction="ignore", lineterminator="\n"
    )
    writer.writeheader()
    for row in rows:
        writer.writerow(
            {key: "" if value is None else csv_text(value) for key, value in row.items()}
        )
    return buffer.getvalue()


def _size(folder: Path) -> int:
    """Bytes of the files in a campaign folder (how long its fit takes, roughly)."""
    total = 0
    for entry in os.scandir(folder):
        if entry.is_file():
            total += entry.stat().st_size
    return total


def _add_to_catalog(db, out: Path, name: str) -> str:
    try:
        from cylfric.catalog import Catalog

        Catalog(db).add(out / name / "datasheet.json", name=name)
    except Exception as exc:  # noqa: BLE001 - reported in the summary, the fit stands
        return f"not added: {type(exc).__name__}: {exc}"
    return "added"


def _run_distributed(jobs, scheduler, workers, done) -> str:
    from ._parallel import require_dask

    require_dask(f"fit-many --scheduler {scheduler}")
    from dask.distributed import Client, LocalCluster, as_completed

    if scheduler == "local-cluster":
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        )
        used = f"dask.distributed LocalCluster, {workers} process(es)"
    else:
        cluster = None
        used = f"dask.distributed scheduler at {scheduler}"
    if cluster is not None:
        client = Client(cluster)
    else:
        from ._parallel import connect

        client = connect(scheduler)  # a bad address: ValueError naming it
    try:
        futures = [client.submit(fit_one, *job, pure=False) for job in jobs]
        for future in as_completed(futures):
            if future.status == "finished":
                done(future.result())
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return used
