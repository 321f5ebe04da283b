"""The extraction's own filters equal scipy.ndimage's with mode="nearest"."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.ndimage import convolve1d, median_filter, uniform_filter1d

from cylfric._filters import convolve_nearest, rolling_mean, rolling_median


@pytest.mark.parametrize("n", [1, 2, 5, 17, 1000, 10001])
@pytest.mark.parametrize("size", [1, 3, 9, 10, 101])
def test_filters_equal_scipy_ndimage_nearest(n, size):
    rng = np.random.default_rng(n * 1000 + size)
    x = 150.0 + rng.normal(size=n).cumsum()  # a force-like level with drift [N]
    x[::7] = x[0]  # ties, as quantised load-cell readings have
    assert_allclose(rolling_mean(x, size), uniform_filter1d(x, size, mode="nearest"), rtol=1e-12)
    if size % 2:
        kernel = np.arange(size // 2, -(size // 2) - 1, -1, dtype=float)
        expected = convolve1d(x, kernel, mode="nearest")
        assert_allclose(convolve_nearest(x, kernel), expected, rtol=1e-12, atol=1e-9)
        assert np.array_equal(rolling_median(x, size), median_filter(x, size, mode="nearest"))
    else:
        with pytest.raises(ValueError, match="odd size"):
            rolling_median(x, size)
