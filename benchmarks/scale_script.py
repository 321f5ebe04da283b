"""A competent user's own script for thousands of runs: the baseline of the ``scale`` section.

Reads a virtual-bench campaign (testing-machine text: ``key: value`` header lines, then
segments of ``Segment N started``, a names row, a units row and tab-separated numbers;
``manifest.csv`` gives each file's pressure and nominal speed) with pyarrow's CSV reader,
one segment block per call, on a ``ProcessPoolExecutor`` (``map`` with a chunk size); per
run the friction is half the difference of the mean extension and retraction forces over the
middle half of each constant-velocity stroke (which removes the load cell's weight offset).
The Stribeck law F = F_c + (F_s - F_c) exp(-v / v_r) + sigma_2 v is fitted per pressure with
``scipy.optimize.curve_fit``, then each parameter by a straight line in pressure
(``numpy.polyfit``). No cylfric imports.

Usage: ``python benchmarks/scale_script.py CAMPAIGN [OUT.json] [WORKERS]`` (2 by default).
"""

from __future__ import annotations

import csv
import io
import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pyarrow.csv as pv

SCALE = {"mm": 1e-3, "m": 1.0, "kN": 1e3, "N": 1.0, "s": 1.0, "ms": 1e-3}
PARSE = pv.ParseOptions(delimiter="\t")
NAMES = ["time", "position", "force"]


def read_run(path):
    """Time [s], position [m], force [N] of one file (its segments in order)."""
    parts = Path(path).read_bytes().split(b"\nSegment ")[1:]
    blocks = []
    for part in parts:
        _, _, units, data = part.split(b"\n", 3)
        data = data.split(b"\nTest run ended", 1)[0]
        table = pv.read_csv(io.BytesIO(data), pv.ReadOptions(column_names=NAMES), PARSE).to_pandas()
        factors = [SCALE[u] for u in units.decode().strip().split("\t")]
        blocks.append(table.to_numpy() * factors)
    data = np.concatenate(blocks)
    return data[:, 0], data[:, 1], data[:, 2]


def run_friction(job):
    """(pressure [bar], speed [m/s], friction [N]) of one run, or None."""
    path, pressure, nominal = job
    time, position, force = read_run(path)
    velocity = np.gradient(position, time)
    direction = np.where(np.abs(velocity) > 0.5 * nominal, np.sign(velocity), 0)
    edges = np.flatnonzero(np.diff(direction)) + 1
    strokes = []
    for a, b in zip(np.r_[0, edges], np.r_[edges, len(direction)], strict=True):
        if direction[a] == 0 or b - a < 20:
            continue
        quarter = (b - a) // 4
        lo, hi = a + quarter, b - quarter - 1
        speed = (position[hi] - position[lo]) / (time[hi] - time[lo])
        strokes.append((speed, force[lo : hi + 1].mean()))
    strokes = np.array(strokes).reshape(-1, 2)
    up, down = strokes[strokes[:, 0] > 0], strokes[strokes[:, 0] < 0]
    if not (len(up) and len(down)):
        return None
    speed = 0.5 * (up[:, 0].mean() - down[:, 0].mean())
    return pressure, speed, 0.5 * (up[:, 1].mean() - down[:, 1].mean())


def stribeck(v, F_c, F_s, v_r, sigma_2):
    return F_c + (F_s - F_c) * np.exp(-v / v_r) + sigma_2 * v


def main(folder, out=None, workers="2"):
    from scipy.optimize import curve_fit

    folder = Path(folder)
    with open(folder / "manifest.csv", newline="") as f:
        jobs = [
            (folder / r["file"], float(r["pressure_bar"]), float(r["velocity_mm_s"]) * 1e-3)
            for r in csv.DictReader(f)
        ]
    workers = int(workers)
    if workers > 1:
        with ProcessPoolExecutor(workers) as pool:
            rows = list(pool.map(run_friction, jobs, chunksize=64))
    else:
        rows = [run_friction(job) for job in jobs]
    points = np.array([r for r in rows if r is not None])
    names = ["F_c", "F_s", "v_r", "sigma_2"]
    per_pressure = {}
    for p in np.unique(points[:, 0]):
        sel = points[points[:, 0] == p]
        v, friction = sel[:, 1], sel[:, 2]
        guess = (friction.min(), friction.max(), 0.01, 0.0)
        bounds = ([0, 0, 1e-4, 0], [np.inf, np.inf, 1, np.inf])
        params, _ = curve_fit(stribeck, v, friction, p0=guess, bounds=bounds)
        per_pressure[float(p)] = params
    pressures = np.array(sorted(per_pressure)) * 1e5  # [Pa]
    table = np.array([per_pressure[p] for p in sorted(per_pressure)])
    laws = {
        name: dict(zip(["slope", "intercept"], np.polyfit(pressures, table[:, i], 1), strict=True))
        for i, name in enumerate(names)
    }
    result = {
        "runs": len(jobs),
        "points": len(points),
        "per_pressure": {
            f"{p:g}": dict(zip(names, per_pressure[p], strict=True)) for p in per_pressure
        },
        "linear_in_pressure": laws,
    }
    text = json.dumps(result, indent=1, default=float)
    if out:
        Path(out).write_text(text)
    else:
        print(text)
    return result


if __name__ == "__main__":
    main(*sys.argv[1:])
