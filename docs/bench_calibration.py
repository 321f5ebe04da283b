"""Measure the rough virtual bench's default levels on the shared Zillen repeatability data.

Run: ``python docs/bench_calibration.py [FOLDER]`` (default
``/work/shared/data/zillen2021-pneumatic-seals/repeatability``); prints the figures quoted in
docs/virtual_bench.md and the ``BenchSettings`` docstring. Columns of the files (README
there): time [ms], laser [V], pressure [V], load cell [V], position [mm], gauge pressure
[bar], force [N]; 100 Hz; 10 extend/retract strokes per file.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import statsmodels.formula.api as smf
from statsmodels.stats.anova import anova_lm

AREA = np.pi * (0.0257 / 2) ** 2  # [m^2], O-ring257 bore 25.7 mm


def strokes(a):
    """(direction, net-force level [N], first sample, last sample) of each stroke."""
    t, x, p, f = a[:, 0] / 1e3, a[:, 4], a[:, 5], a[:, 6]
    v = np.gradient(np.convolve(x, np.ones(5) / 5, mode="same"), t)
    d = np.sign(v) * (np.abs(v) > 4)  # moving faster than 4 mm/s
    out, i = [], 0
    while i < d.size:
        j = i
        while j < d.size and d[j] == d[i]:
            j += 1
        if d[i] and j - i > 100:
            lo, hi = np.percentile(x[i:j], [20, 80])  # the middle 60 % of the stroke
            sel = np.arange(i, j)[(x[i:j] > lo) & (x[i:j] < hi)]
            out.append((int(d[i]), float(np.median(f[sel] - p[sel] * 1e5 * AREA)), i, j))
        i = j
    return out


def main(folder: Path) -> None:
    rows, slopes, startup, spread, stroke = [], [], [], [], []
    steps = {k: [] for k in ("force [N]", "position [mm]", "pressure [bar]")}
    for path in sorted(folder.glob("*_O-ring257_*bar.csv")):
        session, bar = re.match(r"(\d+)_O-ring257_(\d+)bar", path.name).groups()
        a = np.loadtxt(path)
        for col, key in ((6, "force [N]"), (4, "position [mm]"), (5, "pressure [bar]")):
            steps[key].append(np.diff(np.unique(a[:, col])).min())
        s = strokes(a)
        ext, ret = [q for q in s if q[0] > 0], [q for q in s if q[0] < 0]
        n = min(len(ext), len(ret))
        level = np.array([(ext[k][1] - ret[k][1]) / 2 for k in range(n)])  # friction [N]
        offset = np.array([(ext[k][1] + ret[k][1]) / 2 for k in range(n)])  # [N]
        rows.append(dict(session=session, bar=bar, level=level.mean(), offset=offset.mean()))
        slopes.append(np.polyfit(np.arange(n), level / level.mean(), 1)[0])
        spread.append(level.std(ddof=1) / level.mean())
        # one stroke's friction (each direction about the file's mean offset), less the
        # file's linear drift: the stroke-to-stroke repeatability
        k = np.arange(n)
        for one in (
            np.array([q[1] for q in ext[:n]]) - offset.mean(),
            offset.mean() - np.array([q[1] for q in ret[:n]]),
        ):
            detrended = one - np.polyval(np.polyfit(k, one, 1), k)
            stroke.append(detrended.std(ddof=2) / level.mean())
        net = a[:, 6] - a[:, 5] * 1e5 * AREA
        move = np.nonzero(np.abs(a[:, 4] - a[0, 4]) > 0.02)[0][0]
        w = net[move : move + 40] - ext[0][1]
        late = np.nonzero(w > 0.1 * level.mean())[0]
        startup.append((w.max() / level.mean(), 10.0 * (late[-1] if late.size else 0)))
    df = pd.DataFrame(rows)
    print("smallest value steps:", {k: float(np.median(v)) for k, v in steps.items()})
    print("mean friction level [N]:", round(df.level.mean(), 2))
    for bar, g in df.groupby("bar"):
        print(f"{bar} bar: session s.d. of the level {100 * g.level.std() / g.level.mean():.1f} %")
    df["log_level"] = np.log(df.level)
    table = anova_lm(smf.ols("log_level ~ C(session) + C(bar)", df).fit())
    ms_s, ms_e = table.loc["C(session)", "mean_sq"], table.loc["Residual", "mean_sq"]
    print(
        f"two-way ANOVA of ln(level): session x pressure s.d. {100 * np.sqrt(ms_e):.1f} %, "
        f"session s.d. {100 * np.sqrt(max(0.0, (ms_s - ms_e) / df.bar.nunique())):.1f} %"
    )
    off = df.pivot(index="session", columns="bar", values="offset")
    pooled = np.sqrt(((off - off.mean()) ** 2).to_numpy().sum() / ((len(off) - 1) * off.shape[1]))
    print(f"offset (ext+ret)/2 - pA, s.d. between sessions at one pressure: {pooled:.3f} N")
    print(
        f"trend of the level with stroke index: {100 * np.mean(slopes):+.2f} %/stroke "
        f"(s.d. {100 * np.std(slopes, ddof=1):.2f} % over {len(slopes)} files)"
    )
    print(
        f"s.d. of the stroke-pair levels inside a file: {100 * np.median(spread):.1f} % "
        f"(median; {100 * min(spread):.1f}-{100 * max(spread):.1f} %); of one stroke's level "
        f"about the file's linear drift: {100 * np.median(stroke):.2f} % (median of both "
        f"directions; {100 * min(stroke):.1f}-{100 * max(stroke):.1f} %)"
    )
    peaks, settle = np.array(startup).T
    print(
        f"start from rest: force peak above the level {np.median(peaks):.2f} x level "
        f"(median), back within 10 % after {np.median(settle):.0f} ms (median)"
    )


DEFAULT = Path("/work/shared/data/zillen2021-pneumatic-seals/repeatability")

if __name__ == "__main__":
    main(Path(sys.argv[1]) if sys.argv[1:] else DEFAULT)
