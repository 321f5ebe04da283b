"""Forked workers and shared memory (issue 27): the pool forks with this process's objects
frozen, and they stay frozen until the pool is shut down: neither the workers' garbage
collector nor this process's, while workers share its pages, writes into (and so copies)
them; this process's collector works as before afterwards."""

from __future__ import annotations

import gc
import os
import time

from fit_helpers import needs_fork

from cylfric import _parallel


def _frozen_in_worker(_index):
    time.sleep(0.02)
    return gc.get_freeze_count()


@needs_fork
def test_this_process_stays_frozen_while_forked_workers_share_its_pages():
    """Frozen from the fork until the pool is shut down (results or close); new objects are
    still collected meanwhile; no second pool forks while one lives (one freeze at a time)."""
    assert gc.get_freeze_count() == 0
    pending = _parallel.start(_frozen_in_worker, 4, workers=2)
    frozen = gc.get_freeze_count()
    assert frozen > 1000  # this process's objects, while the workers share their pages
    gc.collect()
    assert gc.get_freeze_count() == frozen  # a full collection meanwhile leaves them alone
    cycle: list = []
    cycle.append(cycle)
    del cycle
    assert gc.collect() >= 1  # garbage made after the fork is collected as usual
    # no second pool forks while one lives (its manager thread): here, serially
    assert _parallel.start(lambda i: os.getpid(), 3, workers=2).results() == [os.getpid()] * 3
    assert gc.get_freeze_count() == frozen
    in_workers = pending.results()
    assert all(count > 1000 for count in in_workers)  # the workers' inherited objects
    assert gc.get_freeze_count() == 0  # the pool shut down: thawed
    dropped = _parallel.start(lambda i: time.sleep(0.05) or i, 40, workers=2)
    assert gc.get_freeze_count() > 0
    dropped.close()
    assert gc.get_freeze_count() == 0  # closed early: thawed too
    assert _parallel.start(lambda i: i, 3, workers=1).results() == [0, 1, 2]
    assert gc.get_freeze_count() == 0  # no pool, nothing frozen


@needs_fork
def test_a_pending_dropped_without_close_thaws():
    pending = _parallel.start(_frozen_in_worker, 4, workers=2)
    assert gc.get_freeze_count() > 0
    del pending  # its pool goes with it
    gc.collect()
    assert gc.get_freeze_count() == 0
