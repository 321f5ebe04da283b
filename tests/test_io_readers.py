"""Readers: every dialect of the testing-machine family, bad input, fuzzing."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from cylfric.io import BenchFileError, name_tokens, read_bench_text, read_delimited, read_mat

ROWS = [(0.0, 10.0, 0.1), (0.01, 9.9, 0.1125), (0.02, 9.8, -0.05)]  # s, mm, kN


def _write(tmp_path, text, name="run.txt", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


def _check(data, force_scale=1e3, time_scale=1.0, pos_scale=1e-3):
    assert_allclose(data["time [s]"], [r[0] * time_scale for r in ROWS])
    assert_allclose(data["position [m]"], [r[1] * pos_scale for r in ROWS])
    assert_allclose(data["force [N]"], [r[2] * force_scale for r in ROWS])


def _rows(sep=" \t", dec=".", fmt="{:g}"):
    return "\n".join(sep.join(fmt.format(x).replace(".", dec) for x in r) for r in ROWS) + "\n"


def test_mts_export_with_units_row_and_preamble(tmp_path):
    text = (
        "MTS793|MPT|ENU|1|2|.|/|:|1|0|0|A\nStation Name: Mini Bionix\nPressure: 55 bar\n\n"
        "Time\tAxial Displacement\tAxial Force\nSec\tmm\tkN\n" + _rows("\t")
    )
    data, meta = read_bench_text(_write(tmp_path, text))
    _check(data)
    assert meta["header"]["Pressure"] == "55 bar"
    assert meta["units"] == {"time": "Sec", "position": "mm", "force": "kN"}


def test_a_mixed_case_unit_in_a_units_row_is_refused_naming_the_column(tmp_path):
    """'mS' (millisiemens, or ms?) in an export's units row: refused, never read as ms; the
    line named is the units row's (line 2; the names row's had been named)."""
    path = _write(tmp_path, "Time\tAxial Displacement\tAxial Force\nmS\tmm\tkN\n" + _rows("\t"))
    with pytest.raises(
        BenchFileError,
        match=r"run.txt, line 2: column 'Time': unit 'mS' is ambiguous: .* write ms \(or MS in "
        r"all capitals, as bench exports do\)",
    ):
        read_bench_text(path)


@pytest.mark.parametrize(
    ("header", "sep", "dec"),
    [
        ("Time [s];Position [mm];Force [kN]", ";", ","),
        ("Zeit (s)\tWeg (mm)\tKraft (kN)", "\t", ","),
        ("Running Time [s],Displacement [mm],Load [kN]", ",", "."),
        ("Tid [s]   Position [mm]   Kraft [kN]", "   ", "."),
    ],
)
def test_units_in_cells_any_separator_and_decimal(tmp_path, header, sep, dec):
    path = _write(tmp_path, header + "\n" + _rows(sep, dec))
    data, meta = read_bench_text(path)
    _check(data)
    assert meta["decimal"] == dec


def test_newton_and_milliseconds_and_metres(tmp_path):
    text = (
        "Time\tPosition\tForce\nms\tm\tN\n"
        + "\n".join(f"{r[0] * 1e3:g}\t{r[1] * 1e-3:g}\t{r[2] * 1e3:g}" for r in ROWS)
        + "\n"
    )
    data, _ = read_bench_text(_write(tmp_path, text))
    _check(data)


def test_pressure_units_mpa_psi(tmp_path):
    text = (
        "Time [s]\tForce [N]\tPressure A [MPa]\tPressure B [psi]\n0\t1\t5.5\t100\n1\t2\t5.5\t100\n"
    )
    data, _ = read_bench_text(_write(tmp_path, text))
    assert_allclose(data["pressure_a [Pa]"], 5.5e6)
    assert_allclose(data["pressure_b [Pa]"], 689475.7293168)


def test_segments_status_lines_crlf_latin1(tmp_path):
    block = "Time\tDisplacement\tForce\ns\tmm\tkN\n"
    text = (
        "MTS793|MPT\nOperator: Müller\nSegment 1 started\n"
        + block
        + _rows("\t")
        + "*** Interlock 1 tripped ***\n\n"
        + _rows("\t").replace("0.0", "1.0", 1)
        + "Segment 2 started\n"
        + block
        + _rows("\t")
        + "Test run ended\n"
    )
    path = _write(tmp_path, text.replace("\n", "\r\n"), encoding="latin-1")
    data, meta = read_bench_text(path)
    assert len(data) == 9 and meta["segments"] == 3
    assert meta["header"]["Operator"] == "Müller"
    assert any("Interlock" in e[1] for e in meta["events"])
    assert_allclose(data["force [N]"].iloc[-3:], [100.0, 112.5, -50.0])


def test_segments_of_one_layout_read_as_separate_blocks(tmp_path):
    """Blocks that repeat one header are parsed together: the same columns [SI] and segment
    numbers as each block read on its own, and a bad number named on its own line."""
    block = "Time\tDisplacement\tForce\ns\tmm\tkN\n"
    segments = ["Segment 1 started\n" + block + _rows("\t"), "Segment 2\n" + block + _rows("\t")]
    data, meta = read_bench_text(_write(tmp_path, "".join(segments)))
    parts = [
        read_bench_text(_write(tmp_path, text, f"s{i}.txt"))[0] for i, text in enumerate(segments)
    ]
    assert meta["segments"] == 2
    assert data["segment [-]"].tolist() == [0] * len(ROWS) + [1] * len(ROWS)
    for column in ("time [s]", "position [m]", "force [N]"):
        expected = np.concatenate([part[column].to_numpy() for part in parts])
        assert np.array_equal(data[column].to_numpy(), expected)
    bad = "".join(segments[:1]) + segments[1].replace("0.1", "0.x", 1)
    line = bad.splitlines().index(next(r for r in bad.splitlines() if "0.x" in r)) + 1
    with pytest.raises(BenchFileError, match="expected a number in column") as error:
        read_bench_text(_write(tmp_path, bad, "bad.txt"))
    assert error.value.line == line


def test_headerless_with_column_map(tmp_path):
    path = _write(tmp_path, "  0.000   10.0  0.1\n 10.000  9.9  0.1125\n20.000 9.8 -0.05\n")
    data, meta = read_delimited(
        path, columns=["time", "position", "force"], units=["ms", "mm", "kN"]
    )
    _check(data, time_scale=1e-3 * 1e3)
    assert meta["delimiter"] == "whitespace"


def test_file_name_tokens():
    assert name_tokens("run_7_p55.5bar_v10mms.txt") == {"pressure": 55.5e5, "velocity": 0.01}
    assert name_tokens("55bar_10mm_s.txt") == {"pressure": 55e5, "velocity": 0.01}
    assert name_tokens("test_v2,5mms_5MPa.txt") == {"pressure": 5e6, "velocity": 0.0025}
    assert name_tokens("nothing.txt") == {}


# ------------------------------------------------------------------------------ bad input


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", r"run.txt: the file is empty"),
        (b"\x00\x01\x02binary", r"binary content \(NUL bytes\)"),
        ("Time\tForce\n".encode("utf-16"), r"binary content"),
        (b"Just some notes\nno numbers here\n", r"no numeric data rows"),
        (b"0\t1\t2\n1\t2\t3\n", r"line 1: no header row with column names"),
        (b"Time [s]\tForce [N]\n0\t1\n1\t2\n2", r"run.txt, line 4: the last data row has no line"),
        (
            b"Time [s]\tForce [N]\n0\t1\n1\n2\t2\n",
            r"run.txt, line 3: expected 2 numeric columns, found 1",
        ),
        (
            b"Time [s]\tForce [N]\n0\t1\n1\tabc\n",
            r"line 3: expected a number in column 2, found 'abc'",
        ),
        (b"Time [s]\tForce [N]\n0\t1\n1\t\n", r"line 3: expected a number in column 2, found ''"),
        (b"Time [furlong]\tForce [N]\n0\t1\n", r"column 'Time': unknown unit 'furlong'"),
        (
            b"Time [s]\tForce [mm]\n0\t1\n",
            r"column 'Force' has unit 'mm' \(length\); expected a force",
        ),
        (b"Time\tForce\n0\t1\n", r"column 'Time' has no unit"),
    ],
)
def test_bad_files_raise_bench_file_error_naming_file_and_line(tmp_path, content, message):
    path = tmp_path / "run.txt"
    path.write_bytes(content)
    with pytest.raises(BenchFileError, match=message):
        read_bench_text(path)
    assert path.read_bytes() == content  # never modified


def test_missing_file(tmp_path):
    with pytest.raises(BenchFileError, match="cannot read the file"):
        read_bench_text(tmp_path / "absent.txt")


def test_columns_changing_between_segments(tmp_path):
    text = "Time [s]\tForce [N]\n0\t1\nSegment 2\nTime [s]\tLoad [kN]\tPosition [mm]\n1\t2\t3\n"
    with pytest.raises(BenchFileError, match="the columns change between segments"):
        read_bench_text(_write(tmp_path, text))


def test_bench_file_error_is_a_value_error():
    assert issubclass(BenchFileError, ValueError)


GOOD = (
    "MTS793|MPT\nPressure: 55 bar\nTime\tAxial Displacement\tAxial Force\ns\tmm\tkN\n"
    + _rows("\t")
    + "Test run ended\n"
).encode()


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(blob=st.binary(max_size=400))
def test_fuzz_random_bytes_raise_only_bench_file_error(tmp_path, blob):
    path = tmp_path / "fuzz.txt"
    path.write_bytes(blob)
    try:
        read_bench_text(path)
    except BenchFileError:
        pass


@settings(
    max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    cut=st.integers(0, len(GOOD)),
    position=st.integers(0, len(GOOD) - 1),
    byte=st.integers(0, 255),
    mode=st.sampled_from(["truncate", "mutate", "insert", "delete"]),
)
def test_fuzz_mutated_real_file_raises_only_bench_file_error(tmp_path, cut, position, byte, mode):
    data = bytearray(GOOD)
    if mode == "truncate":
        data = data[:cut]
    elif mode == "mutate":
        data[position] = byte
    elif mode == "insert":
        data.insert(position, byte)
    else:
        del data[position]
    path = tmp_path / "fuzz.txt"
    path.write_bytes(bytes(data))
    try:
        data_frame, _ = read_bench_text(path)
    except BenchFileError:
        return
    assert np.isfinite(data_frame.select_dtypes("number").to_numpy()).all()


def test_read_mat_emps(shared_data):
    data, meta = read_mat(
        shared_data / "emps-benchmark" / "DATA_EMPS.mat",
        variables=["t", "qm", "vir"],
        units={"t": "s", "qm": "m", "vir": "V"},
    )
    assert len(data) == 24841 and list(data) == ["t [s]", "qm [m]", "vir [V]"]
    assert "gtau" in meta["scalars"]


def test_read_mat_errors(tmp_path):
    path = _write(tmp_path, "not a mat file", "x.mat")
    with pytest.raises(BenchFileError, match="not a readable MATLAB .mat file"):
        read_mat(path)


def test_encoding_is_used_and_checked(tmp_path):
    text = "Bediener: Müller\nZeit [s]\tKraft [N]\n0\t1\n1\t2\n"
    path = _write(tmp_path, text, encoding="latin-1")
    _, meta = read_bench_text(path, encoding="latin-1")
    assert meta["header"]["Bediener"] == "Müller"
    with pytest.raises(BenchFileError, match=r"run.txt, line 1: not valid utf-8 text"):
        read_bench_text(path, encoding="utf-8")
    with pytest.raises(ValueError, match="unknown encoding 'klingon'"):
        read_bench_text(path, encoding="klingon")


def test_events_are_status_lines_not_headers(tmp_path):
    block = "Time\tDisplacement\tForce\ns\tmm\tkN\n"
    text = (
        "MTS793|MPT\nSegment 1 started\n"
        + block
        + _rows("\t")
        + "Segment 2 started\n"
        + block
        + _rows("\t")
        + "Test run ended\n"
    )
    _, meta = read_bench_text(_write(tmp_path, text))
    assert [e[1] for e in meta["events"]] == [
        "Segment 1 started",
        "Segment 2 started",
        "Test run ended",
    ]


def test_nul_bytes_past_64_kib_name_the_line(tmp_path):
    """Issue 11: NUL bytes after the first 64 KiB gave 'columns change between segments'
    without a line; now the row that holds them is named."""
    body = "Time [s]\tForce [N]\n" + "".join(f"{i * 0.01:.2f}\t1.0\n" for i in range(8000))
    data = body.encode()
    path = tmp_path / "run.txt"
    path.write_bytes(data[:70000] + b"\x00\x00" + data[70000:])
    with pytest.raises(BenchFileError, match=r"run.txt, line 7100: binary content \(NUL bytes\)"):
        read_bench_text(path)


def test_reader_converts_its_own_columns_in_place_and_leaves_callers_values_alone(tmp_path):
    """Issue 23 (memory): the SI columns of a one-segment file are views of the one parsed
    block (no copy per column), and si_columns, given the caller's array, copies."""
    import numpy as np

    from cylfric.io.text import read_bench_arrays, si_columns

    path = tmp_path / "run.txt"
    path.write_text("Time\tPosition\tForce\ns\tmm\tkN\n0\t1.5\t0.25\n0.01\t2.5\t0.5\n")
    data, _ = read_bench_arrays(path)
    assert data["position [m]"].tolist() == [1.5e-3, 2.5e-3]
    assert data["force [N]"].tolist() == [250.0, 500.0]
    assert data["time [s]"].flags.c_contiguous and data["force [N]"].flags.c_contiguous
    assert data["time [s]"].base is data["force [N]"].base is not None
    values = np.array([[0.0, 1.5], [0.01, 2.5]])
    si_columns(path, ["Time", "Position"], ["s", "mm"], values)
    assert values.tolist() == [[0.0, 1.5], [0.01, 2.5]]
