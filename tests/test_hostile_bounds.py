"""Bounds with a clear error naming the input (issue 43, items 7 and 8): a scheduler that
never answers, a port out of range, a manifest too large or with a huge cell, a campaign
count that is not a count, a run file with many columns. Each test fails on the code
before (the silent scheduler: connect had not returned after 60 s)."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from cylfric._parallel import connect


@pytest.fixture
def silent_server():
    """A TCP server that accepts connections and never says anything."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    held, stop = [], threading.Event()

    def accept():
        server.settimeout(0.2)
        while not stop.is_set():
            try:
                held.append(server.accept()[0])
            except OSError:
                continue

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    stop.set()
    thread.join()
    for conn in held:
        conn.close()
    server.close()


def test_a_scheduler_that_never_answers_is_refused_in_bounded_time(silent_server):
    outcome = {}

    def attempt():
        try:
            connect(silent_server, timeout=2.0)
        except ValueError as exc:
            outcome["error"] = str(exc)

    started = time.monotonic()
    thread = threading.Thread(target=attempt, daemon=True)
    thread.start()
    thread.join(20)
    assert not thread.is_alive(), "connect did not return within 20 s"
    assert time.monotonic() - started < 10
    assert "no Dask scheduler answered within 2 s" in outcome["error"]
    assert silent_server in outcome["error"]


def test_a_port_out_of_range_is_named_at_once():
    started = time.monotonic()
    with pytest.raises(ValueError, match="port 99999 is not a TCP port"):
        connect("tcp://127.0.0.1:99999")
    assert time.monotonic() - started < 5


# --------------------------------------------------------------- campaign inputs
SMALL = {"pressures_bar": (10.0, 80.0), "speeds_mm_s": (2, 10, 50)}


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path_factory.mktemp("bench") / "c"
    generate_campaign(folder, BenchSettings.clean(**SMALL))
    return folder


def _copy(bench, tmp_path):
    import shutil

    folder = tmp_path / "campaign"
    shutil.copytree(bench, folder)
    return folder


def _fit(folder, tmp_path):
    from typer.testing import CliRunner

    from cylfric.cli import app

    return CliRunner().invoke(
        app, ["fit", str(folder), "--out", str(tmp_path / "out"), "--no-report"]
    )


def test_a_10_mb_manifest_cell_is_named_with_its_line(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    manifest = folder / "manifest.csv"
    rows = manifest.read_text().splitlines()
    rows[0] += ",seal"
    rows[2] += "," + "x" * 10_000_000
    manifest.write_text("\n".join(rows) + "\n")
    result = _fit(folder, tmp_path)
    assert result.exit_code == 2, result.output
    assert "manifest.csv, line 3: not a CSV row cylfric reads (field larger" in result.output


def test_a_manifest_with_too_many_rows_is_refused(bench, tmp_path, monkeypatch):
    from cylfric.io import campaign

    monkeypatch.setattr(campaign, "MANIFEST_ROWS", 4)
    folder = _copy(bench, tmp_path)
    with pytest.raises(campaign.BenchFileError, match="line 6: more than 4 rows"):
        campaign.Campaign.open(folder)


def test_a_sample_count_of_1e12_is_refused_by_name(bench, tmp_path):
    folder = _copy(bench, tmp_path)
    (folder / "campaign.toml").write_text("[extraction]\nmin_samples = 1e12\n")
    result = _fit(folder, tmp_path)
    assert result.exit_code == 2, result.output
    assert "campaign.toml, line 2: extraction.min_samples" in result.output


def test_a_whole_float_sample_count_is_passed_on_as_an_int(bench, tmp_path):
    from cylfric.io.campaign import load_config

    folder = _copy(bench, tmp_path)
    (folder / "campaign.toml").write_text("[extraction]\nmin_samples = 20.0\n")
    assert type(load_config(folder).extraction["min_samples"]) is int


def _wide(path, columns, rows=5):
    names = ["time [s]", "position [mm]", "force [N]"]
    names += [f"channel{i} [V]" for i in range(columns - len(names))]
    lines = ["\t".join(names)] + ["\t".join(["1.0"] * columns)] * rows
    path.write_text("\n".join(lines) + "\n")
    return path


def test_header_parsing_is_linear_in_the_columns(tmp_path):
    from cylfric.io.text import read_bench_arrays

    read_bench_arrays(_wide(tmp_path / "warm.txt", 10))  # imports and compiled kernels
    timings = {}
    for columns in (1_000, 9_000):
        path = _wide(tmp_path / f"w{columns}.txt", columns)
        started = time.perf_counter()
        data, _ = read_bench_arrays(path)
        timings[columns] = time.perf_counter() - started
        assert len(data) == columns + 1  # and the position's velocity
    # linear: 9x the columns in about 9x the time (quadratic: 81x; 9,000 took 9 s before)
    assert timings[9_000] < 3.0, timings


def test_more_columns_than_a_run_file_has_are_refused(tmp_path):
    from cylfric.io.text import MAX_COLUMNS, BenchFileError, read_bench_arrays

    path = _wide(tmp_path / "wide.txt", MAX_COLUMNS + 1, rows=2)
    with pytest.raises(BenchFileError, match="wide.txt, line 1: 10,001 columns; a run file"):
        read_bench_arrays(path)


# --------------------------------------------------------------- .mat
def test_a_mat_file_that_inflates_beyond_the_bound_is_refused_before_reading(tmp_path, monkeypatch):
    import resource

    import numpy as np
    from scipy.io import savemat

    from cylfric.io import matfile

    path = tmp_path / "bomb.mat"
    savemat(path, {"t": np.zeros(20_000_000)}, do_compression=True)  # 160 MB in 160 kB
    assert path.stat().st_size < 1_000_000
    monkeypatch.setattr(matfile, "MAT_BYTES", 16 << 20)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(matfile.BenchFileError, match="bomb.mat: its variables take more than 16"):
        matfile.read_mat(path)
    grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before  # [KiB]
    assert grown < 64 * 1024  # the 160 MB were never held


@pytest.mark.parametrize(
    ("variables", "message"),
    [
        (["t", "short"], r"unequal length \(t: 10, short: 5\)"),
        (["t", "c"], "c is complex; expected real numbers"),
        (["t", "m"], r"m is 10x3; expected a vector \(1-D\)"),
        (["t", "s"], "s is a single number; expected a vector"),
        (["t", "txt"], "txt is not numeric"),
    ],
)
def test_mat_variables_that_are_not_vectors_of_one_length_are_named(tmp_path, variables, message):
    import numpy as np
    from scipy.io import savemat

    from cylfric.io.matfile import BenchFileError, read_mat

    path = tmp_path / "run.mat"
    savemat(
        path,
        {
            "t": np.arange(10.0),
            "short": np.arange(5.0),
            "c": np.arange(10) * 1j,
            "m": np.ones((10, 3)),
            "s": np.array([1.0]),
            "txt": "abc",
        },
    )
    with pytest.raises(BenchFileError, match=f"run.mat: .*{message}"):
        read_mat(path, variables=variables)


# --------------------------------------------------------------- plan
@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--candidate-pressures", "3000", "--candidate-speeds", "3000"], "9,000,000 candidates"),
        (["--runs", "100000000"], "100,000,000 runs: expected 1 to 5,000"),
    ],
)
def test_a_plan_too_large_for_memory_is_refused_at_once(tmp_path, options, message):
    from typer.testing import CliRunner

    from cylfric.cli import app

    started = time.monotonic()
    result = CliRunner().invoke(app, ["plan", "--out", str(tmp_path / "plan"), *options])
    assert result.exit_code == 2, result.output
    assert message in result.output
    assert time.monotonic() - started < 20
