"""The fit's residual whiteness: what `bondgraph fit` says about its own standard errors."""

import numpy as np
import pytest

from bondgraph.fit.fitting import residual_correlation


def test_white_noise_is_uncorrelated_and_a_missed_loop_is_not():
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.0, 20001)
    y = np.sin(2 * np.pi * 5 * t)
    assert abs(residual_correlation(y + 0.01 * rng.standard_normal(t.size), y)) < 0.03
    # a first-order autoregressive residual of coefficient 0.8 is found as such
    e = np.zeros(t.size)
    w = rng.standard_normal(t.size)
    for k in range(1, t.size):
        e[k] = 0.8 * e[k - 1] + w[k]
    assert residual_correlation(e, np.zeros(t.size)) == pytest.approx(0.8, abs=0.02)
    # a smooth model error (a loop's width the model lacks) is correlated to 1
    assert residual_correlation(y + 0.1 * np.cos(2 * np.pi * 5 * t), y) > 0.99
    assert residual_correlation([1.0, 1.0, 1.0], [0.0, 0.0, 0.0]) == 0.0
