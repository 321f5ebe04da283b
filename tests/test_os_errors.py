"""OSError messages name the file and the action (issue 23, item 7): a full disk, a file
where a folder is expected; exit code 2, one line, no traceback."""

from __future__ import annotations

import errno
import json
import os

import pytest
from typer.testing import CliRunner

import cylfric._atomic
from cylfric._paths import os_error_message
from cylfric.cli import app
from cylfric.io.writers import atomic_write_text
from cylfric.model import FrictionModel

runner = CliRunner()


@pytest.fixture(scope="module")
def datasheet(tmp_path_factory):
    path = tmp_path_factory.mktemp("sheet") / "datasheet.json"
    path.write_text(json.dumps(FrictionModel().to_datasheet()))
    return path


def _disk_full(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # no file name, as write(2) gives


def test_a_full_disk_names_the_target_keeps_errno_and_leaves_no_temporary(tmp_path, monkeypatch):
    monkeypatch.setattr(cylfric._atomic.os, "replace", _disk_full)
    with pytest.raises(OSError) as caught:
        atomic_write_text(tmp_path / "datasheet.json", "{}")
    assert caught.value.errno == errno.ENOSPC
    assert caught.value.filename == str(tmp_path / "datasheet.json")
    assert os_error_message(caught.value) == (
        f"writing {tmp_path / 'datasheet.json'}: No space left on device"
    )
    assert list(tmp_path.iterdir()) == []


def test_a_permission_error_keeps_its_class(tmp_path, monkeypatch):
    def denied(*args, **kwargs):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(cylfric._atomic.os, "replace", denied)
    with pytest.raises(PermissionError, match="Permission denied"):
        atomic_write_text(tmp_path / "a.csv", "x")


def test_the_command_line_names_the_file_and_the_action_on_a_full_disk(
    datasheet, tmp_path, monkeypatch
):
    monkeypatch.setattr(cylfric._atomic.os, "replace", _disk_full)
    out = tmp_path / "out"
    result = runner.invoke(app, ["export", str(datasheet), "--to", "matlab", "--out", str(out)])
    assert result.exit_code == 2
    message = " ".join(result.output.split())
    assert f"error: writing {out / 'cylfric_params.m'}: No space left on device" in message
    assert "Traceback" not in result.output


def test_a_file_where_a_folder_is_expected_is_named(datasheet, tmp_path):
    blocker = tmp_path / "afile"
    blocker.write_text("")
    result = runner.invoke(
        app, ["export", str(datasheet), "--to", "matlab", "--out", str(blocker / "x")]
    )
    assert result.exit_code == 2 and "Traceback" not in result.output
    message = " ".join(result.output.split())
    assert f"creating the folder {blocker / 'x'}: Not a directory" in message
    simulated = runner.invoke(
        app, ["simulate", "thesis_2016", "--duration", "0.01s", "--out", str(blocker)]
    )
    assert simulated.exit_code == 2
    assert f"--out {blocker} is a file; expected a folder" in " ".join(simulated.output.split())


def test_a_fit_into_a_folder_under_a_file_is_named(tmp_path):
    blocker = tmp_path / "afile"
    blocker.write_text("")
    campaign = tmp_path / "campaign"
    generated = runner.invoke(
        app, ["generate", str(campaign), "--pressures", "10,100", "--speeds", "5,50"]
    )
    assert generated.exit_code == 0, generated.output
    result = runner.invoke(
        app, ["fit", str(campaign), "--no-report", "--out", str(blocker / "out")]
    )
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert f"--out {blocker / 'out'}: its folder {blocker} is a file" in " ".join(
        result.output.split()
    )
