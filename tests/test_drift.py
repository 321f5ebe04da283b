"""Drift between two fits of a cylinder, and friction against run order (warm-up)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

from cylfric.drift import drift, figure_run_order, load_fit, run_order_trend, write_drift
from cylfric.model import FrictionModel

VALIDITY = {"pressure_min": 5e5, "pressure_max": 160e5, "velocity_min": 1e-3, "velocity_max": 0.1}
NAMES = ["F_c.intercept", "F_c.slope", "F_s.intercept", "F_s.slope", "sigma_2.intercept"]


def _model(shift=0.0, relative_se=0.01) -> FrictionModel:
    """The thesis law (eq. 4.1-4.3) with F_c and F_s raised by ``shift`` [N] and a made-up
    diagonal covariance of ``relative_se`` on five coefficients."""
    model = FrictionModel()
    coefficients = model.coefficients(include_dynamic=False)
    coefficients["F_c"] = dict(coefficients["F_c"], intercept=70.2 + shift)
    coefficients["F_s"] = dict(coefficients["F_s"], intercept=112.9 + shift)
    model = model.replace(coefficients=coefficients)
    values = {n: p.value for n, p in model.parameters.items() if p.value is not None}
    cov = np.diag([(relative_se * values[n]) ** 2 for n in NAMES])
    stderr = {
        "F_c": {
            "intercept": relative_se * values["F_c.intercept"],
            "slope": relative_se * values["F_c.slope"],
        },
    }
    return model.replace(
        covariance=(NAMES, cov), stderr=stderr, statistics={"dof": 200}, validity=VALIDITY
    )


def test_same_datasheet_shows_no_change():
    sheet = _model().to_datasheet()
    table = drift(sheet, sheet)
    assert not table["significant"].any()
    assert_allclose(table["change"], 0.0, atol=0)
    friction = table[table["kind"] == "friction"]
    assert len(friction) == 25  # default 5 x 5 grid over the common validity range
    assert friction["pressure [Pa]"].min() == 5e5 and friction["pressure [Pa]"].max() == 160e5
    assert_allclose(friction["velocity [m/s]"].max(), 0.1)


def test_a_shifted_model_is_significant():
    # F_c.intercept + 5 N: se of the change = hypot(0.702, 0.752) = 1.03 N -> z = 4.9
    table = drift(_model(), _model(shift=5.0))
    row = table[table["quantity"] == "F_c.intercept"].iloc[0]
    assert_allclose(row["change"], 5.0, rtol=1e-12)
    assert_allclose(row["z [-]"], 5.0 / np.hypot(0.702, 0.752), rtol=1e-9)
    assert row["significant"]
    assert not table[table["quantity"] == "F_c.slope"]["significant"].any()
    friction = table[table["kind"] == "friction"]
    assert_allclose(friction["change"], 5.0, rtol=1e-9)  # F_c and F_s + 5 N: every point
    assert friction["significant"].all()
    # a 0.5 N shift hides inside the uncertainty
    small = drift(_model(), _model(shift=0.5))
    assert not small["significant"].any()


def test_drift_refuses_disjoint_ranges_and_bad_level():
    other = _model().replace(
        validity={
            "pressure_min": 170e5,
            "pressure_max": 200e5,
            "velocity_min": 1e-3,
            "velocity_max": 0.1,
        }
    )
    with pytest.raises(ValueError, match="validity ranges do not overlap"):
        drift(_model(), other)
    table = drift(_model(), other, pressures=[100e5], velocities=[0.01])
    assert (table["kind"] == "friction").sum() == 1
    with pytest.raises(ValueError, match="level = 1.5"):
        drift(_model(), _model(), level=1.5)


def test_write_drift_and_load_fit(tmp_path):
    folder = tmp_path / "fit"
    folder.mkdir()
    (folder / "datasheet.json").write_text(json.dumps(_model().to_datasheet()))
    model, points, label = load_fit(folder)
    assert points is None and label == "fit"
    table = drift(folder, _model(shift=5.0))
    path = write_drift(table, tmp_path / "out")
    assert pd.read_csv(path).shape[0] == len(table)
    summary = json.loads((tmp_path / "out" / "drift.json").read_text())
    assert summary["significant_points"] == summary["points"] == 25
    with pytest.raises(ValueError, match="no datasheet"):
        load_fit(tmp_path / "nowhere")


def _warm_campaign(drop_per_run=-0.5, drop_per_stroke=0.0, runs=8, strokes=6, seed=0):
    """A points table of a campaign whose friction falls by ``drop_per_run`` [N] each run
    and ``drop_per_stroke`` each stroke, with 0.3 N noise, around the thesis law."""
    rng = np.random.default_rng(seed)
    truth = FrictionModel()
    rows = []
    for run in range(runs):
        p, v = 20e5 + 15e5 * (run % 4), 0.01 * (1 + run % 3)
        for stroke in range(strokes):
            f = truth.friction(v, p) + drop_per_run * run + drop_per_stroke * stroke
            rows.append(
                {
                    "run": run,
                    "file": f"run_{run:03d}.txt",
                    "stroke": stroke,
                    "direction [-]": 1 if stroke % 2 else -1,
                    "pressure [Pa]": p,
                    "velocity [m/s]": v * (1 if stroke % 2 else -1),
                    "friction [N]": f + rng.normal(0, 0.3),
                    "window_start [s]": 2.0 * stroke,
                    "flag": "ok",
                }
            )
    return pd.DataFrame(rows), truth


def test_run_order_trend_finds_warm_up():
    points, truth = _warm_campaign(drop_per_run=-0.5, drop_per_stroke=-0.1)
    trend = run_order_trend(points, truth)
    # 8 run means of 6 points (noise 0.3/sqrt(6) N): slope -0.5 N/run within a few stderr
    assert abs(trend.between_slope + 0.5) < 4 * trend.between_stderr
    assert trend.between_stderr < 0.05
    assert abs(trend.within_slope + 0.1) < 4 * trend.within_stderr
    assert "between runs: -0.5" in trend.summary() or "between runs: -0.4" in trend.summary()
    fig = figure_run_order(trend)
    assert len(fig.axes) == 1


def test_run_order_trend_without_drift_and_errors(tmp_path):
    points, truth = _warm_campaign(drop_per_run=0.0)
    trend = run_order_trend(points, truth)
    assert abs(trend.between_slope) < 4 * trend.between_stderr
    # flagged rows are left out
    flagged = points.assign(flag=["excluded: outlier"] * 6 + ["ok"] * (len(points) - 6))
    assert len(run_order_trend(flagged, truth).runs) == 7
    with pytest.raises(ValueError, match="order = 'mtime' needs the campaign folder"):
        run_order_trend(points, truth, order="mtime")
    with pytest.raises(ValueError, match="run file not found"):
        run_order_trend(points, truth, order="mtime", campaign=tmp_path)
    with pytest.raises(ValueError, match="order = 'time': unknown"):
        run_order_trend(points, truth, order="time")
    with pytest.raises(ValueError, match=r"missing columns \['friction \[N\]'\]"):
        run_order_trend(points.drop(columns="friction [N]"), truth)


def test_run_order_by_modification_time(tmp_path):
    import os

    points, truth = _warm_campaign(drop_per_run=-0.5, runs=4)
    for run in range(4):  # files written in reverse order: the trend reverses
        path = tmp_path / f"run_{run:03d}.txt"
        path.write_text("x")
        os.utime(path, (1000 - run, 1000 - run))
    by_time = run_order_trend(points, truth, order="mtime", campaign=tmp_path)
    assert by_time.runs["file"].tolist() == [f"run_{r:03d}.txt" for r in (3, 2, 1, 0)]
    assert by_time.between_slope > 0


OIL_VG46 = ((313.15, 46e-6), (373.15, 6.8e-6))
"""An ISO VG 46 mineral oil of viscosity index about 100: 46 and 6.8 mm^2/s at 40 and
100 degC (typical data-sheet values, used here only as the two Walther points)."""


def test_walther_viscosity_passes_its_two_points_and_falls_with_temperature():
    from cylfric.viscosity import walther_viscosity

    assert_allclose(walther_viscosity(313.15, OIL_VG46), 46e-6, rtol=1e-12)
    assert_allclose(walther_viscosity(373.15, OIL_VG46), 6.8e-6, rtol=1e-12)
    t = np.linspace(273.15, 393.15, 25)
    nu = walther_viscosity(t, OIL_VG46)
    assert np.all(np.diff(nu) < 0)
    # ASTM D341 is a straight line in log log (nu + 0.7) against log T
    z = np.log10(np.log10(nu * 1e6 + 0.7))
    assert_allclose(np.diff(z) / np.diff(np.log10(t)), (z[1] - z[0]) / np.diff(np.log10(t))[0])
    with pytest.raises(ValueError, match="holds from 2 mm\\^2/s"):
        walther_viscosity(313.15, ((313.15, 46.0e-9), (373.15, 6.8e-9)))
    with pytest.raises(ValueError, match="different positive temperatures"):
        walther_viscosity(313.15, ((313.15, 46e-6), (313.15, 6.8e-6)))


def test_viscosity_correction_lets_runs_at_two_temperatures_be_identified_as_one():
    """Points at 30 and 50 degC of a seal whose Stribeck curve follows the Hersey number:
    friction(v, T) = friction_ref(v nu(T) / nu(T_ref)). Identified raw, the two
    temperatures disagree; mapped to 40 degC they give back the reference model."""
    from cylfric.identify import identify
    from cylfric.viscosity import viscosity_corrected, walther_viscosity

    truth = FrictionModel()  # the thesis law (eq. 4.1-4.3) at the reference 40 degC
    t_ref = 313.15
    rng = np.random.default_rng(3)
    rows = []
    for run, temperature in enumerate((303.15, 323.15)):
        ratio = walther_viscosity(temperature, OIL_VG46) / walther_viscosity(t_ref, OIL_VG46)
        for p in (20e5, 80e5, 150e5):
            for v in (0.001, 0.003, 0.006, 0.01, 0.02, 0.04, 0.08, 0.13):
                f = truth.friction(v * ratio, p) + rng.normal(0, 0.3)
                rows.append(
                    {
                        "run": run,
                        "velocity [m/s]": v,
                        "pressure [Pa]": p,
                        "friction [N]": f,
                        "friction_std [N]": 0.3,
                        "flag": "ok",
                        "temperature [K]": temperature,
                    }
                )
    points = pd.DataFrame(rows)
    raw = identify(points, fixed={"alpha": 1.0}, sensitivity=False).model
    corrected = identify(
        viscosity_corrected(points, oil=OIL_VG46, reference_temperature=t_ref),
        fixed={"alpha": 1.0},
        sensitivity=False,
    ).model
    assert corrected.statistics["rmse"] < 0.5  # the 0.3 N noise
    assert raw.statistics["rmse"] > 3 * corrected.statistics["rmse"]
    assert_allclose(corrected.parameters["v_r"].value, 0.010, rtol=0.03)
    assert_allclose(corrected.friction(0.02, 80e5), truth.friction(0.02, 80e5), rtol=0.01)
    with pytest.raises(ValueError, match="no 'temperature \\[K\\]' column"):
        viscosity_corrected(
            points.drop(columns="temperature [K]"), oil=OIL_VG46, reference_temperature=t_ref
        )
    with pytest.raises(ValueError, match="outside 200-450 K"):
        viscosity_corrected(points, oil=OIL_VG46, reference_temperature=40.0)
    same = viscosity_corrected(points, oil=OIL_VG46, reference_temperature=t_ref, temperature=t_ref)
    assert_allclose(same["velocity [m/s]"], points["velocity [m/s]"], rtol=1e-12)


# Issue 23, item 7: datasheets whose laws differ are compared only where that is exact.


def _quadratic_fc(model: FrictionModel) -> FrictionModel:
    """``model`` with F_c a quadratic law of pressure: the same values at 0 and its slope at
    0, plus a small curvature [N/Pa^2] (made up)."""
    coefficients = model.coefficients(include_dynamic=False)
    linear = coefficients["F_c"]
    coefficients["F_c"] = {
        "law": "quadratic",
        "intercept": linear["intercept"],
        "slope": linear["slope"],
        "curvature": 1e-14,
    }
    return model.replace(coefficients=coefficients)  # the covariance of _model kept


def test_different_pressure_laws_compare_only_the_friction_and_say_why(tmp_path):
    a, b = _model(), _quadratic_fc(_model())
    table = drift(a, b, n=3)
    compared = set(table[table["kind"] == "parameter"]["quantity"])
    assert not any(name.startswith("F_c") for name in compared)  # intercept/slope: other meaning
    assert "F_s.intercept" in compared  # same law in both: still compared
    assert len(table[table["kind"] == "friction"]) == 9
    (note,) = table.attrs["notes"]
    assert "pressure laws of F_c differ" in note and "linear" in note and "quadratic" in note
    write_drift(table, tmp_path)
    assert json.loads((tmp_path / "drift.json").read_text())["notes"] == [note]


def test_different_friction_laws_compare_no_coefficient():
    a = _model()
    coefficients = a.coefficients(include_dynamic=False)
    reduced = FrictionModel(
        {
            "F_c": coefficients["F_c"],
            "F_s": None,
            "sigma_2": coefficients["sigma_2"],
            "v_r": None,
            "alpha": None,
        },
        friction_law="coulomb_viscous",
        validity=VALIDITY,
    )
    table = drift(a, reduced, n=2)
    assert (table["kind"] == "friction").all() and len(table) == 4
    assert "friction laws differ" in table.attrs["notes"][0]
    # the friction values are each model's own: at (v, p) they mean the same under any law
    v, p = table["velocity [m/s]"].to_numpy(), table["pressure [Pa]"].to_numpy()
    assert_allclose(table["b"], reduced.friction(v, p), rtol=1e-12)


def test_different_pressure_references_are_refused_naming_both(tmp_path):
    first, second = tmp_path / "a.json", tmp_path / "b.json"
    first.write_text(json.dumps(_model().to_datasheet()))
    second.write_text(json.dumps(_model().replace(reference="sum").to_datasheet()))
    with pytest.raises(
        ValueError,
        match=r"a\.json and .*b\.json have different pressure "
        r"references .*'mean'.*'sum'",
    ):
        drift(first, second)
    from typer.testing import CliRunner

    from cylfric.cli import app

    result = CliRunner().invoke(app, ["drift", str(first), str(second)])
    assert result.exit_code == 2 and "different pressure references" in result.output
    assert "Traceback" not in result.output


def test_the_command_prints_the_note(tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    first, second = tmp_path / "a.json", tmp_path / "b.json"
    first.write_text(json.dumps(_model().to_datasheet()))
    second.write_text(json.dumps(_quadratic_fc(_model()).to_datasheet()))
    result = CliRunner().invoke(app, ["drift", str(first), str(second)])
    assert result.exit_code == 0, result.output
    assert "note: pressure laws of F_c differ" in " ".join(result.output.split())


# --- issue 39.6: the scope a change is judged against, on the shared real data -------------

REPEATABILITY = (
    Path(__file__).resolve().parents[1] / "examples" / "zillen2021" / "repeatability.toml"
)
BORE = 25.7e-3  # [m] examples/zillen2021/repeatability.toml


def _raise_friction(source: Path, target: Path, factor: float) -> None:
    """Copy the Zillen run files of ``source`` into ``target`` with the friction times
    ``factor``: the force column rewritten so that ``p A - F`` (friction sign(v) plus the
    load cell's offset, the recipe's force balance) grows by ``factor`` about its offset, the
    offset being the middle of the two directions' medians while the rod moves."""
    area = np.pi * (BORE / 2) ** 2
    target.mkdir(parents=True)
    for path in sorted(source.glob("*.csv")):
        data = np.loadtxt(path)
        balance = data[:, 5] * 1e5 * area - data[:, 6]  # p A - F [N]
        speed = np.gradient(-data[:, 4], data[:, 0])  # the laser grows while the rod retracts
        moving = np.abs(speed) > 0.5 * np.percentile(np.abs(speed), 90)
        offset = 0.5 * (
            np.median(balance[moving & (speed > 0)]) + np.median(balance[moving & (speed < 0)])
        )
        data[:, 6] = data[:, 5] * 1e5 * area - (offset + factor * (balance - offset))
        np.savetxt(target / path.name, data, fmt="%.3f", delimiter="\t")
    shutil.copy(REPEATABILITY, target / "campaign.toml")


@pytest.fixture(scope="module")
def session_fits(shared_data, tmp_path_factory):
    """Fit folders of O-ring257 sessions 1 and 3 (each alone) and of session 1 with its
    friction raised by 30 %, through the pipeline with the repeatability recipe."""
    import warnings

    from cylfric.io.campaign import Campaign
    from cylfric.options import FitOptions
    from cylfric.pipeline import fit_campaign

    data = shared_data / "zillen2021-pneumatic-seals" / "repeatability"
    root = tmp_path_factory.mktemp("drift39")
    folders = {}
    for session in ("1", "3"):
        folders[session] = root / f"session{session}"
        folders[session].mkdir()
        for path in data.glob(f"{session}_*.csv"):
            shutil.copy(path, folders[session] / path.name)
        shutil.copy(REPEATABILITY, folders[session] / "campaign.toml")
    folders["raised"] = root / "raised"
    _raise_friction(folders["1"], folders["raised"], 1.3)
    outputs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, folder in folders.items():
            outputs[name] = root / f"out-{name}"
            fit_campaign(Campaign.open(folder), outputs[name], FitOptions(report=False))
    return outputs


def test_two_sessions_of_one_seal_are_judged_against_the_session_scatter(session_fits):
    # on main: "significant" slope change z = -2.62 and 10 of 25 points marked
    table = drift(session_fits["1"] / "datasheet.json", session_fits["3"] / "datasheet.json")
    assert table.attrs["scope"] == "session"
    assert "sessions 1 and 3" in table.attrs["scope_reason"]
    assert not table.attrs["verdict"]["significant"]
    assert not table["significant"].any()
    # the friction rows: one speed per pressure (Coulomb law on both sides), no repeats
    friction = table[table["kind"] == "friction"]
    assert friction["velocity [m/s]"].nunique() == 1 and friction["pressure [Pa]"].is_unique
    # the same pair judged against the fits' standard errors alone marks the change
    alone = drift(session_fits["1"], session_fits["3"], scope="repeatability")
    assert alone["significant"].any()


def test_friction_raised_by_30_percent_is_a_significant_change(session_fits):
    table = drift(session_fits["1"], session_fits["raised"])
    friction = table[table["kind"] == "friction"]
    assert_allclose(friction["b"] / friction["a"], 1.3, rtol=0.03)  # the raise as made
    # the same session (session name 1 in both): the repeatability scope
    assert table.attrs["scope"] == "repeatability"
    assert table.attrs["verdict"]["significant"]
    assert friction["significant"].all()


def test_the_command_labels_each_fit_by_its_datasheet_name(session_fits, tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    out = tmp_path / "drift"
    a, b = session_fits["1"] / "datasheet.json", session_fits["3"] / "datasheet.json"
    result = CliRunner().invoke(app, ["drift", str(a), str(b), "-o", str(out)])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    assert "judged against reproducibility" in text
    assert "no significant change at the session scope" in text
    names = [json.loads(p.read_text())["name"] for p in (a, b)]
    assert names[0] != names[1]
    for name in names:  # on main: run_order_datasheet.csv, the first overwritten
        assert (out / f"run_order_{name}.csv").exists()
    assert not (out / "run_order_datasheet.csv").exists()
    summary = json.loads((out / "drift.json").read_text())
    assert summary["scope"] == "session" and summary["verdict"]["significant"] is False
    assert summary["points"] == 5  # 5 pressures x one speed (Coulomb)


def test_labels_are_distinct_and_a_model_without_scatter_is_judged_by_its_errors(tmp_path):
    from cylfric.drift import fit_labels

    for folder in ("monday", "tuesday"):
        (tmp_path / folder).mkdir()
        sheet = dict(_model().to_datasheet(), name="seal A/1")
        (tmp_path / folder / "datasheet.json").write_text(json.dumps(sheet))
    first, second = tmp_path / "monday" / "datasheet.json", tmp_path / "tuesday" / "datasheet.json"
    assert fit_labels(first, second) == ["seal_A_1_monday", "seal_A_1_tuesday"]
    assert fit_labels(first, first) == ["seal_A_1_monday-a", "seal_A_1_monday-b"]
    table = drift(first, second)
    assert table.attrs["scope"] == "repeatability"
    assert "no scatter components" in table.attrs["scope_reason"]
    with pytest.raises(ValueError, match="no scatter components.*scope 'repeatability'"):
        drift(first, second, scope="session")
    with pytest.raises(ValueError, match="scope = 'day': unknown"):
        drift(first, second, scope="day")
