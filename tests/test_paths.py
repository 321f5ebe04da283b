"""Output paths (issue 23, item 6): an --out that is a symbolic link is refused by every
command that writes, names that become parts of output paths stay inside OUT, globs in
campaign.toml stay inside the campaign folder, and --out NAME.fmu / NAME.mo is that file."""

from __future__ import annotations

import json
import zipfile

import pytest
from typer.testing import CliRunner

from cylfric._paths import OutputPathError, inside, refuse_link
from cylfric.cli import app
from cylfric.export import export
from cylfric.io.writers import atomic_write_text
from cylfric.model import FrictionModel
from cylfric.simulate.bench import BenchSettings, generate_campaign

runner = CliRunner()
VALIDITY = {"pressure_min": 1e4, "pressure_max": 159e5, "velocity_min": 1e-3, "velocity_max": 0.135}
TINY = BenchSettings.clean(pressures_bar=(10.0, 100.0), speeds_mm_s=(5, 50))


@pytest.fixture(scope="module")
def datasheet(tmp_path_factory):
    path = tmp_path_factory.mktemp("sheet") / "datasheet.json"
    path.write_text(json.dumps(FrictionModel(validity=VALIDITY).to_datasheet()))
    return path


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory):
    """A root holding one tiny virtual campaign (the refusals come before any fit)."""
    root = tmp_path_factory.mktemp("root")
    generate_campaign(root / "rig1", TINY)
    return root


def _commands(datasheet, campaigns, tmp_path):
    """Every command that writes an output folder, with the folder left as OUT."""
    record = tmp_path / "record.txt"
    record.write_text("t x\n")
    db = tmp_path / "cat.db"
    added = runner.invoke(app, ["catalog", "add", str(datasheet), "--name", "a", "--db", str(db)])
    assert added.exit_code == 0, added.output
    return {
        "fit": ["fit", str(campaigns / "rig1"), "--no-report", "--out"],
        "demo": ["demo", "--out"],
        "fit-many": ["fit-many", str(campaigns), "--scheduler", "serial", "--out"],
        "export": ["export", str(datasheet), "--to", "matlab", "--out"],
        "fit-motion": ["fit-motion", str(record), "--config", str(record), "--out"],
        "simulate": ["simulate", "thesis_2016", "--out"],
        "plan": ["plan", "--out"],
        "generate": ["generate", "--force"],
        "catalog compare": ["catalog", "compare", "a", "--db", str(db), "--out"],
        "drift": ["drift", str(datasheet), str(datasheet), "--out"],
    }


COMMANDS = (
    "fit",
    "demo",
    "fit-many",
    "export",
    "fit-motion",
    "simulate",
    "plan",
    "generate",
    "catalog compare",
    "drift",
)


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_refuses_an_out_folder_that_is_a_link(
    command, datasheet, campaigns, tmp_path
):
    target = tmp_path / "elsewhere"
    target.mkdir()
    (target / "keep.txt").write_text("the user's\n")
    link = tmp_path / "out"
    link.symlink_to(target, target_is_directory=True)
    args = [*_commands(datasheet, campaigns, tmp_path)[command], str(link)]
    result = runner.invoke(app, args)
    assert result.exit_code == 2, result.output
    assert "is a symbolic link to" in result.output and str(target) in result.output
    assert "Traceback" not in result.output
    assert link.is_symlink() and sorted(p.name for p in target.iterdir()) == ["keep.txt"]


@pytest.mark.parametrize("to", ["fmu", "modelica"])
def test_a_single_file_out_that_is_a_link_is_refused_not_replaced(to, datasheet, tmp_path):
    target = tmp_path / "theirs.bin"
    target.write_text("the user's\n")
    link = tmp_path / ("model.fmu" if to == "fmu" else "Model.mo")
    link.symlink_to(target)
    result = runner.invoke(app, ["export", str(datasheet), "--to", to, "--out", str(link)])
    assert result.exit_code == 2 and "is a symbolic link to" in result.output, result.output
    assert link.is_symlink() and target.read_text() == "the user's\n"


@pytest.mark.parametrize("command", ["predict", "export"])
def test_catalog_file_outputs_refuse_a_link(command, datasheet, tmp_path):
    db = tmp_path / "cat.db"
    runner.invoke(
        app,
        [
            "catalog",
            "add",
            str(datasheet),
            "--name",
            "a",
            "--db",
            str(db),
            "--bore",
            "40",
            "--rod",
            "20",
        ],
    )
    target = tmp_path / "theirs.json"
    target.write_text("{}\n")
    link = tmp_path / "out.json"
    link.symlink_to(target)
    args = (
        ["catalog", "predict", "a", "--bore", "63", "--out", str(link)]
        if command == "predict"
        else ["catalog", "export", str(link)]
    )
    result = runner.invoke(app, [*args, "--db", str(db)])
    assert result.exit_code == 2 and "is a symbolic link to" in result.output, result.output
    assert link.is_symlink() and target.read_text() == "{}\n"


def test_a_dangling_link_is_refused_with_what_to_do(tmp_path):
    link = tmp_path / "out"
    link.symlink_to(tmp_path / "gone")
    with pytest.raises(
        OutputPathError,
        match=r"symbolic link to .*gone.* does not exist; "
        r"remove the link",
    ):
        refuse_link(link)


def test_an_atomic_write_does_not_replace_a_link_inside_an_output_folder(tmp_path):
    target = tmp_path / "theirs.csv"
    target.write_text("kept\n")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "simulation.csv").symlink_to(target)
    with pytest.raises(OutputPathError, match="output file .*simulation.csv is a symbolic link"):
        atomic_write_text(tmp_path / "out" / "simulation.csv", "new\n")
    assert target.read_text() == "kept\n"


def test_an_atomic_write_does_not_replace_a_device(tmp_path):
    with pytest.raises(OutputPathError, match="/dev/null is not a regular file"):
        atomic_write_text("/dev/null", "x")


@pytest.mark.parametrize(
    "name", ["../escape", "a/../../escape", "/abs", "", ".", "a\0b", "a\nb", "..\\x", "C:evil"]
)
def test_names_that_would_leave_out_are_refused(name, tmp_path):
    with pytest.raises(OutputPathError, match="cannot name a file or folder inside"):
        inside(tmp_path / "out", name, "campaign")


def test_names_inside_out_are_kept_and_a_leading_dash_is_harmless(tmp_path):
    out = tmp_path / "out"
    assert inside(out, "rig/-old", "campaign") == out / "rig" / "-old"


def test_a_link_inside_out_pointing_outside_is_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "rig").symlink_to(tmp_path, target_is_directory=True)
    with pytest.raises(OutputPathError):
        inside(out, "rig", "campaign")


@pytest.mark.parametrize("to", ["fmu", "modelica", "hopsan", "matlab"])
def test_a_hostile_model_name_cannot_leave_out(to, datasheet, tmp_path):
    """Names of exported files are identifiers (made or checked): '../' never becomes a
    path part (simscape makes its names as hopsan does, export.simscape._identifier)."""
    out = tmp_path / "out"
    try:
        result = export(datasheet, to, out, name="../../escape")
    except ValueError as exc:  # fmu, matlab: refused as not an identifier
        assert "identifier" in str(exc) or "MATLAB" in str(exc)
        return
    assert all(out in p.resolve().parents for p in result.files)
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_out_f_fmu_writes_that_file_named_after_its_stem(datasheet, tmp_path):
    path = tmp_path / "sub" / "Rig_7.fmu"
    result = runner.invoke(app, ["export", str(datasheet), "--to", "fmu", "--out", str(path)])
    if result.exit_code != 0 and "compiler" in result.output:
        pytest.skip("no C compiler")
    assert result.exit_code == 0, result.output
    assert path.is_file() and zipfile.is_zipfile(path)
    with zipfile.ZipFile(path) as archive:
        assert 'modelIdentifier="Rig_7"' in archive.read("modelDescription.xml").decode()
    assert sorted(p.name for p in path.parent.iterdir()) == ["Rig_7.fmu"]  # no staging left


def test_out_name_mo_writes_that_file_even_when_the_stem_is_no_identifier(datasheet, tmp_path):
    path = tmp_path / "my seal-2.mo"
    result = runner.invoke(app, ["export", str(datasheet), "--to", "modelica", "--out", str(path)])
    assert result.exit_code == 0, result.output
    assert path.is_file() and "package " in path.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["my seal-2.mo"]


def test_an_existing_folder_named_like_a_file_stays_a_folder(datasheet, tmp_path):
    """Before issue 23 --out f.mo made a folder: such a folder is still written into."""
    folder = tmp_path / "f.mo"
    folder.mkdir()
    result = runner.invoke(
        app, ["export", str(datasheet), "--to", "modelica", "--out", str(folder), "--name", "rig"]
    )
    assert result.exit_code == 0, result.output
    assert (folder / "Rig.mo").is_file()  # the package name, capitalised


def test_folder_targets_refuse_a_file_out(datasheet, tmp_path):
    path = tmp_path / "x.m"
    path.write_text("% mine\n")
    result = runner.invoke(app, ["export", str(datasheet), "--to", "matlab", "--out", str(path)])
    assert result.exit_code == 2 and "is a file; expected a folder" in result.output
    assert path.read_text() == "% mine\n"


@pytest.mark.parametrize(
    ("glob", "problem"),
    [
        ("/data/runs/*.txt", "is absolute"),
        ("C:/runs/*.txt", "is absolute"),
        ("../other/*.txt", "climbs out"),
        ("runs/../../*.txt", "climbs out"),
    ],
)
def test_a_glob_outside_the_campaign_is_refused_with_its_line(glob, problem, campaigns, tmp_path):
    folder = tmp_path / "campaign"
    folder.mkdir()
    for path in (campaigns / "rig1").iterdir():
        (folder / path.name).write_bytes(path.read_bytes())
    (folder / "campaign.toml").write_text(f'# runs\n[files]\nglob = "{glob}"\n')
    result = runner.invoke(app, ["fit", str(folder), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    message = " ".join(result.output.split())
    assert f"campaign.toml, line 3: files.glob = '{glob}' {problem}" in message
    assert "relative to it" in message and "Traceback" not in result.output


def test_a_command_line_glob_outside_the_campaign_is_refused(campaigns, tmp_path):
    result = runner.invoke(
        app,
        ["fit", str(campaigns / "rig1"), "--glob", "/tmp/*.txt", "--out", str(tmp_path / "out")],
    )
    assert result.exit_code == 2 and "--glob = '/tmp/*.txt' is absolute" in result.output
