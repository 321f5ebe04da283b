"""The architecture holds (issue 24 item 3): no import circles, no upward imports.

``lint-imports`` checks the contracts of pyproject.toml ([tool.importlinter]): the layers
from the command line down to the friction laws, with one documented exception
(``FrictionModel.plot`` delegating to the report's figures), and no circles among the
modules of a package. grimp, which it uses, counts imports inside functions too.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_import_contracts_are_kept():
    tool = shutil.which("lint-imports") or str(Path(sys.executable).with_name("lint-imports"))
    if not Path(tool).exists():
        pytest.fail("lint-imports (import-linter, a test extra) is not installed")
    done = subprocess.run(
        [tool, "--no-cache"], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stdout[-3000:]
    assert "0 broken" in done.stdout
