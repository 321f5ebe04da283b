"""A competent user's own script: the baseline ``cylfric fit`` is timed against.

Reads a virtual-bench campaign (testing-machine text: ``key: value`` header lines, then
segments of ``Segment N started``, a names row, a units row and tab-separated numbers;
``manifest.csv`` gives each file's pressure and nominal speed), averages the middle half of
each constant-velocity stroke, takes the friction of a run as half the difference of its
mean extension and retraction forces (which removes the load cell's weight offset), and
fits the Stribeck law F = F_c + (F_s - F_c) exp(-v / v_r) + sigma_2 v per pressure with
``scipy.optimize.curve_fit``. No cylfric imports.

Usage: ``python benchmarks/plain_fit.py CAMPAIGN [OUT.json]``
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import curve_fit

SCALE = {"mm": 1e-3, "m": 1.0, "kN": 1e3, "N": 1.0, "s": 1.0, "ms": 1e-3}


def read_run(path):
    """Time [s], position [m], force [N] of one file (every segment, in order)."""
    lines = path.read_text().splitlines()
    units = lines[lines.index("Segment 1 started") + 2].split("\t")
    numbers = [line for line in lines if line[:1].isdigit() or line[:1] == "-"]
    data = np.loadtxt(numbers, delimiter="\t")
    return (data[:, i] * SCALE[u] for i, u in enumerate(units))


def stroke_means(time, position, force, nominal):
    """Mean speed [m/s] and force [N] over the middle half of each stroke."""
    velocity = np.gradient(position, time)
    direction = np.where(np.abs(velocity) > 0.5 * nominal, np.sign(velocity), 0)
    edges = np.flatnonzero(np.diff(direction)) + 1
    starts = np.r_[0, edges]
    stops = np.r_[edges, len(direction)]
    out = []
    for a, b in zip(starts, stops, strict=True):
        if direction[a] == 0 or b - a < 20:
            continue
        quarter = (b - a) // 4
        mid = slice(a + quarter, b - quarter)
        speed = (position[mid.stop - 1] - position[mid.start]) / (
            time[mid.stop - 1] - time[mid.start]
        )
        out.append((speed, force[mid].mean()))
    return np.array(out).reshape(-1, 2)


def stribeck(v, F_c, F_s, v_r, sigma_2):
    return F_c + (F_s - F_c) * np.exp(-v / v_r) + sigma_2 * v


def main(folder, out=None):
    folder = Path(folder)
    manifest = pd.read_csv(folder / "manifest.csv")
    rows = []
    for name, p_bar, v_mm_s in manifest.itertuples(index=False):
        t, x, f = read_run(folder / name)
        strokes = stroke_means(t, x, f, v_mm_s * 1e-3)
        up, down = strokes[strokes[:, 0] > 0], strokes[strokes[:, 0] < 0]
        if len(up) and len(down):
            speed = 0.5 * (up[:, 0].mean() - down[:, 0].mean())
            rows.append((p_bar, speed, 0.5 * (up[:, 1].mean() - down[:, 1].mean())))
    points = pd.DataFrame(rows, columns=["pressure [bar]", "speed [m/s]", "friction [N]"])
    result = {}
    for p_bar, level in points.groupby("pressure [bar]"):
        v, friction = level["speed [m/s]"].to_numpy(), level["friction [N]"].to_numpy()
        guess = (friction.min(), friction.max(), 0.01, 0.0)
        params, cov = curve_fit(
            stribeck, v, friction, p0=guess, bounds=([0, 0, 1e-4, 0], [np.inf, np.inf, 1, np.inf])
        )
        result[f"{p_bar:g}"] = dict(zip(["F_c", "F_s", "v_r", "sigma_2"], params, strict=True))
    text = json.dumps(result, indent=1)
    if out:
        Path(out).write_text(text)
    else:
        print(text)
    return result


if __name__ == "__main__":
    main(*sys.argv[1:])
