"""Benchmark of the closed loop (issue 25): a 10 s simulation at 1 kHz control rate.

Goal: <= 50 ms of compute on one core for 10 s of the default axis (50 plant steps per
controller sample, 500 000 steps) with the LuGre observer. Measured as the best of several
calls of the compiled kernel (after a warm-up call that loads or compiles it), beside the
same through the Python API (``simulate_loop`` with the tuning given). Also records the
acceptance ratios of ``compare_compensators`` on the demo datasheet's model.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from run import _best, _save


def bench_control(repeat=7):
    import subprocess
    import sys

    from cylfric.control.axis import DEFAULT_AXIS as axis
    from cylfric.control.kernel import (
        COMPENSATOR_CODES,
        REFERENCE_CODES,
        closed_loop,
        friction_table,
    )
    from cylfric.control.loop import controller_vector, make_reference, rest_state, simulate_loop
    from cylfric.control.study import compare_compensators
    from cylfric.control.tuning import tune
    from cylfric.model import FrictionModel

    with tempfile.TemporaryDirectory() as tmp:
        exe = str(Path(sys.executable).parent / "cylfric")
        subprocess.run([exe, "demo", "--out", tmp + "/demo"], check=True, capture_output=True)
        model = FrictionModel.from_datasheet(tmp + "/demo/fit/datasheet.json")
    ref = make_reference("sine", axis)
    tuning = tune(axis, viscous=380.0)
    table = friction_table(model)
    args = (
        axis.vector(),
        table,
        REFERENCE_CODES[model.reference],
        table,
        REFERENCE_CODES[model.reference],
        COMPENSATOR_CODES["lugre"],
        controller_vector(axis, tuning, model),
        ref.position,
        ref.velocity,
        axis.substeps,
        rest_state(axis),
    )
    closed_loop(*args)
    kernel, _ = _best(lambda: closed_loop(*args), repeat)
    api, _ = _best(lambda: simulate_loop(model, "lugre", reference=ref, tuning=tuning), repeat)
    t0 = time.perf_counter()
    result = compare_compensators(model)
    study = time.perf_counter() - t0
    return _save(
        "control",
        {
            "goal": "10 s closed loop at 1 kHz <= 50 ms compute on one core",
            "simulated_seconds": float(ref.time[-1]),
            "plant_steps": (len(ref.time) - 1) * axis.substeps,
            "kernel_best [s]": kernel,
            "api_best [s]": api,
            "met": kernel <= 0.05,
            "compare_compensators_with_robustness [s]": study,
            "loop_gain_1_s": result.tuning.loop_gain_1_s,
            "ratios": result.ratios(),
            "robustness": {k: result.ratios(v) for k, v in result.robustness.items()},
            "metrics_um": {
                c: {k: (None if v is None else v * 1e6) for k, v in m.items() if k.endswith("_m")}
                for c, m in result.metrics.items()
            },
        },
    )


SECTIONS = {"control": bench_control}
