"""Ingestion faults of issue 11: each gives the corrected reading or a clear error naming the
file, the line and the key."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cylfric.io import BenchFileError, read_bench_text
from cylfric.io.campaign import _read_manifest, load_config
from cylfric.units import UnitError, parse_quantity


def test_rows_that_begin_with_a_separator_are_read(tmp_path):
    path = tmp_path / "mts793.txt"
    path.write_text(
        "Time\tPosition\tForce\nSec\tmm\tkN\n"
        "\t0,000\t72,0000\t0,01423\n\t0,010\t72,0100\t0,01424\n\t0,020\t72,0200\t0,01425\n"
    )
    data, meta = read_bench_text(path)
    assert list(data["force [N]"]) == pytest.approx([14.23, 14.24, 14.25])
    assert list(data["position [m]"]) == pytest.approx([0.072, 0.07201, 0.07202])
    path.write_text("Time\tPosition\tForce\nSec\tmm\tkN\n\t0,0\t72,0\t0,01\n0,01\t72,1\t0,02\n")
    with pytest.raises(BenchFileError, match=r"mts793.txt, line 4: some data rows begin with"):
        read_bench_text(path)


@pytest.mark.parametrize(
    "text, dimension, expected",
    [
        ("5 mN", "force", 5e-3),
        ("5 MN", "force", 5e6),
        ("5MPa", "pressure", 5e6),
        ("5 MPA", "pressure", 5e6),  # bench exports write upper case
        ("5 mPa", "pressure", 5e-3),
        ("2 KN", "force", 2e3),
        ("55 BAR", "pressure", 55e5),
    ],
)
def test_unit_prefixes_are_case_sensitive(text, dimension, expected):
    assert parse_quantity(text, dimension) == pytest.approx(expected)


def test_ambiguous_lower_case_prefix_is_refused():
    with pytest.raises(UnitError, match="'mn' is ambiguous: write mN \\(milli\\) or MN"):
        parse_quantity("5 mn", "force")


def test_manifest_header_with_spaces_and_capitals_is_read(tmp_path):
    (tmp_path / "manifest.csv").write_text(
        "File, Pressure_bar, velocity_mm_s\nrun1.txt, 55, 10\nrun2.txt, 80 ,20\n"
    )
    rows = _read_manifest(tmp_path)
    assert rows["run1.txt"][:2] == (55e5, 0.010)
    assert rows["run2.txt"][:2] == (80e5, 0.020)


@pytest.mark.parametrize(
    "body, message",
    [
        ("run1.txt,-5,10\n", r"line 2: pressure_bar = -5 of run1.txt; expected a finite"),
        ("run1.txt,inf,10\n", r"line 2: pressure_bar = inf"),
        ("run1.txt,55,0\n", r"line 2: velocity_mm_s = 0 of run1.txt"),
        ("run1.txt,55,10\nrun1.txt,80,10\n", r"line 3: run1.txt is listed twice"),
        ("run1.txt,55bar,10\n", r"line 2: pressure_bar and velocity_mm_s must be numbers"),
    ],
)
def test_manifest_errors_name_the_line(tmp_path, body, message):
    (tmp_path / "manifest.csv").write_text("file,pressure_bar,velocity_mm_s\n" + body)
    with pytest.raises(BenchFileError, match=message):
        _read_manifest(tmp_path)


@pytest.mark.parametrize(
    "toml, message",
    [
        ('[cylinder]\nbor = "25 mm"\n', r"line 2: unknown key 'bor' in \[cylinder\]"),
        ("[files]\nglob = 5\n", r"line 2: files.glob: 5 is not of type 'string'"),
        ('[extraction]\nmin_samples = "ten"\n', r"line 2: extraction.min_samples: 'ten'"),
        (
            '[files]\nname_pattern = "(?P<x"\n',
            r"line 2: files.name_pattern is not a regular expression RE2 accepts",
        ),
        ('[cylinder]\nbore = "25 mm"\nrod = "30 mm"\n', r"line 3: cylinder.rod \(30 mm\)"),
        ('[cylinder]\nkind = "single-acting"\n', r"cylinder.bore is missing or 0"),
    ],
)
def test_campaign_toml_errors_name_the_key_and_line(tmp_path, toml, message):
    (tmp_path / "campaign.toml").write_text(toml)
    with pytest.raises(BenchFileError, match=message):
        load_config(tmp_path)


_TOML_KEYS = st.sampled_from(
    [
        "glob",
        "name_pattern",
        "bore",
        "rod",
        "kind",
        "names",
        "units",
        "load_cell_sign",
        "position_sign",
        "moving_mass",
        "min_samples",
        "method",
        "bor",
        "x",
    ]
)
_TOML_VALUES = st.one_of(
    st.integers(-3, 3),
    st.floats(allow_nan=False, allow_infinity=False),
    st.booleans(),
    st.sampled_from(['"25 mm"', '"40 mm"', '"*.txt"', '"(?P<p>\\\\d+)bar"', '"ten"', '"("', "[1]"]),
)


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    table=st.sampled_from(["files", "columns", "cylinder", "force_balance", "extraction", "oops"]),
    entries=st.lists(st.tuples(_TOML_KEYS, _TOML_VALUES), max_size=4, unique_by=lambda e: e[0]),
)
def test_fuzzed_campaign_toml_gives_a_config_or_a_bench_file_error(tmp_path, table, entries):
    lines = [f"[{table}]"] + [
        f"{k} = {str(v).lower() if isinstance(v, bool) else v}" for k, v in entries
    ]
    (tmp_path / "campaign.toml").write_text("\n".join(lines) + "\n")
    try:
        load_config(tmp_path)
    except BenchFileError:
        pass


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    header=st.lists(
        st.sampled_from(
            ["file", " File", "pressure_bar", " PRESSURE_BAR ", "velocity_mm_s", "x", "pressure"]
        ),
        min_size=1,
        max_size=4,
    ),
    cells=st.lists(
        st.lists(
            st.sampled_from(["run.txt", "55", "-1", "0", "inf", "nan", "", "1e3", "a,b"]),
            max_size=4,
        ),
        max_size=4,
    ),
)
def test_fuzzed_manifest_gives_rows_or_a_bench_file_error(tmp_path, header, cells):
    text = ",".join(header) + "\n" + "".join(",".join(row) + "\n" for row in cells)
    (tmp_path / "manifest.csv").write_text(text)
    try:
        rows = _read_manifest(tmp_path)
    except BenchFileError:
        return
    for pressure, velocity, _ in rows.values():
        assert math.isnan(pressure) or (math.isfinite(pressure) and pressure >= 0)
        assert math.isnan(velocity) or (math.isfinite(velocity) and velocity != 0)


def _two_forces(path, first="Force Setpoint"):
    path.write_text(
        f"Time\tPosition\t{first}\tAxial Force\ns\tmm\tkN\tkN\n"
        "0.00\t10.0\t0.100\t0.071\n0.01\t10.1\t0.100\t0.072\n0.02\t10.2\t0.100\t0.073\n"
    )


def test_setpoint_column_is_never_the_measured_force(tmp_path):
    _two_forces(tmp_path / "run.txt")
    data, _ = read_bench_text(tmp_path / "run.txt")
    assert list(data["force [N]"]) == pytest.approx([71.0, 72.0, 73.0])
    assert "Force Setpoint [kN]" in data  # kept as read


def test_two_measured_force_columns_are_an_error_unless_campaign_toml_chooses(tmp_path):
    _two_forces(tmp_path / "run.txt", first="Load")
    with pytest.raises(BenchFileError, match=r"columns \['Load', 'Axial Force'\] all look like"):
        read_bench_text(tmp_path / "run.txt")
    data, _ = read_bench_text(tmp_path / "run.txt", roles={"force": "Axial Force"})
    assert list(data["force [N]"]) == pytest.approx([71.0, 72.0, 73.0])
    (tmp_path / "campaign.toml").write_text('[columns]\nforce = "Axial Force"\n')
    assert load_config(tmp_path).roles == {"force": "Axial Force"}
    with pytest.raises(BenchFileError, match=r"\[columns\] force = 'Axial' names no column"):
        read_bench_text(tmp_path / "run.txt", roles={"force": "Axial"})


def _campaign_with(tmp_path, name, text):
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path / "camp"
    generate_campaign(folder, BenchSettings.clean(pressures_bar=(10.0,), speeds_mm_s=(5, 50)))
    (folder / name).write_text(text)
    return folder


@pytest.mark.parametrize(
    "text, message",
    [
        ("Position\tForce\nmm\tkN\n1\t0.1\n2\t0.1\n3\t0.1\n", "no time column"),
        ("Time\tPosition\tForce\ns\tmm\tkN\n1\t1\t0.1\n1\t2\t0.1\n0.5\t3\t0.1\n", "does not incr"),
        (
            "Time\tPosition\tForce\ns\tmm\tkN\n0\t1\t0.1\n0.01\t2\tinf\n0.02\t3\t0.1\n",
            "line 4: expected a number in column 3, found .inf.",
        ),
    ],
)
def test_per_file_problems_name_the_file_and_are_skippable(tmp_path, text, message):
    from cylfric.steady_state import extract_campaign

    folder = _campaign_with(tmp_path, "zz_bad_p10bar_v5mms.txt", text)
    (folder / "manifest.csv").unlink()  # let every file in
    with pytest.raises(BenchFileError, match=rf"zz_bad_p10bar_v5mms.txt.*{message}.*--skip-bad"):
        extract_campaign(folder)
    extraction = extract_campaign(folder, skip_bad=True)
    assert [s["file"].endswith("zz_bad_p10bar_v5mms.txt") for s in extraction.skipped] == [True]


def test_every_file_bad_with_skip_bad_says_why(tmp_path):
    from cylfric.steady_state import extract_campaign

    folder = tmp_path / "camp"
    folder.mkdir()
    for i in range(3):
        # distinct bytes: files with the same bytes are one run (issue 22, duplicates)
        (folder / f"run{i}_p10bar_v5mms.txt").write_text(f"not a bench file at all {i}\n" * 3)
    with pytest.raises(
        BenchFileError, match=r"none of the 3 run file\(s\) could be read; the first"
    ):
        extract_campaign(folder, skip_bad=True)


# ------------------------------------------------------------------ name_pattern (issue 23)
@pytest.mark.parametrize(
    ("pattern", "message"),
    [
        (
            r"(?P<p>\d+)\1",
            r"line 2: files.name_pattern is not a regular expression RE2.*back-references",
        ),
        (r"(?=p)p(?P<pressure_bar>\d+)", r"line 2: .*look-around"),
    ],
)
def test_name_pattern_that_re2_cannot_match_is_refused_with_its_line(tmp_path, pattern, message):
    (tmp_path / "campaign.toml").write_text(f"[files]\nname_pattern = '{pattern}'\n")
    with pytest.raises(BenchFileError, match=message):
        load_config(tmp_path)


def test_catastrophic_name_pattern_cannot_hang_a_fit(tmp_path):
    """``^(a+)+$`` against a 40-character name backtracks 2**40 times in Python's re; a
    whole `cylfric fit` of such a campaign ends (here: refuses its unmatched files) in
    seconds, in a subprocess with a hard time limit."""
    import subprocess
    import sys
    from pathlib import Path

    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path / "campaign"
    generate_campaign(folder, BenchSettings.clean(pressures_bar=(10.0, 20.0), speeds_mm_s=(5, 50)))
    (folder / "manifest.csv").unlink(missing_ok=True)
    for k, path in enumerate(sorted(folder.glob("*.txt"))):
        path.rename(folder / ("a" * 40 + f"!_p{10 * (1 + k // 2)}bar_v{(5, 50)[k % 2]}mms.txt"))
    (folder / "campaign.toml").write_text("[files]\nname_pattern = '^(a+)+$'\n")
    script = Path(sys.executable).with_name("cylfric")
    done = subprocess.run(
        [str(script), "fit", str(folder), "--out", str(tmp_path / "o"), "--no-report"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode in (0, 2), done.stderr
    assert "Traceback" not in done.stderr
