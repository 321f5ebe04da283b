"""Lossy exports (Simscape, Hopsan) and the loss report: block equations, fits, honesty."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from numpy.testing import assert_allclose

from cylfric.export import ExportResult, export, parse_targets, resolve
from cylfric.export import hopsan as hop
from cylfric.export import simscape as ssc
from cylfric.export.loss import chamber_pressure, loss_grid, loss_report
from cylfric.friction import simscape_cylinder_friction, stribeck
from cylfric.model import FrictionModel

# The thesis campaign's range (ch. 3: about 1-135 mm/s, 0.1-159 bar)
THESIS_VALIDITY = {
    "pressure_min": 0.1e5,
    "pressure_max": 159e5,
    "velocity_min": 1e-3,
    "velocity_max": 0.135,
}
SMALL_GRID = {"n_velocity": 12, "n_pressure": 4}


@pytest.fixture(scope="module")
def thesis():
    """The thesis law (eq. 4.1-4.3) with the thesis campaign's validity range."""
    return FrictionModel().replace(validity=THESIS_VALIDITY)


# ------------------------------------------------------------------ documented block equations
def test_translational_friction_peaks_at_the_breakaway_velocity_with_the_breakaway_force():
    # MathWorks Translational Friction: the Stribeck term peaks at v_brk (= v_st/sqrt(2))
    # where sqrt(2e) * (1/sqrt(2)) * exp(-1/2) = 1, so F(v_brk) ~ F_brk (+ small terms)
    params = dict(
        breakaway_force=150.0, coulomb_force=100.0, viscous_coefficient=0.0, breakaway_velocity=0.01
    )
    stribeck_part = ssc.translational_friction(0.01, **params) - 100.0 * math.tanh(10.0)
    assert_allclose(stribeck_part, 50.0, rtol=1e-12)
    v = np.linspace(-0.2, 0.2, 101)
    assert_allclose(
        ssc.translational_friction(-v, **params),
        -ssc.translational_friction(v, **params),
        atol=1e-12,
    )
    # far above v_brk: Coulomb plus viscous only
    fast = dict(params, viscous_coefficient=300.0)
    assert_allclose(ssc.translational_friction(1.0, **fast), 100.0 + 300.0, rtol=1e-9)


def test_cylinder_friction_il_coulomb_force_uses_the_sum_of_chamber_pressures():
    params = dict(
        preload_force=80.0,
        coulomb_friction_coefficient=3e-6,
        breakaway_ratio=1.0,
        breakaway_velocity=1e-3,
        viscous_coefficient=0.0,
    )
    # R_brk = 1: no Stribeck term; at 1 m/s tanh = 1: F = F_pr + f_cfr (p_A + p_B)
    force = ssc.cylinder_friction_il(1.0, 50e5, 30e5, **params)
    assert_allclose(force, 80.0 + 3e-6 * 80e5, rtol=1e-12)


def test_legacy_cylinder_friction_is_the_imported_block_and_linear_below_threshold():
    block = dict(
        preload_force=70.0,
        coulomb_friction_coefficient=2e-6,
        breakaway_ratio=1.5,
        transition_coefficient=100.0,
        viscous_coefficient=400.0,
    )
    v = np.array([-0.1, -0.02, 0.003, 0.05])
    expected = stribeck(v, **simscape_cylinder_friction(40e5, 40e5, **block))
    assert_allclose(ssc.cylinder_friction(v, 40e5, 40e5, **block), expected, rtol=1e-14)
    inside = ssc.cylinder_friction(np.array([2.5e-5, 5e-5]), 40e5, 40e5, **block)
    at_threshold = ssc.cylinder_friction(1e-4 * (1 + 1e-12), 40e5, 40e5, **block)
    assert_allclose(inside, at_threshold * np.array([0.25, 0.5]), rtol=1e-9)


# ------------------------------------------------------------------ fits
def test_legacy_fit_recovers_a_model_that_is_the_block(thesis):
    # A cylfric model written in the block's own form (reference "sum", F_s = K F_c,
    # constant sigma_2, alpha = 1, v_r = 1/c_v): the least-squares fit must find it.
    truth = dict(
        preload_force=75.0,
        coulomb_friction_coefficient=2.5e-6,
        breakaway_ratio=1.4,
        transition_coefficient=80.0,
        viscous_coefficient=350.0,
    )
    k = truth["breakaway_ratio"]
    model = FrictionModel(
        {
            "F_c": {"intercept": 75.0, "slope": 2.5e-6},
            "F_s": {"intercept": k * 75.0, "slope": k * 2.5e-6},
            "sigma_2": {"intercept": 350.0, "slope": 0.0},
            "v_r": 1 / 80.0,
            "alpha": 1.0,
        },
        reference="sum",
        validity=dict(THESIS_VALIDITY, pressure_max=318e5),
    )
    speeds, pressures = loss_grid(model, **SMALL_GRID)
    fitted = ssc.fit_cylinder_friction(model, speeds, pressures)
    for name, value in truth.items():
        assert_allclose(fitted[name], value, rtol=1e-6, err_msg=name)


@pytest.mark.parametrize(
    "fit, block",
    [
        (ssc.fit_cylinder_friction_il, ssc.cylinder_friction_il),
        (ssc.fit_cylinder_friction, ssc.cylinder_friction),
    ],
)
def test_simscape_fits_are_least_squares_minima(thesis, fit, block):
    speeds, pressures = loss_grid(thesis, **SMALL_GRID)
    params = fit(thesis, speeds, pressures)

    def rms(p):
        report = loss_report(
            thesis,
            lambda v, a, b: block(v, a, b, **p),
            target="t",
            title="t",
            speeds=speeds,
            pressures=pressures,
        )
        return report.rms

    best = rms(params)
    for name, value in params.items():
        if name == "velocity_threshold" or value == 0:
            continue
        for factor in (0.98, 1.02):
            if name == "breakaway_ratio" and value * factor < 1:
                continue
            assert rms(dict(params, **{name: value * factor})) > best, (name, factor)


def test_translational_friction_is_fitted_per_level_and_exact_at_its_level(thesis):
    speeds, _ = loss_grid(thesis, **SMALL_GRID)
    low = ssc.fit_translational_friction(thesis, speeds, 10e5)
    high = ssc.fit_translational_friction(thesis, speeds, 150e5)
    assert high["coulomb_force"] > low["coulomb_force"]  # F_c rises with pressure (eq. 4.1)
    assert low["breakaway_force"] >= low["coulomb_force"]


def test_hopsan_fit_is_the_linear_least_squares_solution(thesis):
    speeds, pressures = loss_grid(thesis, **SMALL_GRID)
    params = hop.fit_hopsan(thesis, speeds, pressures)
    P, V = np.meshgrid(pressures, speeds, indexing="ij")
    target = thesis.friction(V, P).ravel()
    design = np.column_stack([np.ones(V.size), V.ravel()])
    (f_k, b_p), *_ = np.linalg.lstsq(design, target, rcond=None)  # both positive here
    assert_allclose([params["f_k"], params["B_p"]], [f_k, b_p], rtol=1e-8)
    assert params["b"] == 0.0
    assert_allclose(params["f_s"], thesis.params_at(0.5 * (0.1e5 + 159e5))["F_s"], rtol=1e-12)
    v = np.array([-0.05, 0.01])
    assert_allclose(hop.hopsan_friction(v, **params), f_k * np.sign(v) + b_p * v, rtol=1e-8)
    # f_k wired to a pressure signal: f_k0 + k_p (p_1 + p_2), again a linear least squares
    signal = hop.fit_hopsan_pressure_signal(thesis, speeds, pressures)
    design = np.column_stack([np.ones(V.size), 2 * P.ravel(), V.ravel()])
    (f_k0, k_p, b_p2), *_ = np.linalg.lstsq(design, target, rcond=None)
    assert_allclose(
        [signal["f_k0"], signal["f_k_pressure_coefficient"], signal["B_p"]],
        [f_k0, k_p, b_p2],
        rtol=1e-7,
    )
    assert_allclose(
        hop.hopsan_friction_pressure_signal(0.02, 50e5, 30e5, **signal),
        f_k0 + k_p * 80e5 + b_p2 * 0.02,
        rtol=1e-8,
    )


# ------------------------------------------------------------------ the loss report
def test_loss_report_of_the_thesis_model(thesis, tmp_path):
    """The thesis model's loss, stated honestly (regression values, measured 2026-11-23 with
    the default 40 x 9 grid; the issue's hand fit of the legacy block on the demo datasheet
    gave RMS 2.9 N, max 12.3 N)."""
    result = export(thesis, "simscape", tmp_path, name="thesis")
    reports = {r.target: r for r in result.loss}
    legacy = reports["simscape_cylinder_friction"]
    il = reports["simscape_cylinder_friction_il"]
    assert legacy.rms <= 3.0 and legacy.max_abs <= 12.4  # not worse than the hand fit
    assert_allclose([legacy.rms, legacy.max_abs], [2.99, 12.29], rtol=5e-3)  # regression
    assert_allclose([il.rms, il.max_abs], [6.04, 15.96], rtol=5e-3)  # regression
    hopsan, signal = export(thesis, "hopsan", tmp_path / "hopsan", name="thesis").loss
    assert hopsan.rms > signal.rms > legacy.rms  # no pressure dependence / no Stribeck drop
    assert_allclose([hopsan.rms, signal.rms], [30.96, 11.56], rtol=5e-3)  # regression


def test_loss_report_grid_table_and_worst_point(thesis, tmp_path):
    speeds, pressures = loss_grid(thesis, **SMALL_GRID)
    report = loss_report(
        thesis,
        lambda v, a, b: hop.hopsan_friction(v, f_k=120.0, B_p=300.0),
        target="hopsan",
        title="Hopsan",
        speeds=speeds,
        pressures=pressures,
        parameters={"f_k": (120.0, "N")},
    )
    files = report.write(tmp_path)
    assert [f.suffix for f in files] == [".csv", ".txt", ".png"]
    table = pd.read_csv(files[0])
    assert list(table.columns) == [
        "velocity [mm/s]",
        "pressure [bar]",
        "cylfric [N]",
        "hopsan [N]",
        "difference [N]",
    ]
    assert len(table) == 2 * 12 * 4  # both directions
    assert_allclose(table["difference [N]"], table["hopsan [N]"] - table["cylfric [N]"], atol=1e-6)
    assert_allclose(np.sort(np.abs(table["velocity [mm/s]"].unique()))[[0, -1]], [1.0, 135.0])
    # odd models: retraction mirrors extension
    ext = table[table["velocity [mm/s]"] > 0].sort_values(["pressure [bar]", "velocity [mm/s]"])
    ret = table[table["velocity [mm/s]"] < 0].sort_values(
        ["pressure [bar]", "velocity [mm/s]"], ascending=[True, False]
    )
    assert_allclose(ext["difference [N]"].to_numpy(), -ret["difference [N]"].to_numpy(), atol=1e-9)
    v, p, d = report.worst
    assert abs(d) == pytest.approx(np.abs(table["difference [N]"]).max(), rel=1e-8)
    assert_allclose(report.rms, np.sqrt(np.mean(table["difference [N]"] ** 2)), rtol=1e-8)
    text = files[1].read_text()
    assert f"{report.rms:.3f} N" in text and "f_k = 120 N" in text


def test_chamber_pressure_follows_the_operating_rule():
    summed = FrictionModel(reference="sum")
    assert_allclose(chamber_pressure(summed, 100e5), 50e5)
    assert_allclose(chamber_pressure(FrictionModel(), 100e5), 100e5)


# ------------------------------------------------------------------ dispatcher and outputs
def test_export_writes_script_and_reports_deterministically(thesis, tmp_path):
    first = export(thesis, "simscape", tmp_path / "a", name="demo", **SMALL_GRID)
    second = export(thesis, "simscape", tmp_path / "b", name="demo", **SMALL_GRID)
    assert isinstance(first, ExportResult) and not first.lossless
    names = [p.name for p in first.files]
    assert names == [p.name for p in second.files]
    for a, b in zip(first.files, second.files, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    script = (tmp_path / "a" / "demo_simscape.m").read_text()
    assert "P.cylinder_friction_il.preload_force = " in script
    assert "P.cylinder_friction_il.units.coulomb_friction_coefficient = 'N/Pa';" in script
    assert "cylfric_set(cylinder_friction_il_block, 'Preload force'" in script
    assert "set_param(block, names{i}, num2str(value, 17));" in script
    assert script.count("P.translational_friction(") >= 5 * 5  # 5 levels, 5 fields each


def test_hopsan_export_files_deterministic(thesis, tmp_path):
    first = export(thesis, "hopsan", tmp_path / "a", name="cyl", **SMALL_GRID)
    second = export(thesis, "hopsan", tmp_path / "b", name="cyl", **SMALL_GRID)
    for a, b in zip(first.files, second.files, strict=True):
        assert a.read_bytes() == b.read_bytes(), a.name
    hcom = (tmp_path / "a" / "cyl_hopsan.hcom").read_text()
    params = first.loss[0].parameters
    assert f"chpa Cylinder.B_p {params['B_p'][0]:.10g}" in hcom
    assert "FMIWrapper" in (tmp_path / "a" / "README_hopsan.md").read_text()


def test_dispatcher_errors_name_the_valid_choices(thesis, tmp_path):
    with pytest.raises(ValueError, match=r"unknown export target 'stl'; valid: \['fmu', 'hopsan'"):
        export(thesis, "stl", tmp_path)
    with pytest.raises(ValueError, match=r"unknown option\(s\) \['color'\]; valid: \['name'"):
        export(thesis, "hopsan", tmp_path, color="red")
    with pytest.raises(ValueError, match="unknown export target 'x'"):
        parse_targets("simscape,x")
    assert parse_targets("Simscape, hopsan,simscape") == ["simscape", "hopsan"]
    assert resolve("hopsan") is hop.export_hopsan
    with pytest.raises(ValueError, match="the model has no validity range; give velocity_range"):
        export(FrictionModel(), "hopsan", tmp_path)
    with pytest.raises(ValueError, match=r"pressure_range = \(5.0, 1.0\) Pa is not a range"):
        export(thesis, "simscape", tmp_path, pressure_range=(5.0, 1.0))
    with pytest.raises(TypeError, match="expected a FrictionModel"):
        export(42, "hopsan", tmp_path)
