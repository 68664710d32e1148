"""The screen's chance floor: a first-order product of residual and column, both correlated
in time, is judged by Bartlett's variance at the noise floor, so that columns unrelated to a
residual at the floor pass at the stated rate and a related one does not fall below it."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.signal import lfilter

from bondgraph.diagnosis import Settings
from bondgraph.diagnosis.candidate import Candidate
from bondgraph.diagnosis.screen import FirstOrder, first_order, screen_out


def _ar(rng, n, pole, cols=1):
    """Unit-variance AR(1) series, a slowly varying residual or regressor."""
    return lfilter([1.0], [1.0, -pole], rng.standard_normal((n, cols)), axis=0)


def _chances(draws, pole_r, pole_q, cols, seed=0):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(draws):
        r, q = _ar(rng, 2000, pole_r)[:, 0], _ar(rng, 2000, pole_q, cols)
        out.append(first_order(q - q.mean(axis=0), r - r.mean(), float(np.sum((r - r.mean()) ** 2)), None))
    return out


def test_unrelated_columns_pass_the_floor_at_the_stated_rate():
    # both series AR(1) with pole 0.95: Σ_k ρ_u(k)ρ_r(k) = (1 + 0.95²)/(1 − 0.95²) = 19.5, so
    # N = 2000 samples are worth 103 independent ones
    found = _chances(400, 0.95, 0.95, 1)
    rate = np.mean([f.chance < 0.05 for f in found])
    assert 0.02 <= rate <= 0.09
    # the same shares judged as if the 2000 samples were independent: far too many pass
    naive = np.mean([f.share * 2000 > 3.84 for f in found])
    assert naive > 0.4
    assert 80 < np.median([f.n_eff for f in found]) < 130


def test_two_columns_count_two_degrees_of_freedom():
    found = _chances(400, 0.9, 0.8, 2, seed=1)
    assert 0.02 <= np.mean([f.chance < 0.05 for f in found]) <= 0.09
    # unrelated columns: the chance level is uniform, its mean is 1/2
    assert abs(np.mean([f.chance for f in found]) - 0.5) < 0.06


def test_a_related_column_with_a_small_share_is_kept():
    rng = np.random.default_rng(2)
    q = _ar(rng, 20000, 0.5)
    r = 0.4 * q[:, 0] + _ar(rng, 20000, 0.95)[:, 0]  # 2 % of r's energy
    f = first_order(q, r - r.mean(), float(np.sum((r - r.mean()) ** 2)), None)
    assert 0.005 < f.share < 0.05 and f.chance < 1e-6


def test_a_deterministic_mismatch_far_above_the_noise_is_not_chance():
    # the residual of a periodic effect: a few harmonics, far above white measurement noise;
    # the column shares one of them (6 % of the residual's energy)
    rng = np.random.default_rng(3)
    t = np.arange(20000) / 2000.0
    harmonics = [np.sin(2 * np.pi * 7.0 * k * t + k) for k in (1, 2, 3)]
    r = 1.0 * harmonics[0] + 0.3 * harmonics[1] + 0.2 * harmonics[2] + 0.01 * rng.standard_normal(t.size)
    q = (harmonics[1] + 0.5 * np.cos(2 * np.pi * 3.0 * t))[:, None]
    total = float(np.sum((r - r.mean()) ** 2))
    as_two_series = first_order(q, r - r.mean(), total, None)
    at_the_floor = first_order(q, r - r.mean(), total, 0.01)
    assert 0.03 < as_two_series.share < 0.1 and as_two_series.n_eff < 60
    assert as_two_series.chance > 0.05  # two periodic series: too few effective samples to tell
    assert at_the_floor.chance < 1e-12  # no noise at 1 % explains 6 % of a unit mismatch


class _Said(Candidate):
    cause = "said"

    def __init__(self, found):
        self.found = found

    def screen(self, view):
        return self.found

    def fit(self, view):
        raise AssertionError("the screen fits nothing")


def test_screen_out_names_the_rule_that_left_a_candidate_out():
    view = SimpleNamespace(settings=Settings.from_config(screen_keep=2))
    cands = [
        _Said(FirstOrder(0.30, 1e-9, 500.0)),
        _Said(FirstOrder(0.20, 1e-6, 500.0)),
        _Said(FirstOrder(0.10, 1e-4, 500.0)),
        _Said(FirstOrder(0.002, 0.4, 500.0)),
        _Said(None),
    ]
    left, shares = screen_out(view, cands, range(5))
    assert sorted(shares) == [0, 1, 2, 3]
    assert sorted(left) == [2, 3]
    assert "rule rank" in left[2] and "rule chance" in left[3] and "p = 0.4" in left[3]


def test_the_noise_floor_without_a_quiet_band_is_not_below_coloured_noise():
    """On a broadband drive the screen's noise floor is the residual's part incoherent with the
    drive: for a residual of coloured noise (an AR(1) corner far below Nyquist, RMS 1) plus a
    filtered copy of the drive it is the noise's RMS within a few percent, where the floor of
    the residual's spectrum (a white level at its high-frequency end) is far below it."""
    from bondgraph.diagnosis.account import incoherent_rms
    from bondgraph.diagnosis.context import residual_floor

    rng = np.random.default_rng(3)
    n, fs = 40000, 1000.0
    u = rng.standard_normal(n)
    noise = _ar(rng, n, 0.95)[:, 0]
    noise = noise / noise.std()
    e = noise + lfilter([0.5, 0.3], [1.0, -0.5], u)
    assert incoherent_rms(u, e, fs) == pytest.approx(1.0, rel=0.05)
    assert residual_floor(e, fs) < 0.5
    assert incoherent_rms(u, noise, fs) == pytest.approx(1.0, rel=0.05)
