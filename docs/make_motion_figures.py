"""Draw the figures of docs/motion.md and print the numbers it quotes.

Run: ``.venv/bin/python docs/make_motion_figures.py`` (needs ../shared/data/emps-benchmark;
writes PNGs to docs/img/). The EMPS figures are the ones ``cylfric fit-motion`` writes; the
refinement figure uses the synthetic record of tests/test_motion.py.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
IMG = ROOT / "docs" / "img"
EMPS = ROOT.parent / "shared" / "data" / "emps-benchmark"
CONFIG = ROOT / "examples" / "emps" / "motion.toml"
PUBLISHED = {"mass": 95.1089, "F_v": 203.5034, "F_c": 20.3935, "offset": -3.1648}


def emps():
    from cylfric.identify.motion import fit_motion
    from cylfric.identify.motion_validation import validate_on_record
    from cylfric.io.motion_config import load_motion_config

    with tempfile.TemporaryDirectory() as tmp:
        command = [
            str(Path(sys.executable).parent / "cylfric"),
            "fit-motion",
            str(EMPS / "DATA_EMPS.mat"),
            "--config",
            str(CONFIG),
            "--out",
            tmp,
            "--validate",
            str(EMPS / "DATA_EMPS_PULSES.mat"),
        ]
        print(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
        shutil.copy(Path(tmp) / "motion_fit.png", IMG / "motion_emps_fit.png")
        shutil.copy(Path(tmp) / "motion_validation.png", IMG / "motion_emps_validation.png")
        doc = json.loads((Path(tmp) / "motion_fit.json").read_text())
    print("parameter  cylfric  stderr  published  difference [%]")
    for name, value in PUBLISHED.items():
        ours = doc["parameters"][name]
        diff = 100 * (ours["value"] - value) / abs(value)
        print(f"{name:8s} {ours['value']:9.4f} {ours['stderr']:7.3f} {value:9.4f} {diff:+.3f}")
    config = load_motion_config(CONFIG)
    fit = fit_motion(EMPS / "DATA_EMPS.mat", config)
    split = fit_motion(EMPS / "DATA_EMPS.mat", config, per_direction=True)
    print("per direction:", {k: round(v, 3) for k, v in split.parameters.items()})
    print(f"relative force error: joint {fit.relative_error:.4f}, split {split.relative_error:.4f}")
    quiet = replace(
        config, validation={k: v for k, v in config.validation.items() if k != "disturbance"}
    )
    for label, model in (
        ("cylfric", fit),
        ("published", replace(fit, parameters=dict(PUBLISHED))),
        ("per direction", split),
    ):
        for record, cfg in (("DATA_EMPS.mat", quiet), ("DATA_EMPS_PULSES.mat", config)):
            e = validate_on_record(model, EMPS / record, cfg).errors
            print(
                f"closed loop {label:13s} {record:22s} position {100 * e['position']:.4f} % "
                f"velocity {100 * e['velocity']:.2f} % force {100 * e['force']:.2f} %"
            )


def refinement():
    """The synthetic pressure-dependent record of tests/test_motion.py, fitted and drawn."""
    from cylfric.identify.motion import fit_motion
    from cylfric.io.motion_config import MotionConfig, MotionRecord
    from cylfric.model import FrictionModel
    from cylfric.simulate import Cylinder, PositionServo, simulate

    truth = FrictionModel(
        {
            "F_c": {"intercept": 60.0, "slope": 0.5e-5},
            "F_s": {"intercept": 100.0, "slope": 0.6e-5},
            "sigma_2": {"intercept": 400.0, "slope": 1e-5},
            "v_r": 0.01,
            "alpha": 1.0,
        },
        sigma_0=1e7,
        sigma_1=2.2e4,
    )
    duration = 6.0
    result = simulate(
        Cylinder(50.0),
        truth,
        PositionServo(
            lambda t: 0.08 * np.sin(np.pi * t) + 0.001 * np.sin(10 * np.pi * t),
            kp=2e5,
            kd=5e3,
            ki=2e5,
        ),
        duration,
        pressure_a=lambda t: 20e5 + 140e5 * (0.5 + 0.5 * np.sin(2 * np.pi * t / duration * 1.5)),
    )
    rng = np.random.default_rng(3)
    n = result.time.size
    record = MotionRecord(
        result.time,
        result.states["position"] + rng.normal(0, 1e-7, n),
        result.outputs["drive_force"] + rng.normal(0, 0.5, n),
        result.outputs["pressure_a"],
        None,
        {},
        {},
        1.0,
        "simulated",
    )
    fit = fit_motion(record, MotionConfig(signals={}, reference="a"))
    model = fit.refinement.model
    print("refinement:", model.law_lines())
    print(f"IDIM error {fit.relative_error:.3f}, refined {fit.refinement.relative_error:.4f}")
    fig, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    speed = np.linspace(0.008, 0.28, 300)  # inside the validity range
    for p_bar, color in ((25, "C0"), (90, "C1"), (155, "C2")):
        ax.plot(speed * 1e3, truth.friction(speed, p_bar * 1e5), color=color, lw=2, alpha=0.4)
        ax.plot(
            speed * 1e3,
            model.friction(speed, p_bar * 1e5),
            color=color,
            ls="--",
            label=f"{p_bar} bar: truth (thick), refined (dashed)",
        )
    idim = fit.parameters
    ax.plot(speed * 1e3, idim["F_c"] + idim["F_v"] * speed, "k:", label="IDIM-LS (no pressure)")
    ax.set(xlabel="velocity [mm/s]", ylabel="friction force [N]")
    ax.set_title("Refinement from a simulated servo record with the pressure sweeping 20-160 bar")
    ax.legend(fontsize=8)
    fig.savefig(IMG / "motion_refinement.png", dpi=100)


if __name__ == "__main__":
    IMG.mkdir(exist_ok=True)
    emps()
    refinement()
