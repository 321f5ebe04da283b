"""The batch simulator's second core idle, beside a spinning process and beside a running
closed-loop simulation (issue 26): ``python benchmarks/batch_cores.py``; prints the times."""

import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from bench_stiff import batch_sets, thread_times

from cylfric.simulate import Cylinder, simulate_batch

_, _, _, models, drives = batch_sets(np.random.default_rng(12), 10_000)


def run():
    return simulate_batch(Cylinder(1.0), models, drives, 10.0, record_every=10)


simulate_batch(Cylinder(1.0), models[:2], drives[:2], 10.0, record_every=10)
LOOP = """
from cylfric.control.loop import simulate_loop
from cylfric.simulate.bench import BenchSettings
m = BenchSettings().friction
while True:
    simulate_loop(m, "lugre")
"""


def measure(label, other):
    proc = subprocess.Popen([sys.executable, "-c", other]) if other else None
    try:
        time.sleep(3 if other else 0)
        if proc is not None and proc.poll() is not None:
            raise SystemExit(f"{label}: the other process ended ({proc.returncode})")
        b, _, _ = thread_times(run)
        print(
            f"{label}: 1 thread {b[1]:.2f} s, {max(b)} threads {b[max(b)]:.2f} s, "
            f"gain {b[1] / b[max(b)]:.2f}x",
            flush=True,
        )
    finally:
        if proc:
            proc.kill()
            proc.wait()


measure("idle", None)
measure("busy (spinning process)", "while True: pass")
measure("beside a closed-loop simulation", LOOP)
