"""The EMPS benchmark (real data, ../shared/data/emps-benchmark): IDIM-LS and validation.

Reference values: the IDIM-LS parameters of the data set's authors (Janot, Gautier, Brunot
2019), as set in their simulation script of the benchmark (M1 = 95.1089 kg,
Fv1 = 203.5034 N*s/m, Fc1 = 20.3935 N, OF1 = -3.1648 N).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.identify.motion import fit_motion
from cylfric.identify.motion_validation import controller_output, validate_on_record
from cylfric.io.motion_config import load_motion_config, read_motion_record

CONFIG = Path(__file__).resolve().parents[1] / "examples" / "emps" / "motion.toml"
PUBLISHED = {"mass": 95.1089, "F_v": 203.5034, "F_c": 20.3935, "offset": -3.1648}


@pytest.fixture(scope="module")
def emps(shared_data):
    folder = shared_data / "emps-benchmark"
    if not (folder / "DATA_EMPS.mat").is_file():
        pytest.skip("the EMPS data are absent")
    return folder


@pytest.fixture(scope="module")
def emps_fit(emps):
    config = load_motion_config(CONFIG)
    return fit_motion(emps / "DATA_EMPS.mat", config), config


def test_idim_ls_matches_the_published_emps_parameters(emps_fit):
    fit, _ = emps_fit
    # same procedure, different implementations (MATLAB decimate/filtfilt against scipy's,
    # edge handling): within 0.2 % of the published values, offset 0.5 %
    for name in ("mass", "F_v", "F_c"):
        assert_allclose(fit.parameters[name], PUBLISHED[name], rtol=2e-3, err_msg=name)
    assert_allclose(fit.parameters["offset"], PUBLISHED["offset"], rtol=5e-3)
    # the published values lie within 2 standard errors of ours
    for name, value in PUBLISHED.items():
        assert abs(fit.parameters[name] - value) < 2 * fit.stderr[name], name
    # relative force error of the fit (regression value measured on this data: 4.04 %)
    assert_allclose(fit.relative_error, 0.0404, atol=0.002)


def test_per_direction_fit_lowers_the_force_error(emps_fit, emps):
    fit, config = emps_fit
    split = fit_motion(emps / "DATA_EMPS.mat", config, per_direction=True)
    assert split.relative_error < fit.relative_error - 0.005
    assert split.parameters["F_v_neg"] > split.parameters["F_v_pos"]  # measured asymmetry


def test_the_controller_law_reproduces_the_recorded_controller_output(emps):
    """The cascade P-P law of motion_validation, fed with the recorded qm and qg, gives the
    recorded vir: this checks the controller the closed-loop replay simulates."""
    config = load_motion_config(CONFIG)
    record = read_motion_record(emps / "DATA_EMPS.mat", config)
    u = controller_output(
        record.variables["qg"],
        record.variables["qm"],
        kp=record.scalars["kp"],
        kv=record.scalars["kv"],
        sample_time=1e-3,
        saturation=10.0,
    )
    vir = record.variables["vir"]
    rms = np.sqrt(np.mean((u[5:] - vir[5:]) ** 2)) / np.sqrt(np.mean(vir**2))
    assert rms < 0.005  # measured: 0.24 %


def test_closed_loop_validation_on_the_pulses_record(emps_fit, emps):
    fit, config = emps_fit
    replay = validate_on_record(fit, emps / "DATA_EMPS_PULSES.mat", config)
    # measured: position 0.0016 %, force 5.55 %
    assert replay.errors["position"] < 1e-4
    assert 0.03 < replay.errors["force"] < 0.07
    # the published parameters do no better in the same loop
    published = replace(fit, parameters=dict(PUBLISHED))
    reference = validate_on_record(published, emps / "DATA_EMPS_PULSES.mat", config)
    assert replay.errors["force"] < reference.errors["force"] + 1e-3


def test_fit_motion_command_on_emps(emps, tmp_path):
    out = tmp_path / "emps"
    done = CliRunner().invoke(
        app,
        [
            "fit-motion",
            str(emps / "DATA_EMPS.mat"),
            "--config",
            str(CONFIG),
            "--out",
            str(out),
            "--validate",
            str(emps / "DATA_EMPS_PULSES.mat"),
        ],
    )
    assert done.exit_code == 0, done.output
    assert "relative force error 4.0" in done.output
    doc = json.loads((out / "motion_fit.json").read_text())
    assert doc["record"]["force_scale"] == pytest.approx(35.15065188248547)
    assert doc["parameters"]["mass"]["unit"] == "kg"
    assert doc["validation"]["relative_force_error [%]"] < 7
    assert (out / "motion_validation.png").is_file()
