"""fit-many on a real Dask distributed cluster (issue 27): a scheduler and two workers
started as separate processes with the ``dask`` command, as on a shared machine; the
datasheets equal the serial fits'."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import pytest
from test_many import SMALL, _same_sheets

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


@pytest.mark.skipif(not DASK.is_file(), reason="the dask command is not installed")
def test_fit_many_on_a_scheduler_and_two_worker_processes(tmp_path):
    root = tmp_path / "line"
    for i in range(4):
        generate_campaign(root / f"cyl{i:02d}", replace(SMALL, seed=20 + i))
    serial = fit_many(root, tmp_path / "serial", scheduler="serial", report=False)
    assert serial.succeeded == 4
    with _cluster(tmp_path) as (address, client):
        done = subprocess.run(
            [sys.executable, "-m", "cylfric", "fit-many", str(root), "--out",
             str(tmp_path / "cluster"), "--scheduler", address, "--no-report", "--json"],
            capture_output=True, text=True, timeout=600,
        )  # fmt: skip
        assert done.returncode == 0, done.stderr
        document = json.loads(done.stdout)
        # the fits ran in the two workers' processes, not in the command's
        executed = client.run(lambda dask_worker: dask_worker.state.executed_count)
    assert len(executed) == 2 and sum(executed.values()) == 4, executed
    assert document["scheduler"] == f"dask.distributed scheduler at {address}"
    assert {row["status"] for row in document["campaigns"]} == {"ok"}
    for i in range(4):
        name = f"cyl{i:02d}"
        _same_sheets(
            json.loads((tmp_path / "serial" / name / "datasheet.json").read_text()),
            json.loads((tmp_path / "cluster" / name / "datasheet.json").read_text()),
        )
