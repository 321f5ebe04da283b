"""The data-quality gate between extraction and identification (runs left out, with reasons).

:func:`assess` looks at every run of an :class:`~cylfric.steady_state.Extraction` and flags
those that would mislead the fit:

- ``speed``: the measured window speed differs from the run's nominal speed by more than
  ``speed_tolerance`` (a position column in m instead of mm reads 1000x off);
- ``scale``: the run's friction differs from the other runs at its pressure level by a
  factor of more than ``scale_factor`` (a force column in N instead of kN), or its whole
  level's median friction differs by that factor from the median of the other levels' (a
  test day whose files all say N while the values are kN);
- ``outlier``: the run's friction is far from what its neighbours in speed at the same
  pressure level say (interpolated in log speed), beyond ``outlier_sigma`` robust sigmas of
  all such residuals (a run typed as 0 bar in manifest.csv while measured at 80 bar);
- ``motion``: the run gave no usable constant-velocity window (no motion, too short);
- ``metadata``: the run's nominal pressure or speed differs between its sources
  (manifest.csv, campaign.toml's name_pattern, a header line such as ``Pressure: 103 bar``,
  a file-name token such as ``p103bar``) by more than ``metadata_tolerance`` (a run typed
  as 0 bar in manifest.csv whose file says 103 bar). A pressure the file measures (a
  pressure column) is what the fit uses; it is compared with each nominal value with a
  looser limit (``measured_tolerance``, ``measured_floor``: 20 % and 2 bar), so a column in
  psi or MPa whose unit says bar is found. A nominal pressure of 0, below 0 or not finite
  on a run without a pressure column is a conflict by itself unless it belongs to a 0-bar
  level (at least ``zero_level_runs`` runs, or as many as the median level has when that
  is fewer (a sparse grid), and half the median number of runs per level, at 0 bar).

The gate refuses (:class:`QualityError`, a ValueError: exit 2) rather than pick a side when
the data contradict each other: when the ``scale`` check would flag more than a quarter of
the runs (groups about 1000x apart, no clear majority: with most runs in the wrong unit the
right ones would be the ones left out) or when more than half of the runs would be excluded.

Flagged runs are kept in the points table with the flag ``"excluded: <check>"``, so that
:func:`cylfric.identify.identify` leaves them out, and listed in :attr:`QualityReport.excluded`
(written as ``excluded.csv``, file names relative to the campaign folder). Files that
``manifest.csv`` does not list are listed too, and so are files with the same bytes as an
earlier run (``duplicate``: :attr:`cylfric.io.campaign.Campaign.duplicates`, never read, so
counted once). Nothing is dropped silently.
"""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from .._runtable import RunTable, run_column
from ..friction.pressure import PRESSURE_REFERENCES
from ..levels import pressure_levels

if TYPE_CHECKING:
    from collections.abc import Iterable

    from cylfric.io.campaign import Duplicate
    from cylfric.steady_state import Extraction

__all__ = ["assess", "QualityReport", "QualityError", "CHECKS"]

CHECKS = (
    "metadata",
    "speed",
    "scale",
    "outlier",
    "motion",
    "transient",
    "unlisted",
    "duplicate",
)
"""Names of the checks, as they appear in ``excluded.csv``."""


@dataclass(frozen=True)
class QualityReport:
    """Result of :func:`assess`.

    Attributes
    ----------
    points : pandas.DataFrame
        The points table with the flags of excluded runs set to ``"excluded: <check>"``.
    excluded : pandas.DataFrame
        One row per excluded run or unlisted file: ``file``, ``run``, ``check``, ``reason``.
    notes : tuple of str
        What the physical checks found and were told to accept (``accept_force_balance``),
        for the datasheet's notes.
    """

    points: pd.DataFrame
    excluded: pd.DataFrame
    notes: tuple[str, ...] = ()

    def summary(self) -> str:
        """One line: how many runs each check excluded."""
        if self.excluded.empty:
            return "data-quality gate: no run excluded"
        counts = self.excluded["check"].value_counts()
        parts = ", ".join(f"{n} by {check}" for check, n in counts.items())
        return f"data-quality gate: {len(self.excluded)} excluded ({parts}); see excluded.csv"


def _runs_table(extraction):
    """Per run: file, nominal and measured speed [m/s], pressure [Pa], friction [N]."""
    ok = extraction.points[extraction.points["flag"].eq("ok")]
    n = ok["n [-]"].clip(lower=1) if "n [-]" in ok else 1
    std = ok["friction_std [N]"] if "friction_std [N]" in ok else np.nan
    measured = (
        ok.assign(speed=ok["velocity [m/s]"].abs(), se=std / np.sqrt(n))
        .groupby("run")
        .agg(
            speed=("speed", "median"),
            friction=("friction [N]", "median"),
            pressure=("pressure [Pa]", "median"),
            se=("se", "median"),
        )
    )
    extra = [
        c
        for c in extraction.points.columns
        if c not in _POINT_NAMES and extraction.points[c].dtype == object and c != "flag"
    ]
    runs = pd.DataFrame(
        {
            "run": run_column(extraction.runs, "run"),
            "file": [_relative(f, extraction) for f in run_column(extraction.runs, "file")],
            "nominal_speed": np.abs(
                np.array(
                    run_column(extraction.runs, "velocity [m/s]", default=math.nan), dtype=float
                )
            ),
        }
    )
    if extra:
        first = ok.groupby("run")[extra].first()
        measured["group"] = list(zip(*(first[c] for c in extra), strict=True))
    return runs.join(measured, on="run")


def _speed_cause(ratio):
    """Likely cause of a measured/nominal speed ratio, in words."""
    if 1e3 / 3 < ratio < 3e3:
        return "about 1000 times the nominal: a position in mm whose unit says m?"
    if 1 / 3e3 < ratio < 3 / 1e3:
        return "about 1/1000 of the nominal: a position in m whose unit says mm?"
    return (
        f"{ratio:.3g} times the nominal: the nominal speed in the metadata is wrong, or the "
        "rig did not reach it"
    )


def _relative(file, extraction):
    """``file`` relative to the campaign folder (as given when it is not inside it)."""
    folder = getattr(extraction, "folder", None)
    if folder is None:
        return str(file)
    prefix = _prefix(folder)  # the readers name a run folder / name: a slice of it
    if isinstance(file, str) and prefix is not None and file.startswith(prefix):
        return file[len(prefix) :]  # (20,000 Paths built and compared: 0.1 s)
    try:
        return Path(file).relative_to(folder).as_posix()
    except ValueError:
        return str(file)


@functools.lru_cache(maxsize=8)
def _prefix(folder: str) -> str | None:
    """``folder`` as the start of the names of its files (None where the separator is not
    "/": there :func:`_relative` goes through pathlib)."""
    return str(Path(folder)) + "/" if os.sep == "/" else None


_SOURCE_NAMES = {
    "manifest": "{where}",  # 'manifest.csv line 16'
    "campaign.toml name_pattern": "campaign.toml's name_pattern ({where})",
    "header": "the file header ({where})",
    "file name": "the file name ({where})",
}
_UNITS = {"pressure": (1e5, "bar"), "velocity": (1e-3, "mm/s")}


def _said(quantity, source, value, where):
    """'103 bar in the file header (Pressure: 103 bar)' (``value`` SI)."""
    scale, unit = _UNITS[quantity]
    place = _SOURCE_NAMES.get(source, source + " ({where})").format(where=where)
    return f"{value / scale:.4g} {unit} in {place}"


def _metadata_suspects(runs, measured_flags, run_numbers, nonpositive) -> list[int]:
    """Indices of the runs the metadata check must read in full: a measured pressure, a
    run of ``nonpositive``, or nominal values of a quantity that are not all equal (equal
    values never conflict, :func:`_conflicts`); from the columns, without a dict per run."""
    zero = set(nonpositive)
    suspect = np.array(measured_flags, dtype=bool) | np.array(
        [r in zero for r in run_numbers], dtype=bool
    )
    if not isinstance(runs, RunTable):
        return list(range(len(runs)))
    for quantity in ("pressure", "velocity"):
        try:
            values = np.abs(np.array(runs.leaves("nominal", quantity, index=0), dtype=float))
        except (TypeError, ValueError):  # not numbers: every run read in full
            return list(range(len(runs)))
        if not values.size:
            continue
        nan = np.isnan(values)
        spread = np.nanmax(np.where(nan, -np.inf, values), axis=0) != np.nanmin(
            np.where(nan, np.inf, values), axis=0
        )
        suspect |= (spread & ~nan.all(axis=0)) | (nan.any(axis=0) & ~nan.all(axis=0))
    return np.flatnonzero(suspect).tolist()


def _conflicts(info, tolerance, floors):
    """Text of the nominal values of one run that disagree with the value used, or ''.

    ``info`` is one of ``Extraction.runs``; values differ when they are further apart than
    ``tolerance`` times the larger of the two and more than ``floors[quantity]`` [SI].
    """
    texts = []
    for quantity in ("pressure", "velocity"):
        if quantity == "pressure" and info.get("pressure measured"):
            continue
        values = info.get("nominal", {}).get(quantity, {})
        used = info.get("source", {}).get(quantity)
        if used not in values:
            continue
        value, where = values[used]
        others = [
            (source, other, text)
            for source, (other, text) in values.items()
            if source != used
            and abs(abs(other) - abs(value))
            > max(tolerance * max(abs(other), abs(value)), floors[quantity])
        ]
        if not others:
            continue
        said = [_said(quantity, used, value, where)]
        said += [_said(quantity, *item) for item in others]
        label = "speed" if quantity == "velocity" else quantity
        texts.append(f"{label} {said[0]} (the value used) but " + " and ".join(said[1:]))
    return "; ".join(texts)


def _measured_conflict(info, measured, tolerance, floor, reference="mean"):
    """Text naming a run's measured pressure and the nominal values it contradicts, or ''.

    ``measured`` is the median over the run's windows of the pressure column [Pa]. A
    measured pressure varies more than a nominal one (hand-pumped levels, hose drops), so
    the limit is looser than between nominal sources: ``tolerance`` of the larger and at
    least ``floor`` [Pa]. A column in psi or MPa labelled bar reads 14.5 or 0.1 times the
    nominal and is far outside.

    A nominal value is a chamber pressure (both chambers, or the working one); the measured
    one is the chambers' pressures combined by the campaign's ``reference``
    (:data:`~cylfric.friction.pressure.PRESSURE_REFERENCES`), so the nominal value is
    combined the same way before they are compared (the ``"sum"`` of two chambers at 10 bar
    is 20 bar), as the extraction does for a run without a pressure column.
    """
    values = info.get("nominal", {}).get("pressure", {})
    if not math.isfinite(measured):
        return ""
    combined = {
        source: float(PRESSURE_REFERENCES[reference](np.asarray(value), np.asarray(value)))
        for source, (value, _) in values.items()
    }
    off = [
        (source, value, where, combined[source])
        for source, (value, where) in values.items()
        if not math.isfinite(value)
        or abs(measured - combined[source])
        > max(tolerance * max(abs(measured), abs(combined[source])), floor)
    ]
    if not off:
        return ""
    said = " and ".join(_said("pressure", *item[:3]) for item in off)
    what = "the pressure column"
    if off[0][3] != off[0][1]:  # "sum": the nominal chamber pressure counted twice
        what = f'the pressure columns, pressure_reference = "{reference}"'
        said += f" (both chambers at it: {off[0][3] / 1e5:.4g} bar)"
    units = info.get("units") or {}  # (a summary's dict: info is one run's, in full)
    stated = [units[k] for k in ("pressure", "pressure_a", "pressure_b") if units.get(k)]
    unit = f"; the unit the file states: {stated[0]}" if stated else ""
    return (
        f"measured pressure {measured / 1e5:.4g} bar ({what}, the value used) but {said} "
        f"({_pressure_cause(measured, off[0][3])}{unit})"
    )


_PRESSURE_SLIPS = (
    (14.5038, "values in psi whose unit says bar"),
    (1 / 14.5038, "values in bar whose unit says psi"),
    (0.1, "values in MPa whose unit says bar"),
    (10.0, "values in bar whose unit says MPa"),
    (100.0, "values in kPa whose unit says bar"),
    (1e5, "values in Pa whose unit says bar"),
    (1e-5, "values in bar whose unit says Pa"),
)
"""(measured / nominal pressure, the unit slip that gives it)."""


def _pressure_cause(measured, nominal):
    """Likely cause of a measured pressure far from the nominal one, in words."""
    if math.isfinite(nominal) and nominal > 0 and measured > 0:
        ratio = measured / nominal
        for factor, slip in _PRESSURE_SLIPS:
            if abs(ratio / factor - 1) < 0.2:
                return f"{ratio:.3g} times the nominal: a pressure column with {slip}?"
    return "check the pressure column's unit and the run's nominal pressure"


def _zero_level_size(per_level, zero_level_runs):
    """Fewest runs at 0 bar that make a deliberate 0-bar level [-]: half the median number
    of runs per level ``per_level``, and ``zero_level_runs`` unless the levels have fewer
    (on a sparse grid of two speeds a 0-bar level of two runs is a level like the others;
    a lone 0-bar run among levels of two is not)."""
    return max(math.ceil(per_level / 2), min(zero_level_runs, per_level))


def _deliberate_zero(runs, pressures, min_runs):
    """Runs whose nominal pressure is <= 0 or not finite and not one of a 0-bar level."""
    bad = [run for run, p in zip(runs, pressures, strict=True) if not p > 0]
    zero = [run for run, p in zip(runs, pressures, strict=True) if p == 0]
    if len(zero) >= min_runs:  # a deliberate unpressurised level
        bad = [run for run in bad if run not in set(zero)]
    return set(bad)


_POINT_NAMES = {
    "run",
    "file",
    "stroke",
    "direction [-]",
    "pressure [Pa]",
    "pressure_std [Pa]",
    "velocity [m/s]",
    "velocity_std [m/s]",
    "force [N]",
    "friction [N]",
    "friction_std [N]",
    "n [-]",
    "window_start [s]",
    "window_end [s]",
    "spikes [-]",
    "offset [N]",
    "flag",
}


def _prediction(x, y, i):
    """Friction at ``x[i]`` predicted from the other runs (log speed ``x`` sorted) [N].

    Between neighbours: the line through the nearest run on each side; at an end of the
    speed range: the line through the nearest two, extrapolated. Returns (prediction,
    at_end). (A parabola through two runs on each side was tried: it overshoots the
    Stribeck minimum by 15 N on log-spaced speeds.)
    """
    left = [j for j in (i - 2, i - 1) if j >= 0]
    right = [j for j in (i + 1, i + 2) if j < x.size]
    end = not (left and right)
    a, b = (left[-1], right[0]) if not end else (left[-2:] if left else right[:2])
    if x[a] == x[b]:
        return float((y[a] + y[b]) / 2), end
    slope = (y[b] - y[a]) / (x[b] - x[a])
    return float(y[a] + slope * (x[i] - x[a])), end


def _outliers(groups, outlier_sigma, min_speeds, floor):
    """(run, residual, sigma) of runs far from their neighbours' prediction in log speed.

    ``groups`` is a list of (runs, log speed, friction) arrays sorted by speed, one per
    pressure level (and group of runs); ``floor`` [N] is the smallest robust sigma.
    """
    residuals: dict[bool, list[tuple[Any, float]]] = {False: [], True: []}
    for runs, x, y in groups:
        if np.unique(np.round(x, 6)).size < min_speeds:
            continue
        for i, run in enumerate(runs):
            prediction, end = _prediction(x, y, i)
            residuals[end].append((run, y[i] - prediction))
    out = []
    for part in residuals.values():  # extrapolation at the ends of the speed range errs more
        if len(part) < 5:
            continue
        values = np.array([r for _, r in part])
        mad = float(np.median(np.abs(values - np.median(values))))
        sigma = max(1.4826 * mad, floor, 1e-9)
        out += [(run, r, sigma) for run, r in part if abs(r) > outlier_sigma * sigma]
    return out


def _transients(
    points, runs, skip, transient_sigma, noise_floor, min_points, short_window=0.25, short_sigma=3.0
):
    """Rows of ``points`` (ok windows of runs not in ``skip``) whose friction disagrees with
    the other strokes of the same setting: (row index, cell median [N], robust sigma [N]).

    A setting is a run's nominal pressure and speed (NaN when the metadata give none), its
    labels (the points' text columns: a valve voltage, a seal) and the stroke's direction;
    its strokes are the windows of every run with that setting. A stroke further than
    ``transient_sigma`` robust sigmas (1.4826 MAD of the cell, at least ``noise_floor`` of
    the cell's median) from the cell's median is left out, the worst first, while the cell
    keeps ``min_points``; so is one further than ``short_sigma`` whose window lasts less
    than ``short_window`` of the cell's median window (a step that ended while its
    pressures still settled: on the virtual valve rig a 0.35 s step leaves 10-20 ms windows
    against 1.2 s).
    """
    ok = points[points["flag"].eq("ok") & ~points["run"].isin(skip)]
    if ok.empty:
        return []
    nominal = pd.DataFrame(
        {
            "run": run_column(runs, "run"),
            "_p": np.round(np.array(run_column(runs, "pressure [Pa]", default=math.nan), float)),
            "_v": np.round(
                np.abs(np.array(run_column(runs, "velocity [m/s]", default=math.nan), float)), 9
            ),
        }
    ).set_index("run")
    cells = ok.join(nominal, on="run")
    labels = [
        c
        for c in points.columns
        if c not in _POINT_NAMES and c != "session" and not pd.api.types.is_numeric_dtype(points[c])
    ]
    keys = ["_p", "_v", "direction [-]", *labels]
    cells = cells.assign(**{k: cells[k].astype(str) for k in keys})
    # the cells numbered in key order, as groupby iterates them; only those with min_points
    # windows can be judged, and one pass of numpy slices visits them (a pandas group per
    # cell cost about 1 ms: seconds at a campaign of 20,000 runs with one window per cell)
    codes = cells.groupby(keys, dropna=False).ngroup().to_numpy()
    judged = np.flatnonzero(np.bincount(codes)[codes] >= min_points)
    if judged.size == 0:
        return []
    order = judged[np.argsort(codes[judged], kind="stable")]  # each cell's rows in order
    all_friction = cells["friction [N]"].to_numpy(float)
    all_duration = (cells["window_end [s]"] - cells["window_start [s]"]).to_numpy(float)
    all_index = cells.index.to_numpy()
    found = []
    for rows in np.split(order, np.flatnonzero(np.diff(codes[order])) + 1):
        friction, duration, index = all_friction[rows], all_duration[rows], all_index[rows]
        keep = np.isfinite(friction)
        while keep.sum() >= min_points:
            values = friction[keep]
            median = float(np.median(values))
            mad = float(np.median(np.abs(values - median)))
            sigma = max(1.4826 * mad, noise_floor * abs(median), 1e-9)
            distance = np.where(keep, np.abs(friction - median) / sigma, 0.0)
            # a window much shorter than its setting's others: the stroke ended (or the
            # force settled) late, so a smaller disagreement already marks a transient
            short = duration < short_window * float(np.median(duration[keep]))
            limit = np.where(short, short_sigma, transient_sigma)
            worst = int(np.argmax(distance / limit))
            if distance[worst] <= limit[worst]:
                break
            found.append((index[worst], median, sigma))
            keep[worst] = False
    return found


class QualityError(ValueError):
    """The data contradict each other too much for the gate to pick the runs to keep."""


def _above_noise(median, runs):
    """Whether a median friction [N] stands out of the noise of the window means of
    ``runs`` (5 standard errors; a table without them always does)."""
    se = float(np.nanmedian(runs["se"])) if "se" in runs and runs["se"].notna().any() else 0.0
    return abs(median) > 5 * se and abs(median) > 0


def _level_scale(rest, scale_factor):
    """(row, level median, median of the other levels) of runs whose whole pressure level is
    more than ``scale_factor`` off the other levels of its group (a level in N, not kN).

    A level is compared with the median of the other levels' medians (within a group of
    runs); with two levels each one is compared with the other, so both are flagged and
    :func:`_refuse_scale` refuses (which of the two is right cannot be told).
    """
    out = []
    for _, group in rest.groupby("group", dropna=False):
        medians = group.groupby("level")["friction"].median().abs()
        medians = medians[[_above_noise(m, group[group["level"] == k]) for k, m in medians.items()]]
        if len(medians) < 2:
            continue
        for level, median in medians.items():
            others = float(np.median(medians.drop(level)))
            ratio = median / max(others, 1e-12)
            if ratio > scale_factor or ratio < 1 / scale_factor:
                rows = group[group["level"] == level].to_dict("records")
                out += [(row, float(median), others) for row in rows]
    return out


def _folder(extraction):
    return getattr(extraction, "folder", None) or "the campaign"


def _refuse_scale(excluded, n_runs, max_fraction, factor, extraction) -> None:
    scale = [e for e in excluded if e["check"] == "scale"]
    if n_runs and len(scale) > max_fraction * n_runs:
        files = ", ".join(e["file"] for e in scale[:4]) + (", ..." if len(scale) > 4 else "")
        raise QualityError(
            f"{_folder(extraction)}: the friction of {len(scale)} of {n_runs} runs ({files}) "
            f"differs from the rest by more than {factor:g}x: the runs fall in groups about "
            "1000x apart and none is a clear majority (at most "
            f"{max_fraction:.0%} of the runs may be flagged by scale); expected one force unit "
            "in every file: correct the force unit (N or kN) in the unit row of the files "
            "that are wrong"
        )


def _refuse_most(frame, n_runs, max_fraction, extraction) -> None:
    runs = frame[frame["run"] >= 0]
    if n_runs and runs["run"].nunique() > max_fraction * n_runs:
        counts = ", ".join(f"{n} by {check}" for check, n in runs["check"].value_counts().items())
        first = "; ".join(f"{r.file}: {r.reason}" for r in runs.head(3).itertuples())
        raise QualityError(
            f"{_folder(extraction)}: the data-quality gate would exclude "
            f"{runs['run'].nunique()} of {n_runs} runs ({counts}): the data contradict each "
            f"other, so no datasheet is fitted from the remainder (at most "
            f"{max_fraction:.0%} may be excluded); the first: {first}"
        )


def assess(
    extraction: Extraction,
    *,
    speed_tolerance: float = 0.20,
    scale_factor: float = 30.0,
    outlier_sigma: float = 8.0,
    min_speeds: int = 4,
    noise_floor: float = 0.005,
    metadata_tolerance: float = 0.05,
    pressure_floor: float = 0.2e5,
    speed_floor: float = 0.05e-3,
    measured_tolerance: float = 0.20,
    measured_floor: float = 2e5,
    zero_level_runs: int = 3,
    max_scale_fraction: float = 0.25,
    max_excluded_fraction: float = 0.5,
    duplicates: Iterable[Duplicate] = (),
    accept_force_balance: bool = False,
    transient_sigma: float = 8.0,
    transient_points: int = 3,
) -> QualityReport:
    """Flag the runs that would mislead the fit; see the module docstring for the checks.

    Parameters
    ----------
    extraction : Extraction
        From :func:`cylfric.steady_state.extract_campaign`.
    speed_tolerance : float
        Largest relative difference between measured and nominal speed [-] (0.20: 20 %).
    scale_factor : float
        Largest factor between a run's friction and the median of its pressure level [-];
        a unit slip is a factor of 1000, a real level spread a factor below 3.
    outlier_sigma : float
        Robust sigmas (1.4826 MAD of all runs' residuals against their neighbours'
        prediction, at least ``noise_floor``) beyond which a run is an outlier [-]. 8 keeps
        every run of clean virtual campaigns (the thesis' 270 runs, 144- and 480-run grids
        with 1 mm/s and 7 bar steps), while a run mislabelled by 80 bar sits far out.
    noise_floor : float
        Smallest robust sigma as a fraction of the campaign's median friction [-] (0.005:
        1 N at 200 N). Very clean data would otherwise make a tiny sigma of every bend of the
        Stribeck curve; a pressure typed 20 bar off still moves friction by about 10 N.
    min_speeds : int
        Fewest distinct speeds at a pressure level (within one group of runs, e.g. a seal)
        for the outlier check [-].
    metadata_tolerance : float
        Largest relative difference between two sources of a run's nominal pressure or
        speed [-] (0.05: 5 % of the larger, so a file named p55bar may say 55.3 bar).
    pressure_floor : float
        Pressure differences up to this are never a conflict [Pa] (0.2 bar: a manifest's 0
        against a file's 0.1 bar is the same unpressurised level).
    speed_floor : float
        Speed differences up to this are never a conflict [m/s] (0.05 mm/s).

    measured_tolerance : float
        Largest relative difference between a run's measured pressure (median of its
        pressure column over the windows) and each of its nominal values [-] (0.20: a rig's
        measured pressure sags and scatters more than a nominal value).
    measured_floor : float
        Differences between measured and nominal pressure up to this are never a conflict
        [Pa] (2 bar: an unpressurised run may read 1 bar of back pressure).
    zero_level_runs : int
        A nominal pressure of 0 (or below, or not finite) on a run without a pressure column
        is a metadata conflict unless at least this many runs (or, on a sparse grid whose
        median level has fewer, that many), and at least half the median number of runs
        per level, share 0 bar (a deliberate unpressurised level) [-].
    max_scale_fraction : float
        When the ``scale`` check would flag more than this fraction of the runs [-], the
        runs' friction falls in groups about 10^3 apart without a clear majority: raise
        :class:`QualityError` (exit 2) rather than guess which group is right.
    max_excluded_fraction : float
        When the gate would exclude more than this fraction of the runs [-], the data
        contradict each other: raise :class:`QualityError` rather than fit the remainder.
    duplicates : iterable of Duplicate
        Files left out because their bytes repeat an earlier run's
        (:attr:`cylfric.io.campaign.Campaign.duplicates`): listed with the check
        ``duplicate`` and the file they repeat (they are not runs: never counted against
        ``max_excluded_fraction``).
    transient_sigma : float
        A stroke's window further than this many robust sigmas from the median of the other
        strokes of its setting (1.4826 MAD of the cell, at least ``noise_floor`` of its
        median) is a start transient and left out by itself (``transient``: the window,
        not the run) [-].
    transient_points : int
        Fewest strokes of a setting (run nominal pressure and speed, labels, direction) for
        the ``transient`` check [-].
    accept_force_balance : bool
        Fit even when the physical checks of :mod:`cylfric.quality.plausibility` find the force
        balance or the units contradicted (a sign of campaign.toml, a friction above the
        cylinder's pressure force): their findings become :attr:`QualityReport.notes`
        instead of an error.

    Returns
    -------
    QualityReport

    Raises
    ------
    QualityError
        When the gate would exclude more than ``max_excluded_fraction`` of the runs, or the
        ``scale`` check more than ``max_scale_fraction``; its subclasses
        :class:`~cylfric.quality.plausibility.ForceBalanceError` (the offset or the friction
        follows the balance's pressure force, or is below 0: a sign of campaign.toml) and
        :class:`~cylfric.quality.plausibility.ImplausibleDataError` (a friction above the pressure
        force the cylinder could make: a unit slip), unless ``accept_force_balance``.
    """
    from .plausibility import check_force_balance, check_plausibility

    # a whole campaign in another force unit first (no majority for the scale check), then
    # the force balance on the runs in one unit
    notes = check_plausibility(extraction, accept=accept_force_balance, min_fraction=0.5)
    notes += check_force_balance(extraction, accept=accept_force_balance)
    table = _runs_table(extraction)
    excluded = []

    def exclude(row, check, reason):
        excluded.append({"file": row["file"], "run": row["run"], "check": check, "reason": reason})

    floors = {"pressure": pressure_floor, "velocity": speed_floor}
    config = getattr(extraction, "config", None)
    reference = config.pressure_reference if config is not None else "mean"
    points = extraction.points
    windows = points[points["n [-]"] > 0] if "n [-]" in points else points
    measured = windows.groupby("run")["pressure [Pa]"].median()
    summaries = extraction.runs
    measured_flags = [bool(m) for m in run_column(summaries, "pressure measured", default=False)]
    run_numbers = run_column(summaries, "run")
    pressures = run_column(summaries, "pressure [Pa]", default=math.nan)
    nominal_p = np.array(pressures, dtype=float)
    finite = nominal_p[np.isfinite(nominal_p)]
    per_level = float(np.median(np.bincount(pressure_levels(finite)[0]))) if finite.size else 0.0
    unmeasured = [i for i, m in enumerate(measured_flags) if not m]
    nonpositive = _deliberate_zero(
        [run_numbers[i] for i in unmeasured],
        [pressures[i] for i in unmeasured],
        _zero_level_size(per_level, zero_level_runs),
    )
    for i in _metadata_suspects(summaries, measured_flags, run_numbers, nonpositive):
        info = summaries[i]
        texts = [_conflicts(info, metadata_tolerance, floors)]
        if info.get("pressure measured"):
            texts.append(
                _measured_conflict(
                    info,
                    float(measured.get(info.get("run"), math.nan)),
                    measured_tolerance,
                    measured_floor,
                    reference,
                )
            )
        elif info.get("run") in nonpositive and not texts[0].startswith("pressure"):
            used = info.get("source", {}).get("pressure")
            value, where = (
                info.get("nominal", {})
                .get("pressure", {})
                .get(used, (info.get("pressure [Pa]", math.nan), "the metadata"))
            )
            texts.append(
                f"nominal pressure {_said('pressure', used or '', value, where)}, "
                "and no 0-bar level it belongs to (pressures must be above 0, finite, and "
                "in bar): check this run's pressure"
            )
        text = "; ".join(t for t in texts if t)
        if text:
            row = {"file": _relative(info["file"], extraction), "run": info.get("run")}
            exclude(row, "metadata", f"metadata conflict: {text}")
    table = table[~table["run"].isin({e["run"] for e in excluded})]
    usable = table.dropna(subset=["friction"]) if "friction" in table else table.iloc[:0]
    no_window = table["friction"].isna() if "friction" in table else np.ones(len(table), bool)
    for row in table[no_window].to_dict("records"):
        exclude(row, "motion", "no usable constant-velocity window (no motion, or too short)")
    nominal = usable["nominal_speed"]
    off = (nominal > 0) & ((usable["speed"] / nominal - 1).abs() > speed_tolerance)
    for row in usable[off].to_dict("records"):
        exclude(
            row,
            "speed",
            f"measured speed {row['speed'] * 1e3:.4g} mm/s against nominal "
            f"{row['nominal_speed'] * 1e3:.4g} mm/s "
            f"({_speed_cause(row['speed'] / row['nominal_speed'])})",
        )
    flagged = {e["run"] for e in excluded}
    rest = usable[~usable["run"].isin(flagged)].copy()
    if len(rest):
        rest["level"] = pressure_levels(rest["pressure"].to_numpy())[0]
        if "group" not in rest:
            rest["group"] = 0
        for _, level in rest.groupby(["level", "group"], dropna=False):
            if len(level) < 3:
                continue
            median = float(np.median(level["friction"]))
            if not _above_noise(median, level):
                continue  # a force column of zeros (or noise): no scale to compare
            ratio = level["friction"].abs() / max(abs(median), 1e-12)
            for row in level[(ratio > scale_factor) | (ratio < 1 / scale_factor)].to_dict(
                "records"
            ):
                exclude(
                    row,
                    "scale",
                    f"friction {row['friction']:.4g} N against {median:.4g} N for the "
                    f"runs at {row['pressure'] / 1e5:.3g} bar (a force unit, N or kN?)",
                )
        flagged = {e["run"] for e in excluded}
        rest = rest[~rest["run"].isin(flagged)]
        for row, median, others in _level_scale(rest, scale_factor):
            exclude(
                row,
                "scale",
                f"friction {row['friction']:.4g} N; its pressure level "
                f"({row['pressure'] / 1e5:.3g} bar) has a median of {median:.4g} N against "
                f"{others:.4g} N for the other levels (a force unit, N or kN, for the whole "
                "level?)",
            )
        _refuse_scale(excluded, len(extraction.runs), max_scale_fraction, scale_factor, extraction)
        flagged = {e["run"] for e in excluded}
        rest = rest[~rest["run"].isin(flagged)]
        groups = [
            (g["run"].to_numpy(), np.log(g["speed"].to_numpy()), g["friction"].to_numpy())
            for _, g in rest.sort_values("speed").groupby(["level", "group"], dropna=False)
        ]
        # measurement noise of real rigs is at least a few per mille of the friction level
        floor = noise_floor * float(np.median(np.abs(rest["friction"]))) if len(rest) else 0.0
        rows = rest.set_index("run")
        while True:  # the worst first: a bad run also pulls its neighbours' prediction
            found = _outliers(groups, outlier_sigma, min_speeds, floor)
            if not found:
                break
            run, residual, sigma = max(found, key=lambda item: abs(item[1]) / item[2])
            groups = [(r[r != run], x[r != run], y[r != run]) for r, x, y in groups]
            row = rows.loc[run].to_dict() | {"run": run}
            exclude(
                row,
                "outlier",
                f"friction {row['friction']:.4g} N is {residual:+.3g} N "
                f"({abs(residual) / sigma:.0f} robust sigmas) from its neighbours in speed at "
                f"{row['pressure'] / 1e5:.3g} bar (pressure metadata wrong?)",
            )
    flagged = {e["run"] for e in excluded}
    strokes = []  # single windows left out, not whole runs
    for row, median, sigma in _transients(
        points, extraction.runs, flagged, transient_sigma, noise_floor, transient_points
    ):
        point = points.loc[row]
        direction = "extension" if point["direction [-]"] > 0 else "retraction"
        distance = abs(point["friction [N]"] - median) / sigma
        strokes.append(
            {
                "row": row,
                "file": _relative(point["file"], extraction),
                "run": point["run"],
                "check": "transient",
                "reason": (
                    f"stroke {point['stroke']} ({direction}, window "
                    f"{point['window_start [s]']:.3g}-{point['window_end [s]']:.3g} s): friction "
                    f"{point['friction [N]']:.4g} N against {median:.4g} N for the other "
                    f"strokes of the same setting ({distance:.0f} robust sigmas): a start "
                    "transient, not a steady level"
                ),
            }
        )
    for name in getattr(extraction, "unlisted", []):
        excluded.append(
            {
                "file": name,
                "run": -1,
                "check": "unlisted",
                "reason": "in the folder but not in manifest.csv: not read",
            }
        )
    for duplicate in duplicates:
        excluded.append(
            {"file": duplicate.file, "run": -1, "check": "duplicate", "reason": duplicate.reason}
        )
    frame = pd.DataFrame(excluded, columns=["file", "run", "check", "reason"])
    _refuse_most(frame, len(extraction.runs), max_excluded_fraction, extraction)
    kept = table[~table["run"].isin(set(frame["run"]))].dropna(subset=["friction"])
    if not notes:  # any run the gate keeps
        notes += check_plausibility(extraction, kept, accept=accept_force_balance)
    runs = frame[frame["run"] >= 0]
    if len(runs):
        checks = dict(zip(runs["run"], runs["check"], strict=True))
        mask = points["run"].isin(checks) & points["flag"].eq("ok")
        points = points.copy()
        points.loc[mask, "flag"] = "excluded: " + points.loc[mask, "run"].map(checks)
    if strokes:
        points = points.copy()
        points.loc[[s["row"] for s in strokes], "flag"] = "excluded: transient"
        rows = pd.DataFrame([{k: v for k, v in s.items() if k != "row"} for s in strokes])
        frame = pd.concat([frame, rows], ignore_index=True)
    return QualityReport(points, frame, tuple(notes))
