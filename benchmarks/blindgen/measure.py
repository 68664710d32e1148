"""Measurement chain: sensor gain and offset, white plus AR(1) noise, sampling jitter (the
time stamps record the true instants), quantisation, and a little noise on the recorded
voltage.  Levels are relative to the stroke S (peak-to-peak of the noise-free sensor signal).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.signal import lfilter

from .spread import factor, logu

NOISE_RANGE = (0.002, 0.02)  # total sensor noise RMS / stroke
JITTER_MAX = 0.004  # |jitter| / dt: steps stay within 1 % of dt (uniform sampling)


@dataclass
class Chain:
    gain: float  # sensor gain (1 = exact)
    offset: float  # sensor offset / stroke
    level: float  # noise RMS / stroke (white + coloured, before quantisation)
    white: float  # white share of the noise variance
    corner: float  # AR(1) corner frequency (Hz)
    jitter: float  # sampling jitter RMS / dt
    bits: int  # sensor ADC bits over 2x the signal range
    v_level: float  # voltage noise RMS / voltage range

    def to_dict(self):
        return asdict(self)


def draw(rng) -> Chain:
    return Chain(
        gain=factor(rng, 0.10, False),
        offset=rng.uniform(-0.2, 0.2),
        level=logu(rng, *NOISE_RANGE),
        white=rng.uniform(0.3, 0.9),
        corner=logu(rng, 0.5, 50.0),
        jitter=logu(rng, 1e-4, 1.5e-3),
        bits=int(rng.integers(16, 19)),
        v_level=logu(rng, 1e-4, 1e-3),
    )


def quietest(chain: Chain) -> Chain:
    """The chain with its noise at the lower end of NOISE_RANGE."""
    return Chain(**{**chain.to_dict(), "level": NOISE_RANGE[0]})


def noise_rms(chain: Chain, stroke: float) -> float:
    """RMS (sensor units) of the noise added to a signal of this stroke, quantisation included."""
    lsb = 2 * stroke / 2**chain.bits
    return float(np.sqrt((chain.level * stroke) ** 2 + lsb**2 / 12))


def apply(chain: Chain, rng, V, y, dt):
    """(t, V_rec, x_rec): the record of the noise-free sensor signal y (m) and drive V (V) on
    the nominal grid dt."""
    n = y.size
    k = np.arange(n)
    delta = np.clip(rng.standard_normal(n) * chain.jitter, -JITTER_MAX, JITTER_MAX) * dt
    delta[0] = 0.0
    t = k * dt + delta
    ys = chain.gain * (y + delta * np.gradient(y, dt))
    stroke = np.ptp(ys)
    sw = chain.level * stroke * np.sqrt(chain.white)
    sc = chain.level * stroke * np.sqrt(1 - chain.white)
    phi = np.exp(-2 * np.pi * chain.corner * dt)
    start = rng.standard_normal()  # stationary start of the unit-variance AR(1)
    coloured = lfilter([np.sqrt(1 - phi**2)], [1, -phi], rng.standard_normal(n), zi=[phi * start])[0]
    x = ys + chain.offset * stroke + sw * rng.standard_normal(n) + sc * coloured
    lsb = 2 * stroke / 2**chain.bits
    x = np.round(x / lsb) * lsb
    Vt = np.interp(t, k * dt, V)
    v_range = max(np.ptp(V), 1.0)
    v_lsb = 400.0 / 2**16
    Vr = np.round((Vt + chain.v_level * v_range * rng.standard_normal(n)) / v_lsb) * v_lsb
    return t, Vr, x
