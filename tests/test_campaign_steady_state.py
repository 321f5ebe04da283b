"""Campaigns and steady-state extraction on virtual and real data."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from fit_helpers import needs_fork
from numpy.testing import assert_allclose

from cylfric.friction import params_at_pressure, stribeck
from cylfric.friction.literature import THESIS_2016
from cylfric.io import BenchFileError, discover_runs, load_config, read_bench_text
from cylfric.simulate.bench import BenchSettings, generate_campaign, run_virtual_test
from cylfric.steady_state import extract_campaign, find_windows, smoothed_velocity

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SMALL = BenchSettings.clean(pressures_bar=(0.1, 83.0), speeds_mm_s=(2, 10, 60, 135))


@pytest.fixture(scope="module")
def small_campaign(tmp_path_factory):
    folder = tmp_path_factory.mktemp("campaign")
    info = generate_campaign(folder, SMALL)
    return folder, info


@pytest.mark.parametrize(
    "variant",
    [
        dict(),
        dict(decimal_comma=True),
        dict(force_unit="N", crlf=True),
        dict(pressure_channel=True, decimal_comma=True),
    ],
)
def test_virtual_bench_files_round_trip(tmp_path, variant):
    settings = replace(SMALL, speeds_mm_s=(10,), pressures_bar=(55.0,), **variant)
    info = generate_campaign(tmp_path, settings)
    run = run_virtual_test(
        55.0,
        10,
        settings,
        rng=np.random.default_rng(np.random.SeedSequence(settings.seed).spawn(1)[0]),
        slow=True,
    )
    data, meta = read_bench_text(info["files"][0])
    assert_allclose(data["time [s]"], run.time, atol=5e-4)
    assert_allclose(data["position [m]"], run.position, atol=5.1e-8)  # 4 decimals of mm
    force_step = 5e-3 if settings.force_unit == "kN" else 5e-3
    assert_allclose(data["force [N]"], run.force, atol=force_step + 1e-9)
    if settings.pressure_channel:
        assert_allclose(data["pressure [Pa]"], run.pressure, atol=500.1)
    assert meta["decimal"] == ("," if settings.decimal_comma else ".")
    assert meta["header"]["Pressure"] == "55 bar"


def test_campaign_is_deterministic(tmp_path, small_campaign):
    folder, _ = small_campaign
    other = tmp_path / "again"
    generate_campaign(other, SMALL)
    for path in sorted(folder.glob("*.txt")):
        assert (other / path.name).read_bytes() == path.read_bytes()


def test_manifest_and_sample_budget(small_campaign):
    folder, info = small_campaign
    runs = discover_runs(folder)
    assert len(runs) == 8 and all(r.source["pressure"] == "manifest" for r in runs)
    for path in info["files"]:
        data, _ = read_bench_text(path)
        assert len(data) <= 10_001
        interval = np.median(np.diff(data["time [s]"]))
        slow = "_v2mms" in path.name or "_v10mms" in path.name  # the two slowest speeds
        assert_allclose(interval, 0.020 if slow else 0.010)


def test_extraction_recovers_friction_and_offset(small_campaign):
    folder, _ = small_campaign
    ex = extract_campaign(folder)
    ok = ex.usable
    assert len(ok) == 16  # two strokes per run
    assert_allclose(ex.offset, 35.67 / 2, atol=0.1)  # thesis Fig. 4.3 offset, halved
    truth = np.abs(
        stribeck(
            ok["velocity [m/s]"].to_numpy(),
            **params_at_pressure(ok["pressure [Pa]"].to_numpy(), THESIS_2016.coefficients),
        )
    )
    assert_allclose(ok["friction [N]"], truth, atol=0.5)
    assert set(ok["direction [-]"]) == {-1, 1}


def test_window_excludes_acceleration_and_cushioning():
    settings = replace(SMALL, force_noise=0.3, spike_probability=0.0)
    run = run_virtual_test(55.0, 135, settings, slow=False)
    velocity = smoothed_velocity(run.time, run.position)
    windows = find_windows(run.time, velocity, run.force, nominal_speed=0.135)
    assert len(windows) == 2
    cushioned = np.abs(run.cushion) > 0.5
    accelerating = np.abs(np.abs(run.velocity) - 0.135) > 0.01 * 0.135
    for w in windows:
        inside = np.zeros(run.time.size, bool)
        inside[w.start : w.stop] = True
        assert not (inside & cushioned).any()
        assert not (inside & accelerating).any()
        assert inside.sum() >= 0.5 * (run.steady & (run.segment == (w.direction > 0))).sum()


def test_fixed_index_rule_drops_ten_samples_each_end():
    run = run_virtual_test(55.0, 10, SMALL, slow=False)
    velocity = smoothed_velocity(run.time, run.position)
    auto = find_windows(run.time, velocity, run.force, nominal_speed=0.01)
    fixed = find_windows(run.time, velocity, run.force, nominal_speed=0.01, method="fixed-index")
    assert [w.direction for w in fixed] == [-1, 1]
    assert all(f.stop - f.start > a.stop - a.start for f, a in zip(fixed, auto, strict=True))


def test_unsettled_speed_is_flagged_not_averaged():
    time = np.arange(0, 5, 0.01)
    velocity = 0.01 + 0.005 * np.sin(2 * np.pi * 3 * time)  # never settles within 2 %
    windows = find_windows(time, velocity, np.zeros_like(time), nominal_speed=0.01)
    assert windows and all(w.flag in ("unsettled", "short_window") for w in windows)


def test_skip_bad_lists_the_file_and_default_stops(tmp_path, small_campaign):
    folder, _ = small_campaign
    copy = tmp_path / "copy"
    shutil.copytree(folder, copy)
    bad = sorted(copy.glob("*.txt"))[3]
    bad.write_bytes(bad.read_bytes()[:2000])  # truncated mid-row
    with pytest.raises(BenchFileError, match=rf"{bad.name}, line \d+: the last data row has no"):
        extract_campaign(copy)
    ex = extract_campaign(copy, skip_bad=True)
    assert [s["file"] for s in ex.skipped] == [str(bad)]
    assert "looks truncated" in ex.skipped[0]["reason"]
    assert ex.points["run"].nunique() == 7


def test_missing_pressure_is_an_error(tmp_path):
    path = tmp_path / "run_v10mms.txt"
    path.write_text(
        "Time [s]\tPosition [mm]\tForce [N]\n"
        + "".join(f"{t / 100}\t{t / 10}\t100\n" for t in range(300))
    )
    with pytest.raises(BenchFileError, match="no pressure for this run"):
        extract_campaign(tmp_path)


def test_config_errors_name_the_problem(tmp_path):
    (tmp_path / "campaign.toml").write_text("[cylinder]\nbore = '25 mm'\nkind = 'triple'\n")
    with pytest.raises(BenchFileError, match=r"line 3: cylinder.kind: 'triple' is not one of"):
        load_config(tmp_path)
    (tmp_path / "campaign.toml").write_text("[colums]\n")
    with pytest.raises(BenchFileError, match=r"line 1: unknown key 'colums' in the top level"):
        load_config(tmp_path)
    (tmp_path / "campaign.toml").write_text("[force_balance]\nload_cell_sign = 2\n")
    with pytest.raises(BenchFileError, match=r"force_balance.load_cell_sign: 2 is not one of"):
        load_config(tmp_path)


def test_zillen_real_data_friction_rises_with_pressure(shared_data, tmp_path):
    folder = tmp_path / "zillen"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals", folder)
    shutil.copy(EXAMPLES / "zillen2021" / "campaign.toml", folder / "campaign.toml")
    ex = extract_campaign(folder)
    ok = ex.usable.assign(p_bar=lambda d: d["pressure [Pa]"] / 1e5)
    for seal, group in ok.groupby("seal"):
        level = group.groupby("run").agg(p=("p_bar", "mean"), f=("friction [N]", "mean"))
        level = level.sort_values("p")
        assert np.all(np.diff(level["f"]) > 0), seal
    oring = ok[ok["seal"] == "O-ring"]
    for _, run in oring.groupby("run"):
        extend = run.loc[run["direction [-]"] > 0, "force [N]"].mean()
        retract = run.loc[run["direction [-]"] < 0, "force [N]"].mean()
        half_range = (extend - retract) / 2  # retract minus extend of F - pA, halved
        p = run["p_bar"].mean()
        assert abs(half_range - (3.40 + 0.654 * p)) < 2.0, (p, half_range)


def test_unknown_extraction_option_is_named(tmp_path, small_campaign):
    folder, _ = small_campaign
    copy = tmp_path / "c"
    shutil.copytree(folder, copy)
    (copy / "campaign.toml").write_text("[extraction]\nmin_sample = 10\n")
    with pytest.raises(BenchFileError, match=r"unknown extraction option\(s\) \['min_sample'\]"):
        extract_campaign(copy)


def test_unknown_window_method_lists_valid():
    t = np.arange(0, 1, 0.01)
    with pytest.raises(ValueError, match=r"unknown window method 'thesis'; valid: \['auto'"):
        find_windows(t, np.ones_like(t), np.zeros_like(t), method="thesis")


@pytest.fixture(scope="module")
def campaign_of_20(tmp_path_factory):
    """20 files: enough for extract_campaign to read on a pool (PARALLEL_MIN_FILES)."""
    folder = tmp_path_factory.mktemp("twenty")
    generate_campaign(
        folder, replace(SMALL, pressures_bar=(0.1, 83.0), speeds_mm_s=tuple(range(2, 22, 2)))
    )
    return folder


@needs_fork
def test_the_pool_extraction_equals_the_serial_one(campaign_of_20):
    import pandas as pd

    names = []
    serial = extract_campaign(campaign_of_20, workers=1)
    parallel = extract_campaign(campaign_of_20, progress=names.append)
    assert sorted(names) == sorted(Path(r["file"]).name for r in serial.runs)
    pd.testing.assert_frame_equal(parallel.points, serial.points)
    assert parallel.runs == serial.runs and parallel.bytes_read == serial.bytes_read


@needs_fork
def test_files_of_a_dead_worker_are_extracted_here(campaign_of_20, monkeypatch):
    import os

    import pandas as pd

    import cylfric.steady_state as ss

    parent, original = os.getpid(), ss._point_rows

    def dies_in_a_worker(*args, **kwargs):
        if os.getpid() != parent:
            os._exit(3)
        return original(*args, **kwargs)

    monkeypatch.setattr(ss, "_point_rows", dies_in_a_worker)
    parallel = extract_campaign(campaign_of_20)
    monkeypatch.undo()
    pd.testing.assert_frame_equal(
        parallel.points, extract_campaign(campaign_of_20, workers=1).points
    )


@needs_fork
def test_a_bad_file_read_by_a_worker_is_named_and_skippable(campaign_of_20, tmp_path):
    folder = tmp_path / "c"
    shutil.copytree(campaign_of_20, folder)
    bad = sorted(folder.glob("run_*.txt"))[1]
    bad.write_text(bad.read_text().replace("\t", "\tx", 40))
    with pytest.raises(BenchFileError, match=bad.name):
        extract_campaign(folder)
    result = extract_campaign(folder, skip_bad=True)
    assert [Path(s["file"]).name for s in result.skipped] == [bad.name]


def test_the_datasheet_hashes_the_bytes_each_file_had_when_read(campaign_of_20):
    """The reader hashes each file's bytes on the core that reads it (also in a pool
    worker); the datasheet's provenance lists exactly the files' SHA-256."""
    import hashlib

    from cylfric.datasheet import build_datasheet
    from cylfric.identify import identify

    extraction = extract_campaign(campaign_of_20)
    expected = {
        Path(r["file"]).name: hashlib.sha256(Path(r["file"]).read_bytes()).hexdigest()
        for r in extraction.runs
    }
    assert {Path(r["file"]).name: r["sha256"] for r in extraction.runs} == expected
    sheet = build_datasheet(identify(extraction.usable), extraction=extraction)
    listed = {f["name"]: f["sha256"] for f in sheet["fit"]["source"]["files"]}
    assert listed == expected and len(listed) == 20


def test_a_campaign_of_mat_runs_is_read_with_its_column_units(campaign_of_20, tmp_path):
    """.mat runs (no units in the format) are read with [columns] names and units, converted
    as a text file's columns are: the points equal the text campaign's. Without them the
    error says what to write and lists the variables (hostile check: the old message asked
    for a time column that [columns] could not provide)."""
    import pandas as pd
    from scipy.io import savemat

    folder = tmp_path / "mat"
    folder.mkdir()
    rows = ["file,pressure_bar,velocity_mm_s"]
    for line in (campaign_of_20 / "manifest.csv").read_text().splitlines()[1:]:
        name, rest = line.split(",", 1)
        data, _ = read_bench_text(campaign_of_20 / name)
        stem = Path(name).stem
        savemat(
            folder / f"{stem}.mat",
            {
                "t": data["time [s]"].to_numpy(),
                "x": data["position [m]"].to_numpy() * 1e3,  # mm
                "F": data["force [N]"].to_numpy() / 1e3,  # kN
            },
        )
        rows.append(f"{stem}.mat,{rest}")
    (folder / "manifest.csv").write_text("\n".join(rows) + "\n")
    (folder / "campaign.toml").write_text('[files]\nglob = "*.mat"\n')
    with pytest.raises(BenchFileError, match=r"\.mat run carries no units; expected \[columns\]"):
        extract_campaign(folder, workers=1)
    (folder / "campaign.toml").write_text(
        '[files]\nglob = "*.mat"\n[columns]\nnames = ["t", "x", "F"]\nunits = ["s", "mm", "kN"]\n'
    )
    mat = extract_campaign(folder, workers=1).points
    text = extract_campaign(campaign_of_20, workers=1).points
    assert len(mat) == len(text) == 40
    pd.testing.assert_series_equal(mat["friction [N]"], text["friction [N]"], rtol=1e-12)
    pd.testing.assert_series_equal(mat["velocity [m/s]"], text["velocity [m/s]"], rtol=1e-12)


def test_window_means_and_deviations_are_numpys_bit_for_bit():
    """The points' means and standard deviations (_mean, _mean_std: numpy's pairwise sums
    without its Python wrappers) equal ndarray.mean() and ndarray.std() exactly, for short
    and long windows of forces [N], contiguous or strided."""
    from cylfric.steady_state import _mean, _mean_std

    rng = np.random.default_rng(27)
    for n in [1, 2, 7, 8, 9, 127, 128, 129, 1000, 4831]:
        x = 150.0 + rng.normal(size=n) * rng.choice([1e-3, 1.0, 1e3])
        for y in (x, x[::2], np.round(x, 1)):
            assert _mean(y) == y.mean()
            assert _mean_std(y) == (y.mean(), y.std())
