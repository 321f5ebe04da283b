"""Shared fixtures: the real data in ../shared (skipped cleanly when absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
DATA = SHARED / "data"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path to ../shared/data; skips the test when this clone has no ../shared."""
    if not DATA.is_dir():
        pytest.skip("../shared/data is absent (clone outside the workplace)")
    return DATA
