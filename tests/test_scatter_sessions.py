"""Sessions as a factor (issue 22): where a campaign says which session each run belongs to
(manifest column, name_pattern group, one subfolder per session), and the points' column."""

from __future__ import annotations

from cylfric.io.campaign import Campaign
from cylfric.simulate.bench import BenchSettings, generate_campaign
from cylfric.steady_state import extract_campaign


def _touch(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"# {path}\ntime velocity\n0 1\n")  # distinct bytes: not duplicates
    return path


def test_session_from_name_pattern(tmp_path):
    for name in ("1_seal_3bar.txt", "2_seal_3bar.txt"):
        _touch(tmp_path / name)
    (tmp_path / "campaign.toml").write_text(
        "[files]\nglob = \"*.txt\"\nname_pattern = '^(?P<session>[0-9]+)_(?P<seal>[a-z]+)_'\n"
    )
    runs = Campaign.open(tmp_path).runs
    assert [r.session for r in runs] == ["1", "2"]
    assert runs[0].extra["seal"] == "seal"


def test_session_from_manifest_wins_over_the_name(tmp_path):
    _touch(tmp_path / "1_a.txt")
    (tmp_path / "campaign.toml").write_text("[files]\nname_pattern = '^(?P<session>[0-9]+)_'\n")
    (tmp_path / "manifest.csv").write_text(
        "file,pressure_bar,velocity_mm_s,session\n1_a.txt,3,10,day2\n"
    )
    assert Campaign.open(tmp_path).runs[0].session == "day2"


def test_session_from_subfolders_only_when_the_glob_says_so(tmp_path):
    for name in ("monday/a.txt", "tuesday/a.txt"):
        _touch(tmp_path / name)
    runs = Campaign.open(tmp_path, "*/*.txt").runs
    assert [r.session for r in runs] == ["monday", "tuesday"]
    # a literal folder is a folder of runs, not of sessions
    assert Campaign.open(tmp_path, "monday/*.txt").runs[0].session is None
    assert Campaign.open(tmp_path, "**/*.txt").runs[0].session == "monday"


def test_points_table_has_a_session_column(tmp_path):
    settings = BenchSettings.clean(pressures_bar=(20, 60), speeds_mm_s=(5.0, 20.0), seed=1)
    generate_campaign(tmp_path / "c", settings)
    points = extract_campaign(tmp_path / "c").points
    assert "session" in points
    assert points["session"].isna().all()  # the campaign does not say
    rough = BenchSettings(pressures_bar=(20, 60), speeds_mm_s=(5.0, 20.0), seed=1, sessions=2)
    generate_campaign(tmp_path / "r", rough)  # the rough bench's manifest names the session
    points = extract_campaign(tmp_path / "r").points
    assert sorted(points["session"].unique()) == ["s1", "s2"]
