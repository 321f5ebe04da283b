"""Print the README's performance table from benchmarks/results/*.json (Markdown)."""

from __future__ import annotations

import json
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results"


def load(name):
    return json.loads((RESULTS / f"{name}.json").read_text())


def table() -> str:
    v, p = load("virtual_bench"), load("parse")
    m, q = load("memory"), load("pipeline")
    ratio = q["ratio_report_over_core"]
    met = "met" if ratio <= 1 else ("argued in the README" if ratio <= 1.5 else "not met")
    rows = _simulation_rows() + [
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
            f"<= 1x, or <= 1.5x argued ({met})",
        ),
    ]
    rows += _fit_vs_script_rows() + _parallel_rows() + _later_rows()
    lines = ["| benchmark | measured | goal |", "|---|---|---|"]
    lines += [f"| {name} | {value} | {goal} |" for name, value, goal in rows]
    return "\n".join(lines)


def _ratio(row, name):
    value = row.get(f"ratio_{name}_over_cylfric")
    return (
        f"{value:.0f}x"
        if value and value >= 10
        else (f"{value:.1f}x" if value else "no setting met 1e-4 for")
    )


def _simulation_rows():
    """Issue 12's rows: each case with the measured ratios beside the goal, good or bad."""
    if not (RESULTS / "simulate_stiff.json").is_file():
        return []
    stiff = load("simulate_stiff")
    rows = []
    for r in stiff["rows"]:
        c = r["cylfric"]
        rows.append(
            (
                f"{r['case']}: `simulate()` default (Rodas3) vs scipy LSODA / numbalsoda at "
                "RMS(F-F_ref)/F_c <= 1e-4",
                f"{c['seconds'] * 1e3:.2f} ms (error {c['error']:.0e}): "
                f"{_ratio(r, 'LSODA')} LSODA, {_ratio(r, 'numbalsoda')} numbalsoda; "
                f"kernel {r.get('ratio_numba_kernel_over_c', float('nan')):.2f}x C",
                ">= 20x, >= 3x; <= 1.3x C",
            )
        )
    goals = stiff["goals"]
    rows.append(
        (
            "sigma_0 = 1e10 vs 1e5, Canudas 40 s (same settings)",
            f"{goals['40s_1e10_over_1e5 (< 10)']:.1f}x the time",
            "< 10x",
        )
    )
    if (RESULTS / "simulate_case_b.json").is_file():
        b = load("simulate_case_b")
        rows.append(
            (
                "case B prescribed 50 mm/s sin(2 pi t), sigma_0 = 1e7, vs LSODA / numbalsoda",
                f"{b['cylfric']['seconds'] * 1e3:.2f} ms: {_ratio(b, 'LSODA')} LSODA, "
                f"{_ratio(b, 'numbalsoda')} numbalsoda",
                "(no goal in issue 12)",
            )
        )
    if (RESULTS / "simulate_stiff_batch.json").is_file():
        bt = load("simulate_stiff_batch")
        rows.append(
            (
                f"batch: {bt['sets']:,} heterogeneous Canudas sets (sigma_0 1e5..1e10, springs, "
                "speeds) vs LSODA set by set",
                f"{min(bt['seconds_by_threads'].values()):.1f} s: "
                f"{bt['ratio_lsoda_over_batch']:.0f}x; second core "
                f"{bt['speedup_second_core']:.2f}x",
                ">= 100x; >= 1.7x",
            )
        )
    return rows


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


def _parallel_rows():
    """bench_parallel.py: `cylfric fit --no-report` idle and busy, against the code before
    the simplification (issue 24) and against plain serial reading."""
    if not (RESULTS / "fit_parallel.json").is_file():
        return []
    f = load("fit_parallel")
    rows = []
    for state in ("idle", "busy"):
        for size in ("144", "480"):
            modes = f[f"{state}_{size}_files"]
            now = modes["pool_quick"]["wall_median_seconds"]
            serial = modes["serial_quick"]["wall_median_seconds"]
            before = modes.get("before", {}).get("wall_median_seconds")
            shown = f"{now:.2f} s vs {before:.2f} s before: {now / before:.2f}x" if before else ""
            rows.append(
                (
                    f"`cylfric fit --no-report`, {size} files, {state} (the other core "
                    + ("free" if state == "idle" else "spinning")
                    + "): the standard pool vs the hand-made forked reader before issue 24",
                    f"{shown}; plain serial reading {serial:.2f} s (median of "
                    f"{f['rounds']} rounds)",
                    "<= 1x before (" + ("met" if before and now <= before else "not met") + ")",
                )
            )
    return rows


def _later_rows():
    """Issues 14 and 15: fit-motion on EMPS and fit-many, when their results exist."""
    rows = []
    if (RESULTS / "fit_motion.json").is_file():
        m = load("fit_motion")
        if "wall_best [s]" in m:
            rows.append(
                (
                    "`cylfric fit-motion` DATA_EMPS.mat, end to end (process)",
                    f"{m['wall_best [s]']:.2f} s best, {m['wall_median [s]']:.2f} s median",
                    f"< 2 s ({'met' if m['met'] else 'not met'})",
                )
            )
    if (RESULTS / "fit_many.json").is_file():
        f = load("fit_many")
        r = f["ratios"]
        against = {
            "parallel_cli_vs_serial_cli": "`fit-many --scheduler serial`",
            "parallel_cli_vs_loop": "a shell loop of `cylfric fit`",
            "parallel_warm_vs_serial_warm": "warm serial fits in one process (both warm)",
        }
        for key, baseline in against.items():
            judged = key == f["goal"]["judged"].split(":")[0]
            value = r[key]["ratio_median_of_calm_rounds"]
            rows.append(
                (
                    f"`cylfric fit-many --workers 2`, 8 virtual campaigns, vs {baseline}",
                    f"{value:.2f}x (median of {r[key]['calm_rounds']} calm rounds); same datasheets"
                    if f["goal"]["same_datasheets"]
                    else f"{value:.2f}x; datasheets differ",
                    f">= {f['goal']['ratio']:g}x "
                    + (
                        f"({'met' if value >= f['goal']['ratio'] else 'not met'}; the goal's "
                        "baseline)"
                        if judged
                        else "(not the goal's baseline)"
                    ),
                )
            )
    return rows


if __name__ == "__main__":
    print(table())
