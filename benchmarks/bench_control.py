"""Benchmark of the closed loop (issue 25): a 10 s simulation at 1 kHz control rate.

Goal: <= 50 ms of compute on one core for 10 s of the default axis (10 plant steps per
controller sample, 100 000 steps) with the LuGre observer. Measured as the best of several
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
        subprocess.run(
            [exe, "demo", "--clean", "--out", tmp + "/demo"], check=True, capture_output=True
        )
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
            "feedforward_lead_s": result.to_dict()["controller"]["feedforward_lead_s"],
            "ratios": result.ratios(),
            "robustness": {k: result.ratios(v) for k, v in result.robustness.items()},
            "metrics_um": {
                c: {k: (None if v is None else v * 1e6) for k, v in m.items() if k.endswith("_m")}
                for c, m in result.metrics.items()
            },
        },
    )


_STEP_DRIVER = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "cylfric_compensator.h"
/* times cylfric_compensator_step over a recorded trajectory (read from stdin), cycled */
int main(int argc, char **argv) {
    int kind = atoi(argv[1]), n = 0, i, r, repeats = atoi(argv[2]);
    static cylfric_compensator_input in[20000];
    cylfric_compensator_state st;
    cylfric_compensator_output out;
    double sink = 0.0, best = 1e30;
    struct timespec t0, t1;
    while (n < 20000 && scanf("%lf %lf %lf %lf %lf", &in[n].position, &in[n].pressure_a,
                              &in[n].pressure_b, &in[n].position_reference,
                              &in[n].velocity_reference) == 5) n++;
    for (r = 0; r < repeats; r++) {
        cylfric_compensator_init(&st);
        clock_gettime(CLOCK_MONOTONIC, &t0);
        for (i = 0; i < n; i++) {
            cylfric_compensator_step(kind, &in[i], &st, &out);
            sink += out.command;
        }
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double dt = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
        if (dt < best) best = dt;
    }
    printf("%.9g %d %.17g\n", best / n, n, sink);
    return 0;
}
"""


def bench_compensator_c(repeat=50):
    """The exported C compensator step: best per-step time over a recorded 10 s trajectory
    (10 000 samples of the default axis, demo datasheet), per kind; goal <= 1 us."""
    import subprocess
    import sys

    from cylfric.control.export import EXPORTABLE_COMPENSATORS, export_compensator
    from cylfric.control.kernel import COMPENSATOR_CODES
    from cylfric.control.loop import simulate_loop
    from cylfric.export.fmu import compiler
    from cylfric.model import FrictionModel

    cc = compiler()
    if cc is None:
        return _save("control_c", {"skipped": "no C compiler"})
    with tempfile.TemporaryDirectory() as tmp:
        exe = str(Path(sys.executable).parent / "cylfric")
        subprocess.run(
            [exe, "demo", "--clean", "--out", tmp + "/demo"], check=True, capture_output=True
        )
        model = FrictionModel.from_datasheet(tmp + "/demo/fit/datasheet.json")
        rows = simulate_loop(model, "lugre").measurements()
        export_compensator(model, tmp, targets=["c"])
        Path(tmp, "bench.c").write_text(_STEP_DRIVER)
        command = [cc, "-O2", "-std=c99", f"-I{tmp}", f"{tmp}/bench.c"]
        command += [f"{tmp}/cylfric_compensator.c", "-o", f"{tmp}/bench", "-lm"]
        subprocess.run(command, check=True, capture_output=True)
        text = "\n".join(" ".join(repr(float(v)) for v in row) for row in rows)
        per_step = {}
        for kind in EXPORTABLE_COMPENSATORS:
            done = subprocess.run(
                [f"{tmp}/bench", str(COMPENSATOR_CODES[kind]), str(repeat)],
                input=text,
                capture_output=True,
                text=True,
                check=True,
            )
            per_step[kind] = float(done.stdout.split()[0])
    return _save(
        "control_c",
        {
            "goal": "compensator step in C <= 1 us",
            "compiler": f"{Path(cc).name} -O2",
            "samples": len(rows),
            "best_per_step [s]": per_step,
            "met": max(per_step.values()) <= 1e-6,
        },
    )


SECTIONS = {"control": bench_control, "control_c": bench_compensator_c}
