"""Issue 22, deliverable 10: the report on real rigs.

Legends over no point, no empty panel (a line says what was not identified and why), the
fit report within its page, scatter and lack of fit shown, progress on the slow steps. Judged
on the real Zillen seals (../shared/data) and on a small virtual campaign.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from cylfric.pipeline import fit_campaign
from cylfric.report import figures as figs
from cylfric.report.dynamic import figure_dynamic
from cylfric.report.html import _records, render_report, scatter_html
from cylfric.simulate.bench import BenchSettings, generate_campaign

ROOT = Path(__file__).resolve().parents[1]
RECIPE = ROOT / "examples" / "zillen2021" / "campaign.toml"
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _fit(folder, out, **keywords):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fit_campaign(folder, out, **keywords)


@pytest.fixture(scope="module")
def zillen(shared_data, tmp_path_factory):
    """The shipped Zillen recipe on the real seal files (one speed per direction: the
    Stribeck shape is not identified), one seal (the O-ring) fitted with its report."""
    folder = tmp_path_factory.mktemp("zillen") / "campaign"
    folder.mkdir()
    for path in (shared_data / "zillen2021-pneumatic-seals").glob("*.csv"):
        shutil.copy(path, folder / path.name)
    shutil.copy(RECIPE, folder / "campaign.toml")
    calls = []

    def step(description, total):
        calls.append({"description": description, "total": total, "done": []})
        return calls[-1]["done"].append

    out = folder.parent / "fit"
    return _fit(folder, out, report=True, step=step, seal="O-ring"), calls


@pytest.fixture(scope="module")
def virtual(tmp_path_factory):
    """A small virtual campaign (4 pressures x 8 speeds): every figure, sensitivity included."""
    folder = tmp_path_factory.mktemp("virtual") / "campaign"
    settings = BenchSettings(
        pressures_bar=(10.0, 60.0, 110.0, 160.0), speeds_mm_s=(1, 2, 5, 10, 20, 50, 100, 130)
    )
    generate_campaign(folder, settings)
    return _fit(folder, folder.parent / "fit", report=True)


def _drawn(fig):
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


def _points(fig):
    """Display coordinates [px] of every plotted marker of ``fig`` (lines with markers,
    error bars, scatter collections)."""
    found = []
    for ax in fig.axes:
        for line in ax.get_lines():
            if line.get_marker() in (None, "None", "", " ") or not line.get_visible():
                continue
            xy = np.column_stack(line.get_data()).astype(float)
            if len(xy):
                found.append(line.get_transform().transform(xy))
        for collection in ax.collections:
            offsets = np.asarray(collection.get_offsets(), dtype=float)
            if offsets.size and collection.get_offset_transform() is not None:
                found.append(collection.get_offset_transform().transform(offsets))
    return np.vstack(found) if found else np.empty((0, 2))


def _legends(fig):
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    return legends + list(fig.legends)


def _covered(fig):
    """(number of points under a legend, legends not inside the figure)."""
    renderer = _drawn(fig)
    points = _points(fig)
    covered, outside = 0, 0
    page = fig.bbox
    for legend in _legends(fig):
        box = legend.get_window_extent(renderer)
        inside = (
            (points[:, 0] >= box.x0)
            & (points[:, 0] <= box.x1)
            & (points[:, 1] >= box.y0)
            & (points[:, 1] <= box.y1)
        )
        covered += int(inside.sum())
        if box.x0 < page.x0 - 1 or box.x1 > page.x1 + 1 or box.y0 < page.y0 - 1:
            outside += 1
    return covered, outside


def test_the_overlap_check_sees_a_legend_over_points():
    from matplotlib.figure import Figure

    fig = Figure()
    ax = fig.subplots()
    ax.plot(np.linspace(0, 1, 50), np.full(50, 0.95), "o", label="points along the top")
    ax.set_ylim(0, 1)
    ax.legend(loc="upper left")
    assert _covered(fig)[0] > 0


@pytest.mark.parametrize("case", ["zillen", "virtual"])
def test_no_legend_hides_a_point_or_leaves_the_figure(case, request):
    result = request.getfixturevalue(case)
    result = result[0] if isinstance(result, tuple) else result
    ident, offset = result.identification, result.extraction.offset
    stems = []
    for stem, _, build in figs.all_figures(ident, offset):
        fig = build()
        stems.append(stem)
        assert _legends(fig), stem
        covered, outside = _covered(fig)
        assert covered == 0, f"{case} {stem}: {covered} point(s) under a legend"
        assert outside == 0, f"{case} {stem}: a legend leaves the figure"
    assert {"fit", "directions", "residuals"} <= set(stems)


def test_no_empty_parameter_panel_and_a_line_saying_why(zillen):
    ident = zillen[0].identification
    assert set(ident.model.not_identified) >= {"F_s", "sigma_2", "v_r", "alpha"}
    fig = figs.figure_parameters(ident)
    assert len(fig.axes) == 1 and fig.axes[0].get_ylabel() == "F_c [N]"
    text = " ".join(t.get_text() for t in fig.texts).replace("\n", " ")
    reason = ident.model.not_identified["F_s"]
    assert "F_s, sigma_2, v_r, alpha not identified" in text and reason in text
    for ax in fig.axes:  # every panel draws data
        assert any(len(line.get_xdata()) for line in ax.get_lines())


def test_a_model_with_no_per_pressure_values_has_no_parameter_figure(zillen):
    ident = zillen[0].identification
    empty = SimpleNamespace(
        per_pressure=ident.per_pressure.iloc[0:0], model=ident.model, regressions={}
    )
    assert figs.figure_parameters(empty) is None
    assert figs._shown_parameters(empty)[0] == []


def test_dynamic_figure_without_breakaway_tests_has_no_empty_panel():
    time = np.linspace(0, 2, 400)
    force = 50 * np.sin(2 * np.pi * time)
    record = SimpleNamespace(file="p.txt", displacement=force / 1e6, force=force)
    fit = SimpleNamespace(file="p.txt", simulated=force / 1e6, pressure=20e5, sigma_0=1e6)
    dynamic = SimpleNamespace(
        fits=[fit],
        records=[record],
        breakaway=pd.DataFrame(columns=["pressure [Pa]", "force_rate [N/s]"]),
    )
    fig = figure_dynamic(dynamic)
    assert len(fig.axes) == 1
    assert any("no breakaway tests" in t.get_text() for t in fig.texts)
    assert _covered(fig)[0] == 0


def test_fit_figure_draws_the_band_of_a_new_point_and_names_it(virtual):
    ident = virtual.identification
    model = ident.model
    v, p = np.array([0.01, 0.05]), np.array([60e5, 60e5])
    lower, upper, label = figs._figure_band(model, v, p)
    mean_lower, mean_upper = model.band(v, p)
    assert "new" in label
    assert np.all(upper - lower > mean_upper - mean_lower)  # wider than the mean's
    fig = figs.figure_fit(ident)
    texts = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert any(label in t for t in texts) and any("band of the mean" in t for t in texts)


def test_fit_report_lines_fit_the_page(zillen, virtual):
    from cylfric.model.text import REPORT_WIDTH

    for result in (zillen[0], virtual):
        text = result.identification.model.fit_report(min_correlation=0.3)
        assert max(len(line) for line in text.splitlines()) <= REPORT_WIDTH
        assert "[[Variables]]" in text
    page = (zillen[0].out / "report.html").read_text()
    assert re.search(r"pre\{white-space:pre-wrap", page)
    assert "<div class='scroll'><table>" in page


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (apt-get install chromium)")
def test_report_page_does_not_scroll_sideways_in_chromium(virtual, tmp_path):
    # the virtual fit's report held a 182-character method line: 1440 px wide at 1000 px
    page = (virtual.out / "report.html").read_text()
    probe = "<script>document.title='W'+document.documentElement.scrollWidth+'/'+innerWidth"
    (tmp_path / "r.html").write_text(page.replace("</body>", probe + "</script></body>"))
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        f"--user-data-dir={tmp_path / 'profile'}",
        "--window-size=1000,2000",
        "--dump-dom",
        (tmp_path / "r.html").as_uri(),
    ]
    dom = subprocess.run(cmd, capture_output=True, text=True, timeout=120).stdout
    found = re.search(r"<title>W(\d+)/(\d+)</title>", dom)
    assert found, dom[:300]
    scroll, width = map(int, found.groups())
    assert scroll <= width


SCATTER = {
    "method": "linear mixed model, REML (statsmodels MixedLM)",
    "relative": True,
    "sessions": 1,
    "runs": 4,
    "points": 120,
    "reference_force_N": 6.2,
    "components": {
        "repeatability": {"std_percent": 2.1, "std_N": 0.13, "source": "estimated"},
        "run": {"std_percent": 4.4, "std_N": 0.27, "source": "estimated"},
        "session": {
            "std_percent": 9.5,
            "std_N": 0.59,
            "source": "prior",
            "prior_percent": 9.5,
            "prior_basis": "O-ring257 repeatability sessions 1-3",
        },
    },
    "reproducibility": {"std_percent": 10.7, "std_N": 0.66},
}
LACK = {
    "test": "pure-error F",
    "statistic": 7.25,
    "dof": [2, 116],
    "p_value": 0.0011,
    "significant": True,
    "rms_lack_N": 0.41,
    "action": "bands widened by the lack-of-fit variance",
}


def test_scatter_table_and_lack_of_fit_line():
    text = scatter_html(SCATTER, LACK)
    for expected in (
        "<td>repeatability</td><td>2.1</td><td>0.13</td><td>estimated</td>",
        "<td>session</td><td>9.5</td><td>0.59</td><td>prior</td>",
        "prior 9.5 %: O-ring257 repeatability sessions 1-3",
        "reproducibility (ISO 5725-2 s_R)</td><td>10.7</td><td>0.66",
        "1 sessions, 4 runs, 120 points",
        "pure-error F",
        "statistic 7.25, dof 2, 116, p = 0.0011",
        "the law does not fit the data",
        "Action: bands widened by the lack-of-fit variance",
    ):
        assert expected in text, expected
    assert "s(F)" not in text  # a record without the residual function: no line for it
    shaped = scatter_html(
        {
            **SCATTER,
            "residual_function": {
                "absolute_std_N": 0.28,
                "relative_std_percent": 16.3,
                "components": "absolute and relative <b>",
            },
        },
        None,
    )
    assert "s_a = 0.28 N, s_b = 16.3 %" in shaped and "relative &lt;b&gt;" in shaped
    assert scatter_html(None, None) == ""
    missing = scatter_html({"components": {"run": {"std_percent": None}}}, {"test": "runs"})
    assert "n/a" in missing and "verdict not stated" in missing


def test_the_report_reads_the_records_from_the_model_or_the_datasheet(zillen):
    carrier = SimpleNamespace(scatter=SCATTER, lack_of_fit=LACK)
    assert _records({}, carrier) == (SCATTER, LACK)
    sheet = {"fit": {"scatter": SCATTER}, "quality": {"lack_of_fit": LACK}}
    assert _records(sheet, SimpleNamespace()) == (SCATTER, LACK)
    result = zillen[0]
    carrying = {**result.datasheet, "quality": sheet["quality"]}
    carrying["fit"] = {**result.datasheet["fit"], "scatter": SCATTER}
    page = render_report(carrying, result.identification, result.extraction, [])
    assert "<h2>Scatter and lack of fit</h2>" in page and "id='lack-of-fit'" in page
    fitted = render_report(result.datasheet, result.identification, result.extraction, [])
    assert "<h2>Scatter and lack of fit</h2>" in fitted  # the fit computes both records
    assert "session" in result.datasheet["fit"]["scatter"]["components"]
    assert _records({}, SimpleNamespace()) == (None, None)  # not computed: no section


def test_progress_on_the_figures_of_the_fit(zillen):
    result, calls = zillen
    drawn = [c for c in calls if c["description"] == "drawing the figures"]
    assert len(drawn) == 1
    assert len(drawn[0]["done"]) == drawn[0]["total"] == len(list(result.out.glob("figures/*.png")))


def test_progress_on_every_presliding_fit_and_breakaway_ramp(monkeypatch):
    """identify_dynamic calls its progress once per presliding fit and per breakaway ramp
    (the slow presliding fit is replaced by a stand-in: the wiring is what is tested)."""
    from cylfric.identify import dynamic as module
    from cylfric.model import FrictionModel

    def quick_fit(record, model):
        return module.PreslidingFit(
            file=record.file,
            pressure=record.pressure,
            sigma_0=1e6,
            sigma_0_stderr=1e4,
            sigma_1=2e3,
            sigma_1_stderr=1e2,
            initial_slope=1e6,
            rmse=1e-7,
            n=10,
            simulated=np.zeros(10),
        )

    def quick_breakaway(model, records, *, travel, progress=None):
        rows = []
        for record in records:
            if record.test == "breakaway":
                rows.append(  # validate_breakaway's columns (identify_dynamic's notes read them)
                    {
                        "file": record.file,
                        "force_rate [N/s]": 50.0,
                        "measured [N]": 1.0,
                        "simulated [N]": 1.0,
                        "ramp_length [s]": 2.0,
                        "travel_reached [m]": 1e-3,
                        "ramp_needed [s]": 0.02,
                    }
                )
                if progress is not None:
                    progress(record.file)
        return pd.DataFrame(rows)

    monkeypatch.setattr(module, "fit_presliding", quick_fit)
    monkeypatch.setattr(module, "validate_breakaway", quick_breakaway)
    records = [
        SimpleNamespace(test="presliding", file=f"p{i}.txt", pressure=p)
        for i, p in enumerate((20e5, 80e5, 150e5))
    ] + [SimpleNamespace(test="breakaway", file=f"b{i}.txt", pressure=20e5) for i in range(2)]
    seen = []
    module.identify_dynamic(records, FrictionModel(), progress=seen.append)
    assert seen == ["p0.txt", "p1.txt", "p2.txt", "b0.txt", "b1.txt"]


def test_validate_breakaway_reports_each_ramp(monkeypatch):
    from cylfric.identify import dynamic as module

    monkeypatch.setattr(module, "breakaway_force", lambda *a, **k: 10.0)
    monkeypatch.setattr(module, "ramp_fit", lambda record, travel: (50.0, 0.1))
    monkeypatch.setattr(module, "simulate_record", lambda model, record: np.zeros(3))

    from dataclasses import dataclass

    @dataclass
    class Ramp:
        file: str
        test: str = "breakaway"
        pressure: float = 1e6
        time: np.ndarray = None  # type: ignore[assignment]
        force: np.ndarray = None  # type: ignore[assignment]
        displacement: np.ndarray = None  # type: ignore[assignment]

    from cylfric.model import FrictionModel

    seen = []
    travel = np.array([0.0, 5e-4, 1e-3])  # the rod reached the 1 mm that marks breakaway
    ramps = [
        Ramp("a.txt", time=np.arange(3.0), displacement=travel),
        Ramp("b.txt", time=np.arange(3.0), displacement=travel),
    ]
    table = module.validate_breakaway(FrictionModel(), ramps, progress=seen.append)
    assert seen == ["a.txt", "b.txt"] and len(table) == 2
