"""Forked workers and shared memory (issue 27): the pool forks with this process's objects
frozen (their garbage collector leaves the shared pages alone), and this process's collector
works as before afterwards."""

from __future__ import annotations

import gc

from fit_helpers import needs_fork

from cylfric._parallel import start


def _frozen_in_worker(_index):
    return gc.get_freeze_count()


@needs_fork
def test_workers_start_with_the_objects_frozen_and_this_process_does_not_stay_frozen():
    assert gc.get_freeze_count() == 0
    pending = start(_frozen_in_worker, 4, workers=2)
    assert gc.get_freeze_count() == 0  # unfrozen here once the workers are forked
    frozen = pending.results()
    assert all(count > 1000 for count in frozen)  # the workers' inherited objects
