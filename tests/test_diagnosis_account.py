"""The account's share of the residual that is linear in the drive, by its two routes (the
coherence, :func:`linear_share`, and a fitted ARX filter, :func:`filtered_linear_share`),
against residuals whose linear share is known by construction."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from bondgraph.diagnosis.account import account, filtered_linear_share, linear_share

FS = 1562.5


def blocks(n: int, count: int = 30, share: float = 0.3) -> np.ndarray:
    """A validation mask of ``count`` interleaved blocks, every third or so held out."""
    edges = np.linspace(0, n, count + 1).astype(int)
    val = np.zeros(n, bool)
    for k in range(count):
        if (k % round(1 / share)) == 1:
            val[edges[k] : edges[k + 1]] = True
    return val


def two_modes(u: np.ndarray) -> np.ndarray:
    """``u`` through two lightly damped modes (26 and 39 Hz, ζ = 0.009), as a structure that
    lacks them leaves its residual: each rings for about 0.6 s."""
    out = np.zeros_like(u)
    for f, g in ((26.0, 1.0), (39.0, -0.6)):
        w = 2 * np.pi * f
        num, den = signal.bilinear([g * w**2], [1.0, 2 * 0.009 * w, w**2], FS)
        out += signal.lfilter(num, den, u)
    return out


def test_a_ringing_residual_under_a_sweep_is_linear_by_the_fitted_filter():
    """A sweep of 10-100 Hz over 1.7 s through two lightly damped modes, plus 1 % noise: all of
    it but the noise is linear in the drive.  The modes ring longer than a Welch segment
    (0.16 s), so the coherence credits well under half of it; the fitted filter predicts the
    validation blocks from the drive alone, and the account reports the larger route."""
    t = np.arange(0.0, 1.7, 1 / FS)
    u = signal.chirp(t, 10.0, t[-1], 100.0, method="logarithmic")
    clean = two_modes(u)
    e = clean + 0.01 * np.std(clean) * np.random.default_rng(3).standard_normal(t.size)
    val = blocks(t.size)
    assert linear_share(u, e, FS) < 0.5
    assert filtered_linear_share(u, e, val) > 0.95
    acc = account(u, e, np.zeros_like(e), val, FS, None)
    assert acc.unexplained_linear_share > 0.95
    assert "linear in the drive: missing dynamics" in acc.sentence(False)


@pytest.mark.parametrize("noise, share", [(0.1, 1 / 1.01), (0.5, 1 / 1.25)])
def test_under_the_sweep_the_fitted_share_is_the_signal_to_noise_split(noise, share):
    """The two modes' response to the sweep plus independent noise of ``noise`` times its RMS:
    the linear share is 1/(1 + noise²), within 0.05 (the output-error fit places the lightly
    damped poles; an ARX fit alone, weighing the noise by A(q), predicted nothing here)."""
    t = np.arange(0.0, 1.7, 1 / FS)
    u = signal.chirp(t, 10.0, t[-1], 100.0, method="logarithmic")
    clean = two_modes(u)
    e = clean + noise * np.std(clean) * np.random.default_rng(4).standard_normal(t.size)
    assert filtered_linear_share(u, e, blocks(t.size)) == pytest.approx(share, abs=0.05)


def test_the_fitted_share_is_the_signal_to_noise_split():
    """A second-order filter of a broadband drive plus independent noise of a quarter of its
    power: the linear share of the residual's energy is 1/1.25 = 0.8."""
    rng = np.random.default_rng(5)
    u = rng.standard_normal(20000)
    lin = signal.lfilter([0.2, 0.1], [1.0, -1.2, 0.5], u)
    e = lin / np.std(lin) + 0.5 * rng.standard_normal(u.size)
    assert filtered_linear_share(u, e, blocks(u.size)) == pytest.approx(0.8, abs=0.02)


@pytest.mark.parametrize("kind", ["noise", "square"])
def test_what_no_linear_filter_of_the_drive_makes_is_not_linear(kind):
    """Noise independent of the drive, and the square of a Gaussian drive (uncorrelated with
    every lag of it): the fitted filter predicts nothing of either."""
    rng = np.random.default_rng(7)
    u = rng.standard_normal(20000)
    e = rng.standard_normal(u.size) if kind == "noise" else u**2 - 1.0
    assert filtered_linear_share(u, e, blocks(u.size)) < 0.02


def test_a_record_too_short_for_any_filter_has_no_fitted_share():
    u = np.sin(np.arange(40.0))
    assert filtered_linear_share(u, u.copy(), blocks(u.size)) == 0.0
