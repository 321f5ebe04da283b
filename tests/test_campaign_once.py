"""One ``cylfric fit`` reads campaign.toml and manifest.csv once each (issue 24, item 2).

The campaign is opened once (:meth:`cylfric.io.campaign.Campaign.open`) and passed down to
every step: the progress bar's count, the extraction, the presliding and breakaway tests,
the viscosity correction. Counted here by wrapping the two readers of ``cylfric.io.campaign``
(every caller reaches them through that module's globals).
"""

from __future__ import annotations

import tomllib
from types import SimpleNamespace

import pytest
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.io import campaign as campaign_module
from cylfric.simulate.bench import TESTS, BenchSettings, generate_campaign

CONFIG = """\
[files]
glob = "*.txt"

[force_balance]
load_cell_sign = 1
"""


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A small virtual campaign with presliding and breakaway tests and a campaign.toml."""
    folder = tmp_path_factory.mktemp("once") / "campaign"
    settings = BenchSettings.clean(
        pressures_bar=(20.0, 80.0, 140.0), speeds_mm_s=(5, 20, 100), seed=2
    )
    generate_campaign(folder, settings, tests=TESTS)
    (folder / "campaign.toml").write_text(CONFIG, encoding="utf-8")
    return folder


@pytest.fixture
def reads(monkeypatch):
    """Counts of campaign.toml parses and manifest.csv reads while the test runs."""
    counts = {"campaign.toml": 0, "manifest.csv": 0}
    read_manifest = campaign_module._read_manifest

    def loads(text, **keywords):
        counts["campaign.toml"] += 1
        return tomllib.loads(text, **keywords)

    def counting_manifest(folder):
        counts["manifest.csv"] += 1
        return read_manifest(folder)

    fake = SimpleNamespace(loads=loads, TOMLDecodeError=tomllib.TOMLDecodeError)
    monkeypatch.setattr(campaign_module, "tomllib", fake)
    monkeypatch.setattr(campaign_module, "_read_manifest", counting_manifest)
    return counts


def test_one_fit_reads_the_campaign_files_once(folder, tmp_path, reads):
    result = CliRunner().invoke(
        app, ["fit", str(folder), "--out", str(tmp_path / "fit"), "--no-report"]
    )
    assert result.exit_code == 0, result.output
    assert (tmp_path / "fit" / "dynamic.csv").is_file()  # the dynamic tests were identified
    assert reads == {"campaign.toml": 1, "manifest.csv": 1}


def test_campaign_holds_what_the_steps_need(folder, reads):
    from cylfric.io.campaign import Campaign, discover_runs, unlisted_files

    campaign = Campaign.open(folder)
    assert reads == {"campaign.toml": 1, "manifest.csv": 1}
    assert campaign.folder == folder and campaign.config.glob == "*.txt"
    assert [r.path for r in campaign.runs] == [r.path for r in discover_runs(folder)]
    assert list(campaign.unlisted) == unlisted_files(folder)
    assert set(campaign.manifest) == {r.path.name for r in campaign.runs}
    kinds = {str(r.extra.get("test")) for r in campaign.dynamic_runs}
    assert kinds == {"presliding", "breakaway"}
    assert len(campaign.steady_runs) + len(campaign.dynamic_runs) == len(campaign.runs)
    assert all(r.extra.get("test") == "constant-velocity" for r in campaign.steady_runs)


def test_a_campaign_is_passed_with_its_own_configuration(folder, tmp_path):
    from cylfric.io.campaign import Campaign
    from cylfric.pipeline import fit_campaign
    from cylfric.steady_state import extract_campaign

    campaign = Campaign.open(folder, glob="run_00*.txt")
    assert campaign.config.glob == "run_00*.txt"
    with pytest.raises(ValueError, match="campaign was opened with glob 'run_00\\*.txt'"):
        fit_campaign(campaign, tmp_path / "o", glob="*.txt")
    with pytest.raises(ValueError, match="config comes with the Campaign"):
        extract_campaign(campaign, campaign.config)
