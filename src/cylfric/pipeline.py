"""The main job as one Python function: a campaign folder -> datasheet, tables, figures, report.

``fit_campaign(folder, out)`` is what ``cylfric fit`` runs; notebooks can call it too.
"""

from __future__ import annotations

import io
import time
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .datasheet import build_datasheet, write_datasheet
from .identify import identify
from .io.writers import atomic_write_text
from .steady_state import extract_campaign

__all__ = ["fit_campaign", "FitOutputs"]


@dataclass
class FitOutputs:
    """What :func:`fit_campaign` wrote and found.

    ``files`` maps each output to its path; ``timings`` holds the wall time of each stage
    [s]: ``extract``, ``identify`` (with the sensitivity study), ``datasheet`` (with the
    CSV tables) and, with the report, ``report`` (figures and report.html).
    """

    out: Path
    datasheet: dict
    identification: object
    extraction: object
    files: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)


def _csv(path, frame: pd.DataFrame):
    buffer = io.StringIO()
    frame.to_csv(buffer, index=False)
    return atomic_write_text(path, buffer.getvalue())


def fit_campaign(
    folder,
    out,
    *,
    fixed=None,
    pressure_law="linear",
    per_direction=False,
    skip_bad=False,
    report=True,
    progress=None,
    name=None,
) -> FitOutputs:
    """Read a campaign, extract the points, identify the model, write the outputs.

    Parameters
    ----------
    folder : path-like
        Campaign folder of raw bench files (never modified).
    out : path-like
        Output folder: ``datasheet.json``, ``points.csv``, ``per_pressure.csv``,
        ``sensitivity.csv``, ``law_comparison.csv``, ``skipped.csv`` (when files were
        skipped), and with ``report`` the figures (PNG, SVG) and ``report.html``.
    fixed : dict, optional
        Parameters held fixed (SI), e.g. ``{"alpha": 1.0, "v_r": 0.010}``.
    pressure_law : str
        Pressure law of the datasheet (linear, quadratic, exponential).
    per_direction : bool
        Also identify extension and retraction separately (``per_direction.csv``).
    skip_bad : bool
        Skip unreadable files instead of stopping at the first.
    report : bool
        Draw the figures and write ``report.html``.
    progress : callable, optional
        Called with each file name as it is read.
    name : str, optional
        Name recorded in the datasheet.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    timings = {}
    t0 = time.perf_counter()
    extraction = extract_campaign(folder, skip_bad=skip_bad, progress=progress)
    timings["extract"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ident = identify(
        extraction.points, fixed=fixed, pressure_law=pressure_law, per_direction=per_direction
    )
    timings["identify"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    sheet = build_datasheet(ident, extraction=extraction, campaign=str(folder), name=name)
    files = {"datasheet": write_datasheet(out / "datasheet.json", sheet)}
    files["points"] = _csv(out / "points.csv", extraction.points)
    files["per_pressure"] = _csv(out / "per_pressure.csv", ident.per_pressure)
    files["law_comparison"] = _csv(out / "law_comparison.csv", ident.comparison)
    if ident.sensitivity is not None:
        files["sensitivity"] = _csv(out / "sensitivity.csv", ident.sensitivity)
    if extraction.skipped:
        files["skipped"] = _csv(out / "skipped.csv", pd.DataFrame(extraction.skipped))
    if ident.directions:
        frames = [r.per_pressure.assign(direction=d) for d, r in ident.directions.items()]
        files["per_direction"] = _csv(out / "per_direction.csv", pd.concat(frames))
    timings["datasheet"] = time.perf_counter() - t0
    if report:
        from .report import write_report_folder

        t0 = time.perf_counter()
        files.update(write_report_folder(out, sheet, ident, extraction))
        timings["report"] = time.perf_counter() - t0
    return FitOutputs(out, sheet, ident, extraction, files, timings)
