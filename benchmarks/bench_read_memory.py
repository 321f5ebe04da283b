"""Benchmark of the reader's peak memory on a 200 MB run file (issue 23, item 5).

Goal: reading a text run file takes at most 2x its size plus 300 MB. A virtual-bench run in
the testing-machine dialect (tab separated, preamble, status and header lines) is made
about 200 MB by repeating its data rows; a fresh process imports cylfric, reads a small
file (numba's compiled code is loaded), notes its peak RSS (the baseline of the imports),
then reads the big file with ``read_bench_text`` and notes the peak again. The increase is
what the reading costs.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from pathlib import Path

from run import _save

HERE = Path(__file__).resolve().parent
TARGET_BYTES = 200_000_000

_CHILD = """
import json, os, resource, sys, time
from cylfric.io import read_bench_text
read_bench_text(sys.argv[2])  # the compiled scanner loads: part of the baseline
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t0 = time.perf_counter()
data, meta = read_bench_text(sys.argv[1])
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"baseline": base, "peak": peak, "rows": meta["rows"], "seconds": seconds}))
"""


def _big_run(folder: Path) -> tuple[Path, Path]:
    """A virtual-bench run file and a copy of it grown to about 200 MB."""
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    info = generate_campaign(
        folder / "campaign", BenchSettings.clean(pressures_bar=(50.0,), speeds_mm_s=(1,))
    )
    small = sorted(info["files"])[0]
    lines = small.read_bytes().split(b"\n")
    first = next(i for i, line in enumerate(lines) if line[:1].isdigit())
    end = next(i for i in range(first, len(lines)) if not lines[i][:1].isdigit())
    head, rows = b"\n".join(lines[:first]) + b"\n", b"\n".join(lines[first:end]) + b"\n"
    big = folder / "big_run.txt"
    with big.open("wb") as out:
        out.write(head)
        for _ in range(TARGET_BYTES // len(rows) + 1):
            out.write(rows)
        out.write(b"Test run ended\n")
    return small, big


def bench_read_memory():
    with tempfile.TemporaryDirectory() as tmp:
        small, big = _big_run(Path(tmp))
        size = big.stat().st_size
        done = subprocess.run(
            [sys.executable, "-c", _CHILD, str(big), str(small)],
            check=True,
            capture_output=True,
            text=True,
        )
    child = json.loads(done.stdout)
    increase = child["peak"] - child["baseline"]
    goal = 2 * size + 300e6
    return _save(
        "read_memory",
        {
            "file_bytes": size,
            "rows": child["rows"],
            "baseline_rss_bytes": child["baseline"],
            "peak_rss_bytes": child["peak"],
            "read_increase_bytes": increase,
            "increase_over_file_size": increase / size,
            "seconds": child["seconds"],
            "measured_how": "ru_maxrss of a fresh process before and after read_bench_text "
            "of the big file (after reading a small one: imports and compiled code are the "
            "baseline)",
            "goal": "read_increase_bytes <= 2 x file_bytes + 300 MB",
            "goal_bytes": goal,
            "met": increase <= goal,
        },
    )


SECTIONS = {"read_memory": bench_read_memory}
