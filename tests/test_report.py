"""Report figures: they draw the identification (no fitting), in parallel or not, the same."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from fit_helpers import needs_fork

import cylfric.report
from cylfric.identify import add_sensitivity, identify
from cylfric.report import all_figures, render_all
from cylfric.report import figures as F
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.steady_state import extract_campaign

SMALL = BenchSettings.clean(
    pressures_bar=(0.1, 80.0, 159.0), speeds_mm_s=(1, 3, 8, 15, 30, 60, 135)
)
STEMS = ["fit", "parameters", "directions", "residuals", "sensitivity", "sensitivity_curves"]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("campaign")
    generate_campaign(folder, SMALL)
    extraction = extract_campaign(folder)
    model = identify(extraction.points, sensitivity=False)
    return extraction, model, add_sensitivity(model)


def _png(rendered):
    return {stem: png for stem, _, png, _ in rendered}


def test_add_sensitivity_matches_identify_and_leaves_its_input(results):
    extraction, model, full = results
    assert model.sensitivity is None and model.grid is None and model.recommended == {}
    assert model.sensitivity_refits is None
    direct = identify(extraction.points)
    pd.testing.assert_frame_equal(full.sensitivity, direct.sensitivity)
    assert full.recommended == pytest.approx(direct.recommended)
    assert 0.5 < full.recommended["alpha"] < 2 and 0.003 < full.recommended["v_r"] < 0.03
    assert full.model is model.model  # the model itself is shared, not refitted
    # the refits of Figs. 4.4-4.12 are models; their RMSE is Table 4.3/4.4's
    refits = {(r["panel"], r["alpha [-]"], r["v_r [m/s]"]): r for r in full.sensitivity_refits}
    table = full.sensitivity.set_index(["table", "alpha [-]", "v_r [m/s]"])["rmse [N]"]
    for (_, alpha, v_r), row in refits.items():
        key = ("4.3" if v_r == 0.010 else "4.4", alpha, v_r)
        if key in table.index:
            assert row["rmse [N]"] == pytest.approx(table[key], rel=1e-9)
        assert row["model"].statistics["rmse"] == row["rmse [N]"]


def test_figures_follow_the_results_available(results):
    extraction, model, full = results
    assert all_figures() == []
    only_points = all_figures(offset=extraction.offset, points=extraction.points)
    assert [stem for stem, _, _ in only_points] == ["directions"]
    assert [stem for stem, _, _ in all_figures(model)] == STEMS[:4]
    assert [stem for stem, _, _ in all_figures(full)] == STEMS


@needs_fork
def test_a_pool_draws_what_one_process_draws(results):
    extraction, _, full = results
    serial = render_all(full, extraction.offset, workers=1)
    parallel = render_all(full, extraction.offset, workers=2)
    assert [r[:2] for r in parallel] == [r[:2] for r in serial]  # stems, captions, in order
    assert [r[0] for r in serial] == STEMS
    assert _png(parallel) == _png(serial)
    assert all(svg.lstrip().startswith(b"<?xml") for _, _, _, svg in parallel)


def test_report_imports_nothing_from_identify():
    folder = Path(cylfric.report.__file__).parent
    for path in folder.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                assert "identify" not in (node.module or ""), f"{path.name} imports identify"
            if isinstance(node, ast.Import):
                assert all("identify" not in a.name for a in node.names), path.name


def test_importing_the_report_leaves_the_backend_and_rcparams_alone():
    script = (
        "import matplotlib\n"
        "matplotlib.use('svg')\n"
        "before = dict(matplotlib.rcParams)\n"
        "import cylfric.report, cylfric.pipeline\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n"
        "assert dict(matplotlib.rcParams) == before\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def _log_axes_labels(fig):
    """Per log axis of ``fig``: the tick labels inside its view (after a draw)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    labels = []
    for ax in fig.axes:
        for axis, scale, (lo, hi) in (
            (ax.xaxis, ax.get_xscale(), ax.get_xlim()),
            (ax.yaxis, ax.get_yscale(), ax.get_ylim()),
        ):
            if scale != "log":
                continue
            locs = [x for x in axis.get_major_locator()() if min(lo, hi) <= x <= max(lo, hi)]
            labels.append([t for t in axis.get_major_formatter().format_ticks(locs) if t])
    return labels


def check_legends_and_log_ticks(fig, stem):
    """Issue 11: a legend on every figure; log axes with several labelled ticks."""
    assert any(ax.get_legend() is not None for ax in fig.axes) or fig.legends, stem
    for labels in _log_axes_labels(fig):
        assert len(labels) >= 3, (stem, labels)


def test_every_figure_has_a_legend_and_labelled_log_ticks(results):
    extraction, _, full = results
    figures = all_figures(full, extraction.offset, extraction.points)
    assert [stem for stem, *_ in figures] == STEMS
    for stem, _, build in figures:
        check_legends_and_log_ticks(build(), stem)


def test_the_log_axis_labels_ranges_within_one_decade():
    """20-200 N/s: the default log axis labels only 100 there."""
    from matplotlib.figure import Figure

    fig = Figure()
    ax = fig.subplots()
    ax.plot([20, 200], [1, 2], label="line")
    ax.legend()
    F.log_axis(ax, "x", decades=1.0)
    (labels,) = _log_axes_labels(fig)
    assert labels == ["20", "50", "100", "200"]


def test_the_report_calls_the_offset_the_load_cell_offset_and_says_if_it_follows_pressure():
    from cylfric.report.html import offset_by_pressure
    from cylfric.steady_state import Extraction

    # four runs at 10 and 100 bar, each with both directions; offsets 20 N + 0.1 N/bar * p
    rows = []
    for run, p_bar in enumerate((10, 10, 100, 100)):
        for direction in (1, -1):
            rows.append(
                {
                    "run": run,
                    "direction [-]": direction,
                    "pressure [Pa]": p_bar * 1e5,
                    "offset [N]": 20 + 0.1 * p_bar + 0.01 * (-1) ** run,
                    "flag": "ok",
                }
            )
    text = offset_by_pressure(Extraction(pd.DataFrame(rows)))
    assert "The load-cell offset changes with pressure: +0.1 N/bar, +9 N over 10-100 bar" in text
    flat = pd.DataFrame(rows).assign(**{"offset [N]": lambda d: 20 + 0.01 * (-1) ** d["run"]})
    text = offset_by_pressure(Extraction(flat))
    assert "does not change with pressure beyond its run-to-run spread" in text
    assert "<td>21</td>" not in text and "<td>20</td>" in text  # the per-level table
