"""cylfric._parallel (issue 24): one standard pool for all parallel work, the same results
as serial, and what happens when a worker dies or a task raises."""

from __future__ import annotations

import os
import threading

import pytest
from fit_helpers import needs_fork

from cylfric import _parallel
from cylfric._parallel import can_fork, run, starmap


def _square(x):
    return x * x, os.getpid()


@needs_fork
def test_run_gives_the_serial_results_in_order_from_forked_workers():
    offset = 7  # a closure: forked workers inherit it, nothing is pickled but the index
    seen = []
    results = run(
        lambda i: (i + offset, os.getpid()), 40, workers=2, done=lambda i, r: seen.append(i)
    )
    assert [value for value, _ in results] == [i + offset for i in range(40)]
    assert os.getpid() not in {pid for _, pid in results}  # every task ran in a worker
    assert sorted(seen) == list(range(40))  # done() once per task, in this process


def test_run_stays_serial_below_its_threshold_with_one_worker_or_other_threads():
    here = os.getpid()
    assert run(lambda i: os.getpid(), 3, workers=2, min_items=4) == [here] * 3
    assert run(lambda i: os.getpid(), 5, workers=1) == [here] * 5
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        assert not can_fork()  # a thread could hold a lock at the fork
        assert run(lambda i: os.getpid(), 5, workers=2) == [here] * 5
    finally:
        stop.set()
        thread.join()


@needs_fork
def test_run_does_here_what_a_dead_worker_left():
    parent = os.getpid()

    def task(i):
        if i == 3 and os.getpid() != parent:
            os._exit(9)  # the worker dies while running task 3
        return i, os.getpid()

    results = run(task, 12, workers=2)
    assert [i for i, _ in results] == list(range(12))
    assert results[3][1] == parent  # run again here


@needs_fork
def test_run_raises_a_tasks_exception():
    def task(i):
        if i == 5:
            raise ValueError("file 5 is bad")
        return i

    with pytest.raises(ValueError, match="file 5 is bad"):
        run(task, 20, workers=2)


def test_starmap_gives_the_serial_results_in_order():
    rows = []
    results = starmap(
        _square, [(i,) for i in range(6)], workers=2, done=lambda i, r: rows.append(i)
    )
    assert [value for value, _ in results] == [i * i for i in range(6)]
    assert sorted(rows) == list(range(6))
    assert starmap(_square, [(3,)], workers=2) == [(9, os.getpid())]  # one call: here


def test_the_worker_task_is_installed_only_in_workers():
    assert _parallel._task is None


@needs_fork
def test_start_runs_the_tasks_while_the_caller_works_and_close_stops_them(tmp_path):
    """`start` puts the workers to work at once (pipeline._fit imports the next steps
    meanwhile); `close` drops what has not started; a serial start runs nothing until
    `results`."""
    import time

    from cylfric._parallel import start

    def task(i):
        (tmp_path / f"{i}.started").touch()
        time.sleep(0.05)
        return i

    pending = start(task, 4, workers=2)
    deadline = time.monotonic() + 20
    while not list(tmp_path.glob("*.started")) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert list(tmp_path.glob("*.started"))  # started before results() was asked for
    assert pending.results() == [0, 1, 2, 3]
    with pytest.raises(RuntimeError, match="collected already"):
        pending.results()

    for path in tmp_path.glob("*.started"):
        path.unlink()
    lazy = start(task, 3, workers=1)
    assert not list(tmp_path.glob("*.started"))  # serial: nothing runs before results()
    assert lazy.results() == [0, 1, 2]

    for path in tmp_path.glob("*.started"):
        path.unlink()
    dropped = start(task, 200, workers=2)
    dropped.close()  # the running ones finish, the queued rest is cancelled
    assert len(list(tmp_path.glob("*.started"))) < 200


@needs_fork
def test_a_background_start_runs_one_worker_in_another_process():
    """start(background=True) with one worker: a forked process (the caller goes on with its
    own work meanwhile), one process for every task; without it, one worker means here."""
    here = os.getpid()
    pids = _parallel.start(lambda i: os.getpid(), 6, workers=1, background=True).results()
    assert here not in pids and len(set(pids)) == 1
    assert _parallel.start(lambda i: os.getpid(), 6, workers=1).results() == [here] * 6


def test_few_files_are_read_by_one_forked_reader_many_by_several(tmp_path, monkeypatch):
    """Below TWO_READERS_MIN_FILES the extraction starts one background reader; from it on,
    the first file is read here and ``workers`` readers share the rest."""
    from cylfric import steady_state
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    generate_campaign(
        tmp_path / "c",
        BenchSettings.clean(pressures_bar=(20.0, 80.0), speeds_mm_s=tuple(range(1, 11))),
    )
    calls = []
    real = steady_state.start

    def spy(task, n, **keywords):
        calls.append(keywords)
        return real(task, n, **keywords)

    monkeypatch.setattr(steady_state, "start", spy)
    monkeypatch.setattr(steady_state, "TWO_READERS_MIN_FILES", 1000)
    few = steady_state.start_extraction(tmp_path / "c").result()
    monkeypatch.setattr(steady_state, "TWO_READERS_MIN_FILES", 10)
    many = steady_state.start_extraction(tmp_path / "c").result()
    assert calls[0]["workers"] == 1 and calls[0]["background"] is True
    assert calls[1]["workers"] == 2 and calls[1]["background"] is False
    assert few.points.equals(many.points)  # the same table either way
