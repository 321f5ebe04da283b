"""Benchmark the parallel reading of ``cylfric fit --no-report`` (issue 24), idle and busy.

``cylfric fit CAMPAIGN --no-report`` as a process on 144 and 480 virtual files (the
campaigns of the ``fit_vs_script`` section), in two machine states:

- ``idle``: nothing of ours besides the fit;
- ``busy``: one process spinning (``python -c "while True: pass"``) on the other core.

Modes (each a fresh process, cylfric from ``PYTHONPATH``; benchmarks/fit_process.py):

- ``before``: the code before issue 24 as its console script ran it (its forked reader and
  its quick exit); only when ``CYLFRIC_BEFORE_SRC`` names that code's ``src`` folder
  (e.g. ``git worktree add /tmp/before <commit>``, then ``/tmp/before/src``);
- ``pool``, ``pool_quick``: the code under test as it reads by default (a pool of forked
  processes above :data:`cylfric.steady_state.PARALLEL_MIN_FILES`), the interpreter ending
  as usual / through a quick exit (``gc.freeze`` and ``os._exit`` after the command);
- ``serial``, ``serial_quick``: the same with ``workers=1``: plain serial reading.

The modes alternate (one of each per round, in a rotated order, ``ROUNDS`` rounds per
state and size) so that a change of the machine's load hits every mode alike; medians are
reported, with the processor time of the fit and its children, and the share of a core
other jobs took meanwhile (``others``: the machine's busy time less ours and the hog's).

``python benchmarks/run.py fit_parallel`` writes ``benchmarks/results/fit_parallel.json``.
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from run import FIT_VS_SCRIPT_CAMPAIGNS, HERE, _save

ROUNDS = int(os.environ.get("CYLFRIC_BENCH_ROUNDS", "7"))
SRC = HERE.parent / "src"
HOG = "while True: pass"
MODES = {  # name: (src folder, exit, reading)
    "before": (os.environ.get("CYLFRIC_BEFORE_SRC"), "console", "default"),
    "pool": (str(SRC), "plain", "default"),
    "pool_quick": (str(SRC), "quick", "default"),
    "serial": (str(SRC), "plain", "serial"),
    "serial_quick": (str(SRC), "quick", "serial"),
}


def _busy_seconds() -> float:
    """Processor time [s] the whole machine has spent busy since boot (/proc/stat)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return (sum(fields[:8]) - fields[3] - fields[4]) / os.sysconf("SC_CLK_TCK")


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _command(mode, campaign, out):
    src, exit_mode, reading = MODES[mode]
    args = ["fit", str(campaign), "--out", str(out), "--no-report"]
    if exit_mode == "console":
        return [str(Path(sys.executable).with_name("cylfric")), *args], src
    return [sys.executable, str(HERE / "fit_process.py"), exit_mode, reading, *args], src


def _time(mode, campaign, out, hog_seconds):
    """(wall [s], processor time of the fit and its workers [s], others' share of a core)."""
    command, src = _command(mode, campaign, out)
    env = {**os.environ, "PYTHONPATH": src}
    cpu, busy = _children_cpu(), _busy_seconds()
    t0 = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True, env=env)
    wall = time.perf_counter() - t0
    cpu, busy = _children_cpu() - cpu, _busy_seconds() - busy
    hog = hog_seconds() if hog_seconds else 0.0
    return wall, cpu, max(busy - cpu - hog, 0.0) / wall


def _hog_seconds(pid):
    """A function giving the processor time [s] the hog took since the last call."""
    tick, last = os.sysconf("SC_CLK_TCK"), [None]

    def read():
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / tick

    last[0] = read()

    def since():
        now = read()
        spent, last[0] = now - last[0], now
        return spent

    return since


def bench_fit_parallel():
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    modes = [m for m in MODES if MODES[m][0]]
    timings = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (pressures, speeds) in FIT_VS_SCRIPT_CAMPAIGNS.items():
            campaign = Path(tmp) / name
            generate_campaign(
                campaign, BenchSettings.clean(pressures_bar=pressures, speeds_mm_s=speeds)
            )
            for mode in modes:  # warm the file cache and numba's on-disk cache
                _time(mode, campaign, Path(tmp) / "out", None)
            for state in ("idle", "busy"):
                hog = None
                if state == "busy":
                    hog = subprocess.Popen([sys.executable, "-c", HOG])
                    time.sleep(0.5)
                try:
                    since = _hog_seconds(hog.pid) if hog else None
                    runs = {mode: [] for mode in modes}
                    for r in range(ROUNDS):
                        order = modes[r % len(modes) :] + modes[: r % len(modes)]
                        for mode in order:
                            if since:
                                since()
                            runs[mode].append(_time(mode, campaign, Path(tmp) / "out", since))
                finally:
                    if hog is not None:
                        hog.kill()
                        hog.wait()
                timings[f"{state}_{name}"] = {
                    mode: {
                        "wall_median_seconds": statistics.median(w for w, _, _ in values),
                        "cpu_median_seconds": statistics.median(c for _, c, _ in values),
                        "others_median_share": statistics.median(o for _, _, o in values),
                        "wall_seconds": [round(w, 3) for w, _, _ in values],
                    }
                    for mode, values in runs.items()
                }
                print(
                    state,
                    name,
                    {
                        m: round(v["wall_median_seconds"], 2)
                        for m, v in timings[f"{state}_{name}"].items()
                    },
                    flush=True,
                )
    return _save(
        "fit_parallel",
        {
            "what": "cylfric fit --no-report as a process; medians of alternating rounds; "
            "before = the code before issue 24 (forked reader, quick exit); pool = the "
            "code under test; serial = workers=1; *_quick = with gc.freeze + os._exit "
            "after the command; idle = nothing of ours besides the fit, busy = a spinning "
            "process on the other core; others = share of a core other jobs took",
            "rounds": ROUNDS,
            "before_src": MODES["before"][0],
            **timings,
        },
    )


SECTIONS = {"fit_parallel": bench_fit_parallel}
