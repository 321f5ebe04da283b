"""Every export carries the datasheet's scatter record (issue 22, deliverable 2).

The scatter components (``fit.scatter``) and the lack-of-fit test (``quality.lack_of_fit``)
are computed here by cylfric's own estimators (:func:`cylfric.identify.scatter.
scatter_components`, :func:`cylfric.identify.lack_of_fit.lack_of_fit`) on seeded points of
known run and session offsets, put into a datasheet, and exported to every target; each
target is read back by its own reader (Octave runs the MATLAB struct and the Simscape
script, fmpy reads the FMU's modelDescription, modparc parses the Modelica package, the
Hopsan table is read as CSV) and its numbers compared with the datasheet's. A datasheet of an
older cylfric, without the records, exports as before and says "not computed".
"""

from __future__ import annotations

import copy
import re
import shutil
import subprocess
import zipfile

import numpy as np
import pandas as pd
import pytest
from export_models import MODELS

from cylfric.export import export
from cylfric.identify.lack_of_fit import lack_of_fit
from cylfric.identify.scatter import scatter_components
from cylfric.model import FrictionModel

OCTAVE = shutil.which("octave-cli") or shutil.which("octave")
GRID = {"n_velocity": 10, "n_pressure": 3}  # small loss grids: the lossy fits take < 1 s


def _sheet(sessions: int) -> dict:
    """The mixed_laws test model's datasheet with scatter records of seeded points: 3 runs
    per session, run offsets 3 %, session offsets 5 %, repeatability 2 % of 100 N."""
    rng = np.random.default_rng(22)
    rows = []
    for s in range(sessions):
        for r in range(3):
            offset = 0.05 * s + 0.03 * rng.standard_normal()
            for i in range(8):
                rows.append(
                    {
                        "session": f"s{s}",
                        "run": f"s{s}-r{r}",
                        "pressure [Pa]": 20e5 * (1 + r),
                        "velocity [m/s]": 0.01 * (1 + i % 4),
                        "friction [N]": 100.0 * (1 + offset + 0.02 * rng.standard_normal()),
                    }
                )
    points = pd.DataFrame(rows)
    fitted = np.full(len(points), 100.0)
    sheet = copy.deepcopy(MODELS["mixed_laws"].to_datasheet())
    sheet["fit"]["scatter"] = scatter_components(points, fitted)
    record = lack_of_fit(points, points["friction [N]"].to_numpy() - fitted, 2)
    assert record is not None
    sheet.setdefault("quality", {})["lack_of_fit"] = record
    return sheet


@pytest.fixture(scope="module", params=[1, 2], ids=["one-session-prior", "two-sessions"])
def sheet(request):
    return _sheet(request.param)


def _expected(sheet: dict) -> dict[str, float]:
    """The numbers the exports must carry, read straight from the datasheet dict."""
    scatter = sheet["fit"]["scatter"]
    c = scatter["components"]
    lof = sheet["quality"]["lack_of_fit"]
    return {
        "scatter.reference_force_N": scatter["reference_force_N"],
        "scatter.sessions": scatter["sessions"],
        "scatter.repeatability_percent": c["repeatability"]["std_percent"],
        "scatter.repeatability_N": c["repeatability"]["std_N"],
        "scatter.run_percent": c["run"]["std_percent"],
        "scatter.run_N": c["run"]["std_N"],
        "scatter.session_percent": c["session"]["std_percent"],
        "scatter.session_N": c["session"]["std_N"],
        "scatter.session_prior_percent": c["session"]["prior_percent"],
        "scatter.reproducibility_percent": scatter["reproducibility"]["std_percent"],
        "scatter.reproducibility_N": scatter["reproducibility"]["std_N"],
        "lack_of_fit.statistic": lof["statistic"],
        "lack_of_fit.p_value": lof["p_value"],
        "lack_of_fit.significant": float(lof["significant"]),
    }


def _octave(folder, script: str) -> list[str]:
    done = subprocess.run(
        [OCTAVE, "--no-gui", "--norc", "--quiet", "--eval", script],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.split("\n")


@pytest.mark.skipif(OCTAVE is None, reason="GNU Octave is not installed")
def test_matlab_and_simscape_structs_carry_the_datasheet_numbers(sheet, tmp_path):
    model = FrictionModel.from_datasheet(sheet)
    export(model, "matlab", tmp_path)
    export(model, "simscape", tmp_path, name="rig", **GRID)
    expected = _expected(sheet)
    fields = ", ".join(f"P.{key}" for key in expected)
    printf = "printf('%.17g\\n', " + fields + ");"
    source = sheet["fit"]["scatter"]["components"]["session"]["source"]
    for setup in ("P = cylfric_params();", "run('rig_simscape.m');"):
        out = _octave(tmp_path, setup + printf + "disp(P.scatter.session_source);")
        values = [float(x) for x in out[: len(expected)]]
        np.testing.assert_allclose(values, list(expected.values()), rtol=1e-15)
        assert out[len(expected)] == source
    text = (tmp_path / "rig_simscape.m").read_text()
    assert "F +/- k sqrt(se^2 + (s F)^2)" in text.replace("\n%   ", " ")
    if source == "prior":
        assert "% ASSUMPTION: one session cannot show the between-session scatter" in text.replace(
            "%   ASSUMPTION", "% ASSUMPTION"
        )


def test_fmu_carries_the_numbers_as_fixed_parameters(sheet, tmp_path):
    from fmpy import read_model_description

    model = FrictionModel.from_datasheet(sheet)
    (path,) = export(model, "fmu", tmp_path).files
    variables = {v.name: v for v in read_model_description(str(path)).modelVariables}
    for key, value in _expected(sheet).items():
        variable = variables[key]
        assert (variable.causality, variable.variability) == ("parameter", "fixed"), key
        assert float(variable.start) == value, key
        assert variable.description, key
    assert variables["scatter.session_percent"].unit == "%"
    assert variables["scatter.session_N"].unit == "N"
    assert "basis:" in variables["scatter.session_prior_percent"].description
    assert (
        sheet["quality"]["lack_of_fit"]["action"]
        in variables["lack_of_fit.significant"].description
    )
    with zipfile.ZipFile(path) as archive:
        documentation = archive.read("documentation/index.html").decode()
    assert "F +/- k sqrt(se^2 + (s F)^2)" in documentation


def _modelica_constants(text: str, package: str) -> dict[str, str]:
    body = text[text.index(f"  package {package} ") : text.index(f"  end {package};")]
    pattern = re.compile(r"constant (?:\S+) (\w+)(?:\(unit=\"[^\"]*\"\))? = (.+?)(?: \"|;)")
    return dict(pattern.findall(body))


def test_modelica_constants_carry_the_numbers(sheet, tmp_path):
    modparc = pytest.importorskip("modparc")
    model = FrictionModel.from_datasheet(sheet)
    (path,) = export(model, "modelica", tmp_path).files
    text = path.read_text()
    modparc.parse(text)
    constants = {
        **{f"scatter.{k}": v for k, v in _modelica_constants(text, "Scatter").items()},
        **{f"lack_of_fit.{k}": v for k, v in _modelica_constants(text, "LackOfFit").items()},
    }
    for key, value in _expected(sheet).items():
        written = constants[key]
        number = {"true": 1.0, "false": 0.0}.get(written)
        assert (float(written) if number is None else number) == value, key
    assert re.search(r"constant SI\.Force session_N = ", text)
    assert "F +/- k sqrt(se^2 + (s F)^2)" in text


def test_hopsan_table_and_readme_carry_the_numbers(sheet, tmp_path):
    model = FrictionModel.from_datasheet(sheet)
    export(model, "hopsan", tmp_path, name="rig", **GRID)
    table = pd.read_csv(tmp_path / "rig_hopsan_scatter.csv", keep_default_na=False)
    values = dict(zip(table["field"], table["value"], strict=True))
    for key, value in _expected(sheet).items():
        assert float(values[key]) == value, key
    readme = (tmp_path / "README_hopsan.md").read_text()
    assert "## Scatter about the law" in readme and "F \\+/\\- k sqrt" not in readme
    assert "F +/- k sqrt(se^2 + (s F)^2)" in readme
    assert "# Band for a new session" in (tmp_path / "rig_hopsan.hcom").read_text()


def test_an_old_datasheet_exports_and_says_not_computed(tmp_path):
    sheet = _sheet(1)
    del sheet["fit"]["scatter"], sheet["quality"]  # a datasheet of an older cylfric
    model = FrictionModel.from_datasheet(sheet)
    assert model.scatter is None and model.lack_of_fit is None
    (fmu,) = export(model, "fmu", tmp_path / "fmu").files
    export(model, "matlab", tmp_path / "m")
    (mo,) = export(model, "modelica", tmp_path / "mo").files
    export(model, "simscape", tmp_path / "m", name="rig", **GRID)
    export(model, "hopsan", tmp_path / "h", name="rig", **GRID)

    from fmpy import read_model_description

    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    scatter_names = sorted(n for n in variables if n.startswith(("scatter.", "lack_of_fit.")))
    assert scatter_names == ["lack_of_fit.computed", "scatter.computed"]
    assert float(variables["scatter.computed"].start) == 0.0
    assert variables["scatter.computed"].description.startswith("not computed")
    assert 'constant Boolean computed = false "not computed' in mo.read_text()
    params = (tmp_path / "m" / "cylfric_params.m").read_text()
    assert "P.scatter.computed = false;  % not computed" in params
    assert "Bands for a new run or session: not computed" in params
    assert (
        "scatter.computed,0,1,not computed"
        in (tmp_path / "h" / "rig_hopsan_scatter.csv").read_text()
    )
    assert "Scatter components: not computed" in (tmp_path / "h" / "README_hopsan.md").read_text()
    if OCTAVE is not None:
        out = _octave(
            tmp_path / "m",
            "P = cylfric_params(); printf('%d %d\\n', P.scatter.computed, P.lack_of_fit.computed);"
            "run('rig_simscape.m'); printf('%d\\n', P.scatter.computed);",
        )
        assert out[:2] == ["0 0", "0"]
