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
