"""Error paths not covered elsewhere: each raises with a message that names the problem."""

from __future__ import annotations

import numpy as np
import pytest

from cylfric.identify import fit_surface
from cylfric.io import BenchFileError, CampaignConfig, discover_runs, load_config, read_run
from cylfric.simulate import Cylinder, FrictionModel, SpringPull, simulate, simulate_batch
from cylfric.simulate.bench import run_virtual_test
from cylfric.steady_state import extract_points


def test_cylinder_and_model_checks():
    with pytest.raises(ValueError, match="rod diameter 0.03 m must be >= 0 and smaller than"):
        Cylinder.from_diameters(0.02, 0.03, 1.0)
    with pytest.raises(
        ValueError, match=r"parameter sigma_0 = 0.0 is out of range; expected > 0 N/m"
    ):
        FrictionModel(sigma_0=0.0)
    with pytest.raises(ValueError, match="unknown friction law 'nope'"):
        FrictionModel(simulation_law="nope")


def test_compiled_integrators_need_constant_v_r():
    coefficients = {
        "F_c": 70.0,
        "F_s": 110.0,
        "sigma_2": 300.0,
        "alpha": 1.0,
        "v_r": {"intercept": 0.01, "slope": 1e-9},
    }
    pressure = np.linspace(0, 100e5, 101)
    with pytest.raises(ValueError, match="v_r must not vary with pressure"):
        simulate(
            Cylinder(10.0),
            FrictionModel(coefficients=coefficients),
            SpringPull(2e4, 5e-3),
            0.1,
            pressure_a=pressure,
        )


def test_batch_argument_checks():
    with pytest.raises(ValueError, match="need 0 < dt <= duration and record_every >= 1"):
        simulate_batch(
            Cylinder(10.0),
            FrictionModel(),
            SpringPull(2e4, 5e-3),
            1.0,
            pressures=[0.0],
            record_every=0,
        )
    with pytest.raises(ValueError, match="needs LuGre models"):
        simulate_batch(
            Cylinder(10.0),
            FrictionModel(simulation_law="stribeck"),
            SpringPull(2e4, 5e-3),
            1.0,
            pressures=[0.0],
        )


def test_virtual_bench_checks():
    with pytest.raises(ValueError, match="need pressure >= 0 bar and speed > 0 mm/s"):
        run_virtual_test(-1.0, 10)
    with pytest.raises(ValueError, match="speed 5000 mm/s does not fit the stroke"):
        run_virtual_test(55.0, 5000)


@pytest.mark.parametrize(
    ("manifest", "message"),
    [
        (
            "file,pressure_bar,velocity_mm_s\nrun.txt,high,10\n",
            r"manifest.csv, line 2: pressure_bar and velocity_mm_s must be numbers",
        ),
        ("name,pressure\nrun.txt,55\n", r"manifest.csv, line 1: expected a header row"),
    ],
)
def test_manifest_errors(tmp_path, manifest, message):
    (tmp_path / "run.txt").write_text("Time [s]\tForce [N]\n0\t1\n")
    (tmp_path / "manifest.csv").write_text(manifest)
    with pytest.raises(BenchFileError, match=message):
        discover_runs(tmp_path)


def test_a_manifest_row_for_a_missing_file_names_its_line(tmp_path):
    """Raised when the run is read (so --skip-bad can skip it), not by discover_runs
    (issue 11, F10: the error named no line and stopped every fit)."""
    (tmp_path / "manifest.csv").write_text("file,pressure_bar,velocity_mm_s\nmissing.txt,55,10\n")
    (info,) = discover_runs(tmp_path)
    with pytest.raises(
        BenchFileError,
        match=r"manifest.csv, line 2: lists missing.txt, which is not in the campaign folder",
    ):
        read_run(info, CampaignConfig())


@pytest.mark.parametrize(
    ("toml", "message"),
    [
        ("[files\nglob = '*'", r"campaign.toml: invalid TOML"),
        (
            "[columns]\nnames = ['time', 'force']\nunits = ['s']\n",
            r"\[columns\] needs `names` and `units` of the same length",
        ),
        ("[cylinder]\nbore = '25 bar'\n", r"unit 'bar' is a pressure unit, expected a length"),
    ],
)
def test_campaign_toml_errors(tmp_path, toml, message):
    (tmp_path / "campaign.toml").write_text(toml)
    with pytest.raises(BenchFileError, match=message):
        load_config(tmp_path)


def test_empty_folder_and_not_a_folder(tmp_path):
    with pytest.raises(BenchFileError, match=r"no run files matching '\*'"):
        discover_runs(tmp_path)
    with pytest.raises(BenchFileError, match="not a folder"):
        discover_runs(tmp_path / "absent")


def test_points_need_position_or_velocity():
    data = {"time [s]": np.arange(10.0), "force [N]": np.ones(10)}
    with pytest.raises(BenchFileError, match="no position or velocity column"):
        extract_points(data, {"file": "x.txt", "pressure": 1e5})


def test_surface_fit_fixes_only_shared_parameters():
    v = np.geomspace(1e-3, 0.1, 12)
    with pytest.raises(ValueError, match=r"only v_r and alpha can be fixed .* \['F_c'\]"):
        fit_surface(v, np.zeros_like(v), np.ones_like(v), fixed={"F_c": 1.0})
