"""Hostile motion records (issue 23, item 4, second check): a constant force or position
channel, a sample of absurd magnitude and a least-squares failure are refused with exit 2,
naming the file, the channel and the sample; motion_fit.json is always valid JSON."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.io import savemat
from test_motion_plausibility import _config, _signals
from typer.testing import CliRunner

from cylfric.cli import app
from cylfric.identify.motion import _least_squares

runner = CliRunner()


def _record(tmp_path, *, force=None, spike=None):
    t, x, f = _signals()
    if force is not None:
        f = np.full_like(f, force)
    if spike is not None:
        x[spike] = 1e308
    path = tmp_path / "record.mat"
    savemat(path, {"t": t, "q": x, "u": f})
    return path


def _fit(tmp_path, record):
    out = tmp_path / "out"
    done = runner.invoke(
        app, ["fit-motion", str(record), "--config", str(_config(tmp_path)), "--out", str(out)]
    )
    return done, out


def test_a_force_channel_of_zeros_is_refused_naming_it(tmp_path):
    done, out = _fit(tmp_path, _record(tmp_path, force=0.0))
    assert done.exit_code == 2, done.output
    assert "record.mat" in done.output and "u (force) does not change" in done.output
    assert "Warning" not in done.output and not out.exists()


def test_a_sample_of_absurd_magnitude_is_refused_naming_file_channel_and_index(tmp_path):
    done, out = _fit(tmp_path, _record(tmp_path, spike=5000))
    assert done.exit_code == 2, done.output
    assert "record.mat" in done.output
    assert "q (position) holds 1e+308 m at sample 5000" in done.output
    assert "SVD" not in done.output and not out.exists()


def test_a_failing_least_squares_names_the_record():
    W = np.array([[1.0, np.inf], [2.0, 1.0], [3.0, 0.0]])
    with pytest.raises(ValueError, match=r"rec\.mat: the least-squares fit of"):
        _least_squares(W, np.ones(3), "rec.mat", ("mass", "F_v"))


def test_motion_fit_json_is_valid_json_with_null_for_non_finite(tmp_path, monkeypatch):
    from cylfric.identify import motion

    original = motion.MotionFit.to_dict

    def with_nan(self):
        return {**original(self), "relative_error": float("nan")}

    monkeypatch.setattr(motion.MotionFit, "to_dict", with_nan)
    done, out = _fit(tmp_path, _record(tmp_path))
    assert done.exit_code == 0, done.output
    text = (out / "motion_fit.json").read_text()
    document = json.loads(text, parse_constant=lambda c: pytest.fail(f"bare {c}"))
    assert document["relative_error"] is None
