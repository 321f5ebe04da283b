"""Hypothesis properties over every registered friction law."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.testing import assert_allclose

from cylfric import friction as fr

velocities = st.floats(min_value=-2.0, max_value=2.0, allow_nan=False)
LAW_NAMES = sorted(fr.LAWS)


def _state_args(law, sign=1.0, value=None):
    """Extra positional state/extern inputs for a law, mirrored by ``sign``."""
    kwargs = {}
    if law.state == "z":
        kwargs["z"] = sign * (0.3e-4 if value is None else value)
    elif law.state == "force":
        kwargs["force"] = sign * (20.0 if value is None else value)
    if law.name == "stiction":
        kwargs["external_force"] = sign * 40.0
    return kwargs


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=60, deadline=None)
@given(v=velocities)
def test_every_law_is_odd_in_velocity(name, v):
    law = fr.LAWS[name]
    plus = law.function(v, **_state_args(law, +1.0), **law.example)
    minus = law.function(-v, **_state_args(law, -1.0), **law.example)
    assert_allclose(minus, -plus, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name", LAW_NAMES)
def test_every_law_is_finite_at_zero_velocity(name):
    law = fr.LAWS[name]
    assert np.isfinite(law.function(0.0, **_state_args(law), **law.example))


@pytest.mark.parametrize("name", LAW_NAMES)
@settings(max_examples=25, deadline=None)
@given(v=st.lists(velocities, min_size=1, max_size=7))
def test_every_law_broadcasts(name, v):
    law = fr.LAWS[name]
    arr = np.asarray(v)
    out = law.function(arr, **_state_args(law), **law.example)
    assert isinstance(out, np.ndarray) and out.shape == arr.shape
    scalars = [law.function(x, **_state_args(law), **law.example) for x in v]
    assert all(isinstance(s, float) for s in scalars)
    assert_allclose(out, scalars, rtol=1e-12, atol=1e-12)
    # a column of velocities against a row of parameter values
    grid = law.function(
        arr[:, None], **_state_args(law), **{k: np.full(3, val) for k, val in law.example.items()}
    )
    assert grid.shape == (arr.size, 3)


@pytest.mark.parametrize("name", ["stribeck", "coulomb", "viscous", "lugre_steady_state"])
@settings(max_examples=60, deadline=None)
@given(v=velocities)
def test_steady_laws_dissipate(name, v):
    law = fr.LAWS[name]
    assert law.function(v, **law.example) * v >= 0
