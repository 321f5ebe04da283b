"""Issue 41's acceptance on the virtual field bench: ``python benchmarks/bench_field.py
[--draws 20] [--skip-day]`` writes benchmarks/results/field.json.

* change test: ``--draws`` pairs of days with equal friction and as many with a 15 % rise
  (two logs of 300 s per day, new noise and moves per draw): false alarms and detections;
* accuracy: the friction per speed band and direction against the truth, and whether the
  truth is inside the 95 % band, over the same draws' first days; mass and load curves;
* time: one day of 100 Hz logs (24 hourly logs, 8.64 M samples), read from CSV and from
  MATLAB v7.3 files and identified, on one core (``taskset`` if available, BLAS 1 thread).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cylfric.identify.field import fit_field
from cylfric.io.fieldlog import FieldConfig, load_field_config, read_field_logs
from cylfric.simulate.field_bench import (
    FieldSettings,
    field_records,
    field_toml,
    simulate_log,
    write_log,
)

RESULTS = Path(__file__).parent / "results" / "field.json"
SETTINGS = FieldSettings()
CONFIG = FieldConfig(bore=SETTINGS.crane.bore, rod=SETTINGS.crane.rod)


def _records(scales, seed, duration=300.0, logs_per_day=2):
    return field_records(SETTINGS, scales, duration=duration, seed=seed, logs_per_day=logs_per_day)


def _truth(speed, scale=1.0):
    s = SETTINGS
    return scale * (s.F_c * math.tanh(speed / s.v_s) + s.F_v * speed)


def change_and_accuracy(draws: int) -> dict:
    alarms, detections, rises = 0, 0, []
    errors, inside, total, mass_err, load_err, cross = [], 0, 0, [], [], []
    for draw in range(draws):
        for scales in ([1.0, 1.0], [1.0, 1.15]):
            records, truths = _records(scales, seed=1000 * draw + (0 if scales[1] == 1 else 500))
            fit = fit_field(records, CONFIG)
            (change,) = fit.changes
            if scales[1] == 1.0:
                alarms += change["significant"]
                # accuracy on the equal-days draws (the pooled law has one friction level)
                for band in fit.bands:
                    truth = _truth(band["speed [m/s]"])
                    errors.append(100 * (band["friction [N]"] / truth - 1))
                    total += 1
                    inside += abs(band["friction [N]"] - truth) <= band["band [N]"]
                for row in fit.cross_check:
                    cross.append(100 * (row["friction [N]"] / _truth(row["speed [m/s]"]) - 1))
                for load, mass, tr in zip(fit.loads, fit.masses, truths, strict=True):
                    x = np.array(load["position [m]"])
                    tl = np.interp(x, tr["position [m]"], tr["load [N]"])
                    tm = np.interp(x, tr["position [m]"], tr["mass [kg]"])
                    load_err.append(float(np.max(np.abs(np.array(load["load [N]"]) / tl - 1))))
                    mass_err.append(float(np.max(np.abs(np.array(mass["mass [kg]"]) / tm - 1))))
            else:
                detections += change["significant"]
                rises.append(change["change [%]"])
        print(f"draw {draw + 1}/{draws}: alarms {alarms}, detections {detections}", flush=True)
    return {
        "draws": draws,
        "false alarms (equal days)": int(alarms),
        "detections (15 % rise)": int(detections),
        "estimated rise [%] (mean, sd)": [float(np.mean(rises)), float(np.std(rises))],
        "friction error per band and direction [%] (max |.|, rms)": [
            float(np.max(np.abs(errors))),
            float(np.sqrt(np.mean(np.square(errors)))),
        ],
        "truth inside the 95 % band": f"{inside} of {total} ({100 * inside / total:.1f} %)",
        "cross-check error [%] (max |.|)": float(np.max(np.abs(cross))),
        "load curve error, max over stroke [%] (worst log)": 100 * max(load_err),
        "mass curve error, max over stroke [%] (worst log, median log)": [
            100 * max(mass_err),
            100 * float(np.median(mass_err)),
        ],
    }


def one_day(keep: bool = False) -> dict:
    """24 hourly logs at 100 Hz; the time of reading and identifying them."""
    folder = Path(tempfile.mkdtemp(prefix="cylfric-field-day-"))
    try:
        t0 = time.perf_counter()
        for fmt in ("csv", "mat73"):
            (folder / fmt).mkdir()
            (folder / fmt / "field.toml").write_text(field_toml(SETTINGS, fmt), encoding="utf-8")
        samples = 0
        for hour in range(24):
            log = simulate_log(
                SETTINGS, duration=3600.0, payload=SETTINGS.payloads[hour % 2], seed=hour
            )
            samples += log.time.size
            write_log(folder / "csv" / f"2026-03-01_h{hour:02d}.csv", log, "csv")
            write_log(folder / "mat73" / f"2026-03-01_h{hour:02d}.mat", log, "mat73")
        generated = time.perf_counter() - t0
        out = {"samples": samples, "generation [s]": generated}
        for fmt in ("mat73", "csv"):
            config = load_field_config(folder / fmt / "field.toml")
            files = sorted(p for p in (folder / fmt).iterdir() if p.suffix in (".csv", ".mat"))
            t0, c0 = time.perf_counter(), time.process_time()
            records = read_field_logs(files, config)
            t1, c1 = time.perf_counter(), time.process_time()
            fit = fit_field(records, config)
            t2, c2 = time.perf_counter(), time.process_time()
            out[fmt] = {
                "read [s]": t1 - t0,
                "identify [s]": t2 - t1,
                "total [s]": t2 - t0,
                "CPU read [s]": c1 - c0,
                "CPU identify [s]": c2 - c1,
                "CPU total [s]": c2 - c0,
                "load average at the end": os.getloadavg()[0],
                "F_c [N]": fit.parameters["F_c"],
                "F_v [N*s/m]": fit.parameters["F_v"],
            }
            del records, fit
            print(fmt, out[fmt], flush=True)
        return out
    finally:
        if not keep:
            shutil.rmtree(folder, ignore_errors=True)


def bench_field(draws: int | None = None, skip_day: bool = False) -> dict:
    """The ``field`` section of ``make bench`` (``benchmarks/run.py field``): ``draws``
    (default ``CYLFRIC_FIELD_DRAWS`` or 20) pairs of days, then one day of logs, on one core
    (the affinity is put back after); writes benchmarks/results/field.json."""
    from run import _save

    if draws is None:
        draws = int(os.environ.get("CYLFRIC_FIELD_DRAWS", "20"))
    earlier = json.loads(RESULTS.read_text()) if RESULTS.is_file() else {}
    affinity = os.sched_getaffinity(0) if hasattr(os, "sched_setaffinity") else None
    if affinity is not None:
        os.sched_setaffinity(0, {sorted(affinity)[0]})  # one core
    try:
        result = {
            "python": sys.version.split()[0],
            "cores used": 1,
            "truth": {"F_c [N]": SETTINGS.F_c, "F_v [N*s/m]": SETTINGS.F_v},
        }
        if draws:
            result["change_and_accuracy"] = change_and_accuracy(draws)
        elif "change_and_accuracy" in earlier:  # draws 0: keep the last run's draws
            result["change_and_accuracy"] = earlier["change_and_accuracy"]
        if not skip_day:
            result["one_day"] = one_day()
        elif "one_day" in earlier:
            result["one_day"] = earlier["one_day"]  # the last run's
    finally:
        if affinity is not None:
            os.sched_setaffinity(0, affinity)
    return _save("field", result)


SECTIONS = {"field": bench_field}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--draws", type=int, default=20)
    parser.add_argument("--skip-day", action="store_true")
    args = parser.parse_args()
    print(json.dumps(bench_field(args.draws, args.skip_day), indent=2))


if __name__ == "__main__":
    main()
