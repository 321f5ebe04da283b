"""Report figures: the staged, parallel renderer draws exactly what the serial path draws."""

from __future__ import annotations

import os
import subprocess
import sys

import pandas as pd
import pytest

from cylfric.identify import add_sensitivity, identify
from cylfric.report import FigureRenderer, all_figures
from cylfric.report import figures as F
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.steady_state import extract_campaign

SMALL = BenchSettings(pressures_bar=(0.1, 80.0, 159.0), speeds_mm_s=(1, 3, 8, 15, 30, 60, 135))
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
    direct = identify(extraction.points)
    pd.testing.assert_frame_equal(full.sensitivity, direct.sensitivity)
    assert full.recommended == pytest.approx(direct.recommended)
    assert 0.5 < full.recommended["alpha"] < 2 and 0.003 < full.recommended["v_r"] < 0.03
    assert full.surface is model.surface  # the model itself is shared, not refitted


def test_figures_follow_the_results_available(results):
    extraction, model, full = results
    assert all_figures() == []
    only_points = all_figures(offset=extraction.offset, points=extraction.points)
    assert [stem for stem, _, _ in only_points] == ["directions"]
    assert [stem for stem, _, _ in all_figures(model)] == STEMS[:4]
    assert [stem for stem, _, _ in all_figures(full)] == STEMS


def test_staged_workers_draw_what_the_serial_path_draws(results):
    extraction, model, full = results
    inputs = {"offset": extraction.offset, "points": extraction.points}
    with FigureRenderer(workers=1) as serial:
        assert serial.pool is None
        expected = serial.render(full, extraction.offset)
    with FigureRenderer(workers=2) as parallel:
        if parallel.pool is None:
            pytest.skip("this platform or process cannot fork figure workers")
        parallel.submit(**inputs)  # the directions figure, before any identification
        parallel.submit(model, **inputs)
        parallel.submit(full, **inputs)
        got = parallel.results()
        assert parallel.results() == []  # a round ends with its results
    assert [r[:2] for r in got] == [r[:2] for r in expected]  # stems and captions, in order
    # prepared canvases in the workers, fresh ones here: the same pixels
    assert _png(got) == _png(expected)
    assert all(svg.lstrip().startswith(b"<?xml") for _, _, _, svg in got)


def _die(*args):
    os._exit(3)


def test_figures_are_drawn_here_when_the_workers_die(results, monkeypatch):
    extraction, model, full = results
    monkeypatch.setattr(F, "_warm_up", _die)  # each worker exits at start-up
    drawn_here = []  # figures rendered in this process (the workers are dead)
    draw = F.render
    monkeypatch.setattr(F, "render", lambda fig: drawn_here.append(fig) or draw(fig))
    with FigureRenderer(workers=2) as renderer:
        if renderer.pool is None:
            pytest.skip("this platform or process cannot fork figure workers")
        rendered = renderer.render(full, extraction.offset)
    assert [stem for stem, *_ in rendered] == STEMS
    assert len(drawn_here) == len(STEMS)  # every figure fell back to this process
    assert all(png.startswith(b"\x89PNG") for _, _, png, _ in rendered)


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
