"""Behaviour unchanged (issue 24): the outputs of fixed virtual campaigns, fitted with the
report and every export, equal those recorded before the plumbing was simplified
(``tests/data/golden_outputs.json``, written by ``python tests/golden.py``), byte for byte
where they are deterministic (all but the creation date and the SVG files' ids)."""

from __future__ import annotations

import json

import pytest
from golden import GOLDEN, run


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    return run(tmp_path_factory.mktemp("golden"))


def test_outputs_are_those_recorded_before(outputs):
    expected = json.loads(GOLDEN.read_text())
    for name in expected:
        if name.endswith("/datasheet"):
            assert outputs[name] == expected[name], name
    for name in expected:
        if not name.endswith("/datasheet"):
            assert sorted(outputs[name]) == sorted(expected[name]), f"{name}: files differ"
            changed = [f for f in expected[name] if outputs[name][f] != expected[name][f]]
            assert not changed, f"{name}: changed outputs {changed}"
