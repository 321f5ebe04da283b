"""The runs' CR2 covariance of the surface fits (identify.pressure_fit._cluster_robust).

Identity: the batched computation (runs of equal size stacked) equals the straightforward
per-run formula of Bell & McCaffrey (2002), kept here as a small reference, on a design with
runs of unequal size, interleaved, a run of a single point and points of leverage near 1.
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from cylfric.identify import pressure_fit
from cylfric.identify.pressure_fit import _cluster_robust


def _reference(jac, r, groups, dof):
    """CR2 by the per-run loop: A_g = (I - H_gg)^(-1/2) from the eigenvectors of H_gg."""
    scale = np.linalg.norm(jac, axis=0)
    scaled = jac / scale
    inverse = np.linalg.pinv(scaled.T @ scaled)
    nonrobust = inverse / np.outer(scale, scale) * float(r @ r) / dof
    labels = np.unique(groups)
    influence = np.empty((labels.size, jac.shape[1]))
    for g, label in enumerate(labels):
        js = scaled[groups == label]
        leverage, vectors = np.linalg.eigh(js @ inverse @ js.T)
        adjust = (vectors / np.sqrt(np.clip(1.0 - leverage, 1e-12, None))) @ vectors.T
        influence[g] = inverse @ (js.T @ (adjust @ r[groups == label])) / scale
    return influence.T @ influence, labels.size - jac.shape[1], influence, nonrobust


def _campaign(seed=3):
    """A Jacobian (points x 4 coefficients) of 40 runs of 1 to 5 points, in shuffled order.

    The last coefficient is carried almost only by point 0 (alone in its run), the third by
    point 1 (in a run of three): both have a leverage near 1.
    """
    rng = np.random.default_rng(seed)
    sizes = np.concatenate([[1, 3], rng.integers(1, 6, size=38)])
    groups = np.repeat([f"run_{g:03d}" for g in rng.permutation(sizes.size)], sizes)
    n = groups.size
    jac = rng.normal(size=(n, 4)) * [1.0, 30.0, 1e-4, 1e-4]
    jac[0, 3], jac[1, 2] = 1.0, 0.7
    r = rng.normal(size=n) * rng.uniform(0.2, 3.0, size=n)
    order = rng.permutation(n)  # the runs' points interleaved
    return jac[order], r[order], groups[order]


@pytest.mark.parametrize("stack", [None, 8], ids=["one-stack-per-size", "small-stacks"])
def test_batched_cr2_equals_the_per_run_formula(stack, monkeypatch):
    if stack is not None:  # the memory bound splits the runs of one size into several stacks
        monkeypatch.setattr(pressure_fit, "_STACK", stack)
    jac, r, groups = _campaign()
    scaled = jac / np.linalg.norm(jac, axis=0)
    hat = scaled @ np.linalg.pinv(scaled.T @ scaled) @ scaled.T
    assert np.sort(np.diag(hat))[-2] > 0.99  # two points of leverage near 1
    sizes = np.unique(groups, return_counts=True)[1]
    assert {1, 2, 3, 5} <= set(sizes)  # unequal runs, one of a single point
    dof = groups.size - jac.shape[1]
    got = _cluster_robust(jac, r, groups, dof)
    want = _reference(jac, r, groups, dof)
    assert got[1] == want[1]
    for g, w in zip((got[0], got[2], got[3]), (want[0], want[2], want[3]), strict=True):
        assert_allclose(g, w, rtol=1e-10, atol=1e-10 * np.abs(w).max())


def test_without_runs_or_with_too_few_runs_the_covariance_is_the_model_based_one():
    jac, r, groups = _campaign()
    dof = groups.size - jac.shape[1]
    cov, dof_out, influence, nonrobust = _cluster_robust(jac, r, None, dof)
    assert influence is None and dof_out == dof
    assert_allclose(cov, _reference(jac, r, groups, dof)[3], rtol=1e-12)
    few = np.where(np.arange(groups.size) % 2 == 0, "a", "b")  # 2 runs <= 4 coefficients
    assert _cluster_robust(jac, r, few, dof)[2] is None
