"""What ``cylfric fit-many``'s worker server preloads (see :func:`cylfric.many.fit_many`).

The local workers of :func:`cylfric.many.fit_many` are forked from a server process (a
``multiprocessing`` fork server) that imports this module once, before it forks any worker:

- :mod:`cylfric._warm`: everything a fit needs, its compiled code loaded (about 1.3-1.45 s of
  processor time, paid once instead of once per worker);
- :mod:`cylfric.many` (the task every worker runs) and :mod:`dask.multiprocessing` (the part
  of Dask that runs a task in a worker: 0.15 s per worker otherwise).

And one thing more, only in that server: when the command that started it ends, the server
leaves at once (``os._exit`` after flushing its output) instead of tearing down, module by
module, the interpreter that holds numba, scipy and pandas. That teardown took 0.3-0.4 s of
processor time after the last fit (measured for issue 15), during which the server still
held the command's standard output and error open: a caller reading them
(``subprocess.run(..., capture_output=True)``, a pipe into ``tee``) waited for it. The
server has nothing to save at exit: its workers send their results to the command, and
they are forked children that leave through ``os._exit`` themselves and never run this.

Imported anywhere else (by mistake, or by a test) this module only imports: the fast exit is
installed when the import runs inside the fork server's ``main`` (see
:func:`_in_fork_server`).
"""

from __future__ import annotations

import atexit
import os
import sys

import dask.multiprocessing  # noqa: F401 - preloaded for the workers

from . import _warm, many  # noqa: F401 - preloaded for the workers

_server_pid = None
"""The process id of the fork server that installed the fast exit (None: not installed)."""


def _in_fork_server() -> bool:
    """True when this import runs inside ``multiprocessing.forkserver.main`` (its preload),
    that is in the fork server process itself."""
    from multiprocessing import forkserver

    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code is forkserver.main.__code__:
            return True
        frame = frame.f_back
    return False


def _exit_now() -> None:
    """At exit of the process that installed it: flush the output and leave with
    ``os._exit(0)``, skipping the teardown of the interpreter (no-op in any other process,
    such as a forked worker that runs the exit handlers it inherited)."""
    if os.getpid() != _server_pid:
        return
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except Exception:  # noqa: BLE001 - a closed stream: nothing left to flush
            pass
    os._exit(0)


def _install_fast_exit() -> None:
    """Make this process leave through :func:`_exit_now` when it exits (the handler runs
    before those registered earlier)."""
    global _server_pid
    _server_pid = os.getpid()
    atexit.register(_exit_now)


if _in_fork_server():
    _install_fast_exit()
