"""The batch simulator's second core idle, beside a spinning process and beside a running
closed-loop simulation (issue 26): ``python benchmarks/batch_cores.py``; prints the times."""

import math
import subprocess
import sys
import time

import numba
import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
from bench_stiff import canudas

from cylfric.model import FrictionModel
from cylfric.simulate import Cylinder, SpringPull, plant, simulate_batch

rng = np.random.default_rng(12)
n = 10_000
s0 = 10 ** rng.uniform(5, 10, n)
k = rng.uniform(1, 4, n)
sp = rng.uniform(0.05, 0.2, n)
base = canudas(1e5, 10.0)["params"]
models = [
    FrictionModel({**base, "sigma_0": s, "sigma_1": math.sqrt(s)}, pressure_law="constant")
    for s in s0
]
drives = [SpringPull(float(a), float(b)) for a, b in zip(k, sp, strict=True)]


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
        t = {1: [], 2: []}
        for _ in range(3):
            for th in t:
                numba.set_num_threads(th)
                plant._PARAMS.clear()
                t0 = time.perf_counter()
                run()
                t[th].append(time.perf_counter() - t0)
        b = {th: min(v) for th, v in t.items()}
        print(
            f"{label}: 1 thread {b[1]:.2f} s, 2 threads {b[2]:.2f} s, gain {b[1] / b[2]:.2f}x",
            flush=True,
        )
    finally:
        if proc:
            proc.kill()
            proc.wait()


measure("idle", None)
measure("busy (spinning process)", "while True: pass")
measure("beside a closed-loop simulation", LOOP)
