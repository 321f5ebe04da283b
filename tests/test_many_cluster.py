"""fit-many and fit on a real Dask distributed cluster (issue 27): a scheduler and two
workers started as separate processes with the ``dask`` command, as on a shared machine;
the datasheets equal the serial fits' (fit-many: one campaign per task; fit: one campaign's
files split in tasks over the workers)."""

from __future__ import annotations

import contextlib
import json
import os
import re
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest
from test_many import SMALL, _same_sheets
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.many import fit_many
from cylfric.simulate.bench import generate_campaign

DASK = Path(sys.executable).with_name("dask")


@contextlib.contextmanager
def _cluster(folder: Path, workers: int = 2):
    """A scheduler and ``workers`` worker processes (one thread each), torn down after."""
    scheduler_file = folder / "scheduler.json"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    procs = [
        subprocess.Popen(
            [str(DASK), "scheduler", "--port", "0", "--no-dashboard",
             "--scheduler-file", str(scheduler_file)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
        )
    ]  # fmt: skip
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.is_file() and time.monotonic() < deadline:
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        for i in range(workers):
            procs.append(
                subprocess.Popen(
                    [str(DASK), "worker", "--scheduler-file", str(scheduler_file),
                     "--nthreads", "1", "--nworkers", "1", "--no-dashboard",
                     "--name", f"w{i}", "--local-directory", str(folder / f"w{i}")],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env,
                )
            )  # fmt: skip
        from dask.distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(workers, timeout=120)
            yield address, client
    finally:
        for proc in reversed(procs):
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


needs_dask = pytest.mark.skipif(not DASK.is_file(), reason="the dask command is not installed")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """(address, client) of a scheduler and two worker processes shared by the tests."""
    with _cluster(tmp_path_factory.mktemp("cluster")) as (address, client):
        yield address, client


def _executed(client) -> dict:
    """Tasks each worker has run so far [-]."""
    return client.run(lambda dask_worker: dask_worker.state.executed_count)


@needs_dask
def test_fit_many_on_a_scheduler_and_two_worker_processes(tmp_path, cluster):
    address, client = cluster
    root = tmp_path / "line"
    for i in range(4):
        generate_campaign(root / f"cyl{i:02d}", replace(SMALL, seed=20 + i))
    serial = fit_many(root, tmp_path / "serial", scheduler="serial", report=False)
    assert serial.succeeded == 4
    before = _executed(client)
    done = subprocess.run(
        [sys.executable, "-m", "cylfric", "fit-many", str(root), "--out",
         str(tmp_path / "cluster"), "--scheduler", address, "--no-report", "--json"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    # the fits ran in the two workers' processes, not in the command's
    executed = _executed(client)
    assert len(executed) == 2 and sum(executed.values()) - sum(before.values()) == 4, executed
    assert document["scheduler"] == f"dask.distributed scheduler at {address}"
    assert {row["status"] for row in document["campaigns"]} == {"ok"}
    for i in range(4):
        name = f"cyl{i:02d}"
        _same_sheets(
            json.loads((tmp_path / "serial" / name / "datasheet.json").read_text()),
            json.loads((tmp_path / "cluster" / name / "datasheet.json").read_text()),
        )


def _undated(path: Path) -> str:
    """A file's text without the datasheet's creation time."""
    return re.sub(r'"created": "[^"]*"', '"created": ""', path.read_text())


@needs_dask
def test_one_campaign_split_over_the_workers(tmp_path, cluster):
    address, client = cluster
    generate_campaign(tmp_path / "line" / "cyl00", replace(SMALL, seed=31))
    outputs = {}
    for label, extra in (("local", []), ("cluster", ["--scheduler", address])):
        before = _executed(client)
        # a relative folder: the workers read it under the command's working folder
        done = subprocess.run(
            [sys.executable, "-m", "cylfric", "fit", "line/cyl00", "--out", label,
             "--no-report", *extra],
            capture_output=True, text=True, timeout=600, cwd=tmp_path,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        ran = {w: n - before[w] for w, n in _executed(client).items()}
        outputs[label] = {
            name: _undated(tmp_path / label / name) for name in ("datasheet.json", "points.csv")
        }
        if label == "local":
            assert sum(ran.values()) == 0, ran
        else:  # 21 files in tasks of 2 (chunk_size for 2 threads), on both workers
            assert sum(ran.values()) == 11 and min(ran.values()) > 0, ran
    assert outputs["cluster"] == outputs["local"]
    assert "line/cyl00/run_000" in outputs["cluster"]["points.csv"]  # named as given


@needs_dask
@pytest.mark.parametrize(
    ("address", "expected"),
    [
        ("tcp://127.0.0.1:1", "scheduler tcp://127.0.0.1:1: no Dask scheduler answered"),
        ("nonsense", "scheduler 'nonsense': not a Dask scheduler address"),
    ],
)
def test_a_bad_scheduler_address_is_named(tmp_path, address, expected):
    import dask

    generate_campaign(tmp_path / "cyl", replace(SMALL, seed=32))
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        done = CliRunner().invoke(
            app, ["fit", str(tmp_path / "cyl"), "--out", str(tmp_path / "o"), "--no-report",
                  "--scheduler", address],
        )  # fmt: skip
    assert done.exit_code == 2, done.output
    assert expected in " ".join(done.output.split())
    assert "Traceback" not in done.output
