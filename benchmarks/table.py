"""Print the README's performance table from benchmarks/results/*.json (Markdown)."""

from __future__ import annotations

import json
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def load(name):
    return json.loads((RESULTS / f"{name}.json").read_text())


def table() -> str:
    a, b = load("simulate_case_a"), load("simulate_case_b")
    bt, v, p = load("simulate_batch"), load("virtual_bench"), load("parse")
    m, q = load("memory"), load("pipeline")
    met = "met" if q["ratio_report_over_core"] <= 1 else "not met"
    rows = [
        (
            "case A stick-slip, `simulate()` default (DOPRI5) vs LSODA, RK45 at "
            "RMS(F-F_ref)/F_c <= 1e-4",
            f"{a['cylfric_dopri']['seconds'] * 1e3:.2f} ms: {a['ratio_lsoda_over_dopri']:.0f}x "
            f"LSODA, {a['ratio_rk45_over_dopri']:.0f}x RK45",
            ">= 60x, >= 100x",
        ),
        (
            "case A fixed-step kernel vs the same scheme in C (gcc -O3)",
            f"{a['cylfric_fixed']['kernel_seconds'] * 1e3:.1f} ms vs "
            f"{a['c_gcc_O3']['seconds'] * 1e3:.1f} ms: {a['ratio_kernel_over_c']:.2f}x",
            "<= 1.2x",
        ),
        (
            "case B prescribed 50 mm/s sin(2 pi t), sigma_0 = 1e7, vs LSODA",
            f"{b['cylfric_prescribed']['seconds'] * 1e3:.2f} ms: "
            f"{b['ratio_lsoda_over_cylfric']:.0f}x",
            ">= 25x",
        ),
        (
            "batch: 10,000 case-A sets on 2 cores vs LSODA set by set",
            f"{bt['seconds']:.1f} s: {bt['ratio_lsoda_over_batch']:.0f}x",
            ">= 120x",
        ),
        (
            "virtual bench, default 270-file campaign",
            f"{v['steps_per_second']:.2g} steps/s ({v['seconds']:.2f} s)",
            ">= 2e7",
        ),
        (
            "reading 270 messy files (decimal comma, kN, status lines) vs pandas.read_csv on "
            "clean CSV",
            f"{p['ratio_best']:.2f}x ({p['cylfric_MB_per_s']:.0f} MB/s)",
            ">= 1.0x",
        ),
        (
            "peak memory, 27 -> 270 files",
            f"+{m['peak_growth_bytes_per_added_file'] / 1e3:.1f} kB per file (the points rows) vs "
            f"{m['mean_raw_file_bytes'] / 1e3:.0f} kB raw",
            "flat",
        ),
        (
            f"`cylfric fit --no-report`, 270 files ({q['bytes'] / 1e6:.1f} MB)",
            f"{q['core_seconds']:.2f} s: {q['core_MB_per_s']:.1f} MB/s",
            ">= 30 MB/s",
        ),
        (
            "report (figures PNG+SVG, HTML) on top: full run minus core run",
            f"+{q['report_added_seconds']:.2f} s: {q['ratio_report_over_core']:.2f}x the core",
            f"<= 1x ({met})",
        ),
    ]
    rows += _fit_vs_script_rows()
    lines = ["| benchmark | measured | goal |", "|---|---|---|"]
    lines += [f"| {name} | {value} | {goal} |" for name, value, goal in rows]
    return "\n".join(lines)


def _fit_vs_script_rows():
    if not (RESULTS / "fit_vs_script.json").is_file():
        return []
    f = load("fit_vs_script")
    rows = []
    for name in ("144_files", "480_files"):
        c = f[name]
        rows.append(
            (
                f"`cylfric fit --no-report` process vs a plain numpy/scipy script "
                f"(benchmarks/plain_fit.py), {c['files']} files ({c['bytes'] / 1e6:.0f} MB)",
                f"{c['cylfric_fit_seconds']:.2f} s vs {c['plain_script_seconds']:.2f} s: "
                f"{c['ratio_fit_over_script']:.2f}x",
                f"<= {c['goal_ratio']:g}x ({'met' if c['met'] else 'not met'})",
            )
        )
    return rows


if __name__ == "__main__":
    print(table())
