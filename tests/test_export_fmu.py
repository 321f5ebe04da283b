"""FMU export (cylfric.export.fmu): FMI 2.0 model exchange + co-simulation, checked with fmpy.

References:
- cylfric's exact LuGre z update (``cylfric.friction.lugre_z_update``, DESIGN.md) on
  piecewise-constant inputs: the closed-form solution of eq. 2.5, so both the co-simulation
  (exact for held inputs) and model exchange (CVode) must reproduce it;
- ``cylfric.simulate`` with ``PrescribedMotion`` (exact z with mid-step velocity, the velocity
  linear between samples) for the co-simulation driven with input derivatives;
- ``FrictionModel.friction`` (eq. 2.7) for the steady friction at constant velocity.
The FMUs are built once per module; tests that need the binary skip only without a C compiler.
"""

from __future__ import annotations

import shutil
import warnings
import zipfile

import numpy as np
import pytest
from numpy.testing import assert_allclose

fmpy = pytest.importorskip("fmpy")

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from cylfric.export.fmu import compiler, export_fmu, fmi_platform  # noqa: E402
from cylfric.friction import lugre_z_update  # noqa: E402
from cylfric.model import FrictionModel  # noqa: E402
from cylfric.simulate import (  # noqa: E402
    AppliedForce,
    Cylinder,
    PositionServo,
    PrescribedMotion,
    simulate,
)

needs_cc = pytest.mark.skipif(
    compiler() is None or fmi_platform() is None,
    reason="no C compiler (CC, cc, gcc, clang) or no FMI 2.0 platform name for this machine: "
    "the FMU binary cannot be built here",
)

from export_models import MODELS  # noqa: E402  (tests/export_models.py)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """name -> (model, path of the FMU), each exported once for the module."""
    out = tmp_path_factory.mktemp("fmu")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # no compiler: sources-only FMUs
        return {
            key: (model, export_fmu(model, out / key, name=f"cylfric_{key}")[0])
            for key, model in MODELS.items()
        }


@pytest.fixture(scope="module")
def slave(fmus, tmp_path_factory):
    """Factory of initialised co-simulation instances (FMU2Slave) of an exported model."""
    made = []

    def make(key, **parameters):
        _, path = fmus[key]
        md = read_model_description(str(path))
        unzipped = extract(str(path), unzipdir=str(tmp_path_factory.mktemp(f"unzip_{key}")))
        fmu = FMU2Slave(
            guid=md.guid,
            unzipDirectory=unzipped,
            modelIdentifier=md.coSimulation.modelIdentifier,
            instanceName=key,
        )
        fmu.instantiate()
        vr = {v.name: v.valueReference for v in md.modelVariables}
        if parameters:
            fmu.setReal([vr[n] for n in parameters], list(parameters.values()))
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        made.append((fmu, unzipped))
        return fmu, vr

    yield make
    for fmu, unzipped in made:
        fmu.terminate()
        fmu.freeInstance()
        shutil.rmtree(unzipped, ignore_errors=True)


# ----------------------------------------------------------------------------- description
@pytest.mark.parametrize("key", list(MODELS))
def test_validate_fmu_finds_nothing(fmus, key):
    assert validate_fmu(str(fmus[key][1])) == []


@pytest.mark.parametrize("key", list(MODELS))
def test_coefficients_are_tunable_parameters_with_units(fmus, key):
    model, path = fmus[key]
    md = read_model_description(str(path))
    variables = {v.name: v for v in md.modelVariables}
    units = {u.name for u in md.unitDefinitions}
    for name, parameter in model.parameters.items():
        if parameter.value is None:
            assert name not in variables  # not identified: not a parameter of the FMU
            continue
        variable = variables[name]
        assert (variable.causality, variable.variability) == ("parameter", "tunable")
        assert float(variable.start) == parameter.value  # exact (repr round trip)
        expected = parameter.unit.replace("*", ".").replace("^2", "2")
        assert (variable.unit or "-") == (expected if expected != "-" else "-")
        if variable.unit:
            assert variable.unit in units
    for name, unit in (("velocity", "m/s"), ("pressure_a", "Pa"), ("pressure_b", "Pa")):
        assert (variables[name].causality, variables[name].unit) == ("input", unit)
    assert (variables["friction_force"].causality, variables["friction_force"].unit) == (
        "output",
        "N",
    )
    assert variables["der(z)"].derivative is variables["z"]
    assert md.modelExchange is not None and md.coSimulation is not None


def test_archive_carries_sources_binary_and_datasheet(fmus):
    model, path = fmus["thesis"]
    with zipfile.ZipFile(path) as archive:
        names = archive.namelist()
        sheet = archive.read("resources/datasheet.json").decode()
    assert names[0] == "modelDescription.xml"
    for required in (
        "sources/cylfric_fmu.c",
        "sources/cylfric_model.h",
        "sources/cylfric_params.h",
        "sources/fmi2Functions.h",
        "sources/buildDescription.xml",
    ):
        assert required in names
    assert FrictionModel.from_datasheet(__import__("json").loads(sheet)).coefficients() == (
        model.coefficients()
    )
    if compiler() is not None and fmi_platform() is not None:
        folder, suffix = fmi_platform()
        assert f"binaries/{folder}/cylfric_thesis{suffix}" in names


def test_export_is_deterministic(tmp_path):
    model = MODELS["mixed_laws"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        first = export_fmu(model, tmp_path / "a")[0]
        second = export_fmu(model, tmp_path / "b")[0]
        other = export_fmu(model.replace(sigma_1=901.0), tmp_path / "c")[0]
    assert first.name == "cylfric_friction.fmu"
    assert first.read_bytes() == second.read_bytes()
    guids = [read_model_description(str(p)).guid for p in (first, other)]
    assert guids[0] != guids[1]


def test_export_accepts_a_datasheet(tmp_path):
    sheet = MODELS["thesis"].to_datasheet()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        path = export_fmu(sheet, tmp_path, name="from_sheet")[0]
    assert read_model_description(str(path)).coSimulation.modelIdentifier == "from_sheet"


def test_bad_arguments_raise(tmp_path):
    with pytest.raises(ValueError, match="unknown FMU element 'piston'; valid"):
        export_fmu(MODELS["thesis"], tmp_path, element="piston")
    with pytest.raises(ValueError, match="name '1st' is not a valid model identifier"):
        export_fmu(MODELS["thesis"], tmp_path, name="1st")
    with pytest.raises(ValueError, match="model is a int; expected a cylfric.model.FrictionModel"):
        export_fmu(3, tmp_path)
    assert not list(tmp_path.iterdir())


def test_without_compiler_the_fmu_carries_sources_only(tmp_path, monkeypatch):
    import cylfric.export.fmu as module

    monkeypatch.setattr(module, "compiler", lambda: None)
    with pytest.warns(RuntimeWarning, match="no C compiler .*C sources only"):
        path = export_fmu(MODELS["thesis"], tmp_path)[0]
    with zipfile.ZipFile(path) as archive:
        assert not [n for n in archive.namelist() if n.startswith("binaries/")]
    assert validate_fmu(str(path)) == []


# ----------------------------------------------------------------------------- simulation
PLATEAU = 0.2  # [s] each velocity/pressure level is held this long
VELOCITIES = np.array([0.02, 0.05, -0.01, -0.05, 0.002, 0.1])  # [m/s], reversals included
PRESSURES = np.array([20e5, 20e5, 60e5, 60e5, 100e5, 100e5])  # [Pa] chamber A; B = 0.8 A
DT = 1e-3  # [s] output interval


def _staircase():
    """fmpy input table: levels held for PLATEAU, steps as repeated time points (events)."""
    edges = np.arange(VELOCITIES.size + 1) * PLATEAU
    times = np.concatenate([[0.0], np.repeat(edges[1:-1], 2), [edges[-1]]])
    signals = np.zeros(
        times.size,
        dtype=[("time", float), ("velocity", float), ("pressure_a", float), ("pressure_b", float)],
    )
    signals["time"] = times
    signals["velocity"] = np.repeat(VELOCITIES, 2)
    signals["pressure_a"] = np.repeat(PRESSURES, 2)
    signals["pressure_b"] = 0.8 * np.repeat(PRESSURES, 2)
    return signals, edges[-1]


def _exact_staircase(model, time):
    """Force [N] on ``time`` from cylfric's exact z update, level by level (left-held)."""
    level = np.clip(np.ceil(time / PLATEAU - 1e-9).astype(int) - 1, 0, VELOCITIES.size - 1)
    pressure = model.operating_pressure(PRESSURES, 0.8 * PRESSURES)
    z = np.zeros(time.size)
    for k in range(time.size - 1):
        j = level[k + 1]  # the level held over (t_k, t_k+1]
        prm = model.params_at(pressure[j])
        z[k + 1] = lugre_z_update(
            z[k],
            VELOCITIES[j],
            time[k + 1] - time[k],
            prm["sigma_0"],
            prm["F_c"],
            prm["F_s"],
            prm["v_r"],
            alpha=prm["alpha"],
        )
    return model.dynamic_force(VELOCITIES[level], z, pressure[level]), level


def _on_grid(result, time):
    """Outputs at ``time``; at an event fmpy records before and after: take the one before."""
    index = np.searchsorted(result["time"], time - 1e-12, side="left")
    assert_allclose(result["time"][index], time, atol=1e-12)
    return result["friction_force"][index]


@needs_cc
@pytest.mark.parametrize("key", list(MODELS))
@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
def test_simulate_fmu_reproduces_cylfric(fmus, key, fmi_type):
    model, path = fmus[key]
    signals, stop = _staircase()
    result = fmpy.simulate_fmu(
        str(path),
        fmi_type=fmi_type,
        stop_time=stop,
        output_interval=DT,
        input=signals,
        output=["friction_force"],
        relative_tolerance=1e-9,
    )
    time = np.round(np.arange(0.0, stop + DT / 2, DT), 12)
    expected, level = _exact_staircase(model, time)
    force = _on_grid(result, time)
    scale = np.abs(expected).max()
    # co-simulation is exact for held inputs (rounding only); model exchange within CVode's
    # tolerance (1e-9 relative; measured 7e-9 of the largest force on the thesis model)
    assert_allclose(
        force, expected, rtol=0, atol=(1e-12 if fmi_type == "CoSimulation" else 1e-6) * scale
    )
    # steady friction at the end of each plateau whose z has settled (|v| >= 10 mm/s: the
    # bristles decay with sigma_0 |v| / g, at least 90 1/s there, exp(-18) after 0.2 s)
    ends = np.flatnonzero(np.isclose(time % PLATEAU, 0.0, atol=1e-9) & (time > 0))
    fast = ends[np.abs(VELOCITIES[level[ends]]) >= 0.01]
    pressure = model.operating_pressure(PRESSURES, 0.8 * PRESSURES)[level[fast]]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the validity check is not what is tested here
        steady = model.friction(VELOCITIES[level[fast]], pressure)
    assert_allclose(force[fast], steady, rtol=1e-4)


@needs_cc
@pytest.mark.parametrize("key", list(MODELS))
def test_steady_friction_at_constant_velocity(slave, key):
    """One long doStep at constant inputs ends on the steady state: model.friction (eq. 2.7)."""
    model = MODELS[key]
    fmu, vr = slave(key)
    inputs = [vr["velocity"], vr["pressure_a"], vr["pressure_b"]]
    time = 0.0
    for v in (-0.1, -0.02, -0.003, 0.001, 0.004, 0.01, 0.05, 0.1):
        for pa, pb in ((30e5, 10e5), (120e5, 140e5)):
            fmu.setReal(inputs, [v, pa, pb])
            fmu.doStep(currentCommunicationPoint=time, communicationStepSize=5.0)
            time += 5.0
            force = fmu.getReal([vr["friction_force"]])[0]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                expected = model.friction(v, model.operating_pressure(pa, pb))
            # exact update: after 5 s z is z_ss to rounding even at 1 mm/s (decay exp(-44))
            assert_allclose(force, expected, rtol=1e-9)


@needs_cc
def test_input_derivatives_match_cylfric_simulate(slave):
    """Co-simulation with first input derivatives = cylfric.simulate(PrescribedMotion)."""
    model = MODELS["thesis"]
    fmu, vr = slave("thesis")
    dt, duration = 1e-3, 0.6
    time = np.arange(int(round(duration / dt)) + 1) * dt
    velocity = 0.05 * np.sin(2 * np.pi * 2.5 * time) + 0.01
    pressure_a = 50e5 + 30e5 * np.sin(2 * np.pi * 1.5 * time)
    pressure_b = 40e5 - 20e5 * np.cos(2 * np.pi * 1.0 * time)
    reference = simulate(
        Cylinder(2.5),
        model,
        PrescribedMotion(velocity),
        duration,
        dt=dt,
        pressure_a=pressure_a,
        pressure_b=pressure_b,
        step=1e-4,
    ).outputs["friction_force"]
    inputs = [vr["velocity"], vr["pressure_a"], vr["pressure_b"]]
    fmu.setReal(inputs, [velocity[0], pressure_a[0], pressure_b[0]])
    force = [fmu.getReal([vr["friction_force"]])[0]]
    for k in range(time.size - 1):
        fmu.setReal(inputs, [velocity[k], pressure_a[k], pressure_b[k]])
        slopes = [(s[k + 1] - s[k]) / dt for s in (velocity, pressure_a, pressure_b)]
        fmu.setRealInputDerivatives(inputs, [1, 1, 1], slopes)
        fmu.doStep(currentCommunicationPoint=time[k], communicationStepSize=dt)
        force.append(fmu.getReal([vr["friction_force"]])[0])
    # the same scheme (10 substeps, mid-substep inputs, exact z); the FMU interpolates the
    # pressure and cylfric the (linear-law) parameters: equal up to rounding
    assert_allclose(force, reference, rtol=0, atol=1e-9 * np.abs(reference).max())


@needs_cc
def test_parameters_are_tunable(slave):
    model = MODELS["thesis"]
    changed = {"F_c.intercept": 80.0, "sigma_2.slope": 2e-5}
    fmu, vr = slave("thesis", **changed)
    fmu.setReal([vr["velocity"], vr["pressure_a"], vr["pressure_b"]], [0.03, 70e5, 70e5])
    fmu.doStep(currentCommunicationPoint=0.0, communicationStepSize=1.0)
    coefficients = model.coefficients()
    coefficients["F_c"] = dict(coefficients["F_c"], intercept=80.0)
    coefficients["sigma_2"] = dict(coefficients["sigma_2"], slope=2e-5)
    expected = model.replace(coefficients=coefficients).friction(0.03, 70e5)
    assert_allclose(fmu.getReal([vr["friction_force"]])[0], expected, rtol=1e-9)


@needs_cc
def test_unphysical_parameters_are_an_error(fmus):
    _, path = fmus["thesis"]
    with pytest.raises(Exception, match="(?i)fmi2ExitInitializationMode|failed|error"):
        fmpy.simulate_fmu(
            str(path),
            fmi_type="CoSimulation",
            stop_time=0.01,
            start_values={"F_c.intercept": -500.0, "F_s.intercept": -500.0},
        )


# ----------------------------------------------------------------------------- cylinder
CYLINDER_CASES = {
    # drive between F_c and F_s of the thesis law at 45 bar: the rod nearly sticks (LuGre
    # creep, 0.6 mm in 0.5 s)
    "stuck": (100.0, 0.0, 0.0, 45e5, 45e5),
    # 60 N plus the pressure force 1e-4 m^2 * 50 bar - 0.5e-4 m^2 * 40 bar = 360 N: it slides
    "sliding": (60.0, 1e-4, 0.5e-4, 50e5, 40e5),
}


@pytest.fixture(scope="module")
def cylinder_fmu(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return export_fmu(MODELS["thesis"], tmp_path_factory.mktemp("cyl"), element="cylinder")[0]


def test_cylinder_fmu_validates(cylinder_fmu):
    assert validate_fmu(str(cylinder_fmu)) == []
    md = read_model_description(str(cylinder_fmu))
    variables = {v.name: v for v in md.modelVariables}
    assert [u.variable.name for u in md.outputs] == ["friction_force", "position", "velocity"]
    assert [u.variable.name for u in md.derivatives] == ["velocity", "der(velocity)", "der(z)"]
    assert (variables["force"].causality, variables["force"].unit) == ("input", "N")
    assert (variables["mass"].causality, variables["mass"].unit) == ("parameter", "kg")
    assert md.coSimulation.modelIdentifier == "cylfric_cylinder"


@needs_cc
@pytest.mark.parametrize("case", list(CYLINDER_CASES))
def test_cylinder_reproduces_cylfric_simulate(cylinder_fmu, case):
    """Co-simulation = cylfric.simulate "fixed" (the same impulse scheme, 1e-4 s steps);
    model exchange = cylfric.simulate "dopri" at rtol 1e-10 (an independent integrator)."""
    force, area_a, area_b, pa, pb = CYLINDER_CASES[case]
    model, mass, dt, duration = MODELS["thesis"], 2.5, 1e-3, 0.5
    cylinder = Cylinder(mass, area_a=area_a, area_b=area_b)
    signals = np.array(
        [(0.0, force, pa, pb), (duration, force, pa, pb)],
        dtype=[("time", float), ("force", float), ("pressure_a", float), ("pressure_b", float)],
    )
    start = {"mass": mass, "area_a": area_a, "area_b": area_b}
    for fmi_type, method, options, tolerance in (
        ("CoSimulation", "fixed", {"step": 1e-4}, 1e-9),
        ("ModelExchange", "dopri", {"rtol": 1e-10}, 1e-6),
    ):
        reference = simulate(
            cylinder,
            model,
            AppliedForce(force),
            duration,
            dt=dt,
            pressure_a=pa,
            pressure_b=pb,
            method=method,
            **options,
        )
        result = fmpy.simulate_fmu(
            str(cylinder_fmu),
            fmi_type=fmi_type,
            stop_time=duration,
            output_interval=dt,
            input=signals,
            start_values=start,
            output=["friction_force", "position", "velocity"],
            relative_tolerance=1e-10,
        )
        for name, expected in (
            ("friction_force", reference.outputs["friction_force"]),
            ("position", reference.states["position"]),
            ("velocity", reference.states["velocity"]),
        ):
            scale = np.abs(expected).max()
            assert_allclose(result[name], expected, rtol=0, atol=tolerance * scale, err_msg=name)


@needs_cc
def test_cylinder_position_drive_reproduces_cylfric_simulate(cylinder_fmu):
    """A 10 mm position step through the servo inputs = cylfric.simulate with PositionServo."""
    model, mass, dt, duration = MODELS["thesis"], 2.5, 1e-3, 0.3
    kp, kd, target, pressure = 1e5, 1e3, 0.01, 80e5
    signals = np.array(
        [(0.0, target, 0.0, pressure, pressure), (duration, target, 0.0, pressure, pressure)],
        dtype=[
            ("time", float),
            ("position_reference", float),
            ("velocity_reference", float),
            ("pressure_a", float),
            ("pressure_b", float),
        ],
    )
    drive = PositionServo(target, kp=kp, kd=kd, reference_velocity=0.0)
    for fmi_type, method, options, tolerance in (
        ("CoSimulation", "fixed", {"step": 1e-4}, 1e-9),
        ("ModelExchange", "dopri", {"rtol": 1e-10}, 1e-6),
    ):
        reference = simulate(
            Cylinder(mass),
            model,
            drive,
            duration,
            dt=dt,
            pressure_a=pressure,
            method=method,
            **options,
        )
        result = fmpy.simulate_fmu(
            str(cylinder_fmu),
            fmi_type=fmi_type,
            stop_time=duration,
            output_interval=dt,
            input=signals,
            start_values={"mass": mass, "kp": kp, "kd": kd},
            output=["friction_force", "position", "velocity"],
            relative_tolerance=1e-10,
        )
        for name, expected in (
            ("friction_force", reference.outputs["friction_force"]),
            ("position", reference.states["position"]),
            ("velocity", reference.states["velocity"]),
        ):
            scale = np.abs(expected).max()
            assert_allclose(result[name], expected, rtol=0, atol=tolerance * scale, err_msg=name)
