"""cylfric benchmarks: timing goals as ratios measured in one run (``make bench``).

Writes one JSON file per benchmark to ``benchmarks/results/`` and prints a summary.
Sections (all by default, or name some): bench, parse, memory, pipeline, fit_vs_script, and
those of benchmarks/bench_*.py: simulate and batch (bench_stiff.py), ...

Goals (issues "Simulation", "Ingestion", "The main job", 12):
- simulate, batch: see benchmarks/bench_stiff.py (stiff bristles, sigma_0 = 1e5..1e10, every
  baseline at its loosest tolerances that meet RMS(F - F_ref)/F_c <= 1e-4);
- virtual bench: the default 270-file campaign at >= 2e7 simulated steps/s;
- parse: messy testing-machine files at least as fast as pandas.read_csv on clean CSV;
  peak memory flat in the number of files;
- pipeline: core (read, extract, identify, datasheet) >= 30 MB/s; report <= core time;
- fit_vs_script: ``cylfric fit --no-report`` as a process <= 1.0x a plain numpy/scipy script
  (benchmarks/plain_fit.py) on 144 files, <= 0.5x on 480 files (about 44 MB).
"""

from __future__ import annotations

import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"
BUILD = HERE / "build"


def _machine():
    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "cores": os.cpu_count(),
    }


def _save(name, payload):
    RESULTS.mkdir(parents=True, exist_ok=True)
    payload = {
        "benchmark": name,
        "machine": _machine(),
        "measured": time.strftime("%Y-%m-%dT%H:%M:%S"),
        **payload,
    }
    (RESULTS / f"{name}.json").write_text(json.dumps(payload, indent=2) + "\n")
    return payload


def _best(fn, repeat=5):
    best = math.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _thesis_params(p):
    from cylfric.friction import params_at_pressure
    from cylfric.friction.literature import THESIS_2016

    return params_at_pressure(p, THESIS_2016.coefficients)


def bench_virtual_bench():
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    with tempfile.TemporaryDirectory() as tmp:
        generate_campaign(Path(tmp) / "warm", _small_settings())
        t0 = time.perf_counter()
        info = generate_campaign(Path(tmp) / "campaign", BenchSettings.clean())
        elapsed = time.perf_counter() - t0
        size = sum(f.stat().st_size for f in info["files"])
    return _save(
        "virtual_bench",
        {
            "files": len(info["files"]),
            "steps": info["steps"],
            "samples": info["samples"],
            "bytes": size,
            "seconds": elapsed,
            "steps_per_second": info["steps"] / elapsed,
            "goal": ">= 2e7 steps/s",
        },
    )


def _small_settings():
    from cylfric.simulate.bench import BenchSettings

    return BenchSettings.clean(pressures_bar=(50.0,), speeds_mm_s=(10, 100))


def bench_parse():
    import pandas as pd

    from cylfric.io import read_bench_text
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    with tempfile.TemporaryDirectory() as tmp:
        messy = Path(tmp) / "messy"
        clean = Path(tmp) / "clean"
        clean.mkdir()
        info = generate_campaign(messy, BenchSettings.clean(decimal_comma=True, force_unit="kN"))
        for path in info["files"]:
            data, _ = read_bench_text(path)
            data.iloc[:, :3].to_csv(clean / (path.stem + ".csv"), index=False)
        messy_files = sorted(info["files"])
        clean_files = sorted(clean.glob("*.csv"))
        read_bench_text(messy_files[0])
        rounds = []
        for _ in range(5):
            t_pandas, _ = _best(lambda: [pd.read_csv(f) for f in clean_files], 1)
            t_cylfric, _ = _best(lambda: [read_bench_text(f) for f in messy_files], 1)
            rounds.append(
                {
                    "pandas_clean_seconds": t_pandas,
                    "cylfric_messy_seconds": t_cylfric,
                    "ratio": t_pandas / t_cylfric,
                }
            )
        size = sum(f.stat().st_size for f in messy_files)
        rows = sum(len(read_bench_text(f)[0]) for f in messy_files)
    ratios = [r["ratio"] for r in rounds]
    return _save(
        "parse",
        {
            "files": len(messy_files),
            "rows": rows,
            "bytes": size,
            "dialect": "tab, decimal comma, kN, status lines, repeated headers",
            "rounds": rounds,
            "ratio_best": min(r["pandas_clean_seconds"] for r in rounds)
            / min(r["cylfric_messy_seconds"] for r in rounds),
            "ratio_median": float(np.median(ratios)),
            "ratio_min": float(np.min(ratios)),
            "cylfric_MB_per_s": size / 1e6 / min(r["cylfric_messy_seconds"] for r in rounds),
            "goal": "ratio_best (best of 5 rounds on each side) >= 1.0",
        },
    )


def bench_memory():
    from cylfric.simulate.bench import BenchSettings, generate_campaign
    from cylfric.steady_state import extract_campaign

    peaks = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n_pressures in (1, 10):
            folder = Path(tmp) / f"c{n_pressures}"
            settings = BenchSettings.clean(
                pressures_bar=BenchSettings().pressures_bar[:n_pressures]
            )
            info = generate_campaign(folder, settings)
            raw_bytes = sum(f.stat().st_size for f in info["files"])
            extract_campaign(folder)  # warm-up (compilation)
            tracemalloc.start()
            extract_campaign(folder)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            peaks[len(info["files"])] = peak
    files = sorted(peaks)
    per_file = (peaks[files[-1]] - peaks[files[0]]) / (files[-1] - files[0])
    return _save(
        "memory",
        {
            "peak_bytes_by_files": {str(k): v for k, v in peaks.items()},
            "ratio_peak": peaks[files[-1]] / peaks[files[0]],
            "files_ratio": files[-1] / files[0],
            "peak_growth_bytes_per_added_file": per_file,
            "mean_raw_file_bytes": raw_bytes / files[-1],
            "note": "the growth is the points table itself (two rows per "
            "file); no raw data is kept between files",
            "goal": "peak memory flat in the number of files",
        },
    )


def bench_pipeline():
    from cylfric.pipeline import fit_campaign
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    with tempfile.TemporaryDirectory() as tmp:
        campaign = Path(tmp) / "campaign"
        info = generate_campaign(campaign, BenchSettings.clean())
        size = sum(f.stat().st_size for f in info["files"])
        fit_campaign(campaign, Path(tmp) / "warm", report=True)  # warm caches and compilation
        t_core, core = _best(lambda: fit_campaign(campaign, Path(tmp) / "core", report=False), 3)
        t_full, full = _best(lambda: fit_campaign(campaign, Path(tmp) / "full", report=True), 3)
    # The figures are drawn on the second core while the identification and the datasheet
    # run, so what the report adds is the difference of the two runs' wall times.
    added = t_full - t_core
    return _save(
        "pipeline",
        {
            "files": len(info["files"]),
            "bytes": size,
            "core_seconds": t_core,
            "core_MB_per_s": size / 1e6 / t_core,
            "core_timings": core.timings,
            "full_seconds": t_full,
            "full_timings": full.timings,
            "report_added_seconds": added,
            "ratio_report_over_core": added / t_core,
            "goals": {"core": ">= 30 MB/s", "report": "adds <= core time"},
        },
    )


FIT_VS_SCRIPT_CAMPAIGNS = {
    # name: (pressures [bar], speeds [mm/s]); 8 x 18 = 144 and 24 x 20 = 480 files
    "144_files": (
        (0.1, 20, 40, 60, 80, 100, 130, 159),
        (1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 70, 100, 135),
    ),
    "480_files": (
        (0.1, *range(7, 162, 7))[:24],
        tuple(range(1, 21)),
    ),
}
FIT_VS_SCRIPT_GOALS = {"144_files": 1.0, "480_files": 0.5}
FIT_STARTUP = "import cylfric.cli, cylfric.pipeline"
"""What ``cylfric fit`` loads before it forks its extraction child (numpy and the command
line; the child then loads numba and the compiled reader, the caller pandas, scipy.optimize
and jsonschema)."""
FIT_EVERYTHING = (
    "import numpy, jsonschema, pandas, cylfric.cli, cylfric.pipeline, cylfric.datasheet, "
    "cylfric.quality, cylfric.identify.steady\n"
    "from cylfric.io._scan import scan_lines\n"
    "scan_lines(numpy.frombuffer(b'0.1\\t2.5\\n', dtype=numpy.uint8))"
)
"""Everything a fit loads, in one process, the compiled reader included (numba's first call
in a process)."""
LIBRARY_STARTUP = "import numpy, pandas, scipy.optimize, jsonschema"
"""The libraries the process that identifies and writes the datasheet needs, whatever the
design (the reading, with numba, could run in a second process meanwhile)."""
SCRIPT_STARTUP = "import numpy, pandas, scipy.optimize"
"""What benchmarks/plain_fit.py loads."""


def _process_seconds(command, repeat=3):
    """Best wall time of ``command`` run as a fresh process (imports included) [s]."""
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        best = min(best, time.perf_counter() - t0)
    return best


def bench_fit_vs_script():
    """End-to-end ``cylfric fit --no-report`` against benchmarks/plain_fit.py (processes)."""
    from cylfric.pipeline import fit_campaign
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    cylfric = str(Path(sys.executable).with_name("cylfric"))
    script = str(HERE / "plain_fit.py")
    # the start-up before cylfric's first file, and that of the libraries any design needs
    t_startup = _process_seconds([sys.executable, "-c", FIT_STARTUP])
    t_everything = _process_seconds([sys.executable, "-c", FIT_EVERYTHING])
    t_libraries = _process_seconds([sys.executable, "-c", LIBRARY_STARTUP])
    t_script_startup = _process_seconds([sys.executable, "-c", SCRIPT_STARTUP])
    cases = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, (pressures, speeds) in FIT_VS_SCRIPT_CAMPAIGNS.items():
            campaign = Path(tmp) / name
            info = generate_campaign(
                campaign, BenchSettings.clean(pressures_bar=pressures, speeds_mm_s=speeds)
            )
            size = sum(f.stat().st_size for f in info["files"])
            fit = [cylfric, "fit", str(campaign), "--out", str(Path(tmp) / "out"), "--no-report"]
            plain = [sys.executable, script, str(campaign), str(Path(tmp) / "plain.json")]
            _process_seconds(fit, 1), _process_seconds(plain, 1)  # warm the file cache
            t_fit, t_plain = _process_seconds(fit), _process_seconds(plain)
            ratio = t_fit / t_plain
            goal = FIT_VS_SCRIPT_GOALS[name]
            fit_campaign(campaign, Path(tmp) / "stages", report=False)  # warm
            stages = fit_campaign(campaign, Path(tmp) / "stages", report=False).timings
            # after the files are read, identification and the datasheet run on one core
            tail = stages["identify"] + stages["datasheet"]
            cases[name] = {
                "files": len(info["files"]),
                "bytes": size,
                "cylfric_fit_seconds": t_fit,
                "plain_script_seconds": t_plain,
                "ratio_fit_over_script": ratio,
                "goal_ratio": goal,
                "met": ratio <= goal,
                "cylfric_stage_seconds_in_process": stages,
                "startup_before_fork_seconds": t_startup,
                "everything_loaded_in_one_process_seconds": t_everything,
                "floor": {
                    "what": "a lower bound for any design on these libraries: loading "
                    "numpy, pandas, scipy.optimize and jsonschema (as a process) plus "
                    "identification and datasheet as they are (in process, warm), with the "
                    "reading taken as free (overlapped on the second core); floor_over_goal "
                    "> 1: the goal needs a faster identification or other libraries",
                    "libraries_startup_seconds": t_libraries,
                    "identify_and_datasheet_seconds": tail,
                    "floor_seconds": t_libraries + tail,
                    "goal_seconds": goal * t_plain,
                    "floor_over_goal": (t_libraries + tail) / (goal * t_plain),
                    "script_startup_seconds": t_script_startup,
                },
            }
    return _save(
        "fit_vs_script",
        {
            "what": "best of 3 process wall times, imports included; cylfric fit --no-report "
            "(quality gate, global surface fit, sensitivity study, datasheet, tables) vs "
            "benchmarks/plain_fit.py (numpy.loadtxt, middle half of each stroke, curve_fit "
            "per pressure)",
            **cases,
        },
    )


SECTIONS = {
    "bench": bench_virtual_bench,
    "parse": bench_parse,
    "memory": bench_memory,
    "pipeline": bench_pipeline,
    "fit_vs_script": bench_fit_vs_script,
}


def _discover_sections():
    """Sections of ``benchmarks/bench_*.py`` modules (each defines a ``SECTIONS`` dict)."""
    import importlib.util

    for path in sorted(HERE.glob("bench_*.py")):
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        for name, fn in module.SECTIONS.items():
            if name in SECTIONS:
                raise SystemExit(f"{path.name}: benchmark section {name!r} defined twice")
            SECTIONS[name] = fn


def main(argv):
    _discover_sections()
    chosen = argv or list(SECTIONS)
    unknown = set(chosen) - set(SECTIONS)
    if unknown:
        sys.exit(f"unknown sections {sorted(unknown)}; valid: {list(SECTIONS)}")
    for name in chosen:
        t0 = time.perf_counter()
        print(f"== {name} ...", flush=True)
        result = SECTIONS[name]()
        print(json.dumps(result, indent=1, default=str)[:3000])
        print(f"   ({time.perf_counter() - t0:.1f} s)", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
