"""The ``cylfric`` command line (typer + rich): one module per command group, each thin
(parse the options, call the library, print). No physics here.

Exit codes: 0 success; 2 bad input (one line naming the file and the problem, no
traceback); 1 unexpected error (rerun with ``--debug`` for the traceback).
Unit-bearing options accept units (``10mm/s``, ``55bar``, ``5MPa``); bare numbers are read in
bar, mm/s, s, kg, N/m as each option's help says.

:mod:`.common` holds the app, the consoles and :func:`~.common.guarded`; :mod:`.fit`
(``fit``, ``demo``, ``show``), :mod:`.bench` (``generate``, ``simulate``), :mod:`.catalog`,
:mod:`.drift`, :mod:`.export`, :mod:`.many` (``fit-many``), :mod:`.motion` (``fit-motion``),
:mod:`.plan` and :mod:`.control` add their commands. A command module imports only typer, rich and
:mod:`.common` at the top and the library inside its command bodies, so ``cylfric
--version`` stays fast.
"""

from __future__ import annotations

import sys

from ..escape import terminal
from .common import UNEXPECTED_EXIT, app, err_console

# isort: split
# importing them adds their @app.command()s, in this order: fit, demo, show, generate, simulate
from . import fit  # noqa: F401

# isort: split
from . import bench  # noqa: F401

# isort: split
from . import field  # noqa: F401  (fit-field, generate-field)

# isort: split
from . import axis  # noqa: F401  (identify-axis)

# isort: split
from . import catalog, control, drift, export, many, motion, plan
from .fit import run_fit

# isort: split
from . import inspect  # noqa: F401  (adds cylfric inspect)

for _module in (drift, export, catalog, many, motion, plan, control):
    _module.register(app)


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except SystemExit:
        raise
    except Exception as exc:  # pragma: no cover - typer's own failures
        err_console.print(
            terminal(f"error: unexpected {type(exc).__name__}: {exc}", markup=False),
            markup=False,
        )
        err_console.print("rerun with --debug for the traceback")
        sys.exit(UNEXPECTED_EXIT)


def console_main() -> None:
    """The ``cylfric`` command (console script): :func:`main`, then a quick exit.

    Once the command is done (its outputs written and closed), its objects are frozen (the
    final collections skip them), the exit handlers run and the process ends with the
    command's exit code without tearing down the interpreter's modules (numba, scipy, pandas:
    about 0.3 s of a ``cylfric fit`` together). With threads of its own still running it
    exits the usual way, still frozen. :func:`main` itself, for use in-process, does neither.
    """
    code: str | int | None
    _arrow_system_pool()
    _usable_streams()
    try:
        main()
        code = 0
    except SystemExit as exc:
        code = exc.code
    _freeze_for_exit()
    _exit_now(code)


def _usable_streams():
    """Standard output and error that cannot end a command in an unexpected error: a stream
    the caller closed (``cylfric show x --json >&-``: Python's ``sys.stdout`` is None) is
    discarded as rich discards it, and one whose encoding cannot hold a name
    (``PYTHONIOENCODING=ascii``) writes what it cannot encode as backslash escapes."""
    import os

    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        if stream is None:
            setattr(sys, name, open(os.devnull, "w", encoding="utf-8"))  # noqa: SIM115
        elif getattr(stream, "errors", None) == "strict" and hasattr(stream, "reconfigure"):
            try:
                "\u00e4\u2603".encode(stream.encoding or "ascii")
            except (UnicodeEncodeError, LookupError):
                stream.reconfigure(errors="backslashreplace")


def _arrow_system_pool():
    """pyarrow's memory from the C library's allocator in this process (and the processes
    it forks), unless ``ARROW_DEFAULT_MEMORY_POOL`` already says otherwise.

    pyarrow's default pool (mimalloc) keeps memory it has freed: a ``cylfric fit
    --no-report`` of 20,000 runs peaked at 393 MB of the process tree's PSS with it and
    373-377 MB without (a 30 ms sampler; 4-5 MB less at 1,000 runs), in the same time (the
    README, section Performance). Only the command line does this: a notebook's pool is its
    own. Set before pyarrow's first allocation, which is where the pool is chosen."""
    import os

    os.environ.setdefault("ARROW_DEFAULT_MEMORY_POOL", "system")


def _exit_now(code):
    """End the process with ``code`` as SystemExit would, skipping the interpreter's
    teardown when no other non-daemon thread runs; exit handlers and stream flushes first."""
    import atexit
    import contextlib
    import os
    import threading

    if code is None:
        status = 0
    elif isinstance(code, int):
        status = code
    else:  # SystemExit("message"): printed, exit status 1
        print(code, file=sys.stderr)
        status = 1
    main_thread = threading.main_thread()
    if any(t is not main_thread and not t.daemon for t in threading.enumerate()):
        sys.exit(status)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):  # a closed pipe (cylfric ... | head)
            stream.flush()
    os._exit(status)


def _freeze_for_exit():
    """Spare the interpreter's last garbage collections over everything numba, scipy and
    pandas loaded (0.2 s of a `cylfric fit` on 144 files, measured): the command's work is
    done and written, so its objects move to the permanent generation, which the collector
    skips; exit handlers still run."""
    import gc

    gc.freeze()


__all__ = ["app", "main", "console_main", "run_fit"]
