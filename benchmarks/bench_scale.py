"""Benchmark ``cylfric fit`` at scale (issue 27): 1,000 / 5,000 / 20,000 runs.

Campaigns: 200 distinct virtual-bench runs (10 pressures x 20 speeds, the clean bench)
replicated to the size wanted; each copy gets its own ``Test Run Name`` header line and its
own closing status line (``Test run ended (copy N)``), so no two files have the same bytes
nor the same data block (cylfric leaves exact and near-duplicates out: same samples under
another header) while every size has the same mixture of runs (per-run costs comparable
across sizes). Until 2026-12-06 only the header differed; a cylfric with the near-duplicate
check then fitted the 200 distinct runs alone.

Measured per size, each command a fresh process, in one run (ratios at one machine load):

- ``cylfric fit --no-report`` and ``cylfric fit`` (with the report);
- ``benchmarks/scale_script.py``: a competent user's own script (pyarrow CSV reader per
  file, a ``ProcessPoolExecutor(2)``, scipy's Stribeck fit per pressure, linear laws in
  pressure), with 2 processes;
- each again on one core (``cylfric fit --no-report`` and the script with 1 process, pinned
  to processor 0 by their CPU affinity): the second core's gain.

Wall time [s] and processor time [s] from rounds with nothing but the command running; peak
PSS [MB] of the process tree (the process and all its descendants, ``/proc/PID/smaps_rollup``
sampled every 20 ms: shared pages counted once per process share) from one more round of each
command with the sampler, whose wall times are not used: reading smaps_rollup of the tree every
20 ms took about 0.28 of the 2 cores itself (measured: other jobs' share 0.27-0.31 cores with
it, 0.01 without), time that only the commands using both cores lose.

Sizes from ``CYLFRIC_SCALE_SIZES`` (default ``1000,5000,20000``); the files go to
``CYLFRIC_SCALE_DIR`` (default a temporary folder; about 1.5 GB at 20,000 runs), deleted
after. Not run by the test suite. ``python benchmarks/run.py scale`` writes
``benchmarks/results/scale.json``.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BASE_PRESSURES_BAR = (0.1, 20, 30, 40, 50, 60, 80, 100, 130, 159)
BASE_SPEEDS_MM_S = (1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 70, 85, 100, 135)
SIZES = tuple(int(n) for n in os.environ.get("CYLFRIC_SCALE_SIZES", "1000,5000,20000").split(","))
ROUNDS = int(os.environ.get("CYLFRIC_SCALE_ROUNDS", "3"))
HERE = Path(__file__).resolve().parent


def base_campaign(folder: Path) -> list[tuple[bytes, float, float]]:
    """(bytes, pressure [bar], speed [mm/s]) of the 200 distinct runs (generated once into
    ``folder``)."""
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    if not (folder / "manifest.csv").is_file():
        generate_campaign(
            folder,
            BenchSettings.clean(pressures_bar=BASE_PRESSURES_BAR, speeds_mm_s=BASE_SPEEDS_MM_S),
        )
    lines = (folder / "manifest.csv").read_text().splitlines()[1:]
    runs = []
    for line in lines:
        name, pressure, speed = line.split(",")
        runs.append(((folder / name).read_bytes(), float(pressure), float(speed)))
    return runs


def make_campaign(folder: Path, n: int, base: list[tuple[bytes, float, float]]) -> int:
    """Write ``n`` run files (copies of ``base`` in turn, each with its own run name) and
    ``manifest.csv`` into ``folder``; the bytes written."""
    folder.mkdir(parents=True, exist_ok=True)
    manifest = ["file,pressure_bar,velocity_mm_s"]
    total = 0
    for index in range(n):
        data, pressure, speed = base[index % len(base)]
        name = f"run_{index:05d}_p{pressure:g}bar_v{speed:g}mms.txt"
        head, rest = data.split(b"Test Run Name: ", 1)
        rest = rest.split(b"\n", 1)[1]
        # the closing status line carries the copy's number too: a copy whose samples and
        # closing line equal another's is a near-duplicate cylfric leaves out (issue 43)
        rest = rest.replace(b"Test run ended", f"Test run ended (copy {index})".encode(), 1)
        text = head + f"Test Run Name: {name[:-4]}\n".encode() + rest
        (folder / name).write_bytes(text)
        total += len(text)
        manifest.append(f"{name},{pressure:g},{speed:g}")
    (folder / "manifest.csv").write_text("\n".join(manifest) + "\n")
    return total


def _pss_kb(pid: int) -> int:
    """PSS [kB] of one process (0 when it has gone)."""
    try:
        with open(f"/proc/{pid}/smaps_rollup") as f:
            for line in f:
                if line.startswith("Pss:"):
                    return int(line.split()[1])
    except (FileNotFoundError, ProcessLookupError, PermissionError):
        pass
    return 0


def _tree(pid: int) -> list[int]:
    """The process and all its descendants (from /proc/*/task/*/children)."""
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        found.append(p)
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    todo.extend(int(c) for c in f.read().split())
        except (FileNotFoundError, ProcessLookupError):
            pass
    return found


def measure(
    command: list[str],
    env: dict | None = None,
    interval: float = 0.02,
    sample: bool = True,
    cpus: set[int] | None = None,
) -> dict:
    """Run ``command`` (on the processors ``cpus`` only: its CPU affinity, as ``taskset``
    sets it); its wall time [s], peak tree PSS [MB] (``sample``; else 0), processor time of
    the tree [s] and the machine's load (others' share of the 2 cores) meanwhile."""
    import resource

    def children_cpu():
        usage = resource.getrusage(resource.RUSAGE_CHILDREN)
        return usage.ru_utime + usage.ru_stime

    cpu0, busy0 = children_cpu(), _busy_seconds()
    t0 = time.perf_counter()
    pin = None if cpus is None else (lambda: os.sched_setaffinity(0, cpus))
    errors = tempfile.TemporaryFile()  # not a pipe: a command's long stderr cannot block it
    process = subprocess.Popen(
        command, env=env, stdout=subprocess.DEVNULL, stderr=errors, preexec_fn=pin
    )
    peak = 0
    while sample and process.poll() is None:
        peak = max(peak, sum(_pss_kb(p) for p in _tree(process.pid)))
        time.sleep(interval)
    process.wait()
    wall = time.perf_counter() - t0
    errors.seek(0)
    stderr = errors.read().decode(errors="replace")
    errors.close()
    if process.returncode != 0:
        raise RuntimeError(f"{command} failed ({process.returncode}): {stderr[-2000:]}")
    cpu, busy = children_cpu() - cpu0, _busy_seconds() - busy0
    return {
        "wall_seconds": wall,
        "peak_tree_pss_MB": peak / 1024,
        "cpu_seconds": cpu,
        "cores_used": cpu / wall,
        "others_cores": max(busy - cpu, 0.0) / wall,
    }


def _busy_seconds() -> float:
    """Processor time [s] the whole machine has spent busy since boot (/proc/stat)."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return (sum(fields[:8]) - fields[3] - fields[4]) / os.sysconf("SC_CLK_TCK")


ONE_CORE = {0}
"""The processor the one-core commands are pinned to (their CPU affinity): the same command
on one core, which cylfric sees (its default workers, ``_parallel.cores``) and the script is
told (one process)."""


def _modes(campaign: Path, out: Path) -> dict:
    """name: (command, the processors it may use or None: all) of each measured process."""
    cylfric = str(Path(sys.executable).with_name("cylfric"))
    fit = [cylfric, "fit", str(campaign), "--out", str(out)]
    script = [sys.executable, str(HERE / "scale_script.py"), str(campaign), str(out) + ".json"]
    return {
        "fit_no_report": ([*fit, "--no-report"], None),
        "fit_report": (fit, None),
        "fit_no_report_1_core": ([*fit, "--no-report"], ONE_CORE),
        "script": ([*script, "2"], None),
        "script_1_core": ([*script, "1"], ONE_CORE),
    }


def _warm(folder: Path) -> float:
    """Read every file once (the page cache); the seconds it took (the bytes' floor)."""
    t0 = time.perf_counter()
    for path in folder.iterdir():
        path.read_bytes()
    return time.perf_counter() - t0


def _ratios(size: dict, first: dict | None, previous: dict | None = None) -> dict:
    med = {m: v["wall_median_seconds"] for m, v in size["modes"].items()}
    pss = {m: v["peak_tree_pss_MB_max"] for m, v in size["modes"].items()}
    cpu = {m: v["cpu_median_seconds"] for m, v in size["modes"].items()}
    ratios = {
        "fit_over_script": med["fit_no_report"] / med["script"],
        "fit_over_script_processor_time": cpu["fit_no_report"] / cpu["script"],
        "second_core_gain": med["fit_no_report_1_core"] / med["fit_no_report"],
        "report_over_no_report": med["fit_report"] / med["fit_no_report"],
        "report_over_no_report_processor_time": cpu["fit_report"] / cpu["fit_no_report"],
        "script_second_core_gain": med["script_1_core"] / med["script"],
        "fit_seconds_per_1000_runs": 1000 * med["fit_no_report"] / size["runs"],
        "fit_peak_tree_pss_MB": pss["fit_no_report"],
        "fit_report_peak_tree_pss_MB": pss["fit_report"],
    }
    if first is not None:
        ratios["per_run_time_vs_smallest"] = ratios["fit_seconds_per_1000_runs"] / (
            1000 * first["modes"]["fit_no_report"]["wall_median_seconds"] / first["runs"]
        )
        ratios["peak_pss_vs_smallest"] = (
            pss["fit_no_report"] / (first["modes"]["fit_no_report"]["peak_tree_pss_MB_max"])
        )
    if previous is not None:
        # the cost of each added run, the fixed start-up taken out: the wall time the runs
        # added since the previous size took, per run [ms] (fit and script alike)
        for mode, key in (("fit_no_report", "fit"), ("script", "script")):
            added = med[mode] - previous["modes"][mode]["wall_median_seconds"]
            ratios[f"{key}_added_ms_per_run"] = 1000 * added / (size["runs"] - previous["runs"])
        if "fit_added_ms_per_run" in previous["ratios"]:
            ratios["added_per_run_vs_previous"] = (
                ratios["fit_added_ms_per_run"] / previous["ratios"]["fit_added_ms_per_run"]
            )
    return ratios


def bench_scale():
    src = HERE.parent / "src"
    env = {**os.environ, "PYTHONPATH": str(src)}
    root = Path(os.environ.get("CYLFRIC_SCALE_DIR") or tempfile.mkdtemp(prefix="cylfric-scale-"))
    sizes = {}
    try:
        base = base_campaign(root / "base")
        first = previous = None
        for n in SIZES:
            campaign = root / f"runs_{n}"
            written = make_campaign(campaign, n, base)
            cat = _warm(campaign)
            out = root / f"out_{n}"
            modes = _modes(campaign, out)
            runs: dict = {m: [] for m in modes}
            sampled: dict = {}
            names = list(modes)
            for r in range(ROUNDS + 1):  # the timed rounds, then the sampled one
                for mode in names[r % len(names) :] + names[: r % len(names)]:
                    shutil.rmtree(out, ignore_errors=True)
                    command, cpus = modes[mode]
                    result = measure(command, env, sample=r == ROUNDS, cpus=cpus)
                    if r < ROUNDS:
                        runs[mode].append(result)
                    else:
                        sampled[mode] = result
                    print(n, mode, {k: round(v, 2) for k, v in result.items()}, flush=True)
            size = {
                "runs": n,
                "bytes": written,
                "read_all_seconds": cat,
                "modes": {
                    mode: {
                        "wall_median_seconds": statistics.median(x["wall_seconds"] for x in xs),
                        "wall_seconds": [round(x["wall_seconds"], 2) for x in xs],
                        "peak_tree_pss_MB_max": sampled[mode]["peak_tree_pss_MB"],
                        "sampled_round_wall_seconds": round(sampled[mode]["wall_seconds"], 2),
                        "cpu_median_seconds": statistics.median(x["cpu_seconds"] for x in xs),
                        "cores_used_median": statistics.median(x["cores_used"] for x in xs),
                        "others_cores_median": statistics.median(x["others_cores"] for x in xs),
                    }
                    for mode, xs in runs.items()
                },
            }
            size["ratios"] = _ratios(size, first, previous)
            first, previous = first or size, size
            sizes[str(n)] = size
            print(n, {k: round(v, 3) for k, v in size["ratios"].items()}, flush=True)
            shutil.rmtree(campaign, ignore_errors=True)
            shutil.rmtree(out, ignore_errors=True)
    finally:
        if not os.environ.get("CYLFRIC_SCALE_DIR"):
            shutil.rmtree(root, ignore_errors=True)
    from run import _save

    return _save(
        "scale",
        {
            "what": "cylfric fit (--no-report, with the report, --no-report on one core: its "
            "CPU affinity processor 0) and a pyarrow + "
            "ProcessPoolExecutor + scipy script (benchmarks/scale_script.py, 2 and 1 "
            "processes) on replicated virtual campaigns, each a fresh process; medians of "
            "rounds in rotated order, nothing sampled meanwhile; peak PSS of the process "
            "tree from one more round of each command, sampled every 20 ms (the sampler "
            "takes about 0.28 of the 2 cores: that round's wall time is not used); "
            "others_cores = the cores other jobs on the machine took during the timed rounds "
            "(of 2)",
            "rounds": ROUNDS,
            "goals": {
                "fit_over_script": "<= 1.0 at 5,000 and 20,000 runs",
                "second_core_gain": ">= 1.7",
                "fit_peak_tree_pss_MB": "<= 500",
                "report_over_no_report": "<= 1.15",
                "per_run_time_vs_smallest": "within 20 % (0.8-1.2)",
                "peak_pss_vs_smallest": "within 20 % (<= 1.2)",
                "added_per_run_vs_previous": "(no goal: the time per added run, start-up out)",
            },
            "sizes": sizes,
        },
    )


SECTIONS = {"scale": bench_scale}
