"""Benchmark of ``cylfric fit-motion`` (issue 14): the EMPS identification as a process.

Goal: ``cylfric fit-motion DATA_EMPS.mat`` runs in under 2 s end to end (process start,
imports, reading, IDIM-LS, JSON, CSV and figure). Measured as the wall time of the whole
process, best and median of several runs, beside ``cylfric --version`` (the start-up floor)
and the load average of the machine (the goal assumes an otherwise idle machine).
"""

from __future__ import annotations

import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from run import _save

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
EMPS = ROOT.parent / "shared" / "data" / "emps-benchmark"
CONFIG = ROOT / "examples" / "emps" / "motion.toml"


def _timed(command):
    """Wall time [s] and CPU time [s] of the process and its children."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def bench_fit_motion(repeat=5):
    if not (EMPS / "DATA_EMPS.mat").is_file():
        return _save("fit_motion", {"skipped": f"{EMPS} is absent"})
    exe = str(Path(sys.executable).parent / "cylfric")
    out = Path(tempfile.mkdtemp(prefix="fit-motion-"))
    try:
        command = [exe, "fit-motion", str(EMPS / "DATA_EMPS.mat"), "--config", str(CONFIG)]
        command += ["--out", str(out)]
        _timed(command)  # warm the file cache and the compiled-bytecode cache
        load = os.getloadavg()
        runs = [_timed(command) for _ in range(repeat)]
        version = [_timed([exe, "--version"]) for _ in range(repeat)]
    finally:
        shutil.rmtree(out, ignore_errors=True)
    walls = [w for w, _ in runs]
    return _save(
        "fit_motion",
        {
            "goal": "cylfric fit-motion DATA_EMPS.mat < 2 s end to end",
            "wall_best [s]": min(walls),
            "wall_median [s]": statistics.median(walls),
            "cpu_median [s]": statistics.median(c for _, c in runs),
            "version_wall_best [s]": min(w for w, _ in version),
            "load_average_1min": load[0],
            "met": min(walls) < 2.0,
        },
    )


SECTIONS = {"fit_motion": bench_fit_motion}
