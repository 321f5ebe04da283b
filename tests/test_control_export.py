"""The exported compensator (cylfric.control.export): the C step, the FMU and the MATLAB
function reproduce the Python compensator (``kernel.compensator_step``, the loop's own) to
1e-9 on measurements recorded from a closed-loop run, for every exportable kind.

The C tests need a C compiler, the FMU tests fmpy, the MATLAB test GNU Octave; each skips
with the reason where its tool is missing.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import zipfile

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.control.export import C_FILES, EXPORTABLE_COMPENSATORS, export_compensator
from cylfric.control.kernel import COMPENSATOR_CODES
from cylfric.control.loop import compensator_outputs, make_reference, simulate_loop
from cylfric.export.fmu import compiler
from cylfric.model import FrictionModel

CC = compiler()
OCTAVE = shutil.which("octave-cli") or shutil.which("octave")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler ($CC, cc, gcc, clang)")
needs_octave = pytest.mark.skipif(OCTAVE is None, reason="GNU Octave is not installed")

DRIVER = r"""
#include <stdio.h>
#include "cylfric_compensator.h"
int main(int argc, char **argv) {
    int kind = argv[1][0] - '0';
    cylfric_compensator_input in;
    cylfric_compensator_state st;
    cylfric_compensator_output out;
    (void)argc;
    cylfric_compensator_init(&st);
    in.velocity = 0.0;
    while (scanf("%lf %lf %lf %lf %lf", &in.position, &in.pressure_a, &in.pressure_b,
                 &in.position_reference, &in.velocity_reference) == 5) {
        if (cylfric_compensator_step(kind, &in, &st, &out) != 0) return 3;
        printf("%.17g %.17g\n", out.force, out.command);
    }
    return 0;
}
"""


@pytest.fixture(scope="module")
def model():
    # the thesis law with pressure-dependent F_c, F_s, sigma_2 and assumed sigma_0, sigma_1;
    # a source with characters that must not break the generated code
    return FrictionModel().replace(source="evil */ name\n#include <x> 'quote' %comment")


@pytest.fixture(scope="module")
def recorded(model):
    """Measurements recorded from a 2 s closed-loop run with the LuGre compensator."""
    reference = make_reference("sine", duration=2.0, amplitude=5e-3, period=2.0)
    return simulate_loop(model, "lugre", reference=reference).measurements()


@pytest.fixture(scope="module")
def exported(model, tmp_path_factory):
    out = tmp_path_factory.mktemp("compensator")
    export_compensator(model, out)
    return out


def _close(actual, expected):
    scale = np.max(np.abs(expected), axis=0) + 1e-300
    assert_allclose(actual, expected, rtol=1e-9, atol=0)  # relative per sample
    assert np.all(np.abs(actual - expected) <= 1e-9 * scale)


def test_python_reference_is_the_loops_compensation(model, recorded):
    run = simulate_loop(model, "lugre", reference=make_reference("sine", duration=2.0, period=2.0))
    outputs = compensator_outputs(model, "lugre", run.measurements())
    assert_allclose(outputs[:, 0], run.outputs[:, 7], rtol=0, atol=0)
    assert np.ptp(outputs[:, 0]) > 10.0  # the estimate moves with the reversals [N]


@needs_cc
@pytest.mark.parametrize("kind", EXPORTABLE_COMPENSATORS)
def test_c_step_reproduces_python(model, recorded, exported, kind, tmp_path):
    assert all((exported / f).is_file() for f in C_FILES)
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    subprocess.run(
        [
            CC,
            "-O2",
            "-std=c99",
            "-Wall",
            "-Wextra",
            "-Werror",
            f"-I{exported}",
            str(tmp_path / "driver.c"),
            str(exported / "cylfric_compensator.c"),
            "-o",
            str(exe),
            "-lm",
        ],
        check=True,
        capture_output=True,
    )
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in recorded)
    done = subprocess.run(
        [str(exe), str(COMPENSATOR_CODES[kind])], input=text, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    c_out = np.loadtxt(done.stdout.splitlines())
    expected = compensator_outputs(model, kind, recorded)
    _close(c_out, expected)
    if kind != "none":
        assert np.count_nonzero(expected[:, 1]) > len(expected) // 2


@pytest.fixture(scope="module")
def fmpy():
    return pytest.importorskip("fmpy")


@needs_cc
def test_fmu_validates_and_reproduces_python(model, recorded, exported, fmpy, tmp_path):
    from fmpy.validation import validate_fmu

    fmu = exported / "cylfric_compensator.fmu"
    assert validate_fmu(str(fmu)) == []
    n = len(recorded)
    names = ["position", "pressure_a", "pressure_b", "position_reference", "velocity_reference"]
    # the sixth input, velocity, keeps its start value 0 (read only with the velocity input)
    time = np.arange(n) * 1e-3
    signals = np.zeros(n, dtype=[("time", float)] + [(c, float) for c in names])
    signals["time"] = time
    for i, c in enumerate(names):
        signals[c] = recorded[:, i]
    result = fmpy.simulate_fmu(
        str(fmu),
        fmi_type="CoSimulation",
        start_time=0.0,
        stop_time=time[-1],
        output_interval=1e-3,
        input=signals,
        output=["force", "command"],
    )
    # fmpy applies the inputs at t_k, steps, records at t_(k+1): row k+1 is sample k
    got = np.column_stack([result["force"], result["command"]])
    expected = compensator_outputs(model, "lugre", recorded)
    assert len(got) == n
    _close(got[1:], expected[:-1])


@needs_cc
def test_fmu_outputs_feed_through_before_the_step(model, recorded, exported, fmpy, tmp_path):
    """A master that sets the inputs, reads the outputs, then steps (no extra delay)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    fmu = str(exported / "cylfric_compensator.fmu")
    description = read_model_description(fmu)
    slave = FMU2Slave(
        guid=description.guid,
        unzipDirectory=extract(fmu, str(tmp_path / "x")),
        modelIdentifier=description.coSimulation.modelIdentifier,
        instanceName="compensator",
    )
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    rows = recorded[:300]
    got = []
    for k, row in enumerate(rows):
        slave.setReal(list(range(6)), [*row, 0.0])
        got.append(slave.getReal([6, 7]))
        slave.doStep(k * 1e-3, 1e-3)
        assert slave.getReal([6, 7]) == got[-1]  # the step commits what was previewed
    with pytest.raises(Exception, match="fmi2DoStep"):
        slave.doStep(0.3, 2e-3)  # not the compensator's sample time
    slave.terminate()
    slave.freeInstance()
    _close(np.array(got), compensator_outputs(model, "lugre", rows))


@needs_octave
def test_matlab_function_reproduces_python(model, recorded, exported, tmp_path):
    rows = recorded[:400]
    np.savetxt(tmp_path / "m.txt", rows, fmt="%.17g")
    script = f"""
M = load('{tmp_path / "m.txt"}');
for kind = 0:3
  state = zeros(4, 1);
  out = zeros(size(M, 1), 2);
  for k = 1:size(M, 1)
    [f, u, state] = cylfric_compensator_step(kind, M(k,1), M(k,2), M(k,3), M(k,4), M(k,5), 0, state);
    out(k, :) = [f, u];
  end
  dlmwrite(sprintf('{tmp_path}/out%d.txt', kind), out, 'precision', '%.17g', 'delimiter', ' ');
end
"""
    (tmp_path / "run.m").write_text(script)
    done = subprocess.run(
        [OCTAVE, "--no-gui", "--quiet", "--norc", "--path", str(exported), str(tmp_path / "run.m")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    for kind in EXPORTABLE_COMPENSATORS:
        got = np.loadtxt(tmp_path / f"out{COMPENSATOR_CODES[kind]}.txt")
        _close(got, compensator_outputs(model, kind, rows))


def test_generated_text_escapes_the_datasheet_source(exported):
    header = (exported / "cylfric_compensator_params.h").read_text()
    assert "evil * / name" in header  # the comment cannot be closed
    assert not any(line.startswith("#include") for line in header.splitlines())
    matlab = (exported / "cylfric_compensator_step.m").read_text()
    lines = [s for s in matlab.splitlines() if "evil" in s or "'quote'" in s]
    assert len(lines) == 1 and lines[0].startswith("%")  # one comment line


def test_export_refuses_bad_arguments(model, tmp_path):
    with pytest.raises(ValueError, match="oracle"):
        export_compensator(model, tmp_path, compensator="oracle")
    with pytest.raises(ValueError, match="targets"):
        export_compensator(model, tmp_path, targets=["c", "simulink"])
    with pytest.raises(ValueError, match="identifier"):
        export_compensator(model, tmp_path, name="bad name")
    with pytest.raises(ValueError, match="expected one of"):
        compensator_outputs(model, "oracle", np.zeros((3, 5)))
    with pytest.raises(ValueError, match="shape"):
        compensator_outputs(model, "lugre", np.zeros((3, 4)))


def test_export_is_deterministic(model, tmp_path):
    a = export_compensator(model, tmp_path / "a", targets=["c", "matlab"])
    b = export_compensator(model, tmp_path / "b", targets=["c", "matlab"])
    assert [p.read_bytes() for p in a] == [p.read_bytes() for p in b]


def test_cli_export_compensator(tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    sheet = tmp_path / "datasheet.json"
    sheet.write_text(json.dumps(FrictionModel().to_datasheet()))
    runner = CliRunner()
    out = tmp_path / "out"
    args = ["control", str(sheet), "--out", str(out), "--export-only"]
    done = runner.invoke(app, [*args, "--export-compensator", "c,matlab"])
    assert done.exit_code == 0, done.output
    assert sorted(p.name for p in (out / "compensator").iterdir()) == sorted(
        [*C_FILES, "cylfric_compensator_step.m"]
    )
    assert not (out / "metrics.json").exists()
    done = runner.invoke(app, [*args, "--export-compensator", "c,simulink"])
    assert done.exit_code == 2 and "simulink" in done.output
    done = runner.invoke(app, [*args, "--export-compensator", "c", "--fmu-compensator", "oracle"])
    assert done.exit_code == 2 and "oracle" in done.output


# another axis: 50/36 x 300 mm, 140 bar, a 20 L/min valve, 500 Hz control (the values the
# generated texts must state; an axis.toml with the same values for the CLI test)
OTHER_AXIS = dict(
    bore=0.050,
    rod=0.036,
    rod_a=0.036,
    stroke=0.300,
    supply_pressure=140e5,
    valve_nominal_flow=20e-3 / 60,
    control_rate=500.0,
)
OTHER_AXIS_TOML = """[axis]
bore = "50 mm"
rod = "36 mm"
rod_a = "36 mm"
stroke = "300 mm"
supply_pressure = "140 bar"
valve_nominal_flow = "20 L/min"
control_rate = "500 Hz"
"""
OTHER_AXIS_TEXT = (
    "bore 50 mm, rod 36 mm",
    "stroke 300 mm",
    "supply 140 bar",
    "valve 20 L/min",
    "control rate 500 Hz (sample time T = 0.002 s)",
)


def _defines(header: str) -> dict[str, float]:
    found = re.findall(r"^#define (CYLFRIC_\w+) \(([^)]*)\)", header, flags=re.MULTILINE)
    return {name: float(value) for name, value in found}


def test_generated_files_state_the_axis_they_bake_in(model, exported, tmp_path):
    """The command depends on the axis: every generated text names the axis, with units."""
    from cylfric.control.axis import DEFAULT_AXIS

    # the default axis (no axis given): said so, in the C header, the FMU and the MATLAB help
    header = (exported / "cylfric_compensator_params.h").read_text()
    with zipfile.ZipFile(exported / "cylfric_compensator.fmu") as fmu:
        description = fmu.read("modelDescription.xml").decode()
    matlab = (exported / "cylfric_compensator_step.m").read_text()
    help_text = matlab[: matlab.index("\nT = ")]
    bore = f"bore {DEFAULT_AXIS.bore * 1e3:g} mm"
    for text in (header, description, help_text):
        assert "DEFAULT axis" in text and bore in text and "`force`" in text
    assert "#define CYLFRIC_DEFAULT_AXIS 1" in header
    assert "exactly once per sample" in header
    words = " ".join(help_text.replace("%", " ").split())
    assert "exactly once per controller sample" in words and "absolute from the cap end" in words
    # another axis: its values with units, and the defines are its SI values to the bit
    axis = DEFAULT_AXIS.replace(**OTHER_AXIS)
    export_compensator(model, tmp_path, targets=["c", "matlab"], axis=axis)
    header = (tmp_path / "cylfric_compensator_params.h").read_text()
    help_text = (tmp_path / "cylfric_compensator_step.m").read_text().split("\nT = ")[0]
    for text in (header, help_text):
        assert "DEFAULT axis" not in text and "the axis given at export" in text
        for fact in OTHER_AXIS_TEXT:
            assert fact in text, fact
    assert "#define CYLFRIC_DEFAULT_AXIS 0" in header
    defines = _defines(header)
    assert defines["CYLFRIC_AREA_A"] == axis.area_a
    assert defines["CYLFRIC_SUPPLY"] == axis.supply_pressure
    assert defines["CYLFRIC_VALVE_K"] == axis.valve_coefficient
    assert defines["CYLFRIC_SAMPLE_TIME"] == axis.sample_time


@needs_cc
def test_c_step_on_another_axis_reproduces_python(model, recorded, tmp_path):
    from cylfric.control.axis import DEFAULT_AXIS

    axis = DEFAULT_AXIS.replace(**OTHER_AXIS)
    export_compensator(model, tmp_path, targets=["c"], axis=axis)
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    sources = [str(tmp_path / "driver.c"), str(tmp_path / "cylfric_compensator.c")]
    subprocess.run(
        [CC, "-O2", "-std=c99", f"-I{tmp_path}", *sources, "-o", str(exe), "-lm"], check=True
    )
    rows = recorded[:500]
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in rows)
    done = subprocess.run([str(exe), "3"], input=text, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    expected = compensator_outputs(model, "lugre", rows, axis=axis)
    _close(np.loadtxt(done.stdout.splitlines()), expected)
    # the command is the axis's: the default axis's command differs on the same samples
    default = compensator_outputs(model, "lugre", rows)
    assert not np.allclose(default[:, 1], expected[:, 1], rtol=1e-3, atol=0)


def test_cli_notes_the_default_axis_on_stderr(tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    sheet = tmp_path / "datasheet.json"
    sheet.write_text(json.dumps(FrictionModel().to_datasheet()))
    axis_toml = tmp_path / "axis.toml"
    axis_toml.write_text(OTHER_AXIS_TOML)
    runner = CliRunner()
    args = ["control", str(sheet), "--export-only", "--export-compensator", "c"]
    done = runner.invoke(app, [*args, "--out", str(tmp_path / "a")])
    assert done.exit_code == 0, done.output
    note = " ".join(done.stderr.split())  # rich wraps the note
    assert "no --axis given" in note and "DEFAULT axis" in note and "`force` output" in note
    assert "DEFAULT axis" not in done.stdout
    done = runner.invoke(app, [*args, "--out", str(tmp_path / "b"), "--axis", str(axis_toml)])
    assert done.exit_code == 0, done.output
    assert "--axis" not in done.stderr
    header = (tmp_path / "b" / "compensator" / "cylfric_compensator_params.h").read_text()
    assert all(fact in header for fact in OTHER_AXIS_TEXT)


@needs_cc
def test_c_step_carries_the_force_filter(model, recorded, tmp_path):
    # the first-order filter on the force estimate (tau_f = 3 ms) is in the exported step
    out = tmp_path / "filtered"
    export_compensator(model, out, targets=["c"], force_filter=3e-3)
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    subprocess.run(
        [CC, "-O2", "-std=c99", f"-I{out}", str(tmp_path / "driver.c"),
         str(out / "cylfric_compensator.c"), "-o", str(exe), "-lm"],
        check=True, capture_output=True,
    )  # fmt: skip
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in recorded)
    done = subprocess.run([str(exe), "3"], input=text, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    c_out = np.loadtxt(done.stdout.splitlines())
    filtered = compensator_outputs(model, "lugre", recorded, force_filter=3e-3)
    raw = compensator_outputs(model, "lugre", recorded)
    _close(c_out, filtered)
    # the filter acts: a = 1 - exp(-1 ms / 3 ms) on every force change after the first sample
    a = -np.expm1(-1e-3 / 3e-3)
    assert filtered[1, 0] == pytest.approx(raw[0, 0] + a * (raw[1, 0] - raw[0, 0]), rel=1e-12)
    assert np.abs(np.diff(filtered[:, 0])).max() < np.abs(np.diff(raw[:, 0])).max()


@needs_cc
def test_c_step_reads_the_velocity_input(model, recorded, tmp_path):
    # exported with the velocity input, the step uses the measured velocity, not x's difference
    out = tmp_path / "velocity"
    export_compensator(model, out, targets=["c"], velocity_input=True)
    driver = DRIVER.replace("    in.velocity = 0.0;\n", "").replace(
        '"%lf %lf %lf %lf %lf", &in.position, &in.pressure_a, &in.pressure_b,\n'
        "                 &in.position_reference, &in.velocity_reference) == 5",
        '"%lf %lf %lf %lf %lf %lf", &in.position, &in.pressure_a, &in.pressure_b,\n'
        "                 &in.position_reference, &in.velocity_reference, &in.velocity) == 6",
    )
    assert "&in.velocity) == 6" in driver
    (tmp_path / "driver.c").write_text(driver)
    exe = tmp_path / "driver"
    subprocess.run(
        [CC, "-O2", "-std=c99", f"-I{out}", str(tmp_path / "driver.c"),
         str(out / "cylfric_compensator.c"), "-o", str(exe), "-lm"],
        check=True, capture_output=True,
    )  # fmt: skip
    # a velocity unlike the position's difference: the reference velocity
    rows = np.column_stack([recorded, recorded[:, 4]])
    text = "\n".join(" ".join(repr(float(v)) for v in row) for row in rows)
    done = subprocess.run([str(exe), "3"], input=text, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    c_out = np.loadtxt(done.stdout.splitlines())
    expected = compensator_outputs(model, "lugre", rows, velocity_input=True)
    _close(c_out, expected)
    differenced = compensator_outputs(model, "lugre", recorded)
    assert np.abs(expected[:, 0] - differenced[:, 0]).max() > 1.0  # [N]: it reads the input
