"""Plausibility gates of fit-motion (issue 23, item 4): non-finite samples refused with their
index and line; a unit off by 1000 or magnitudes the record cannot support flagged in the
result and refused by the command (exit 2) unless --accept-implausible.

Synthetic records come from the IDIM equation itself (EMPS-like magnitudes, seeded noise);
the real one is the EMPS benchmark (../shared/data/emps-benchmark).
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.io import savemat
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.identify.motion import fit_motion
from cylfric.identify.motion_plausibility import LIMITS, check_plausibility
from cylfric.io import BenchFileError
from cylfric.io.motion_config import load_motion_config, read_motion_record

runner = CliRunner()
EMPS_CONFIG = Path(__file__).resolve().parents[1] / "examples" / "emps" / "motion.toml"
CONFIG = '[signals]\ntime = "t"\nposition = "q"\nforce = "u"\n'
TEXT_CONFIG = '[signals]\ntime = "time"\nposition = "position"\nforce = "force"\n'


def _signals(seed=0):
    """Time [s], position [m] and force [N] of a back-and-forth motion: mass 20 kg, F_v 150
    N*s/m, F_c 15 N, offset -2.5 N (the truth of tests/test_motion.py)."""
    t = np.arange(12001) * 1e-3
    w1, w2 = 2 * np.pi * 0.4, 2 * np.pi * 2.3
    x = 0.05 * np.sin(w1 * t) + 0.004 * np.sin(w2 * t)
    v = 0.05 * w1 * np.cos(w1 * t) + 0.004 * w2 * np.cos(w2 * t)
    a = -0.05 * w1**2 * np.sin(w1 * t) - 0.004 * w2**2 * np.sin(w2 * t)
    force = 20.0 * a + 150.0 * v + 15.0 * np.sign(v) - 2.5
    return t, x, force + np.random.default_rng(seed).normal(0, 0.3, t.size)


def _mat(tmp_path, *, position_scale=1.0, name="record.mat", nan_at=None):
    t, x, force = _signals()
    x = x * position_scale
    if nan_at is not None:
        x[nan_at] = np.nan
    path = tmp_path / name
    savemat(path, {"t": t, "q": x, "u": force})
    return path


def _config(tmp_path, text=CONFIG):
    path = tmp_path / "motion.toml"
    path.write_text(text)
    return path


def _fit_motion(*args):
    return runner.invoke(app, ["fit-motion", *map(str, args)])


# ------------------------------------------------------------------ non-finite samples
def test_nan_in_a_mat_record_is_refused_naming_the_channel_and_the_sample(tmp_path):
    record = _mat(tmp_path, nan_at=777)
    config = load_motion_config(_config(tmp_path))
    with pytest.raises(
        BenchFileError, match=r"record\.mat: q \(position\) holds nan at sample 777"
    ):
        read_motion_record(record, config)
    done = _fit_motion(record, "--config", _config(tmp_path), "--out", tmp_path / "out")
    assert done.exit_code == 2, done.output
    assert "q (position) holds nan at sample 777" in done.output
    assert "Traceback" not in done.output
    assert not (tmp_path / "out").exists()


def test_inf_in_a_text_record_is_refused_with_its_line(tmp_path):
    t, x, force = _signals()
    rows = [f"{a:.6g},{b * 1e3:.8g},{c:.6g}" for a, b, c in zip(t, x, force, strict=True)]
    rows[500] = f"{t[500]:.6g},1e999,{force[500]:.6g}"  # parses to inf: too large a number
    path = tmp_path / "record.csv"
    path.write_text("Bench log\nTime [s],Position [mm],Force [N]\n" + "\n".join(rows) + "\n")
    config = load_motion_config(_config(tmp_path, TEXT_CONFIG))
    # sample 500 is data row 501: line 503 after the two preamble lines
    with pytest.raises(
        BenchFileError, match=r"record\.csv, line 503: position .* inf at sample 500"
    ):
        read_motion_record(path, config)


def test_a_record_built_in_python_with_nan_is_refused_by_fit_motion(tmp_path):
    config = load_motion_config(_config(tmp_path))
    record = read_motion_record(_mat(tmp_path), config)
    force = record.force.copy()
    force[1234] = np.inf
    with pytest.raises(ValueError, match=r"force signal holds inf at sample 1234"):
        fit_motion(replace(record, force=force), config)


# ------------------------------------------------------------------ magnitudes
def test_a_clean_record_raises_no_flag(tmp_path):
    config = load_motion_config(_config(tmp_path))
    for per_direction in (False, True):
        fit = fit_motion(
            read_motion_record(_mat(tmp_path), config), config, per_direction=per_direction
        )
        assert fit.flags == ()
        assert fit.to_dict()["plausibility"] == []


def test_a_position_in_mm_read_as_m_is_flagged(tmp_path):
    config = load_motion_config(_config(tmp_path))
    fit = fit_motion(read_motion_record(_mat(tmp_path, position_scale=1e3), config), config)
    codes = {flag.code: flag for flag in fit.flags}
    assert set(codes) == {"position_unit", "velocity_unit"}
    assert codes["position_unit"].quantity == "stroke [m]"
    assert 100 < codes["position_unit"].value < 110  # 2 x (50 + 4) mm read as m
    assert "mm whose unit says m" in codes["position_unit"].hint
    assert fit.to_dict()["plausibility"][0]["code"] == "position_unit"


def test_the_command_refuses_a_flagged_fit_unless_told_to_accept_it(tmp_path):
    record, config = _mat(tmp_path, position_scale=1e3), _config(tmp_path)
    out = tmp_path / "out"
    done = _fit_motion(record, "--config", config, "--out", out)
    assert done.exit_code == 2, done.output
    assert "implausible fit, nothing written: position_unit: stroke [m] = " in done.output
    assert "--accept-implausible" in done.output
    assert not out.exists()
    done = _fit_motion(record, "--config", config, "--out", out, "--accept-implausible")
    assert done.exit_code == 0, done.output
    assert "implausible: position_unit" in done.output
    doc = json.loads((out / "motion_fit.json").read_text())
    assert [f["code"] for f in doc["plausibility"]] == ["position_unit", "velocity_unit"]
    assert doc["plausibility"][1]["expected"] == "at most 20 m/s for a cylinder"


def _fake_fit(parameters, stderr=None, force=100.0, acceleration=1.0, speed=0.1):
    """What the checks read of a MotionFit: parameters, stderr and regression signals."""
    signals = {
        "velocity [m/s]": np.array([-speed, speed]),
        "acceleration [m/s^2]": np.array([-acceleration, acceleration]),
        "force [N]": np.array([-force, force]),
    }
    stderr = stderr or {name: 0.01 * abs(value) for name, value in parameters.items()}
    return SimpleNamespace(parameters=parameters, stderr=stderr, signals=signals)


@pytest.mark.parametrize(
    ("parameters", "code"),
    [
        ({"mass": -20.0, "F_v": 150.0, "F_c": 15.0}, "mass_negative"),
        # 10 x 100 N / 1 m/s^2 = 1000 kg supported at most
        ({"mass": 2000.0, "F_v": 150.0, "F_c": 15.0}, "mass_magnitude"),
        ({"mass": 20.0, "F_v": 150.0, "F_c": 150.0}, "coulomb_level"),
        ({"mass": 20.0, "F_v": 2500.0, "F_c": 15.0}, "friction_level"),  # 15 + 250 > 200 N
        (
            {"mass": 20.0, "F_v_pos": 1.0, "F_c_pos": 1.0, "F_v_neg": 1.0, "F_c_neg": 120.0},
            "coulomb_level",
        ),
    ],
)
def test_each_check_fires_on_its_magnitude(parameters, code):
    fit = _fake_fit(parameters)
    flags = check_plausibility(fit, np.array([0.0, 0.1]))
    assert [flag.code for flag in flags] == [code]
    assert str(flags[0]).startswith(f"{code}: ")


def test_a_negative_mass_within_its_noise_is_not_flagged():
    fit = _fake_fit({"mass": -2.0, "F_v": 150.0, "F_c": 15.0}, stderr={"mass": 1.0})
    assert check_plausibility(fit, np.array([0.0, 0.1])) == ()
    assert LIMITS["negative_mass_sigmas"] == 3.0


def test_an_unknown_limit_is_refused_listing_the_valid_ones():
    fit = _fake_fit({"mass": 20.0, "F_v": 150.0, "F_c": 15.0})
    with pytest.raises(ValueError, match=r"unknown plausibility limit 'max_strok'; valid: \["):
        check_plausibility(fit, np.array([0.0, 0.1]), max_strok=1.0)


def test_a_raised_limit_lets_a_long_stroke_pass(tmp_path):
    config = load_motion_config(_config(tmp_path))
    record = read_motion_record(_mat(tmp_path, position_scale=1e3), config)
    fit = fit_motion(record, config, plausibility={"max_stroke": 1e3, "max_speed": 1e3})
    assert fit.flags == ()


# ------------------------------------------------------------------ the EMPS benchmark
@pytest.fixture(scope="module")
def emps(shared_data):
    folder = shared_data / "emps-benchmark"
    if not (folder / "DATA_EMPS.mat").is_file():
        pytest.skip("the EMPS data are absent")
    return folder


@pytest.mark.parametrize("name", ["DATA_EMPS.mat", "DATA_EMPS_PULSES.mat"])
def test_the_emps_records_raise_no_flag_and_x1000_positions_do(emps, name):
    config = load_motion_config(EMPS_CONFIG)
    record = read_motion_record(emps / name, config)
    for per_direction in (False, True):
        assert fit_motion(record, config, per_direction=per_direction).flags == ()
    scaled = replace(record, position=record.position * 1e3)
    codes = [flag.code for flag in fit_motion(scaled, config).flags]
    assert codes == ["position_unit", "velocity_unit"]
