"""Many campaigns at once (issue 15): ``fit_many`` / ``cylfric fit-many`` on Dask.

The acceptance: 8 small virtual campaigns fitted with 2 local workers give the same
datasheets as serial fits (every number equal to 1e-12 relative; only the creation time
differs). The speed goal (>= 1.6x serial) is a benchmark (benchmarks/bench_many.py), never a
timed assertion here.
"""

from __future__ import annotations

import json
import subprocess
import sys
import types
import warnings
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.many import SUMMARY_COLUMNS, find_campaigns, fit_many
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.simulate.plant import Cylinder

# small campaigns: 60 mm strokes, 3 pressures x 7 speeds (21 runs, about 0.3 s to fit)
SMALL = BenchSettings.clean(
    cylinder=Cylinder.from_diameters(0.040, 0.028, 2.5, double_rod=True, stroke=0.060),
    pressures_bar=(0.1, 80, 159),
    speeds_mm_s=(2, 4, 8, 15, 30, 60, 100),
)


@pytest.fixture(scope="module")
def eight(tmp_path_factory):
    root = tmp_path_factory.mktemp("many") / "line"
    for i in range(8):
        generate_campaign(root / f"cyl{i:02d}", replace(SMALL, seed=i))
    return root


def _numbers(sheet, path=""):
    """(path, value) of every number, string and null of a datasheet, without ``created``."""
    if isinstance(sheet, dict):
        for key in sorted(sheet):
            if key != "created":
                yield from _numbers(sheet[key], f"{path}/{key}")
    elif isinstance(sheet, list):
        for i, item in enumerate(sheet):
            yield from _numbers(item, f"{path}[{i}]")
    else:
        yield path, sheet


def _same_sheets(a, b):
    left, right = dict(_numbers(a)), dict(_numbers(b))
    assert left.keys() == right.keys()
    for key, x in left.items():
        y = right[key]
        if isinstance(x, float) and isinstance(y, float):
            assert x == pytest.approx(y, rel=1e-12, abs=1e-300), key
        else:
            assert x == y, key


def test_two_local_workers_give_the_datasheets_of_serial_fits(eight, tmp_path):
    from cylfric.pipeline import fit_campaign

    seen = []
    result = fit_many(eight, tmp_path / "par", workers=2, report=False, progress=seen.append)
    assert result.succeeded == 8 and result.failed == 0
    assert result.scheduler == "local process pool, 2 process(es)"
    assert sorted(r["campaign"] for r in seen) == [f"cyl{i:02d}" for i in range(8)]
    for i in range(8):
        name = f"cyl{i:02d}"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            serial = fit_campaign(eight / name, tmp_path / "serial" / name, name=name, report=False)
        parallel = json.loads((tmp_path / "par" / name / "datasheet.json").read_text())
        _same_sheets(parallel, serial.datasheet)
    summary = pd.read_csv(tmp_path / "par" / "fit_many.csv")
    assert list(summary.columns) == list(SUMMARY_COLUMNS)
    assert summary["status"].eq("ok").all() and summary["runs [-]"].eq(21).all()


def test_a_failing_campaign_is_reported_not_fatal(eight, tmp_path):
    root = tmp_path / "root"
    root.mkdir()
    for name in ("cyl00", "cyl01"):
        (root / name).symlink_to(eight / name)
    broken = root / "broken"
    broken.mkdir()
    (broken / "run_001.txt").write_text("this is not a bench file\n1;2;3\n")
    out = tmp_path / "out"
    done = CliRunner().invoke(
        app, ["fit-many", str(root), "--out", str(out), "--no-report", "-j", "2"]
    )
    assert done.exit_code == 0, done.output
    summary = pd.read_csv(out / "fit_many.csv").set_index("campaign")
    assert summary.loc["broken", "status"] == "failed"
    assert "run_001.txt" in summary.loc["broken", "reason"]
    assert summary.loc[["cyl00", "cyl01"], "status"].eq("ok").all()
    assert (out / "cyl00" / "datasheet.json").is_file() and not (out / "broken").exists()
    assert "2 of 3 fitted" in done.output and "failed" in done.output


def test_all_failing_exits_2(tmp_path):
    root = tmp_path / "root"
    for name in ("a", "b"):
        (root / name).mkdir(parents=True)
        (root / name / "x.txt").write_text("nothing numeric here\n")
    done = CliRunner().invoke(
        app, ["fit-many", str(root), "--out", str(tmp_path / "o"), "--scheduler", "serial"]
    )
    assert done.exit_code == 2, done.output
    assert pd.read_csv(tmp_path / "o" / "fit_many.csv")["status"].eq("failed").all()


def test_find_campaigns_walks_folders_of_folders(tmp_path):
    (tmp_path / "line1" / "cylA").mkdir(parents=True)
    (tmp_path / "line1" / "cylA" / "manifest.csv").write_text("file,pressure_bar,velocity_mm_s\n")
    (tmp_path / "line1" / "cylB").mkdir()
    (tmp_path / "line1" / "cylB" / "r.txt").write_text("")
    (tmp_path / ".hidden" / "c").mkdir(parents=True)
    (tmp_path / ".hidden" / "c" / "r.txt").write_text("")
    (tmp_path / "old-out" / "cylA").mkdir(parents=True)
    (tmp_path / "old-out" / "cylA" / ".cylfric-output").write_text("")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "fit_many.csv").write_text("")
    found = find_campaigns(tmp_path, exclude=[tmp_path / "out"])
    assert [p.relative_to(tmp_path).as_posix() for p in found] == ["line1/cylA", "line1/cylB"]
    with pytest.raises(ValueError, match="not a folder"):
        find_campaigns(tmp_path / "nope")


def test_results_go_into_the_catalogue(eight, tmp_path, monkeypatch):
    """The one touch point with cylfric.catalog (issue 15a): Catalog(db).add(path, name=)."""
    calls = []

    class Catalog:
        def __init__(self, db):
            self.db = db

        def add(self, path, *, name):
            if name == "cyl01":
                raise ValueError("name taken")
            calls.append((self.db, path, name))

    monkeypatch.setitem(sys.modules, "cylfric.catalog", types.SimpleNamespace(Catalog=Catalog))
    root = tmp_path / "root"
    root.mkdir()
    for name in ("cyl00", "cyl01"):
        (root / name).symlink_to(eight / name)
    db = tmp_path / "cat.sqlite"
    out = tmp_path / "out"
    result = fit_many(root, out, scheduler="serial", catalog=db, report=False)
    assert calls == [(db, out / "cyl00" / "datasheet.json", "cyl00")]
    summary = result.summary.set_index("campaign")
    assert summary.loc["cyl00", "catalog"] == "added"
    assert summary.loc["cyl01", "status"] == "ok"
    assert summary.loc["cyl01", "catalog"] == "not added: ValueError: name taken"


def test_a_distributed_scheduler_address(eight, tmp_path):
    from dask.distributed import LocalCluster

    root = tmp_path / "root"
    root.mkdir()
    (root / "cyl02").symlink_to(eight / "cyl02")
    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        address = cluster.scheduler_address
        result = fit_many(root, tmp_path / "out", scheduler=address, report=False)
    assert result.succeeded == 1
    assert result.scheduler == f"dask.distributed scheduler at {address}"
    with pytest.raises(ValueError, match="workers is set by the cluster"):
        fit_many(root, tmp_path / "out", scheduler="tcp://127.0.0.1:1", workers=2)


def test_bad_arguments(eight, tmp_path):
    with pytest.raises(ValueError, match="unknown fit options"):
        fit_many(eight, tmp_path / "o", report_figures=False)
    with pytest.raises(ValueError, match="no campaign folder found"):
        fit_many(tmp_path, tmp_path / "o")
    with pytest.raises(ValueError, match="inside the campaign folder"):
        fit_many(eight, eight / "cyl00" / "out")
    with pytest.raises(ValueError, match="at least 1"):
        fit_many(eight, tmp_path / "o", workers=0)
    done = CliRunner().invoke(app, ["fit-many", str(tmp_path / "nope"), "--out", str(tmp_path)])
    assert done.exit_code == 2 and "not a folder" in done.output


@pytest.mark.slow
def test_a_local_cluster(eight, tmp_path):
    root = tmp_path / "root"
    root.mkdir()
    (root / "cyl03").symlink_to(eight / "cyl03")
    result = fit_many(root, tmp_path / "out", scheduler="local-cluster", workers=1, report=False)
    assert result.succeeded == 1
    assert result.scheduler == "dask.distributed LocalCluster, 1 process(es)"
    sheet = json.loads((tmp_path / "out" / "cyl03" / "datasheet.json").read_text())
    assert sheet["name"] == "cyl03"


def test_fit_many_adds_each_datasheet_to_a_real_catalogue(eight, tmp_path):
    """The one touch point with cylfric.catalog (the two branches of issue 15 met here)."""
    from cylfric.catalog import Catalog

    root = tmp_path / "two"
    for name in ("cyl00", "cyl01"):
        (root / name).mkdir(parents=True)
        for path in (eight / name).iterdir():
            (root / name / path.name).write_bytes(path.read_bytes())
    db = tmp_path / "seals.sqlite"
    first = fit_many(
        root, tmp_path / "out", workers=1, scheduler="serial", catalog=db, report=False
    )
    assert list(first.summary["catalog"]) == ["added", "added"]
    assert sorted(Catalog(db).names()) == ["cyl00", "cyl01"]
    sheet = json.loads((tmp_path / "out" / "cyl01" / "datasheet.json").read_text())
    assert Catalog(db).get("cyl01")["parameters"] == sheet["parameters"]
    again = fit_many(
        root, tmp_path / "out2", workers=1, scheduler="serial", catalog=db, report=False
    )
    assert list(again.summary["status"]) == ["ok", "ok"]  # the fits stand ...
    assert all(c.startswith("not added") for c in again.summary["catalog"])  # ... reported


_COMMAND_SCRIPT = """
import sys, warnings
warnings.simplefilter("ignore")
from cylfric.many import fit_many
result = fit_many(sys.argv[1], sys.argv[2], workers=2, report=False)
print("fitted", result.succeeded)
loaded = ("numba", "scipy", "pandas", "dask", "cylfric.io")
print("loaded", [m for m in loaded if m in sys.modules])
"""


def test_the_calling_process_loads_no_reader_while_the_workers_fit(eight, tmp_path):
    """The caller of fit_many with local workers (a standard process pool) imports neither
    pandas, Dask nor the readers (numba, scipy): 0.3 s of processor time each at its start,
    and more at its exit (measured for issue 15); the workers import what a fit needs. Its
    fit_many.csv is still written atomically (cylfric._atomic, re-exported by io.writers)."""
    from cylfric._atomic import atomic_write_text
    from cylfric.io import writers

    assert writers.atomic_write_text is atomic_write_text
    root = tmp_path / "root"
    root.mkdir()
    for name in ("cyl00", "cyl01"):
        (root / name).symlink_to(eight / name)
    done = subprocess.run(
        [sys.executable, "-c", _COMMAND_SCRIPT, str(root), str(tmp_path / "out")],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "fitted 2" in done.stdout and "loaded []" in done.stdout, done.stdout
    summary = pd.read_csv(tmp_path / "out" / "fit_many.csv")
    assert list(summary["status"]) == ["ok", "ok"]


def test_the_summary_csv_reads_as_the_summary_frame():
    """fit_many.csv is written without pandas; read back it is the frame pandas writes."""
    import io

    from cylfric.many import ManyResult, _summary_csv

    ok = {
        "campaign": "a/cyl00",
        "status": "ok",
        "reason": "",
        "out": "o/a/cyl00",
        "runs [-]": 21,
        "excluded [-]": 0,
        "seconds [s]": 0.412,
        "cpu [s]": 0.398,
        "catalog": "added",
        "start [s]": 0.002,
        "worker": 4242,
    }
    failed = dict(
        ok,
        campaign="broken",
        status="failed",
        reason='run_001.txt, line 2: expected numbers, found "1;2;3"',
        **{"runs [-]": None, "excluded [-]": None, "catalog": ""},
    )
    lost = {"campaign": "c", "status": "failed", "reason": "lost", "out": "o/c", "catalog": ""}
    rows = [ok, failed, lost]
    result = ManyResult(rows, Path("o"), "serial", 1.0)
    assert (result.succeeded, result.failed) == (1, 2)
    back = pd.read_csv(io.StringIO(_summary_csv(rows)))
    expected = pd.read_csv(io.StringIO(result.summary.to_csv(index=False)))
    assert list(back.columns) == list(SUMMARY_COLUMNS)
    pd.testing.assert_frame_equal(back, expected)
    assert back.loc[1, "reason"] == failed["reason"]


def test_a_lone_campaign_is_fitted_on_every_core(tmp_path, monkeypatch):
    """fit-many gives fits that run side by side workers=1 (one core each); a single
    campaign runs alone, so its fit keeps the default workers (every core), not one."""
    import cylfric.pipeline as pipeline

    seen = []
    real = pipeline.fit_campaign

    def spy(folder, out, options=None, **keywords):
        seen.append(options.workers)
        return real(folder, out, options, **keywords)

    monkeypatch.setattr(pipeline, "fit_campaign", spy)
    lone = tmp_path / "lone"
    generate_campaign(lone / "cyl00", replace(SMALL, seed=0))
    fit_many(lone, tmp_path / "out1", workers=2, report=False)
    assert seen == [None]
