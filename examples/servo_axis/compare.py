"""The loop study on the example axis in both implementations (docs/control.md's table).

Run: ``PYTHONPATH=src python examples/servo_axis/compare.py [seconds [tau_f_ms]]``
(``tau_f_ms``: the LuGre step's force filter). cylfric's loop
(:func:`cylfric.control.loop.simulate_loop`) and the independent reference loop
(:mod:`cylfric.control.reference_loop`) on the differential axis of ``axis.toml`` and its
double-rod twin, sine 5 mm / 5 s, the seal of ``tests/test_control_reference.py``
(sigma_0 = 1e7 N/m identified). RMS tracking error [um] and ratios to PI alone.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from cylfric.control.axis import load_axis
from cylfric.control.loop import (
    PlantFriction,
    compensator_function,
    make_reference,
    simulate_loop,
)
from cylfric.control.reference_loop import (
    ReferenceAxis,
    ReferenceSeal,
    reference_tuning,
    run_reference,
)
from cylfric.control.tuning import tune
from cylfric.model import FrictionModel

HERE = Path(__file__).resolve().parent
SEAL = dict(fc0=40.0, fc1=4e-6, fs0=45.0, fs1=4.5e-6, sigma_2=2000.0, v_r=0.01, alpha=1.0,
            sigma_0=1e7, sigma_1=2e4)  # fmt: skip
NULL_LEAKAGE = 1e-7


def model_of(seal, sigma_0=None, sigma_1=None):
    return FrictionModel(
        {
            "F_c": {"intercept": seal["fc0"], "slope": seal["fc1"]},
            "F_s": {"intercept": seal["fs0"], "slope": seal["fs1"]},
            "sigma_2": seal["sigma_2"], "v_r": seal["v_r"], "alpha": seal["alpha"],
            "sigma_0": sigma_0 or seal["sigma_0"], "sigma_1": sigma_1 or seal["sigma_1"],
        },
        reference="sum",
    )  # fmt: skip


def rows(axis, seconds, datasheet, level=1.0, force_filter=0.0):
    model = model_of(SEAL)  # the plant
    ref = make_reference("sine", axis, duration=seconds)
    tuning = tune(axis, viscous=SEAL["sigma_2"])
    ours = {}
    for name in ("none", "oracle", "lugre"):
        sheet = datasheet if name == "lugre" else model
        plant_case = PlantFriction("p", level=level, model=model)
        run = simulate_loop(
            sheet, name, axis=axis, reference=ref, tuning=tuning, plant=plant_case,
            force_filter=force_filter if name == "lugre" else 0.0,
        )  # fmt: skip
        ours[name] = float(np.sqrt(np.mean(run.error**2)))
    rax = ReferenceAxis.from_axis(
        axis, null_leakage=NULL_LEAKAGE, resolution=axis.position_resolution
    )
    rseal = ReferenceSeal(**SEAL).scaled(level)
    rt = reference_tuning(rax, ReferenceSeal(**SEAL), SEAL["sigma_2"])
    theirs = {}
    cases = (("none", "none", "force"), ("oracle", "oracle", "force"),
             ("lugre", None, "force"), ("lugre command", None, "command"))  # fmt: skip
    for name, comp, path in cases:
        comp = (
            compensator_function(datasheet, axis, force_filter=force_filter)
            if comp is None
            else comp
        )
        theirs[name] = run_reference(rax, rseal, ref.position, ref.velocity, compensator=comp,
                                     path=path, tuning=rt).rms_error  # fmt: skip
    return ours, theirs


def main(seconds: float = 10.0, force_filter: float = 0.0) -> None:
    base = load_axis(HERE / "axis.toml")
    identified = model_of(SEAL)
    assumed = model_of(SEAL, sigma_0=1e6, sigma_1=1.58e3)
    double = load_axis(HERE / "axis_double_rod.toml")
    for kind, axis in (("differential", base), ("double-rod", double)):
        for label, sheet, level in (("identified", identified, 1.0),
                                    ("identified, plant +20 %", identified, 1.2),
                                    ("identified, plant -20 %", identified, 0.8),
                                    ("assumed sigma_0 1e6", assumed, 1.0)):  # fmt: skip
            ours, theirs = rows(axis, seconds, sheet, level, force_filter)
            n0, n1 = ours["none"], theirs["none"]
            print(
                f"| {kind} | {label} | {n0 * 1e6:.3f} / {n1 * 1e6:.3f} | "
                f"{ours['oracle'] / n0:.3f} / {theirs['oracle'] / n1:.3f} | "
                f"{ours['lugre'] / n0:.3f} / {theirs['lugre'] / n1:.3f} | "
                f"{theirs['lugre command'] / n1:.3f} | "
                f"{ours['lugre'] / ours['oracle']:.2f} / "
                f"{theirs['lugre'] / theirs['oracle']:.2f} |",
                flush=True,
            )


if __name__ == "__main__":
    main(
        float(sys.argv[1]) if len(sys.argv) > 1 else 10.0,
        float(sys.argv[2]) * 1e-3 if len(sys.argv) > 2 else 0.0,
    )
