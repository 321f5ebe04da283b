"""``cylfric ARGS`` as a process, with a chosen exit and reading (for bench_parallel.py).

Usage: ``python benchmarks/fit_process.py EXIT READING ARGS...``

- EXIT ``plain``: the interpreter ends as usual (:func:`cylfric.cli.main`, then teardown);
  ``quick``: what cylfric's console script did before issue 24 (``gc.freeze()``, exit
  handlers, flush, ``os._exit``), done here so that it can be timed whatever ``src`` holds;
- READING ``default``: as the installed code does it; ``serial``: every fit with
  ``workers=1`` (the files read one after another in this process).

Takes cylfric from ``PYTHONPATH`` (the code under test).
"""

from __future__ import annotations

import atexit
import functools
import gc
import os
import sys


def main(argv):
    exit_mode, reading, *args = argv
    if reading == "serial":
        import cylfric.pipeline as pipeline

        original = pipeline.fit_campaign

        @functools.wraps(original)
        def serial(folder, out, options=None, **keywords):
            if options is not None:  # a FitOptions (cylfric.options): the same, on one core
                from dataclasses import replace

                return original(folder, out, replace(options, workers=1), **keywords)
            return original(folder, out, workers=1, **keywords)

        pipeline.fit_campaign = serial
    from cylfric.cli import main as cylfric_main

    sys.argv = ["cylfric", *args]
    code = 0
    try:
        cylfric_main()
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    if exit_mode == "plain":
        sys.exit(code)
    gc.freeze()
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    main(sys.argv[1:])
