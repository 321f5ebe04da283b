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


def test_a_run_keeps_only_what_the_manifest_did_not_say(tmp_path):
    """RunInfo keeps no dictionaries for a run whose values all come from manifest.csv (made
    when asked for, the same as before); a run named by name_pattern keeps its own; both
    compare, copy, pickle and refuse changes like the dataclass they were."""
    import math
    import pickle

    from cylfric.io.campaign import Campaign, RunInfo

    (tmp_path / "campaign.toml").write_text(
        '[files]\nname_pattern = "p(?P<pressure_bar>[0-9]+)bar"\n'
    )
    (tmp_path / "manifest.csv").write_text(
        "file,pressure_bar,velocity_mm_s,seal\n"
        "a.txt,20,5,S1\n"  # everything from the manifest
        "b_p30bar.txt,,8,\n"  # the pressure from the file name
        "c.txt,,,\n"  # nothing known
    )
    for name in ("a.txt", "b_p30bar.txt", "c.txt"):
        (tmp_path / name).write_text(f"{name}\n")
    a, b, c = Campaign.open(tmp_path).runs
    assert a._source is None and a._nominal is None  # made from pressure, velocity, line
    assert a.source == {"pressure": "manifest", "velocity": "manifest"}
    assert a.nominal == {
        "pressure": {"manifest": (20e5, "manifest.csv line 2")},
        "velocity": {"manifest": (5e-3, "manifest.csv line 2")},
    }
    assert a.extra == {"seal": "S1"} and a.seal == "S1"
    assert b._nominal is not None  # a value from name_pattern: its own dictionaries
    assert b.source == {"velocity": "manifest", "pressure": "campaign.toml name_pattern"}
    assert b.nominal["pressure"] == {"campaign.toml name_pattern": (30e5, "pressure_bar = 30")}
    assert b.seal is None
    assert math.isnan(c.pressure) and c.source == {}
    assert c.nominal == {"pressure": {}, "velocity": {}}
    for run in (a, b):
        assert pickle.loads(pickle.dumps(run)) == run  # to a Dask worker and back
    assert repr(pickle.loads(pickle.dumps(c))) == repr(c)  # NaN != NaN
    assert repr(a).startswith("RunInfo(path=") and "nominal={'pressure': {'manifest'" in repr(a)
    moved = a.replace(path=tmp_path / "elsewhere.txt")
    assert moved.path.name == "elsewhere.txt" and moved.nominal == a.nominal and moved != a
    assert moved.replace(path=a.path) == a
    built = RunInfo(a.path, a.pressure, a.velocity, a.extra, a.source, a.nominal, 2, a.manifest)
    assert built == a and built._nominal is None
    with pytest.raises(AttributeError, match="immutable"):
        a.pressure = 1.0
    # built by hand: kept as given unless exactly the manifest's own form
    assert RunInfo(a.path).nominal == {} and RunInfo(a.path).source == {}
    given = {"velocity": "manifest", "pressure": "manifest"}  # another order
    assert list(RunInfo(a.path, 2e6, 5e-3, None, given, a.nominal, 2).source) == list(given)
    exact = {"pressure": {"manifest": (2000000, "manifest.csv line 2")}, "velocity": {}}
    as_int = RunInfo(a.path, 2e6, math.nan, None, {"pressure": "manifest"}, exact, 2)
    assert as_int.nominal["pressure"]["manifest"][0].__class__ is int  # not made from 2e6
