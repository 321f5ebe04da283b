"""cylfric._parallel (issue 24): one standard pool for all parallel work, the same results
as serial, and what happens when a worker dies or a task raises."""

from __future__ import annotations

import json
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
def test_a_background_start_runs_one_worker_in_another_process(monkeypatch):
    """start(background=True) with one worker: a forked process (the caller goes on with its
    own work meanwhile), one process for every task; without it, one worker means here."""
    monkeypatch.setattr(_parallel, "cores", lambda: 2)  # a second core (else: here)
    here = os.getpid()
    pids = _parallel.start(lambda i: os.getpid(), 6, workers=1, background=True).results()
    assert here not in pids and len(set(pids)) == 1
    assert _parallel.start(lambda i: os.getpid(), 6, workers=1).results() == [here] * 6


def test_few_files_are_read_by_one_forked_reader_many_by_several(tmp_path, monkeypatch):
    """Below TWO_READERS_MIN_FILES the extraction starts one background reader; from it on,
    the first file is read here and ``workers`` readers share the rest."""
    from cylfric import steady_state

    _small_campaign(tmp_path / "c")
    calls = []
    real = steady_state.start

    def spy(task, n, **keywords):
        calls.append(keywords)
        return real(task, n, **keywords)

    monkeypatch.setattr(steady_state, "start", spy)
    monkeypatch.setattr(steady_state, "cores", lambda: 2)  # the default workers: 2 here
    monkeypatch.setattr(steady_state, "TWO_READERS_MIN_FILES", 1000)
    few = steady_state.start_extraction(tmp_path / "c").result()
    monkeypatch.setattr(steady_state, "TWO_READERS_MIN_FILES", 10)
    many = steady_state.start_extraction(tmp_path / "c").result()
    assert calls[0]["workers"] == 1 and calls[0]["background"] is True
    assert calls[1]["workers"] == 2 and calls[1]["background"] is False
    assert few.points.equals(many.points)  # the same table either way


@needs_fork
def test_one_background_task_is_forked_and_its_result_comes_back(monkeypatch):
    """start(task, 1, min_items=1, background=True): one computation in a forked process
    beside this one (the sensitivity study, points.csv); its exception is raised here."""
    monkeypatch.setattr(_parallel, "cores", lambda: 2)  # a second core (else: here)
    here = os.getpid()
    assert _parallel.start(lambda i: os.getpid(), 1, min_items=1, background=True).results() != [
        here
    ]
    assert _parallel.start(lambda i: os.getpid(), 1, background=True).results() == [here]

    def fails(i):
        raise OSError(28, "No space left on device")

    with pytest.raises(OSError, match="No space left"):
        _parallel.start(fails, 1, min_items=1, background=True).results()


@needs_fork
def test_the_sensitivity_study_and_points_csv_from_forked_processes_equal_serial(
    tmp_path, monkeypatch
):
    """The after-extraction overlap (issue 27): identify's sensitivity study in a forked
    process while the models are fitted here, points.csv written by one while the datasheet
    is built here. Forced on a small campaign (thresholds at 1), the outputs are byte for
    byte those of the serial path (thresholds out of reach), and both forks happened."""
    from cylfric import pipeline
    from cylfric.identify import steady

    _small_campaign(tmp_path / "c")
    forked = _count_forks(monkeypatch)
    monkeypatch.setattr(_parallel, "cores", lambda: 2)  # the forks need a second core
    outputs = {}
    for mode, threshold in (("serial", 10**9), ("forked", 1)):
        monkeypatch.setattr(steady, "STUDY_FORK_MIN_POINTS", threshold)
        monkeypatch.setattr(pipeline, "BACKGROUND_CSV_MIN_ROWS", threshold)
        forked.clear()
        result = pipeline.fit_campaign(tmp_path / "c", tmp_path / mode, report=False)
        outputs[mode] = result
        if mode == "forked":
            assert forked.count(True) == 2  # the study, points.csv
    for name in ("points.csv", "per_pressure.csv", "sensitivity.csv", "law_comparison.csv"):
        assert (tmp_path / "serial" / name).read_bytes() == (
            tmp_path / "forked" / name
        ).read_bytes()
    serial, fork = outputs["serial"].identification, outputs["forked"].identification
    assert serial.sensitivity.equals(fork.sensitivity) and serial.grid.equals(fork.grid)
    assert serial.recommended == fork.recommended and serial.notes == fork.notes
    assert [r["rmse [N]"] for r in serial.sensitivity_refits] == [
        r["rmse [N]"] for r in fork.sensitivity_refits
    ]
    sheets = [json.loads((tmp_path / mode / "datasheet.json").read_text()) for mode in outputs]
    for sheet in sheets:
        sheet.pop("created")
    assert sheets[0] == sheets[1]


@needs_fork
def test_one_core_or_workers_1_keeps_the_fit_in_this_process(tmp_path, monkeypatch):
    """With one usable core (an affinity of one CPU, :func:`_parallel.cores`) a background
    task runs here and the extraction reads serially by default; ``workers=1`` (fit-many's
    fits) forks neither the study nor points.csv even where both would pay."""
    from cylfric import pipeline, steady_state
    from cylfric.identify import steady

    assert _parallel.cores() >= 1
    if hasattr(os, "sched_getaffinity"):
        assert _parallel.cores() == len(os.sched_getaffinity(0))
    monkeypatch.setattr(_parallel, "cores", lambda: 1)
    monkeypatch.setattr(steady_state, "cores", lambda: 1)  # imported by name there
    here = os.getpid()
    assert _parallel.start(lambda i: os.getpid(), 1, min_items=1, background=True).results() == [
        here
    ]
    assert steady_state._readers(5000, None)[:2] == (1, False)  # one reader, no pool
    monkeypatch.undo()

    _small_campaign(tmp_path / "c")
    forked = _count_forks(monkeypatch)
    monkeypatch.setattr(steady, "STUDY_FORK_MIN_POINTS", 1)
    monkeypatch.setattr(pipeline, "BACKGROUND_CSV_MIN_ROWS", 1)
    pipeline.fit_campaign(tmp_path / "c", tmp_path / "one", report=False, workers=1)
    assert forked and not any(forked)


def _in_a_daemonic_worker(_):
    """(can_fork, every task ran in this process) inside a multiprocessing.Pool worker."""
    here = os.getpid()
    pids = _parallel.start(lambda i: os.getpid(), 3, workers=2).results()
    alone = _parallel.start(lambda i: os.getpid(), 1, min_items=1, background=True).results()
    return _parallel.can_fork(), pids + alone == [here] * 4


@needs_fork
def test_a_daemonic_pool_worker_forks_nothing():
    """A multiprocessing.Pool worker (daemonic: it may not have children) runs the tasks
    itself: identify's background study or an extraction there does not fail."""
    import multiprocessing

    with multiprocessing.get_context("fork").Pool(1) as pool:
        assert pool.map(_in_a_daemonic_worker, [0]) == [(False, True)]


def test_many_cores_do_not_fork_a_reader_per_handful_of_files(monkeypatch):
    """With 64 cores the extraction still gives each reader at least half of
    TWO_READERS_MIN_FILES files (forking one costs more than it reads below that)."""
    from cylfric import steady_state

    monkeypatch.setattr(steady_state, "cores", lambda: 64)
    half = steady_state.TWO_READERS_MIN_FILES // 2
    assert steady_state._readers(20, None)[:3] == (1, True, True)  # one background reader
    assert steady_state._readers(2 * half, None)[0] == 2
    assert steady_state._readers(1000, None)[0] == 1000 // half
    assert steady_state._readers(20_000, None)[0] == 64


def _small_campaign(folder):
    """A clean virtual campaign of 2 pressures x 10 speeds in ``folder``."""
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    generate_campaign(
        folder, BenchSettings.clean(pressures_bar=(20.0, 80.0), speeds_mm_s=tuple(range(1, 11)))
    )


def _count_forks(monkeypatch) -> list[bool]:
    """Watch ``_parallel.start``: the list gets, per call, whether it forked a pool."""
    forked: list[bool] = []
    real = _parallel.start

    def spy(task, n, **keywords):
        pending = real(task, n, **keywords)
        forked.append(pending._pool is not None)
        return pending

    monkeypatch.setattr(_parallel, "start", spy)
    return forked


def _resident_mb() -> float:
    with open("/proc/self/statm") as handle:
        return int(handle.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e6


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="needs Linux's /proc")
def test_release_free_memory_gives_freed_heap_pages_back():
    """Memory freed by numpy stays resident in the C heap (and would be shared by a fork)
    until release_free_memory gives it back; nothing alive is touched."""
    import ctypes

    import numpy as np

    if not hasattr(ctypes.CDLL(None), "malloc_trim"):
        pytest.skip("the C library has no malloc_trim (not glibc)")
    if any(name in os.environ.get("LD_PRELOAD", "") for name in ("jemalloc", "tcmalloc")):
        pytest.skip("another allocator preloaded: glibc's heap is not the one used")
    _parallel.release_free_memory()
    kept = np.arange(1000.0)
    blocks = [np.ones(1024) for _ in range(60_000)]  # 8 kB each: the heap, not mmap
    blocks = blocks[::2]  # half freed, interleaved with live ones: no trim at the top
    before = _resident_mb()
    blocks = blocks[-1:]
    freed = _resident_mb()
    _parallel.release_free_memory()
    after = _resident_mb()
    assert before - after > 150  # about 490 MB allocated, then half, then all but one freed
    assert freed - after > 100  # the freed pages were still resident before the call
    assert kept.sum() == 499500.0 and blocks[0].sum() == 1024.0


def test_a_missing_dask_is_named_with_the_extra_to_install(monkeypatch):
    """Dask is the optional extra 'cluster' (issue 42.7): without it, --scheduler and
    fit-many's cluster schedulers say what to install instead of an ImportError."""
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util,
        "find_spec",
        lambda name, *a, **k: None if name == "distributed" else real(name, *a, **k),
    )
    from cylfric.many import _run_distributed

    with pytest.raises(
        ValueError, match=r"local-cluster needs Dask.*pip install 'cylfric\[cluster\]'"
    ):
        _run_distributed([], "local-cluster", 1, print)
    from cylfric._parallel import connect

    with pytest.raises(ValueError, match=r"pip install 'cylfric\[cluster\]'"):
        connect("tcp://127.0.0.1:8786", timeout=1)
