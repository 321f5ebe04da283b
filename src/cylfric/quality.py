"""The data-quality gate between extraction and identification (runs left out, with reasons).

:func:`assess` looks at every run of an :class:`~cylfric.steady_state.Extraction` and flags
those that would mislead the fit:

- ``speed``: the measured window speed differs from the run's nominal speed by more than
  ``speed_tolerance`` (a position column in m instead of mm reads 1000x off);
- ``scale``: the run's friction differs from the other runs at its pressure level by a
  factor of more than ``scale_factor`` (a force column in N instead of kN);
- ``outlier``: the run's friction is far from what its neighbours in speed at the same
  pressure level say (interpolated in log speed), beyond ``outlier_sigma`` robust sigmas of
  all such residuals (a run typed as 0 bar in manifest.csv while measured at 80 bar);
- ``motion``: the run gave no usable constant-velocity window (no motion, too short).

Flagged runs are kept in the points table with the flag ``"excluded: <check>"``, so that
:func:`cylfric.identify.identify` leaves them out, and listed in :attr:`QualityReport.excluded`
(written as ``excluded.csv``). Files that ``manifest.csv`` does not list are listed too.
Nothing is dropped silently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .levels import pressure_levels

__all__ = ["assess", "QualityReport", "CHECKS"]

CHECKS = ("speed", "scale", "outlier", "motion", "unlisted")
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
    """

    points: pd.DataFrame
    excluded: pd.DataFrame

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
    measured = (
        ok.assign(speed=ok["velocity [m/s]"].abs())
        .groupby("run")
        .agg(
            speed=("speed", "median"),
            friction=("friction [N]", "median"),
            pressure=("pressure [Pa]", "median"),
        )
    )
    extra = [
        c
        for c in extraction.points.columns
        if c not in _POINT_NAMES and extraction.points[c].dtype == object and c != "flag"
    ]
    runs = pd.DataFrame(
        {
            "run": [info.get("run") for info in extraction.runs],
            "file": [info["file"] for info in extraction.runs],
            "nominal_speed": [
                abs(info.get("velocity [m/s]", math.nan)) for info in extraction.runs
            ],
        }
    )
    if extra:
        first = ok.groupby("run")[extra].first()
        measured["group"] = list(zip(*(first[c] for c in extra), strict=True))
    return runs.join(measured, on="run")


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
    residuals = {False: [], True: []}
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


def assess(
    extraction,
    *,
    speed_tolerance=0.20,
    scale_factor=30.0,
    outlier_sigma=8.0,
    min_speeds=4,
    noise_floor=0.005,
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

    Returns
    -------
    QualityReport
    """
    table = _runs_table(extraction)
    excluded = []

    def exclude(row, check, reason):
        excluded.append({"file": row["file"], "run": row["run"], "check": check, "reason": reason})

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
            f"{row['nominal_speed'] * 1e3:.4g} mm/s (a position unit, m or mm?)",
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
    for name in getattr(extraction, "unlisted", []):
        excluded.append(
            {
                "file": name,
                "run": -1,
                "check": "unlisted",
                "reason": "in the folder but not in manifest.csv: not read",
            }
        )
    frame = pd.DataFrame(excluded, columns=["file", "run", "check", "reason"])
    points = extraction.points
    runs = frame[frame["run"] >= 0]
    if len(runs):
        checks = dict(zip(runs["run"], runs["check"], strict=True))
        mask = points["run"].isin(checks) & points["flag"].eq("ok")
        points = points.copy()
        points.loc[mask, "flag"] = "excluded: " + points.loc[mask, "run"].map(checks)
    return QualityReport(points, frame)
