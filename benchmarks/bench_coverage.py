"""Coverage of the prediction bands on rough virtual campaigns (issue 22).

Each campaign is the default rough virtual bench (session, pressure-block and run scatter,
warm-up, start-up transients, load-cell offset, quantisation; docs/virtual_bench.md) on a
short-stroke cylinder, 4 pressures x 5 speeds, fitted with defaults (``fit_campaign``,
no report). New data are then drawn from the same bench with seeds that say what is new
(``BenchSettings``: ``seed`` the noise, ``run_seed`` the runs' multipliers, ``session_seed``
the session's and its pressure blocks' multipliers and load-cell offset):

- scope ``point``: the same runs again (same session and run seeds, new noise): a new point
  of the fitted runs;
- scope ``run``: new runs on the same mount (same session seed, new run seed and noise);
- scope ``session``: a new session (every seed new): remounted, another day.

Coverage = the share of the new data's steady-state points (extracted as a fit extracts
them, flagged runs left out) inside the 95 % band of that scope, pooled over the campaigns;
the goal is 90-97 % for each scope. Campaigns the fit refuses (an error, e.g. a level pushed
to 0 N) are counted and left out of the coverage, and so are new-data files the quality gate
flags. Also reported: the per-campaign coverage (median and 10th percentile: one campaign's
points share its session draw, so a campaign is either covered or not) and the mean relative
half-width of each band.

``python benchmarks/run.py coverage`` writes ``benchmarks/results/coverage.json``;
``CYLFRIC_COVERAGE_CAMPAIGNS`` (default 200) and ``CYLFRIC_COVERAGE_SESSIONS`` (sessions in
each fitted campaign, default 1).
"""

from __future__ import annotations

import os
import tempfile
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
from run import _save

CAMPAIGNS = int(os.environ.get("CYLFRIC_COVERAGE_CAMPAIGNS", "200"))
SESSIONS = int(os.environ.get("CYLFRIC_COVERAGE_SESSIONS", "1"))
SCOPES = ("point", "run", "session")
LEVEL = 0.95
GOAL = (0.90, 0.97)
DESIGNS = {  # name: (pressures [bar], speeds [mm/s])
    # the thesis' ten pressure levels (0.1-159 bar) at six speeds
    "thesis 10 x 6": (
        (0.1, 20.7, 38.0, 55.0, 69.0, 83.0, 103.0, 124.0, 141.0, 159.0),
        (1, 3, 10, 20, 50, 100),
    ),
    # four pressure levels, as the shared real repeatability data (Zillen: 1/3/5/7 bar)
    "four pressures 4 x 5": ((20.0, 60.0, 100.0, 150.0), (1, 3, 10, 30, 100)),
}
SELECTED = [
    name
    for name in DESIGNS
    if os.environ.get("CYLFRIC_COVERAGE_DESIGNS", "all") in ("all", name.split()[0])
]


def _settings(index: int, design: str):
    from cylfric.simulate.bench import BenchSettings
    from cylfric.simulate.plant import Cylinder

    pressures, speeds = DESIGNS[design]
    return BenchSettings(
        cylinder=Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.060),
        pressures_bar=pressures,
        speeds_mm_s=speeds,
        sessions=SESSIONS,
        seed=100_000 + index,
        session_seed=200_000 + index,
        run_seed=300_000 + index,
    )


def one_campaign(index: int, folder: str, design: str) -> dict:
    """Fit campaign ``index`` of ``design`` and count the new data of each scope inside
    its bands."""
    from cylfric.model import FrictionModel
    from cylfric.pipeline import fit_campaign
    from cylfric.simulate.bench import generate_campaign
    from cylfric.steady_state import extract_campaign

    root = Path(folder) / f"c{index:04d}"
    settings = _settings(index, design)
    new = {  # one new session's worth of runs each
        "point": replace(settings, seed=400_000 + index, sessions=1),
        "run": replace(settings, seed=400_000 + index, run_seed=500_000 + index, sessions=1),
        "session": replace(
            settings,
            seed=400_000 + index,
            run_seed=500_000 + index,
            session_seed=600_000 + index,
            sessions=1,
        ),
    }
    t0 = time.perf_counter()
    generate_campaign(root / "fit", settings, workers=1)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = fit_campaign(root / "fit", root / "out", report=False, workers=1)
    except Exception as exc:  # noqa: BLE001 - a refused fit is a result here
        return {"index": index, "fitted": False, "error": f"{type(exc).__name__}: {exc}"[:300]}
    model = FrictionModel.from_datasheet(result.datasheet)
    row: dict = {"index": index, "fitted": True, "law": model.friction_law, "seconds": 0.0}
    for scope, drawn in new.items():
        generate_campaign(root / scope, drawn, workers=1)
        points = extract_campaign(root / scope, workers=1).points
        points = points[points["flag"].eq("ok")]
        speed = points["velocity [m/s]"].abs().to_numpy()
        pressure = points["pressure [Pa]"].to_numpy()
        friction = points["friction [N]"].abs().to_numpy()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            low, high = model.prediction_band(speed, pressure, LEVEL, scope=scope)
            level = model.friction(speed, pressure)
        inside = (friction >= low) & (friction <= high)
        row[scope] = {
            "inside": int(inside.sum()),
            "points": int(inside.size),
            "half_width_rel": float(np.nanmean(0.5 * (high - low) / level)),
        }
    row["seconds"] = time.perf_counter() - t0
    return row


def bench_coverage():
    payload = {
        "level": LEVEL,
        "campaigns": CAMPAIGNS,
        "sessions_fitted": SESSIONS,
        "designs": {name: _one_design(name) for name in SELECTED},
    }
    return _save("coverage", payload)


def _one_design(design: str) -> dict:
    import cylfric.pipeline  # noqa: F401 - loaded once, inherited by the forked workers
    from cylfric._parallel import run

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        rows = run(
            lambda i: one_campaign(i, folder, design), CAMPAIGNS, workers=os.cpu_count() or 1
        )
    fitted = [r for r in rows if r and r.get("fitted")]
    failed = [r for r in rows if r and not r.get("fitted")]
    scopes = {}
    for scope in SCOPES:
        inside = sum(r[scope]["inside"] for r in fitted)
        points = sum(r[scope]["points"] for r in fitted)
        per_campaign = [
            r[scope]["inside"] / r[scope]["points"] for r in fitted if r[scope]["points"]
        ]
        coverage = inside / points if points else float("nan")
        scopes[scope] = {
            "coverage": coverage,
            "points": points,
            "per_campaign_median": float(np.median(per_campaign)),
            "per_campaign_p10": float(np.percentile(per_campaign, 10)),
            "campaigns_below_50_percent": int(sum(c < 0.5 for c in per_campaign)),
            "half_width_rel_median": float(np.median([r[scope]["half_width_rel"] for r in fitted])),
            "half_width_rel_p90": float(
                np.percentile([r[scope]["half_width_rel"] for r in fitted], 90)
            ),
            "campaigns_wider_than_the_level": int(
                sum(r[scope]["half_width_rel"] > 1.0 for r in fitted)
            ),
            "goal": list(GOAL),
            "goal_met": GOAL[0] <= coverage <= GOAL[1],
        }
    pressures, speeds = DESIGNS[design]
    return {
        "design": {"pressures_bar": pressures, "speeds_mm_s": speeds},
        "fitted": len(fitted),
        "refused": len(failed),
        "refusals": sorted({r["error"].split(":")[0] for r in failed}),
        "refusal_examples": [r["error"] for r in failed[:3]],
        "friction_laws": {
            law: sum(r["law"] == law for r in fitted) for law in sorted({r["law"] for r in fitted})
        },
        "scopes": scopes,
        "seconds": time.perf_counter() - t0,
    }


SECTIONS = {"coverage": bench_coverage}
