"""Standard streams a careless caller leaves unusable (issue 43, item 8): a closed standard
output and an ASCII-only encoding end in no "unexpected" error. Both fail on the code
before (exit 1, "unexpected AttributeError"; exit 2, "'ascii' codec can't encode")."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from cylfric.model import FrictionModel


def _sheet(tmp_path, name="cylinder"):
    sheet = FrictionModel().to_datasheet()
    sheet["name"] = name
    path = tmp_path / "ds.json"
    path.write_text(json.dumps(sheet))
    return path


def _cylfric(*args, **options):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    env.update(options.pop("env", {}))
    return subprocess.run(
        [sys.executable, "-m", "cylfric", *args],
        capture_output="stdout" not in options,
        stderr=subprocess.PIPE if "stdout" in options else None,
        text=True,
        env=env,
        timeout=120,
        **options,
    )


def test_json_to_a_closed_standard_output_is_no_unexpected_error(tmp_path):
    path = _sheet(tmp_path)
    result = _cylfric("show", str(path), "--json", stdout=None, preexec_fn=lambda: os.close(1))
    assert "unexpected" not in result.stderr, result.stderr
    assert result.returncode == 0, result.stderr


def test_an_ascii_only_terminal_shows_names_as_escapes(tmp_path):
    path = _sheet(tmp_path, "Dichtung \u00e4 \u2603")
    result = _cylfric("show", str(path), env={"PYTHONIOENCODING": "ascii"})
    assert result.returncode == 0, result.stderr
    assert "Dichtung \\xe4 \\u2603" in result.stdout
