"""Notebook habits (issue 24, item 5): FrictionModel and the identification show a parameter
table with units and standard errors (``_repr_html_``), plot through the report's figures and
give their coefficients as a DataFrame (``to_pandas``), as lmfit's ModelResult and
python-control's responses do."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure

from cylfric.model import FrictionModel
from cylfric.model.text import PARAMETER_COLUMNS


def _with_stderr(model: FrictionModel) -> FrictionModel:
    names = ["F_c.intercept", "F_c.slope"]
    values = [model.parameters[n].value for n in names]
    return model.replace(
        covariance=(names, np.diag([(0.01 * v) ** 2 for v in values])),
        stderr={"F_c": {"intercept": 0.01 * values[0], "slope": 0.01 * values[1]}},
        statistics={"dof": 50},
        validity={
            "pressure_min": 10e5,
            "pressure_max": 150e5,
            "velocity_min": 2e-3,
            "velocity_max": 0.1,
        },
    )


def test_to_pandas_gives_si_and_engineering_values_with_units():
    frame = _with_stderr(FrictionModel()).to_pandas()
    assert list(frame.columns) == list(PARAMETER_COLUMNS)
    slope = frame.loc["F_c.slope"]
    assert slope["unit"] == "N/Pa" and slope["unit (engineering)"] == "N/bar"
    assert slope["value"] == pytest.approx(0.5e-5) and slope["value (engineering)"] == 0.5
    assert slope["stderr (engineering)"] == pytest.approx(0.005)
    assert frame.loc["sigma_0", "status"] == "assumed"
    assert frame.loc["v_r", "unit (engineering)"] == "mm/s"


def test_reduced_model_says_what_was_not_identified():
    model = FrictionModel(
        {
            "F_c": {"intercept": 80.0, "slope": 5e-6},
            "F_s": None,
            "sigma_2": {"intercept": 350.0, "slope": 1e-6},
            "v_r": None,
            "alpha": None,
        },
        friction_law="coulomb_viscous",
    )
    frame = model.to_pandas()
    assert frame.loc["v_r", "status"].startswith("not identified")
    assert "not identified" in model._repr_html_()


def test_html_shows_laws_units_and_standard_errors():
    text = _with_stderr(FrictionModel())._repr_html_()
    assert "<table>" in text and "N/bar" in text and "mm/s" in text
    assert "0.005" in text  # the slope's standard error in N/bar
    assert "valid for 10-150 bar, 2-100 mm/s" in text


def test_plot_draws_one_curve_and_band_per_pressure():
    model = _with_stderr(FrictionModel())
    fig = model.plot([20e5, 80e5])
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    assert len(ax.lines) == 2 and len(ax.collections) == 3  # two bands, the legend's patch
    assert ax.get_xlabel() == "speed |v| [mm/s]"
    # the curve is the model's friction
    speed_mm_s, force = ax.lines[1].get_data()
    expected = model.friction(speed_mm_s * 1e-3, np.full_like(speed_mm_s, 80e5))
    np.testing.assert_allclose(force, expected)


def test_identification_displays_and_plots(tmp_path):
    from cylfric.identify import identify
    from cylfric.simulate.bench import BenchSettings, generate_campaign
    from cylfric.steady_state import extract_campaign

    folder = tmp_path / "c"
    generate_campaign(
        folder,
        BenchSettings.clean(pressures_bar=(10.0, 100.0), speeds_mm_s=(2, 5, 10, 20, 50, 100)),
    )
    ident = identify(extract_campaign(folder).points)
    assert "points at 2 pressure level(s)" in ident._repr_html_()
    assert ident.to_pandas().loc["F_c.slope", "stderr"] > 0
    fig = ident.plot()
    assert fig.axes[0].get_title().startswith("Steady-state friction and the fitted")


def test_python_dash_m_runs_the_command_line():
    import subprocess
    import sys

    from cylfric import __version__

    done = subprocess.run(
        [sys.executable, "-m", "cylfric", "--version"], capture_output=True, text=True, check=True
    )
    assert done.stdout.strip() == f"cylfric {__version__}"


def test_shell_completion_completes_commands():
    import os
    import subprocess
    import sys
    from pathlib import Path

    script = Path(sys.executable).with_name("cylfric")
    env = {**os.environ, "_CYLFRIC_COMPLETE": "complete_bash", "COMP_WORDS": "cylfric ca"}
    env["COMP_CWORD"] = "1"
    done = subprocess.run([str(script)], env=env, capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["catalog"]
