"""Start-up (issue 11): the core pipeline loads no matplotlib, and scipy.io only for .mat
files; `cylfric --version` imports no numerical library. A one-session fit loads neither
statsmodels nor scipy.stats (issue 22: its scatter is a one-way analysis of variance and its
runs test textbook arithmetic; statsmodels' mixed model comes in from two sessions on)."""

from __future__ import annotations

import subprocess
import sys


def _run(script):
    """``python -c script`` in a fresh process (imports measured from nothing)."""
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)


def _loaded_after(imports: str, modules: tuple[str, ...]) -> str:
    """Which of ``modules`` a fresh process has loaded after ``imports`` (its printed list)."""
    script = f"import sys\n{imports}\nprint([m for m in {modules!r} if m in sys.modules])"
    done = _run(script)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


SCRIPT = """
import sys, warnings
warnings.simplefilter("ignore")
from cylfric.pipeline import fit_campaign
from cylfric.simulate.bench import BenchSettings, generate_campaign
generate_campaign(sys.argv[1], BenchSettings.clean(pressures_bar=(0.1, 80.0), speeds_mm_s=(2, 5, 10, 30, 80)))
fit_campaign(sys.argv[1], sys.argv[2], report=False)
loaded = [m for m in ("matplotlib", "scipy.io", "scipy.stats", "statsmodels") if m in sys.modules]
print("LOADED", loaded)
"""


def test_fit_without_report_loads_no_plotting(tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(tmp_path / "camp"), str(tmp_path / "out")],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "LOADED []" in done.stdout, done.stdout


def test_version_imports_no_numerical_library():
    loaded = _loaded_after(
        "from cylfric.cli import app", ("numpy", "scipy", "pandas", "matplotlib")
    )
    assert loaded == "[]"


def test_the_command_line_starts_without_the_web_and_xml_libraries():
    """xml.sax.saxutils (escape.xml_attr, for the FMU export) is imported where it is used:
    at start-up it brought urllib.request, http.client and email into every command."""
    web = ("xml.sax", "urllib.request", "http.client", "email.parser")
    assert _loaded_after("from cylfric.cli import app", web) == "[]"


def test_window_velocity_is_the_savitzky_golay_derivative():
    import numpy as np
    from numpy.testing import assert_allclose
    from scipy.signal import savgol_filter

    from cylfric.steady_state import smoothed_velocity

    rng = np.random.default_rng(0)
    t = np.arange(700) * 0.01
    x = np.sin(t) + rng.normal(0, 1e-3, t.size)
    for window in (0.05, 0.2, 0.5, 1.0):
        n = max(5, int(round(window / 0.01)) | 1)
        expected = savgol_filter(x, n, 2, deriv=1, delta=0.01, mode="nearest")
        assert_allclose(smoothed_velocity(t, x, window=window), expected, rtol=0, atol=1e-10)


def test_the_pipeline_imports_the_identification_only_where_it_is_used():
    """pandas, the quality gate, scipy.optimize, jsonschema and the identification load
    where a fit first uses them, not when the pipeline is imported: the reading (also in
    the forked pool workers) needs none of them."""
    later = ("scipy.optimize", "scipy.ndimage", "jsonschema", "cylfric.identify", "pandas")
    loaded = _loaded_after("import cylfric.pipeline, cylfric.cli", (*later, "cylfric.quality"))
    assert loaded == "[]"


def test_the_version_is_the_installed_one():
    """cylfric.__version__ comes from cylfric/_version.py (no importlib.metadata at start-up);
    the installed metadata is built from the same attribute (pyproject.toml)."""
    from importlib.metadata import version

    import cylfric

    assert cylfric.__version__ == version("cylfric")


def test_the_command_line_freezes_its_objects_before_exit_but_main_in_process_does_not():
    """console_main (the `cylfric` script) moves every object to the permanent generation on
    its way out, so the last collections skip them; exit handlers still run after it.
    main(), called in a notebook or script, leaves the caller's collector alone."""
    script = (
        "import atexit, gc, sys\nfrom cylfric.cli import console_main, main\n"
        "sys.argv = ['cylfric', '--version']\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        "print('after main', gc.get_freeze_count())\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 1000))\n"
        "console_main()"
    )
    done = _run(script)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines == ["cylfric " + cylfric_version(), "after main 0"] + lines[2:]
    assert lines[-1] == "frozen True"


def test_the_console_script_exits_quickly_with_the_commands_code_and_handlers_run():
    """console_main (the `cylfric` script) skips the interpreter's teardown but keeps the
    exit code, the output and the exit handlers."""
    head = "import atexit, sys\nfrom cylfric.cli import console_main\n"
    handler = "atexit.register(lambda: print('handler ran'))\n"
    done = _run(head + handler + "sys.argv = ['cylfric', '--version']\nconsole_main()")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [f"cylfric {cylfric_version()}", "handler ran"]
    done = _run(head + handler + "sys.argv = ['cylfric', 'show', 'no_such.json']\nconsole_main()")
    assert done.returncode == 2
    assert "no_such.json" in done.stderr and done.stdout.strip() == "handler ran"


def test_the_quick_exit_keeps_systemexit_semantics_and_waits_for_running_threads():
    head = "from cylfric.cli import _exit_now\n"
    done = _run(head + "_exit_now('boom')")
    assert (done.returncode, done.stderr.strip()) == (1, "boom")
    done = _run(head + "_exit_now(None)")
    assert done.returncode == 0
    thread = (
        "import threading, time\n"
        "def late():\n    time.sleep(0.2)\n    print('thread finished', flush=True)\n"
        "threading.Thread(target=late).start()\n"
    )
    done = _run(head + thread + "_exit_now(3)")
    assert done.returncode == 3 and done.stdout.strip() == "thread finished"


def cylfric_version():
    import cylfric

    return cylfric.__version__


def test_the_command_line_takes_pyarrows_memory_from_the_c_allocator_unless_told_otherwise():
    """console_main sets ARROW_DEFAULT_MEMORY_POOL=system before pyarrow's first allocation
    (mimalloc's freed memory stayed resident: 16-20 MB of a 20,000-run fit's peak), keeps a
    value the user set, and main() in a notebook leaves the caller's pool alone."""
    report = (
        "import atexit, os, sys\n"
        "from cylfric.cli import console_main, main\n"
        "def pool():\n"
        "    import pyarrow as pa\n"
        "    print(os.environ.get('ARROW_DEFAULT_MEMORY_POOL'), pa.default_memory_pool().backend_name)\n"
        "atexit.register(pool)\n"
        "sys.argv = ['cylfric', '--version']\n"
    )
    clean = "import os\nos.environ.pop('ARROW_DEFAULT_MEMORY_POOL', None)\n"
    done = _run(clean + report + "console_main()")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "system system"
    done = _run(
        clean + "os.environ['ARROW_DEFAULT_MEMORY_POOL'] = 'mimalloc'\n" + report + "console_main()"
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "mimalloc mimalloc"
    plain = _run(clean + "import pyarrow as pa\nprint(pa.default_memory_pool().backend_name)")
    done = _run(clean + report + "try:\n    main()\nexcept SystemExit:\n    pass\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == f"None {plain.stdout.strip()}"
