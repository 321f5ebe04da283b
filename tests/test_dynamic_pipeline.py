"""`cylfric fit` on a campaign that also holds presliding and breakaway runs; `generate --tests`.

The virtual bench's default friction model has sigma_0 = 1e6 N/m and sigma_1 = 1.58e3 N*s/m
(``cylfric.model.core._DEFAULT_DYNAMIC``): the ground truth here.
"""

from __future__ import annotations

import csv
import json

import pytest
from numpy.testing import assert_allclose
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.io.campaign import discover_runs
from cylfric.model import FrictionModel
from cylfric.pipeline import fit_campaign
from cylfric.simulate.bench import TESTS, BenchSettings, DynamicTestSettings, generate_campaign

runner = CliRunner()
SPEEDS = (5, 10, 20, 50, 100)  # [mm/s]: enough for the Stribeck fit, short records


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    folder = tmp_path_factory.mktemp("dyn") / "campaign"
    settings = BenchSettings.clean(pressures_bar=(20.0, 80.0, 140.0), speeds_mm_s=SPEEDS, seed=11)
    generate_campaign(folder, settings, tests=TESTS)
    return folder


@pytest.fixture(scope="module")
def fitted(campaign, tmp_path_factory):
    return fit_campaign(campaign, tmp_path_factory.mktemp("out") / "fit")


def test_manifest_tells_the_test_kind_and_stays_readable(campaign):
    with open(campaign / "manifest.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    kinds = {row["test"] for row in rows}
    assert kinds == {"constant-velocity", "presliding", "breakaway"}
    assert len(rows) == 3 * len(SPEEDS) + 3 * (1 + 3)
    runs = discover_runs(campaign)  # today's reader: the extra columns are extra metadata
    assert len(runs) == len(rows)
    ramps = [r for r in runs if r.extra["test"] == "breakaway"]
    assert {float(r.extra["force_rate_n_s"]) for r in ramps} == set(
        DynamicTestSettings().breakaway_rates
    )


def test_fit_identifies_sigmas_from_the_dynamic_runs(fitted):
    sheet = fitted.datasheet
    for name, truth in (("sigma_0", 1e6), ("sigma_1", 1.58e3)):
        entry = sheet["dynamic"][name]
        assert entry["status"] == "identified"
        assert_allclose(entry["value"], truth, rtol=0.10)
        law = sheet["dynamic_fit"]["laws"][name]
        assert law["stderr"]["intercept"] > 0
    # breakaway against force rate reproduced by the identified model within 3 %
    validation = sheet["dynamic_fit"]["breakaway_validation"]
    assert len(validation["tests"]) == 9
    assert validation["max_relative_error"] < 0.03
    # the written datasheet reads back into the model with the identified values
    model = FrictionModel.from_datasheet(fitted.files["datasheet"])
    assert model.dynamic_status["sigma_0"][0] == "identified"
    assert_allclose(model.params_at(50e5)["sigma_0"], sheet["dynamic"]["sigma_0"]["value"])
    assert json.loads(fitted.files["datasheet"].read_text())["dynamic_fit"]["method"]


def test_dynamic_runs_stay_out_of_the_steady_state_fit(fitted):
    files = set(fitted.extraction.points["file"].map(lambda f: f.split("/")[-1]))
    assert files and not any(name.startswith("dyn_") for name in files)
    assert fitted.excluded.empty  # no presliding/breakaway run reaches the quality gate
    assert_allclose(fitted.datasheet["parameters"]["F_c"]["intercept"], 70.2, rtol=0.05)


def test_outputs_report_figure_and_tables(fitted):
    out = fitted.out
    assert (out / "dynamic.csv").read_text().startswith("pressure [Pa],sigma_0 [N/m]")
    assert (out / "breakaway.csv").is_file()
    assert (out / "figures" / "dynamic.png").stat().st_size > 10_000
    report = (out / "report.html").read_text()
    assert "Dynamic parameters (presliding and breakaway tests)" in report
    assert "Breakaway validation: RMS error" in report


def test_the_dynamic_figure_has_legends_and_labelled_log_ticks(fitted):
    """Issue 11: a legend on every figure, log axes with several labelled ticks."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from cylfric.report.dynamic import figure_dynamic

    fig = figure_dynamic(fitted.dynamic)
    assert all(ax.get_legend() is not None for ax in fig.axes)  # both panels
    FigureCanvasAgg(fig).draw()
    right = fig.axes[1]
    assert right.get_xscale() == "log"
    lo, hi = right.get_xlim()
    locs = [x for x in right.xaxis.get_major_locator()() if lo <= x <= hi]
    labels = [t for t in right.xaxis.get_major_formatter().format_ticks(locs) if t]
    assert len(labels) >= 3, labels


def test_campaign_without_dynamic_runs_keeps_sigmas_assumed(campaign, tmp_path):
    result = fit_campaign(campaign, tmp_path / "cv", glob="run_*", report=False)
    for name in ("sigma_0", "sigma_1"):
        assert result.datasheet["dynamic"][name]["status"] == "assumed"
    assert "dynamic_fit" not in result.datasheet and result.dynamic is None


def test_only_dynamic_runs_is_a_clear_error(tmp_path):
    folder = tmp_path / "dyn"
    result = runner.invoke(
        app, ["generate", str(folder), "--pressures", "50", "--tests", "presliding,breakaway"]
    )
    assert result.exit_code == 0, result.output
    header = (folder / "manifest.csv").read_text().splitlines()[0]
    assert header == "file,pressure_bar,velocity_mm_s,test,force_rate_N_s"
    assert len(list(folder.glob("dyn_*_presliding.txt"))) == 1
    assert len(list(folder.glob("dyn_*_breakaway_r*Ns.txt"))) == 3
    result = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "no constant-velocity runs" in result.output


def test_generate_refuses_unknown_tests(tmp_path):
    result = runner.invoke(app, ["generate", str(tmp_path / "x"), "--tests", "presliding,creep"])
    assert result.exit_code == 2
    assert "unknown test(s) ['creep']" in result.output
    assert "constant-velocity, presliding, breakaway" in result.output


def test_dynamic_settings_refuse_bad_values():
    with pytest.raises(ValueError, match=r"presliding_fraction = 1.2; expected < 1"):
        DynamicTestSettings(presliding_fraction=1.2)
    with pytest.raises(ValueError, match=r"breakaway_rates \[N/s\] -5.*expected a number > 0"):
        DynamicTestSettings(breakaway_rates=(-5.0,))
    with pytest.raises(ValueError, match=r"need the same length"):
        DynamicTestSettings(presliding_frequencies=(2.0,), presliding_periods=(1, 2))
    with pytest.raises(ValueError, match=r"unknown tests \['creep'\]"):
        generate_campaign("unused", tests=("creep",))


def test_breakaway_tests_alone_leave_the_sigmas_assumed_with_a_note(campaign, tmp_path):
    # the campaign's constant-velocity runs plus its breakaway ramps, no presliding test
    folder = tmp_path / "ramps"
    folder.mkdir()
    with open(campaign / "manifest.csv", newline="") as handle:
        rows = [r for r in csv.DictReader(handle) if r["test"] != "presliding"]
    for row in rows:
        (folder / row["file"]).write_bytes((campaign / row["file"]).read_bytes())
    lines = ["file,pressure_bar,velocity_mm_s,test,force_rate_N_s"]
    lines += [",".join(row[k] for k in lines[0].split(",")) for row in rows]
    (folder / "manifest.csv").write_text("\n".join(lines) + "\n")
    result = fit_campaign(folder, tmp_path / "out", report=False)
    assert result.datasheet["dynamic"]["sigma_0"]["status"] == "assumed"
    assert any("9 breakaway test(s) but no presliding test" in n for n in result.datasheet["notes"])
    assert result.excluded.empty
