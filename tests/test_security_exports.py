"""User text never becomes code in an export (issue 23, item 1; docs/security.md).

A datasheet comes from someone else: every text field of it (name, notes, fit method, source
campaign and file names, the reasons of parameters not identified, the status reasons and
units of the dynamic parameters, the equation text, the scatter record's method, sources and
prior basis, the lack-of-fit test's name and action) is filled with hostile strings (quotes,
backslashes, comment closers and openers, newlines, %, ;, NUL, non-ASCII, bidirectional
overrides, 4 KB) and the model is exported to every target. Each payload starts with a line
break followed by a marker call, so that a payload that escaped its comment or literal would
begin a generated line with the marker's call. The checks: no generated line starts with a marker,
the marker does reach the files (so the check is not vacuous), the FMU validates with fmpy and
its compiled binary references no symbol a clean export does not, the Modelica package parses,
the Hopsan script holds only comments and ``chpa`` commands, and the MATLAB files run in
Octave where it is installed.
"""

from __future__ import annotations

import copy
import re
import shutil
import subprocess
import zipfile

import pytest
from export_models import MODELS

from cylfric import escape
from cylfric.export import export
from cylfric.model import FrictionModel

MARKER = "INJECTED"
PAYLOADS = {
    "c_comment": f"\n{MARKER}_c(); */ extern void {MARKER}_call(void); void h(void){{{MARKER}_call();}} /*",
    "quotes": f"\n{MARKER}_q(); \" ' \\\" \\' '' \"\" ; %",
    "matlab": f"\n{MARKER}_m(); % ; ... %{{\n%}}\n{MARKER}_m2()",
    "backslash": f"\\\n{MARKER}_b(); \\n \\x00 \\\\ ??/",
    "nul_and_controls": f"\x00\r{MARKER}_nul();\x1b[31m\x07\x0b\x0c\u2028{MARKER}_ls();\u2029",
    "non_ascii": f"\n{MARKER}_u(); Pérez Dorado – 漢字 \u202e evil \U0001f600 \ud800",
    "markup": f"\n{MARKER}_x(); <script>alert(1)</script> [bold]x[/] ]]> <!-- # | `",
    "long": f"\n{MARKER}_long();" + "A" * 4096 + "*/ /* \n" * 8,
}

CALL = re.compile(rf"\s*{MARKER}\w*\s*\(")
"""A generated line that begins with a marker call: a payload out of its comment or literal
(an identifier mangled from a name may begin with the marker, but never with its call)."""


MATLAB_LITERAL = re.compile(r"P\.[A-Za-z_][\w.]* = '(?:[^']|'')*';")
"""A MATLAB line that assigns one character literal to a struct field and does nothing else."""


def hostile_sheet(payload: str) -> dict:
    """The coulomb_viscous test model's datasheet with ``payload`` in every text field."""
    model = MODELS["coulomb_viscous"]
    sheet = copy.deepcopy(model.to_datasheet())
    sheet["name"] = payload
    sheet["notes"] = [payload, "a second note " + payload]
    sheet["created"] = payload
    sheet["cylfric_version"] = payload
    sheet["model"]["equation"] = payload
    sheet["fit"]["method"] = payload
    sheet["fit"]["source"] = {
        "campaign": payload,
        "files": [{"name": payload, "sha256": "0" * 64}],
    }
    sheet["not_identified"] = {k: payload for k in sheet["not_identified"]}
    for entry in sheet["dynamic"].values():
        entry["reason"] = payload  # (a unit is not free text: a non-SI one is refused, issue 43)
    component = {"std_percent": 3.0, "std_N": 2.7, "source": payload, "dof": 10}
    sheet["fit"]["scatter"] = {  # issue 22: the scatter record's texts reach every export
        "method": payload,
        "relative": True,
        "sessions": 1,
        "runs": 3,
        "points": 30,
        "reference_force_N": 90.0,
        "components": {
            "repeatability": dict(component),
            "run": dict(component),
            "session": {  # the session source is an enum of the schema
                **component,
                "source": "prior",
                "prior_percent": 14.0,
                "prior_basis": payload,
            },
        },
        "reproducibility": {"std_percent": 14.5, "std_N": 13.0},
    }
    sheet["quality"] = {
        "lack_of_fit": {
            "test": payload,
            "statistic": 3.0,
            "dof": [4, 20],
            "p_value": 0.02,
            "significant": True,
            "rms_lack_N": 1.0,
            "action": payload,
        }
    }
    sheet["validity"] = {
        "pressure_min": 1e5,
        "pressure_max": 100e5,
        "velocity_min": 1e-3,
        "velocity_max": 0.1,
    }
    return sheet


def _text_files(folder) -> dict[str, str]:
    """Every generated text file under ``folder`` (FMU members included), by relative name."""
    texts = {}
    for path in sorted(folder.rglob("*")):
        if path.suffix == ".fmu":
            with zipfile.ZipFile(path) as archive:
                for member in archive.namelist():
                    if not member.startswith("binaries/"):
                        texts[f"{path.name}/{member}"] = archive.read(member).decode("utf-8")
        elif path.is_file() and path.suffix not in (".png", ".svg"):
            texts[path.name] = path.read_text(encoding="utf-8")
    return texts


def _assert_payload_is_data(texts: dict[str, str]) -> None:
    reached = False
    for name, text in texts.items():
        for number, line in enumerate(text.splitlines(), 1):
            assert not CALL.match(line), f"{name}:{number}: {line[:120]!r}"
            assert "\x00" not in line and "\x1b" not in line, f"{name}:{number}: raw control"
        reached = reached or MARKER in text
    assert reached, "no generated file carries the user text: the check would be vacuous"


@pytest.fixture(scope="module", params=sorted(PAYLOADS))
def hostile(request):
    return request.param, FrictionModel.from_datasheet(hostile_sheet(PAYLOADS[request.param]))


def _undefined_symbols(fmu_path) -> set[str]:
    with zipfile.ZipFile(fmu_path) as archive:
        binaries = [m for m in archive.namelist() if m.startswith("binaries/")]
        assert binaries, "the FMU was exported without a binary"
        data = archive.read(binaries[0])
    target = fmu_path.with_suffix(".so")
    target.write_bytes(data)
    done = subprocess.run(
        ["nm", "-D", "--undefined-only", str(target)], capture_output=True, text=True, check=True
    )
    return {line.split()[-1] for line in done.stdout.splitlines() if line.strip()}


@pytest.mark.skipif(shutil.which("nm") is None, reason="nm (binutils) is not installed")
def test_fmu_holds_user_text_only_in_comments_and_xml_values(hostile, tmp_path):
    from fmpy.validation import validate_fmu

    key, model = hostile
    (path,) = export(model, "fmu", tmp_path / "fmu").files
    _assert_payload_is_data(_text_files(tmp_path / "fmu"))
    assert validate_fmu(str(path)) == []
    clean = export(MODELS["coulomb_viscous"], "fmu", tmp_path / "clean").files[0]
    symbols = _undefined_symbols(path)
    assert not any(MARKER in s for s in symbols), sorted(symbols)
    assert symbols == _undefined_symbols(clean)


def test_matlab_and_simscape_hold_user_text_only_in_comments(hostile, tmp_path):
    _, model = hostile
    export(model, "matlab", tmp_path)
    export(model, "simscape", tmp_path, n_velocity=12, n_pressure=3)
    texts = _text_files(tmp_path)
    _assert_payload_is_data(texts)
    for name, text in texts.items():
        if not name.endswith(".m"):
            continue
        for line in text.splitlines():
            # every MATLAB line that carries the marker has it after a comment sign, or is
            # one assignment of a character literal (the scatter record's texts)
            if MARKER in line and not MATLAB_LITERAL.fullmatch(line):
                assert "%" in line and line.index("%") < line.index(MARKER), (name, line)


def test_modelica_package_parses_with_user_text_in_literals(hostile, tmp_path):
    modparc = pytest.importorskip("modparc")
    _, model = hostile
    (path,) = export(model, "modelica", tmp_path).files
    text = path.read_text(encoding="utf-8")
    _assert_payload_is_data({path.name: text})
    modparc.parse(text)
    # the name is the package's identifier, mangled; the text itself only inside strings
    assert re.match(r"within ;\npackage [A-Za-z_][A-Za-z0-9_]* \"", text)


def test_hopsan_script_is_comments_and_chpa_commands_only(hostile, tmp_path):
    _, model = hostile
    export(model, "hopsan", tmp_path, n_velocity=12, n_pressure=3)
    texts = _text_files(tmp_path)
    _assert_payload_is_data(texts)
    (script,) = [t for n, t in texts.items() if n.endswith(".hcom")]
    for line in script.splitlines():
        assert (
            line == ""
            or line.startswith("#")
            or re.fullmatch(r"chpa [A-Za-z]+\.[A-Za-z_]+ [-+0-9.eE]+", line)
        ), line
    readme = texts["README_hopsan.md"]
    assert readme.startswith("# Hopsan friction parameters from ")
    assert "<script>" not in readme


OCTAVE = shutil.which("octave-cli") or shutil.which("octave")


@pytest.mark.skipif(OCTAVE is None, reason="octave-cli is not installed")
def test_octave_runs_the_hostile_matlab_export(hostile, tmp_path):
    _, model = hostile
    export(model, "matlab", tmp_path)
    export(model, "simscape", tmp_path, n_velocity=12, n_pressure=3)
    stem = escape.identifier(model.record["name"])
    script = (
        "P = cylfric_params(); disp(P.friction_law); "
        "F = cylfric_friction(0.02, 50e5, 50e5, P); printf('%.12g\\n', F); "
        f"run('{stem}_simscape.m'); disp(numel(P.translational_friction))"
    )
    done = subprocess.run(
        [OCTAVE, "--no-gui", "--norc", "--quiet", "--eval", script],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert MARKER not in done.stdout + done.stderr
    lines = done.stdout.split()
    assert lines[0] == "coulomb_viscous"
    expected = model.friction(0.02, model.operating_pressure(50e5, 50e5))
    assert float(lines[1]) == pytest.approx(float(expected), rel=1e-9)


# ---------------------------------------------------------------------------- the escapers
@pytest.mark.parametrize("payload", list(PAYLOADS.values()))
def test_escapers_give_one_line_without_their_terminators(payload):
    for function in (
        escape.c_comment,
        escape.matlab_comment,
        escape.hcom_comment,
        escape.markdown_text,
        escape.html_text,
        escape.terminal,
    ):
        text = function(payload)
        assert len(text.splitlines()) == 1 and text.isprintable(), function.__name__
    assert "*/" not in escape.c_comment(payload) and "/*" not in escape.c_comment(payload)
    assert escape.c_comment(payload).isascii()
    literal = escape.c_string(payload)
    assert literal.isascii() and literal.isprintable() and "??" not in literal
    assert escape.matlab_string(payload)[1:-1].replace("''", "").count("'") == 0
    inner = escape.modelica_string(payload, quotes=False)
    assert re.fullmatch(r'(?:[^"\\]|\\["\\])*', inner)
    assert "<" not in escape.html_text(payload) and "<" not in escape.markdown_text(payload)


def test_c_string_compiles_to_the_same_bytes(tmp_path):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    payload = PAYLOADS["non_ascii"].replace("\ud800", "") + PAYLOADS["c_comment"] + "??/??="
    source = tmp_path / "s.c"
    source.write_text(
        "#include <stdio.h>\nint main(void){fputs(" + escape.c_string(payload) + ", stdout);"
        "return 0;}\n",
        encoding="ascii",
    )
    subprocess.run([cc, "-std=c99", "-o", str(tmp_path / "s"), str(source)], check=True)
    out = subprocess.run([str(tmp_path / "s")], capture_output=True, check=True).stdout
    assert out == payload.encode("utf-8")


@pytest.mark.parametrize(
    ("name", "expected"),
    [
        ("zillen PK", "zillen_PK"),
        ("3 bar", "cylfric_3_bar"),
        ("a\nb(); %", "a_b"),
        ("漢字", "cylfric"),
        ("", "cylfric"),
        ("_x", "x"),
    ],
)
def test_identifier_mangles_to_a_c_identifier(name, expected):
    assert escape.identifier(name) == expected
    assert re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", escape.identifier(name))


def test_fit_of_a_hostile_campaign_folder_exports_text_as_data(tmp_path):
    """A campaign folder and a run file named with a newline, a comment closer, quotes,
    markup and ESC, fitted with the report and every export: the name reaches the files
    only as data."""
    from typer.testing import CliRunner

    from cylfric.cli import app
    from cylfric.simulate.bench import BenchSettings, generate_campaign

    folder = tmp_path / f"rig\n{MARKER}_f(); */ \" ' % ; [bold] \x1b[31m é"
    generate_campaign(
        folder, BenchSettings.clean(pressures_bar=(10.0, 80.0), speeds_mm_s=(2, 10, 50))
    )
    (folder / "manifest.csv").unlink()
    first = sorted(folder.glob("*.txt"))[0]
    first.rename(folder / f"run\n{MARKER}_r(); */{first.name}".replace("/", "|"))
    out = tmp_path / "out"
    result = CliRunner().invoke(
        app, ["fit", str(folder), "--out", str(out), "--export", "fmu,matlab,modelica,hopsan"]
    )
    assert result.exit_code == 0, result.output
    texts = _text_files(out)
    # CSV tables hold the names as data with their control characters shown (issue 43:
    # escape.csv_text), so a spreadsheet or a terminal shows the name, not a new row
    import pandas as pd

    points = pd.read_csv(out / "points.csv")
    assert any(f"run\\x0a{MARKER}_r();" in str(name) for name in points["file"])
    assert not any("\n" in str(name) for name in points["file"])
    _assert_payload_is_data({n: t for n, t in texts.items() if not n.endswith(".csv")})
    assert "<script" not in texts["report.html"].lower()
