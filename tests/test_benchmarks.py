"""benchmarks/run.py finds every benchmark module's sections (``make bench`` runs them all).

A ``bench_*.py`` without a ``SECTIONS`` table stopped ``make bench`` before any benchmark ran
(bench_field.py, issue 41's, did)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def test_every_benchmark_module_has_sections():
    script = "import run; run._discover_sections(); print(','.join(sorted(run.SECTIONS)))"
    done = subprocess.run(
        [sys.executable, "-c", script],
        cwd=BENCHMARKS,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    sections = set(done.stdout.strip().split(","))
    modules = sorted(BENCHMARKS.glob("bench_*.py"))
    assert len(modules) >= 9
    assert {"field", "coverage", "control", "scale", "fit_many"} <= sections
