"""Benchmark fit_many: 8 small virtual campaigns, 2 local workers against serial fits.

Goal (issue 15): ``cylfric fit-many`` with 2 local workers >= 1.6x faster than the same
fits one after another, with the same datasheets. Measured two ways, alternating the two
modes so that a change of machine load hits both:

- ``cold``: each mode as its own process (``cylfric fit-many ROOT --no-report
  [--scheduler serial | --workers 2]``), imports included: what a user waits for;
- ``warm``: :func:`cylfric.many.fit_many` called in this process after a first call of each
  mode (imports done, the forkserver of the workers started): the throughput once running.

``python benchmarks/run.py fit_many`` writes ``benchmarks/results/fit_many.json``.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from dataclasses import replace
from pathlib import Path

from run import _save

CAMPAIGNS = 8
PRESSURES_BAR = (0.1, 20.7, 38.0, 55.0, 69.0, 83.0, 103.0, 124.0, 141.0, 159.0)  # the thesis'
# ten levels; with 10 speeds a campaign has 100 runs, a third of the thesis' 270: small, yet its
# fit (0.6 s of processor time) is large enough beside the one-off start of the workers (the
# pipeline's import in the server that forks them, 1.06 s of processor time) for 8 of them to
# show the speed-up: estimated 5.9 s serial and 3.5 s on 2 workers on an idle machine
SPEEDS_MM_S = (1, 2, 4, 7, 10, 15, 25, 40, 70, 135)  # the README's band-study speeds
REPEATS = 3
GOAL = 1.6
CPU = {}  # mode -> processor seconds of the 8 fits, per warm call


def _generate(root: Path):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    base = BenchSettings(pressures_bar=PRESSURES_BAR, speeds_mm_s=SPEEDS_MM_S)
    for i in range(CAMPAIGNS):
        generate_campaign(root / f"cyl{i:02d}", replace(base, seed=i))


def _cli(root, out, *mode):
    cylfric = Path(sys.executable).with_name("cylfric")
    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    done = subprocess.run(
        [str(cylfric), "fit-many", str(root), "--out", str(out), "--no-report", *mode],
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - t0
    if done.returncode != 0:
        raise RuntimeError(done.stdout[-2000:] + done.stderr[-2000:])
    return seconds


def _warm(root, out, **mode):
    from cylfric.many import fit_many

    shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = fit_many(root, out, report=False, **mode)
    seconds = time.perf_counter() - t0
    assert result.succeeded == CAMPAIGNS, result.summary
    CPU.setdefault(mode.get("scheduler") or "parallel", []).append(
        float(result.summary["cpu [s]"].sum())
    )
    return seconds


def _import_cpu() -> float:
    """Processor time [s] of importing the pipeline in a fresh process (median of 3)."""
    code = "import time, cylfric.pipeline; print(time.process_time())"
    times = [
        float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout)
        for _ in range(3)
    ]
    return statistics.median(times)


def _numbers(sheet, path=""):
    if isinstance(sheet, dict):
        for key in sorted(sheet):
            if key != "created":
                yield from _numbers(sheet[key], f"{path}/{key}")
    elif isinstance(sheet, list):
        for i, item in enumerate(sheet):
            yield from _numbers(item, f"{path}[{i}]")
    else:
        yield path, sheet


def _largest_difference(a: Path, b: Path) -> float:
    """Largest relative difference of any number between the datasheets of two outputs."""
    worst = 0.0
    for i in range(CAMPAIGNS):
        name = f"cyl{i:02d}"
        left = dict(_numbers(json.loads((a / name / "datasheet.json").read_text())))
        right = dict(_numbers(json.loads((b / name / "datasheet.json").read_text())))
        if left.keys() != right.keys():
            return float("inf")
        for key, x in left.items():
            y = right[key]
            if isinstance(x, float) and isinstance(y, float):
                worst = max(worst, abs(x - y) / max(abs(x), abs(y), 1e-300))
            elif x != y:
                return float("inf")
    return worst


def _summary(serial, parallel):
    pairs = [s / p for s, p in zip(serial, parallel, strict=True)]
    return {
        "serial_seconds": serial,
        "parallel_seconds": parallel,
        "ratio_per_pair": pairs,
        "ratio_of_best": min(serial) / min(parallel),
        "ratio_median_pair": statistics.median(pairs),
        "ratio_spread": [min(pairs), max(pairs)],
    }


def bench_fit_many():
    work = Path(tempfile.mkdtemp(prefix="cylfric-bench-many-"))
    try:
        root = work / "line"
        t0 = time.perf_counter()
        _generate(root)
        generate_seconds = time.perf_counter() - t0
        load_before = os.getloadavg()
        cold_serial, cold_parallel = [], []
        for _ in range(REPEATS):
            cold_serial.append(_cli(root, work / "serial", "--scheduler", "serial"))
            cold_parallel.append(_cli(root, work / "parallel", "--workers", "2"))
        difference = _largest_difference(work / "serial", work / "parallel")
        _warm(root, work / "w", scheduler="serial")  # imports, numba caches
        _warm(root, work / "w", workers=2)  # starts the forkserver
        warm_serial, warm_parallel = [], []
        for _ in range(REPEATS):
            warm_serial.append(_warm(root, work / "ws", scheduler="serial"))
            warm_parallel.append(_warm(root, work / "wp", workers=2))
        load_after = os.getloadavg()
    finally:
        shutil.rmtree(work, ignore_errors=True)
    cold = _summary(cold_serial, cold_parallel)
    warm = _summary(warm_serial, warm_parallel)
    import_cpu = _import_cpu()
    cpu_serial = statistics.median(CPU["serial"])
    cpu_parallel = statistics.median(CPU["parallel"])
    estimate = {
        "what": "NOT measured ratios: what an idle 2-core machine would give, from the "
        "processor times measured here (the fits' processor time in each mode, the import "
        "of the pipeline); warm = serial fits / (parallel fits / 2), cold = (import + serial "
        "fits) / (import + parallel fits / 2)",
        "import_cpu_seconds": import_cpu,
        "fits_cpu_seconds_serial": cpu_serial,
        "fits_cpu_seconds_parallel": cpu_parallel,
        "warm_ratio": cpu_serial / (cpu_parallel / 2),
        "cold_ratio": (import_cpu + cpu_serial) / (import_cpu + cpu_parallel / 2),
    }
    result = {
        "what": f"{CAMPAIGNS} virtual campaigns of {len(PRESSURES_BAR)} pressures x "
        f"{len(SPEEDS_MM_S)} speeds ({len(PRESSURES_BAR) * len(SPEEDS_MM_S)} runs, 150 mm "
        "strokes), fit --no-report; serial (--scheduler serial) against 2 local workers "
        f"(Dask multiprocessing scheduler); {REPEATS} alternating repeats",
        "generate_seconds": generate_seconds,
        "cold_processes": cold,
        "warm_in_process": warm,
        "warm_cpu_seconds_of_the_fits": CPU,
        "estimate_for_an_idle_machine": estimate,
        "largest_relative_difference_of_datasheet_numbers": difference,
        "goal_ratio": GOAL,
        "met_cold_median": cold["ratio_median_pair"] >= GOAL,
        "met_warm_median": warm["ratio_median_pair"] >= GOAL,
        "load_average_1_5_15_min": {"before": load_before, "after": load_after},
        "note": "the machine was shared with other jobs when measured: see the load averages "
        "and the spread of the ratios",
    }
    print(
        f"fit_many: cold {cold['ratio_median_pair']:.2f}x (pairs "
        f"{cold['ratio_spread'][0]:.2f}-{cold['ratio_spread'][1]:.2f}), warm "
        f"{warm['ratio_median_pair']:.2f}x (pairs {warm['ratio_spread'][0]:.2f}-"
        f"{warm['ratio_spread'][1]:.2f}); datasheets differ by at most {difference:.1e}; "
        f"load {load_before[0]:.1f} -> {load_after[0]:.1f}; estimate for an idle machine from "
        f"processor times: warm {estimate['warm_ratio']:.2f}x, cold {estimate['cold_ratio']:.2f}x"
    )
    return _save("fit_many", result)


SECTIONS = {"fit_many": bench_fit_many}
