"""Parallel work in one place: a standard process pool, or plain serial where it does not pay.

Three things in cylfric run on several cores: the run files of one campaign
(:func:`cylfric.steady_state.extract_campaign`), the figures of a report
(:func:`cylfric.report.figures.render_all`) and whole campaigns
(:func:`cylfric.many.fit_many`). All of them use a
:class:`concurrent.futures.ProcessPoolExecutor`, through one of two functions:

- :func:`run`: ``[task(i) for i in range(n)]`` with workers forked from this process, or
  in this process where a pool would not pay or cannot be forked. A forked worker starts
  with everything this process has loaded (numpy, the campaign's configuration, the task
  itself, which may be a closure): only the index is pickled on the way in, nothing is
  imported again. Where forking is not available (Windows, macOS) or not safe (a process
  with other threads: a thread holding a lock at the fork leaves it locked in the child),
  the tasks run here, one after another.
- :func:`starmap`: ``[function(*a) for a in arguments]`` with a picklable module-level
  function, forked where it can, else started fresh (a notebook: its kernel runs threads).

On a Dask distributed cluster instead (``--scheduler tcp://host:8786``): :func:`connect`
to its scheduler, then :class:`ClusterPending` submits picklable module-level calls to its
workers (``cylfric fit``'s extraction; ``cylfric fit-many`` submits whole fits).

The results are the same whichever way the work ran.
"""

from __future__ import annotations

import gc
import multiprocessing
import os
import sys
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any

__all__ = [
    "ClusterPending",
    "Pending",
    "can_fork",
    "connect",
    "cores",
    "release_free_memory",
    "run",
    "start",
    "starmap",
]


def cores() -> int:
    """The processor cores this process may run on (>= 1): its CPU affinity where the
    system has one (``taskset``, a container's CPU set), else the machine's count. The
    default number of workers of ``cylfric fit``."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # no affinity (macOS, Windows)
        return os.cpu_count() or 1


def can_fork() -> bool:
    """Whether :func:`run` may fork workers here: on Linux, in a process without other
    threads that is not itself a daemonic worker (a ``multiprocessing.Pool``'s worker may
    not have children)."""
    return (
        sys.platform.startswith("linux")
        and threading.active_count() == 1
        and not multiprocessing.current_process().daemon
    )


def release_free_memory() -> None:
    """Give the free pages of the C heap back to the system (glibc's ``malloc_trim(0)``; a
    few milliseconds; nothing where the C library has no such call).

    Memory Python and numpy free stays in the process's heap, resident and counted in its
    PSS, until the heap reuses it; after a large step (the extraction's results unpacked,
    the identification's fits) and before a fork that would share it, that is some 20 MB at
    20,000 runs (benchmarks/bench_scale.py)."""
    global _malloc_trim
    if _malloc_trim is None:
        _malloc_trim = False
        if sys.platform.startswith("linux"):
            try:
                import ctypes

                _malloc_trim = getattr(ctypes.CDLL(None), "malloc_trim", False)
            except (ImportError, OSError):  # a Python without ctypes: no trim, no harm
                pass
            if _malloc_trim:
                _malloc_trim.argtypes, _malloc_trim.restype = [ctypes.c_size_t], ctypes.c_int
    if _malloc_trim:
        _malloc_trim(0)


_malloc_trim: Any = None
"""glibc's ``malloc_trim`` once looked up (False: none)."""


_task: Callable[[int], Any] | None = None
"""The task of the pool this worker belongs to (set in each worker by :func:`_install`)."""


def _install(task: Callable[[int], Any]) -> None:
    global _task
    _task = task


def _call(index: int) -> Any:
    assert _task is not None  # set by _install in each worker
    return _task(index)


def start(
    task: Callable[[int], Any],
    n: int,
    *,
    workers: int = 1,
    min_items: int = 2,
    done: Callable[[int, Any], object] | None = None,
    background: bool = False,
) -> Pending:
    """Start ``[task(i) for i in range(n)]`` in ``workers`` forked processes when that pays;
    :meth:`Pending.results` collects it.

    The workers start now and run while this process goes on with other work (``cylfric
    fit`` imports the identification meanwhile); without a pool (see :func:`run`) nothing
    runs until :meth:`Pending.results`, which then runs the tasks here. ``background``: one
    worker is a forked process too (not this process later), for work that this process's
    own meanwhile covers (then a single task, ``n = 1`` with ``min_items=1``, is forked
    too: one computation beside this process's own), where this process may run on a
    second core (:func:`cores`; else the task runs here, in :meth:`Pending.results`).
    Other parameters as :func:`run`.
    """
    pool = None
    fewest = max(min_items, 1 if background else 2)  # one background task is a fork too
    # a background worker beside this process's own work pays only with a second core
    beside = background and cores() >= 2
    if (workers >= 2 or beside) and workers >= 1 and n >= fewest and can_fork():
        pool = ProcessPoolExecutor(
            max_workers=min(workers, n),
            mp_context=multiprocessing.get_context("fork"),
            initializer=_install,
            initargs=(task,),  # inherited by the forked workers, not pickled
        )
        release_free_memory()  # pages freed but kept by the C heap would be shared too
        # the workers fork at the first submit, with this process's objects frozen until
        # the pool is shut down (Pending._thaw): a full collection writes into the header
        # of every object it visits, so without it the workers' collector, and this
        # process's while they live, copy each page they share (copy on write; about 35 MB
        # at 20,000 runs). Objects made meanwhile are collected as usual; only reference
        # cycles among the frozen wait. No second pool forks while one lives (its manager
        # thread: can_fork), so one freeze at a time.
        gc.freeze()
        try:
            return Pending(pool, _call, task, [(index,) for index in range(n)], done, frozen=True)
        except BaseException:
            pool.shutdown(wait=True, cancel_futures=True)
            gc.unfreeze()
            raise
    return Pending(pool, _call, task, [(index,) for index in range(n)], done)


def run(
    task: Callable[[int], Any],
    n: int,
    *,
    workers: int = 1,
    min_items: int = 2,
    done: Callable[[int, Any], object] | None = None,
) -> list:
    """``[task(i) for i in range(n)]``, in ``workers`` forked processes when that pays.

    Parameters
    ----------
    task : callable
        ``task(index)`` for index 0..n-1; any callable (a closure too: the workers are
        forked, so it is not pickled). Its return value is pickled back.
    n : int
        Number of items.
    workers : int
        Worker processes; 1 (or ``n < min_items``, or no :func:`can_fork`) runs every task
        in this process, one after another.
    min_items : int
        Fewest items for which a pool is started: below it, starting the workers costs more
        than they save (the callers say where they measured their threshold).
    done : callable, optional
        ``done(index, result)`` in this process as each task finishes (in the order they
        finish).

    Returns
    -------
    list
        The results, in index order. An exception raised by a task is raised here (the
        tasks not yet started are cancelled). The tasks a dead worker (a crash, a signal)
        left unfinished are run here.
    """
    return start(task, n, workers=workers, min_items=min_items, done=done).results()


def starmap(
    function: Callable[..., Any],
    arguments: Sequence[tuple],
    *,
    workers: int,
    done: Callable[[int, Any], object] | None = None,
) -> list:
    """``[function(*a) for a in arguments]`` on a pool of ``workers`` processes.

    Unlike :func:`run` it needs no fork: ``function`` (a module-level function) and its
    ``arguments`` are pickled, so where this process cannot fork (a notebook's kernel runs
    threads; Windows, macOS) the workers are started fresh (``forkserver`` or ``spawn``,
    which run the calling script's main module again: guard it with
    ``if __name__ == "__main__":``). ``done(index, result)`` as each call finishes;
    results in order. When a worker dies (a crash, a signal, memory), the calls the pool
    had not finished are not run again (they might kill this process too): their results
    are None. ``workers`` < 2: serial, here.
    """
    pool = None
    if workers >= 2 and len(arguments) >= 2:
        methods = multiprocessing.get_all_start_methods()
        fresh = "forkserver" if "forkserver" in methods else "spawn"
        method = "fork" if "fork" in methods and can_fork() else fresh
        pool = ProcessPoolExecutor(
            max_workers=min(workers, len(arguments)),
            mp_context=multiprocessing.get_context(method),
        )
    return Pending(pool, function, None if pool else function, list(arguments), done).results()


class Pending:
    """Calls submitted to a pool (or to be run here); :meth:`results` waits for them."""

    def __init__(self, pool, remote, local, arguments, done, frozen=False) -> None:
        # ``remote(*a)`` on ``pool`` (None: no pool) for each ``a``; what the pool does not
        # finish, ``local(*a)`` here (None: left as None)
        self._pool, self._local, self._done = pool, local, done
        self._frozen = frozen  # this process's objects frozen for the pool's life (start)
        self._arguments = arguments
        self._futures = (
            {pool.submit(remote, *a): index for index, a in enumerate(arguments)}
            if pool is not None
            else {}
        )

    def close(self) -> None:
        """Cancel what has not started and wait for the running calls (after
        :meth:`results`, nothing to do)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._thaw()

    def _thaw(self) -> None:
        """The pool is shut down: nothing shares this process's pages any more."""
        if getattr(self, "_frozen", False):
            self._frozen = False
            gc.unfreeze()

    def __del__(self) -> None:
        # dropped without close() or results(): its pool goes with it, so thaw here (else
        # this process's reference cycles among the frozen would wait for the next pool)
        self._thaw()

    def results(self) -> list:
        """The results in order (once; a second call is a RuntimeError)."""
        if self._arguments is None:
            raise RuntimeError("these results were collected already")
        arguments, done, self._arguments = self._arguments, self._done, None
        n = len(arguments)
        results: list = [None] * n
        finished = [False] * n
        if self._pool is not None:
            try:
                for future in as_completed(self._futures):
                    index = self._futures[future]
                    results[index], finished[index] = future.result(), True
                    if done is not None:
                        done(index, results[index])
            except BrokenProcessPool:
                pass  # a worker died: what the pool had not finished is run below
            finally:
                self._pool.shutdown(wait=True, cancel_futures=True)
                self._thaw()
        for index in range(n):
            if not finished[index] and self._local is not None:
                results[index] = self._local(*arguments[index])
                if done is not None:
                    done(index, results[index])
        return results


SCHEDULER_TIMEOUT = 30.0
"""Seconds :func:`connect` waits in all for a scheduler: the connection, its first answer
and the client's start (a server that accepts and never answers had hung ``fit
--scheduler`` for more than 300 s)."""


def require_dask(what: str) -> None:
    """ValueError naming ``what`` and the install command when Dask's distributed scheduler
    (the optional extra ``cluster``) is not installed: only ``--scheduler`` and fit-many's
    ``local-cluster`` / ``tcp://`` schedulers need it."""
    import importlib.util

    if importlib.util.find_spec("distributed") is None:
        raise ValueError(
            f"{what} needs Dask's distributed scheduler, which is not installed; install the "
            "extra: pip install 'cylfric[cluster]'"
        )


def _scheduler_host_port(address: str) -> tuple[str, str, int]:
    """(scheme, host, port) of a scheduler address; ValueError naming it when it is not
    one (a port outside 1-65535 among them)."""
    require_dask(f"scheduler {address!r}")
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port

    try:
        if "://" not in address and ":" not in address:  # a word, not host:port
            raise ValueError("no scheme and no port")
        scheme, location = parse_address(address)
        host, port = parse_host_port(location, default_port=8786)
    except (ValueError, TypeError) as exc:
        raise ValueError(
            f"scheduler {address!r}: not a Dask scheduler address ({exc}); expected e.g. "
            "tcp://10.0.0.5:8786"
        ) from None
    if not 0 < int(port) < 65536:
        raise ValueError(
            f"scheduler {address!r}: port {port} is not a TCP port (1-65535); expected e.g. "
            "tcp://10.0.0.5:8786"
        )
    return scheme, host, int(port)


def _probe(address: str, host: str, port: int, deadline: float, timeout: float) -> None:
    """Wait until ``deadline`` (time.monotonic) for the server at ``host:port`` to speak
    first, as a Dask scheduler does (it sends its handshake when a connection opens); a
    refused connection, silence or a closed connection is a ValueError naming the address."""
    import socket
    import time

    def remaining() -> float:
        return max(deadline - time.monotonic(), 0.001)

    try:
        with socket.create_connection((host, port), timeout=remaining()) as sock:
            sock.settimeout(remaining())
            greeting = sock.recv(1)
    except TimeoutError:
        raise ValueError(
            f"scheduler {address}: no Dask scheduler answered within {timeout:g} s "
            "(the server there accepts connections but says nothing); check the address"
        ) from None
    except OSError as exc:
        raise ValueError(
            f"scheduler {address}: no Dask scheduler answered ({exc.strerror or exc}); start "
            "one there (`dask scheduler`) or check the address"
        ) from None
    if not greeting:
        raise ValueError(
            f"scheduler {address}: the server closed the connection without answering; "
            "expected a Dask scheduler there (`dask scheduler`)"
        )


def connect(address: str, timeout: float = SCHEDULER_TIMEOUT) -> Any:
    """A ``dask.distributed.Client`` of the scheduler at ``address`` (``tcp://host:8786``).

    Raises ValueError naming the address when it is not a scheduler address (a port outside
    1-65535), no scheduler answers there within ``timeout`` seconds in all (the TCP
    connection, the scheduler's first answer and the client's start; a ``tcp://`` server is
    first asked with a plain socket, so one that accepts and never answers cannot hold the
    command), or when the scheduler has no worker.
    """
    import time

    from dask.distributed import Client

    deadline = time.monotonic() + timeout
    scheme, host, port = _scheduler_host_port(address)
    if scheme == "tcp":
        _probe(address, host, port, deadline, timeout)
    try:
        client = Client(address, timeout=max(deadline - time.monotonic(), 1.0))
    except OSError as exc:  # TimeoutError, a refused connection
        raise ValueError(
            f"scheduler {address}: no Dask scheduler answered ({exc}); start one there "
            "(`dask scheduler`) or check the address"
        ) from None
    except (ValueError, TypeError) as exc:
        raise ValueError(
            f"scheduler {address!r}: not a Dask scheduler address ({exc}); expected e.g. "
            "tcp://10.0.0.5:8786"
        ) from None
    if not client.nthreads():
        client.close()
        raise ValueError(
            f"scheduler {address}: no worker is connected; start some (`dask worker {address}`)"
        )
    return client


class ClusterPending:
    """Calls submitted to a Dask cluster: ``function(*a)`` for each ``a`` of ``arguments``
    (a picklable module-level function; each ``a`` pickled to a worker, each result
    pickled back). :meth:`results` gathers them in order and closes ``client``.

    A worker lost with its tasks: the scheduler runs them on another (Dask's own
    retries); an exception raised by a call is raised by :meth:`results`.
    """

    def __init__(self, client, function, arguments, done=None) -> None:
        self._client, self._done = client, done
        self._futures = [client.submit(function, *a, pure=False) for a in arguments]

    def close(self) -> None:
        """Cancel what has not finished and close the client."""
        if self._client is not None:
            self._client.cancel(self._futures)
            self._client.close()
            self._client = None

    def results(self) -> list:
        """The results in order; ``done(index, result)`` as each call finishes."""
        from dask.distributed import as_completed

        if self._client is None:
            raise RuntimeError("these results were collected already")
        index = {future.key: i for i, future in enumerate(self._futures)}
        results: list = [None] * len(self._futures)
        try:
            for future in as_completed(self._futures):
                i = index[future.key]
                results[i] = future.result()
                if self._done is not None:
                    self._done(i, results[i])
        finally:
            self.close()
        return results
