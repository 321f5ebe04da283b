"""Machine logs as they come (issue 41): text with units, .mat v5 and v7.3/HDF5, field.toml
errors naming file, line and key, and ``cylfric fit-field`` / ``generate-field`` end to end."""

from __future__ import annotations

import builtins
import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.io.fieldlog import load_field_config, read_field_log
from cylfric.io.text import BenchFileError
from cylfric.simulate.field_bench import FieldSettings, field_toml, simulate_log, write_log

runner = CliRunner()
SETTINGS = FieldSettings()


@pytest.fixture(scope="module")
def log():
    return simulate_log(SETTINGS, duration=20.0, payload=500.0, seed=4)


def _columns(log):
    """A PLC's variables in engineering units (mm, bar, %)."""
    return {
        "time": log.time,
        "position": log.position * 1e3,
        "p_A": log.pressure_a / 1e5,
        "p_B": log.pressure_b / 1e5,
        "valve_command": log.valve * 100,
    }


def _mat_config(tmp_path: Path) -> Path:
    path = tmp_path / "field.toml"
    text = field_toml(SETTINGS, "mat")
    path.write_text(text, encoding="utf-8")
    return path


def test_text_log_with_units_in_the_header(tmp_path, log):
    write_log(tmp_path / "2026-03-01_a.csv", log, "csv")
    (tmp_path / "field.toml").write_text(field_toml(SETTINGS, "csv"), encoding="utf-8")
    config = load_field_config(tmp_path / "field.toml")
    record = read_field_log(tmp_path / "2026-03-01_a.csv", config)
    assert record.day == "2026-03-01"
    assert_allclose(record.position, log.position, atol=1e-8)  # mm -> m
    assert_allclose(record.pressure_a, log.pressure_a, rtol=1e-5)  # bar -> Pa
    assert record.valve is not None


def test_mat_v5_log(tmp_path, log):
    from scipy.io import savemat

    savemat(tmp_path / "day.mat", _columns(log))
    record = read_field_log(tmp_path / "day.mat", load_field_config(_mat_config(tmp_path)))
    assert record.metadata["kind"] == "mat v5"
    assert_allclose(record.position, log.position, atol=1e-9)
    assert_allclose(record.pressure_b, log.pressure_b, rtol=1e-12)


def test_mat_v73_log_written_with_h5py(tmp_path, log):
    """MATLAB v7.3 lays a column vector out as a (1, n) HDF5 dataset behind a 512-byte
    header; written here with h5py directly, as MATLAB's layout (not by cylfric's writer)."""
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "day73.mat"
    with h5py.File(path, "w", userblock_size=512) as handle:
        for name, values in _columns(log).items():
            data = handle.create_dataset(name, data=np.asarray(values)[None, :])
            data.attrs["MATLAB_class"] = np.bytes_("double")
    with open(path, "r+b") as handle:
        handle.write(b"MATLAB 7.3 MAT-file".ljust(116) + bytes(8) + b"\x00\x02IM")
    record = read_field_log(path, load_field_config(_mat_config(tmp_path)))
    assert record.metadata["kind"] == "mat v7.3"
    assert_allclose(record.position, log.position, atol=1e-9)
    assert_allclose(record.pressure_a, log.pressure_a, rtol=1e-12)
    assert_allclose(record.valve, log.valve * 100)


def test_mat_v73_without_h5py_names_the_install_command(tmp_path, log, monkeypatch):
    pytest.importorskip("h5py")
    from cylfric.simulate.field_bench import write_mat73

    path = tmp_path / "day73.mat"
    write_mat73(path, _columns(log))
    config = load_field_config(_mat_config(tmp_path))
    real_import = builtins.__import__

    def no_h5py(name, *args, **kwargs):
        if name == "h5py":
            raise ImportError("No module named 'h5py'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_h5py)
    with pytest.raises(ImportError, match=r"pip install 'cylfric\[field\]'"):
        read_field_log(path, config)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('[cylinder]\nbore = "125 mm"\n', r"field.toml: cylinder.rod: missing"),
        (
            '[cylinder]\nbore = "125 mm"\nrod = "70 mm"\ncolour = "red"\n',
            r"line 4: cylinder.colour: unknown key",
        ),
        (
            '[cylinder]\nbore = "125 bar"\nrod = "70 mm"\n',
            r"line 2: cylinder.bore: .*pressure",
        ),
        (
            '[cylinder]\nbore = "125 mm"\nrod = "70 mm"\n[columns]\ntime = "t"\n'
            'position = "x"\npressure_a = "a"\npressure_b = "b"\n[sensors]\n'
            'pressure_a = "under the seat"\n',
            r"line 10: sensors.pressure_a: 'under the seat'; valid",
        ),
        (
            '[cylinder]\nbore = "125 mm"\nrod = "70 mm"\n[columns]\ntime = "t"\n'
            'position = "x"\npressure_a = "a"\npressure_b = "b"\n[units]\nposition = "bar"\n',
            r"line 10: units.position: 'bar' is a pressure unit; expected a length unit",
        ),
    ],
)
def test_config_errors_name_file_line_and_key(tmp_path, text, match):
    path = tmp_path / "field.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(BenchFileError, match=match):
        load_field_config(path)


def test_missing_column_names_the_config_key_and_its_line(tmp_path, log):
    write_log(tmp_path / "a.csv", log, "csv")
    text = field_toml(SETTINGS, "csv").replace('pressure_b = "p_B"', 'pressure_b = "p_rod"')
    (tmp_path / "field.toml").write_text(text, encoding="utf-8")
    config = load_field_config(tmp_path / "field.toml")
    with pytest.raises(
        BenchFileError, match=r"a.csv: no column 'p_rod' \(columns.pressure_b in .*line 11\)"
    ):
        read_field_log(tmp_path / "a.csv", config)


def test_non_finite_sample_names_its_line_or_sample(tmp_path, log):
    write_log(tmp_path / "a.csv", log, "csv")
    lines = (tmp_path / "a.csv").read_text().splitlines()
    fields = lines[5].split(",")
    fields[2] = "nan"
    lines[5] = ",".join(fields)
    (tmp_path / "a.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "field.toml").write_text(field_toml(SETTINGS, "csv"), encoding="utf-8")
    config = load_field_config(tmp_path / "field.toml")
    with pytest.raises(BenchFileError, match=r"a.csv, line 6: expected a number in column 3"):
        read_field_log(tmp_path / "a.csv", config)
    from scipy.io import savemat

    columns = _columns(log)
    columns["p_A"] = columns["p_A"].copy()
    columns["p_A"][41] = np.inf
    savemat(tmp_path / "b.mat", columns)
    mat_config = load_field_config(_mat_config(tmp_path))
    with pytest.raises(
        BenchFileError, match=r"b.mat: 'p_A' \(pressure_a\) is not finite at sample 42"
    ):
        read_field_log(tmp_path / "b.mat", mat_config)


def test_generate_and_fit_field_end_to_end(tmp_path):
    logs = tmp_path / "logs"
    done = runner.invoke(app, ["generate-field", str(logs), "--duration", "200", "--rise", "15"])
    assert done.exit_code == 0, done.output
    truth = json.loads((logs / "truth.json").read_text())
    out = tmp_path / "out"
    files = sorted(str(p) for p in logs.glob("*.csv"))
    from cylfric.model import FrictionModel

    sheet = FrictionModel(
        {
            "F_c": {"intercept": SETTINGS.F_c, "slope": 0.0},
            "sigma_2": {"intercept": SETTINGS.F_v, "slope": 0.0},
        },
        friction_law="coulomb_viscous",
    )
    (tmp_path / "sheet.json").write_text(json.dumps(sheet.to_datasheet()))
    done = runner.invoke(
        app,
        [
            "fit-field",
            *files,
            "--config",
            str(logs / "field.toml"),
            "--out",
            str(out),
            "--json",
            "--datasheet",
            str(tmp_path / "sheet.json"),
        ],
    )
    assert done.exit_code == 0, done.output
    document = json.loads((out / "field.json").read_text())
    assert document["friction"]["identified"]
    for name in ("friction_bands.csv", "cross_check.csv", "trend.csv", "changes.csv"):
        assert (out / name).stat().st_size > 0
    for name in ("load.png", "friction.png", "mass.png", "force.png", "trend.png", "report.html"):
        assert (out / name).is_file()
    (change,) = document["trend"]["changes"]
    assert change["significant"] and abs(change["change [%]"] - 15) < 3
    # the pooled law of a +0 % and a +15 % day sits about 7 % above the first day's sheet
    comparison = document["datasheet"]
    assert len(comparison["points"]) == len(document["cross_check"]) >= 2
    assert (out / "datasheet_comparison.csv").stat().st_size > 0
    assert all(0 < p["difference [%]"] < 15 for p in comparison["points"])
    days = {log["day"] for log in truth["logs"].values()}
    assert len(document["trend"]["days"]) == len(days) == 2
    # the summary states its units (field.json is SI; the terminal engineering units)
    shown = runner.invoke(
        app, ["fit-field", *files, "--config", str(logs / "field.toml"), "--out", str(out)]
    )
    assert shown.exit_code == 0, shown.output
    assert " N\n" in shown.output and "N*s/mm" in shown.output
    # the output folder is replaced whole (cylfric._outfolder): a file of the user's in it
    # stops the next fit-field, named, and is kept
    (out / "notes.txt").write_text("mine\n")
    again = runner.invoke(
        app, ["fit-field", *files, "--config", str(logs / "field.toml"), "--out", str(out)]
    )
    assert again.exit_code == 2 and "notes.txt" in again.output
    assert (out / "notes.txt").read_text() == "mine\n" and (out / "field.json").is_file()


def test_fit_field_bad_config_is_exit_2_without_traceback(tmp_path, log):
    write_log(tmp_path / "a.csv", log, "csv")
    (tmp_path / "field.toml").write_text('[cylinder]\nbore = "125 mm"\n', encoding="utf-8")
    done = runner.invoke(
        app,
        [
            "fit-field",
            str(tmp_path / "a.csv"),
            "--config",
            str(tmp_path / "field.toml"),
            "--out",
            str(tmp_path / "o"),
        ],
    )
    assert done.exit_code == 2
    assert "cylinder.rod: missing" in done.output
    assert "Traceback" not in done.output
    assert not (tmp_path / "o").exists()
