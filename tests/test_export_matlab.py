"""MATLAB export (cylfric.export.matlab): the parameter struct reads back to the same model;
with GNU Octave installed, the functions reproduce ``FrictionModel.friction`` (eq. 2.7) and
cylfric's exact LuGre z update (eq. 2.5) to 1e-12 relative. Octave is not a dependency: its
tests skip (with the reason) where ``octave-cli``/``octave`` is not on the PATH.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import warnings

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.export.matlab import export_matlab
from cylfric.friction import lugre_z_update
from cylfric.model import FrictionModel

OCTAVE = shutil.which("octave-cli") or shutil.which("octave")
needs_octave = pytest.mark.skipif(
    OCTAVE is None, reason="GNU Octave is not installed: the .m files cannot be run here"
)

from export_models import MODELS  # noqa: E402  (tests/export_models.py)

_ASSIGN = re.compile(r"^P\.(\w+)(?:\.(\w+))? = (.+?);")


def _read_params(path):
    """The struct of a generated ``*_params.m`` as a dict (numbers as floats, [] as None,
    logicals as bool)."""
    struct = {}
    for line in path.read_text().splitlines():
        match = _ASSIGN.match(line)
        if not match:
            continue
        field, sub, value = match.groups()
        if value == "[]":
            parsed = None
        elif value.startswith("'"):
            parsed = value.strip("'")
        elif value in ("true", "false"):  # P.scatter.computed, P.lack_of_fit.significant
            parsed = value == "true"
        else:
            parsed = float(value)
        if sub is None:
            struct[field] = parsed
        else:
            struct.setdefault(field, {})[sub] = parsed
    return struct


@pytest.mark.parametrize("key", list(MODELS))
def test_parameter_struct_reads_back_to_the_same_model(tmp_path, key):
    model = MODELS[key]
    paths = export_matlab(model, tmp_path)
    assert [p.name for p in paths] == [
        "cylfric_params.m",
        "cylfric_params_at.m",
        "cylfric_friction.m",
        "cylfric_lugre_step.m",
    ]
    struct = _read_params(tmp_path / "cylfric_params.m")
    assert struct["reference"] == model.reference
    assert struct["friction_law"] == model.friction_law
    coefficients = {}
    for name in ("F_c", "F_s", "sigma_2", "v_r", "alpha", "sigma_0", "sigma_1"):
        spec = struct[name]
        if spec is None:
            assert model.laws[name] is None
            coefficients[name] = None
            continue
        coefficients[name] = dict(spec)  # includes "law"
    back = FrictionModel(
        coefficients, friction_law=struct["friction_law"], reference=struct["reference"]
    )
    for name, parameter in model.parameters.items():
        assert back.parameters[name].value == parameter.value  # exact: lossless
    v = np.linspace(-0.12, 0.12, 25)[:, None]
    p = np.linspace(5e5, 160e5, 7)[None, :]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.array_equal(back.friction(v, p), model.friction(v, p))
    if model.validity is not None:
        assert struct["validity"] == dict(model.validity)


def test_units_are_in_the_comments(tmp_path):
    export_matlab(MODELS["thesis"], tmp_path)
    text = (tmp_path / "cylfric_params.m").read_text()
    assert "P.F_c.slope = 5e-06;  % [N/Pa]" in text
    assert "P.sigma_0.intercept = 1000000.0;  % [N/m]" in text
    assert "assumed" in text  # the status of sigma_0 and sigma_1 is stated


def test_export_is_deterministic_and_named(tmp_path):
    first = export_matlab(MODELS["mixed_laws"], tmp_path / "a", name="rig2")
    second = export_matlab(MODELS["mixed_laws"], tmp_path / "b", name="rig2")
    assert [p.name for p in first][2] == "rig2_friction.m"
    assert [p.read_bytes() for p in first] == [p.read_bytes() for p in second]
    assert "function F = rig2_friction(v, p_a, p_b, P)" in first[2].read_text()


def test_export_accepts_a_datasheet(tmp_path):
    paths = export_matlab(MODELS["thesis"].to_datasheet(), tmp_path)
    assert _read_params(paths[0])["F_c"]["intercept"] == 70.2


def test_bad_names_raise(tmp_path):
    with pytest.raises(ValueError, match="name '_x' does not make MATLAB function names"):
        export_matlab(MODELS["thesis"], tmp_path, name="_x")
    with pytest.raises(ValueError, match="name 'a-b' is not a valid model identifier"):
        export_matlab(MODELS["thesis"], tmp_path, name="a-b")
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------------------- Octave
def _octave(folder, script):
    """Run ``script`` in Octave inside ``folder``; returns the printed numbers."""
    done = subprocess.run(
        [OCTAVE, "--no-gui", "--norc", "--quiet", "--eval", script],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return np.array([float(x) for x in done.stdout.split()])


def _vector(values):
    return "[" + " ".join(repr(float(x)) for x in np.ravel(values)) + "]"


@needs_octave
@pytest.mark.parametrize("key", list(MODELS))
def test_octave_friction_matches_the_model(tmp_path, key):
    model = MODELS[key]
    export_matlab(model, tmp_path)
    v = np.array([-0.1, -0.03, -0.008, -0.001, 0.0, 0.0005, 0.002, 0.01, 0.04, 0.12])
    pa = np.array([5e5, 40e5, 100e5, 160e5])
    pb = np.array([3e5, 60e5, 100e5, 20e5])
    # elementwise on a grid, and broadcasting (column v, row pressures)
    vv, ii = np.meshgrid(v, np.arange(pa.size), indexing="ij")
    script = (
        f"v = {_vector(vv)}; pa = {_vector(pa[ii])}; pb = {_vector(pb[ii])};"
        "F = cylfric_friction(v, pa, pb); fprintf('%.17g\\n', F);"
        f"G = cylfric_friction({_vector(v)}', {_vector(pa)}, {_vector(pb)});"
        "fprintf('%.17g\\n', G);"
    )
    out = _octave(tmp_path, script)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        expected = model.friction(vv.ravel(), model.operating_pressure(pa[ii], pb[ii]).ravel())
        grid = model.friction(v[:, None], model.operating_pressure(pa, pb)[None, :])
    n = expected.size
    assert_allclose(out[:n], expected, rtol=1e-12, atol=0)
    # MATLAB prints column-major: transpose the (v, p) grid to compare
    assert_allclose(out[n:], grid.T.ravel(), rtol=1e-12, atol=0)


@needs_octave
@pytest.mark.parametrize("key", list(MODELS))
def test_octave_lugre_step_matches_the_exact_update(tmp_path, key):
    model = MODELS[key]
    export_matlab(model, tmp_path)
    z0 = np.array([0.0, 5e-5, -1e-4, 2e-5, 0.0])
    v = np.array([0.01, -0.02, 0.003, 0.0, -0.1])
    pa = np.array([20e5, 80e5, 140e5, 50e5, 10e5])
    pb = 0.7 * pa
    h = 2e-4
    script = (
        f"[z, F] = cylfric_lugre_step({_vector(z0)}, {_vector(v)}, {_vector(pa)},"
        f" {_vector(pb)}, {h!r}); fprintf('%.17g\\n', z); fprintf('%.17g\\n', F);"
    )
    out = _octave(tmp_path, script)
    p = model.operating_pressure(pa, pb)
    prm = model.params_at(p)
    z1 = lugre_z_update(
        z0, v, h, prm["sigma_0"], prm["F_c"], prm["F_s"], prm["v_r"], alpha=prm["alpha"]
    )
    assert_allclose(out[: v.size], z1, rtol=1e-12, atol=1e-20)
    assert_allclose(out[v.size :], model.dynamic_force(v, z1, p), rtol=1e-12, atol=1e-12)
