"""Identification from a logged motion (issue 14): IDIM-LS, motion.toml, fit-motion.

Synthetic records are made from the IDIM equation itself (known parameters, seeded noise),
or with cylfric.simulate and a known pressure-dependent friction model (public API only).
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.io import savemat
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.identify.motion import central_difference, fit_motion
from cylfric.io import BenchFileError
from cylfric.io.motion_config import (
    MotionConfig,
    MotionRecord,
    load_motion_config,
    read_motion_record,
)

runner = CliRunner()

# the truth of the synthetic IDIM records (SI): EMPS-like magnitudes
TRUTH = {"mass": 20.0, "F_v": 150.0, "F_c": 15.0, "offset": -2.5}
GAIN = 4.0  # [N/V]: the force signal is recorded in volts, force = GAIN * u


def _motion(duration=12.0, dt=1e-3):
    """Smooth back-and-forth motion: position [m], velocity [m/s], acceleration [m/s^2]."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    w1, w2 = 2 * np.pi * 0.4, 2 * np.pi * 2.3
    x = 0.05 * np.sin(w1 * t) + 0.004 * np.sin(w2 * t)
    v = 0.05 * w1 * np.cos(w1 * t) + 0.004 * w2 * np.cos(w2 * t)
    a = -0.05 * w1**2 * np.sin(w1 * t) - 0.004 * w2**2 * np.sin(w2 * t)
    return t, x, v, a


def _idim_record(tmp_path, *, per_direction=None, seed=0, noise=0.3):
    """A .mat record from the IDIM equation, force in volts (divided by GAIN)."""
    rng = np.random.default_rng(seed)
    t, x, v, a = _motion()
    if per_direction is None:
        force = TRUTH["mass"] * a + TRUTH["F_v"] * v + TRUTH["F_c"] * np.sign(v) + TRUTH["offset"]
    else:
        p = per_direction
        force = (
            p["mass"] * a
            + p["offset"]
            + np.where(v > 0, p["F_v_pos"] * v + p["F_c_pos"], p["F_v_neg"] * v - p["F_c_neg"])
        )
    force = force + rng.normal(0, noise, t.size)
    position = x + rng.normal(0, 1e-7, t.size)
    path = tmp_path / "record.mat"
    savemat(path, {"t": t, "q": position, "u": force / GAIN, "gain": GAIN})
    return path


CONFIG = """\
[signals]
time = "t"
position = "q"
force = "u"
force_scale = "gain"
"""


def _config(tmp_path, text=CONFIG, name="motion.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_central_difference_is_exact_for_a_parabola():
    t = np.arange(20) * 0.1
    assert_allclose(central_difference(t**2, 0.1)[1:-1], 2 * t[1:-1], rtol=0, atol=1e-12)


def test_idim_recovers_the_parameters_of_a_synthetic_record(tmp_path):
    config = load_motion_config(_config(tmp_path))
    record = read_motion_record(_idim_record(tmp_path), config)
    assert record.force_scale == GAIN
    fit = fit_motion(record, config)
    for name, value in TRUTH.items():
        # noise-limited: within 4 standard errors, and within 1 % (0.05 N for the offset)
        assert abs(fit.parameters[name] - value) < 4 * fit.stderr[name], name
        assert_allclose(fit.parameters[name], value, rtol=1e-2, atol=0.05)
    assert fit.relative_error < 0.02
    assert fit.settings["decimation"] == 10
    assert fit.settings["regression_samples"] == pytest.approx(12001 / 10 - 10, abs=2)


def test_per_direction_recovers_what_the_data_identify(tmp_path):
    truth = {
        "mass": 20.0,
        "F_v_pos": 120.0,
        "F_c_pos": 18.0,
        "F_v_neg": 180.0,
        "F_c_neg": 12.0,
        "offset": -2.5,
    }
    config = load_motion_config(_config(tmp_path))
    record = read_motion_record(_idim_record(tmp_path, per_direction=truth), config)
    fit = fit_motion(record, config, per_direction=True)
    p = fit.parameters
    assert_allclose(
        [p["mass"], p["F_v_pos"], p["F_v_neg"]],
        [truth["mass"], truth["F_v_pos"], truth["F_v_neg"]],
        rtol=1e-2,
    )
    # a constant and the two direction indicators are collinear when the axis never rests:
    # only F_c_pos + offset and F_c_neg - offset are identified (the offset is the joint fit's)
    assert_allclose(p["F_c_pos"] + p["offset"], truth["F_c_pos"] + truth["offset"], atol=0.1)
    assert_allclose(p["F_c_neg"] - p["offset"], truth["F_c_neg"] - truth["offset"], atol=0.1)
    assert p["offset"] == fit.joint["offset"][0]
    assert fit.relative_error < 0.02
    assert any("collinear" in note for note in fit.notes)


def test_text_record_in_mm_gives_the_same_fit_as_the_mat_record(tmp_path):
    config = load_motion_config(_config(tmp_path))
    mat = read_motion_record(_idim_record(tmp_path), config)
    text = tmp_path / "record.csv"
    rows = np.column_stack([mat.time, mat.position * 1e3, mat.force])
    header = "Time [s],Position [mm],Force [N]\n"
    text.write_text(header + "".join(",".join(f"{x:.10g}" for x in row) + "\n" for row in rows))
    text_config = _config(
        tmp_path, '[signals]\ntime = "time"\nposition = "position"\nforce = "force"\n', "t.toml"
    )
    text_fit = fit_motion(text, load_motion_config(text_config))
    mat_fit = fit_motion(mat, config)
    for name in TRUTH:
        assert_allclose(text_fit.parameters[name], mat_fit.parameters[name], rtol=1e-6)


@pytest.mark.slow
def test_refinement_recovers_a_known_pressure_dependent_friction():
    """Simulated servo motion with friction F_c = 60 + 0.5 p, F_s = 100 + 0.6 p,
    sigma_2 = 0.4 + 0.001 p N*s/mm (p in bar), v_r = 10 mm/s, under a pressure sweeping 20 to
    160 bar; stiff bristles (sigma_0 = 1e7 N/m), so the steady-state law holds away from
    reversals."""
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
    duration, mass = 6.0, 50.0

    def reference(t):
        return 0.08 * np.sin(2 * np.pi * 0.5 * t) + 0.001 * np.sin(2 * np.pi * 5 * t)

    def pressure(t):
        return 20e5 + 140e5 * (0.5 + 0.5 * np.sin(2 * np.pi * t / duration * 1.5))

    result = simulate(
        Cylinder(mass),
        truth,
        PositionServo(reference, kp=2e5, kd=5e3, ki=2e5),
        duration,
        dt=1e-3,
        pressure_a=pressure,
    )
    rng = np.random.default_rng(3)
    record = MotionRecord(
        time=result.time,
        position=result.states["position"] + rng.normal(0, 1e-7, result.time.size),
        force=result.outputs["drive_force"] + rng.normal(0, 0.5, result.time.size),
        pressure_a=result.outputs["pressure_a"],
        pressure_b=None,
        variables={},
        scalars={},
        force_scale=1.0,
        file="simulated",
    )
    fit = fit_motion(record, MotionConfig(signals={}, reference="a"))
    # the IDIM cannot follow friction that varies with pressure: a large error ...
    assert fit.relative_error > 0.1
    refined = fit.refinement
    assert refined.model is not None
    # ... which the pressure-dependent refinement removes
    assert refined.relative_error < 0.03
    assert_allclose(refined.mass, mass, rtol=0.03)
    model = refined.model
    speeds = np.array([0.02, 0.05, 0.1, 0.2])[:, None]
    pressures = np.array([30e5, 90e5, 150e5])[None, :]
    assert_allclose(model.friction(speeds, pressures), truth.friction(speeds, pressures), rtol=0.05)
    for name, value in (("F_c.slope", 0.5e-5), ("sigma_2.slope", 1e-5)):
        assert_allclose(model.parameters[name].value, value, rtol=0.1)
    assert model.validity["pressure_min"] >= 19e5 and model.validity["pressure_max"] <= 161e5


# ----------------------------------------------------------------------------- the command
def test_fit_motion_command_writes_the_fit_and_leaves_the_record_alone(tmp_path):
    record = _idim_record(tmp_path)
    before = hashlib.sha256(record.read_bytes()).hexdigest()
    out = tmp_path / "out"
    done = runner.invoke(
        app, ["fit-motion", str(record), "--config", str(_config(tmp_path)), "--out", str(out)]
    )
    assert done.exit_code == 0, done.output
    assert "relative force error" in done.output
    assert hashlib.sha256(record.read_bytes()).hexdigest() == before
    doc = json.loads((out / "motion_fit.json").read_text())
    assert doc["record"]["sha256"] == before
    for name, unit in (("mass", "kg"), ("F_v", "N*s/m"), ("F_c", "N"), ("offset", "N")):
        entry = doc["parameters"][name]
        assert entry["unit"] == unit and entry["stderr"] > 0
        assert_allclose(entry["value"], TRUTH[name], rtol=1e-2, atol=0.05)
    assert 0 < doc["relative_force_error"] < 0.02
    assert doc["refinement"] is None and doc["validation"] is None
    header = (out / "motion_signals.csv").read_text().splitlines()[0]
    assert '"force [N]"' in header and '"predicted force [N]"' in header
    assert (out / "motion_fit.png").read_bytes()[:4] == b"\x89PNG"


def test_fit_motion_per_direction_writes_the_direction_parameters(tmp_path):
    out = tmp_path / "out"
    done = runner.invoke(
        app,
        [
            "fit-motion",
            str(_idim_record(tmp_path)),
            "--config",
            str(_config(tmp_path)),
            "--out",
            str(out),
            "--per-direction",
        ],
    )
    assert done.exit_code == 0, done.output
    doc = json.loads((out / "motion_fit.json").read_text())
    assert set(doc["parameters"]) == {"mass", "F_v_pos", "F_c_pos", "F_v_neg", "F_c_neg", "offset"}
    assert set(doc["joint_fit"]) == {"mass", "F_v", "F_c", "offset"}


BAD_CONFIGS = [
    # (motion.toml, text the one-line error must contain)
    ('[signals]\ntime = "t"\nforce = "u"\n', "missing signal 'signals.position'"),
    ('[signals]\ntime = "t"\nposition = "qq"\nforce = "u"\n', "line 3: signals.position = 'qq'"),
    ('[signals]\ntime = "t"\nposition = "q"\nforce = "u"\nforce_scale = "gtau"\n', "line 5"),
    ('[signals]\ntime = "t"\nposition = 3\nforce = "u"\n', "line 3: signals.position: 3"),
    ('[signals]\ntime = "t"\nposition = "q"\nforce = "u"\n[filter]\ncutoff = "high"\n', "line 6"),
    ('[signals]\ntime = "t"\nposition = "q"\nforce = "u"\nspeed = "v"\n', "unknown key 'speed'"),
    ('[signals]\ntime = "t"\nposition = "q"\nforce = "u"\n[filter]\ncutof = 50\n', "line 6"),
    ('[signals]\ntime = "t"\nposition = "q"\nforce = "u"\n[units]\nposition = "bar"\n', "line 6"),
    ('[signals]\ntime = "t"\nposition = "q"\nforce = "u"\n[filter]\ncutoff = 800.0\n', "Nyquist"),
    ("[signals\n", "invalid TOML"),
]


@pytest.mark.parametrize(("text", "expected"), BAD_CONFIGS)
def test_bad_motion_toml_exits_2_naming_the_key(tmp_path, text, expected):
    config = _config(tmp_path, text)
    done = runner.invoke(
        app, ["fit-motion", str(_idim_record(tmp_path)), "--config", str(config), "-o", "x"]
    )
    assert done.exit_code == 2, done.output
    assert expected in done.output
    assert "Traceback" not in done.output
    assert not (tmp_path / "x").exists()


def test_config_errors_name_the_file_and_the_line_of_the_key_in_its_table(tmp_path):
    text = '[signals]\ntime = "t"\nposition = "q"\nforce = "u"\n[units]\nposition = "mm"\n'
    config = load_motion_config(_config(tmp_path, text))
    with pytest.raises(BenchFileError, match=r"motion\.toml, line 6: units\.position"):
        raise config.error("units", "position", "units.position: wrong")
    with pytest.raises(BenchFileError, match=r"motion\.toml, line 3: signals\.position"):
        raise config.error("signals", "position", "signals.position: wrong")


def test_wrong_type_names_what_was_expected(tmp_path):
    path = _config(
        tmp_path, '[signals]\ntime = "t"\nposition = "q"\nforce = "u"\nforce_scale = [1]\n'
    )
    with pytest.raises(BenchFileError, match=r"line 5: signals\.force_scale: .*wrong type"):
        load_motion_config(path)


def test_units_for_a_text_record_are_refused(tmp_path):
    text = tmp_path / "r.csv"
    text.write_text("Time [s],Position [mm],Force [N]\n" + "0,1,2\n" * 3)
    path = _config(
        tmp_path,
        '[signals]\ntime = "time"\nposition = "position"\nforce = "force"\n'
        '[units]\nposition = "mm"\n',
    )
    with pytest.raises(BenchFileError, match=r"line 6: units\.position: a text record"):
        read_motion_record(text, load_motion_config(path))


def test_irregular_sampling_and_short_records_are_refused(tmp_path):
    config = load_motion_config(_config(tmp_path))
    t, x, v, a = _motion()
    t_bad = t.copy()
    t_bad[100:] += 0.01
    savemat(tmp_path / "bad.mat", {"t": t_bad, "q": x, "u": v, "gain": 1.0})
    with pytest.raises(BenchFileError, match="not uniformly sampled"):
        read_motion_record(tmp_path / "bad.mat", config)
    savemat(tmp_path / "short.mat", {"t": t[:200], "q": x[:200], "u": v[:200], "gain": 1.0})
    with pytest.raises(ValueError, match="too few for decimation 10"):
        fit_motion(tmp_path / "short.mat", config)
    savemat(tmp_path / "still.mat", {"t": t, "q": 0 * x, "u": v, "gain": 1.0})
    with pytest.raises(ValueError, match="does not change"):
        fit_motion(tmp_path / "still.mat", config)


def test_closed_loop_record_is_identified_and_replayed():
    """A record made by the closed-loop replay itself (EMPS-like gains and force scale, the
    TRUTH parameters): fit_motion recovers the parameters from the closed-loop data and the
    replay of the fit reproduces the recorded force."""
    from cylfric.identify.motion_validation import ServoReplay, replay_closed_loop

    class Truth:  # the replay needs only parameters and per_direction of a MotionFit
        parameters = TRUTH
        per_direction = False

    t = np.arange(10001) * 1e-3
    reference = 0.04 * (1 - np.cos(2 * np.pi * 0.3 * t)) + 0.002 * np.sin(2 * np.pi * 2.1 * t)
    made = replay_closed_loop(
        Truth,
        t,
        reference,
        reference,
        np.ones_like(t),
        kp=160.0,
        kv=243.0,
        force_scale=GAIN * 8,
        saturation=10.0,
        border=0,
    )
    assert isinstance(made, ServoReplay)
    record = MotionRecord(
        time=t,
        position=made.position,
        force=made.force,
        pressure_a=None,
        pressure_b=None,
        variables={},
        scalars={},
        force_scale=1.0,
        file="closed loop",
    )
    fit = fit_motion(record, MotionConfig(signals={}))
    for name, value in TRUTH.items():
        assert_allclose(fit.parameters[name], value, rtol=0.03, atol=0.1, err_msg=name)
    replay = replay_closed_loop(
        fit,
        t,
        reference,
        made.position,
        made.force,
        kp=160.0,
        kv=243.0,
        force_scale=GAIN * 8,
        saturation=10.0,
    )
    assert replay.errors["force"] < 0.03
    assert replay.errors["position"] < 1e-3


FRESH = """
import sys
from cylfric.cli import main

sys.argv = ["cylfric", "fit-motion", *sys.argv[1:]]
main()
"""


@pytest.mark.slow
def test_a_fresh_process_writes_what_the_command_writes_in_process(tmp_path):
    import struct
    import subprocess
    import sys

    record, config = _idim_record(tmp_path), _config(tmp_path)
    fresh, here = tmp_path / "fresh", tmp_path / "here"
    done = subprocess.run(
        [sys.executable, "-c", FRESH, str(record), "--config", str(config), "--out", str(fresh)],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    result = runner.invoke(
        app, ["fit-motion", str(record), "--config", str(config), "--out", str(here)]
    )
    assert result.exit_code == 0, result.output
    sizes = []
    for folder in (fresh, here):
        png = (folder / "motion_fit.png").read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        sizes.append(struct.unpack(">II", png[16:24]))  # IHDR width, height
    assert sizes[0] == sizes[1]
    assert (fresh / "motion_fit.json").read_text() == (here / "motion_fit.json").read_text()


def test_fit_motion_with_pressures_writes_a_datasheet_of_the_refined_model(tmp_path):
    """Coulomb + viscous friction rising with pressure (F_c = 10 + 0.2 p, sigma_2 = 100 +
    0.5 p N*s/m, p in bar), pressures recorded in bar ([units]): the coulomb_viscous
    refinement recovers the laws and writes a datasheet that reads back."""
    from cylfric.model import FrictionModel

    t, x, v, a = _motion()
    p_bar = 20 + 120 * (0.5 + 0.5 * np.sin(2 * np.pi * t / t[-1] * 1.3))
    force = 20.0 * a + (10 + 0.2 * p_bar) * np.sign(v) + (100 + 0.5 * p_bar) * v - 1.0
    force += np.random.default_rng(5).normal(0, 0.2, t.size)
    record = tmp_path / "pressure.mat"
    savemat(record, {"t": t, "q": x, "u": force, "pa": p_bar})
    config = _config(
        tmp_path,
        '[signals]\ntime = "t"\nposition = "q"\nforce = "u"\npressure_a = "pa"\n'
        '[units]\npressure_a = "bar"\n[refinement]\nfriction_law = "coulomb_viscous"\n'
        'reference = "a"\nmin_speed = "1 mm/s"\n',
    )
    out = tmp_path / "out"
    done = runner.invoke(
        app, ["fit-motion", str(record), "--config", str(config), "--out", str(out)]
    )
    assert done.exit_code == 0, done.output
    doc = json.loads((out / "motion_fit.json").read_text())
    assert doc["refinement"]["status"] == "identified"
    assert doc["refinement"]["relative_force_error"] < 0.01 < doc["relative_force_error"]
    model = FrictionModel.from_datasheet(out / "datasheet.json")
    assert model.friction_law == "coulomb_viscous"
    assert_allclose(model.parameters["F_c.intercept"].value, 10.0, atol=0.3)
    assert_allclose(model.parameters["F_c.slope"].value, 0.2e-5, rtol=0.03)
    assert_allclose(model.parameters["sigma_2.slope"].value, 0.5e-5, rtol=0.05)
    assert model.dynamic_status["sigma_0"][0] == "assumed"
    assert 130e5 < model.validity["pressure_max"] <= 140e5  # the samples used
