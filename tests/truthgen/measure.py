"""The measurement chain: sampling (jittered clocks or stamps, a sensor delay), sensor gain and
offset, white and coloured noise, quantisation.

Drawn per record (:func:`draw`):

* noise RMS ``level`` x stroke, ``level`` log-uniform in [0.1 %, 2 %] of the effect-free
  peak-to-peak output; a share 0-70 % of its power is coloured: first-order (AR(1)) noise
  with a 0.5-50 Hz corner, pink (1/f) noise, or mains hum (50/60 Hz with a third harmonic)
  plus AR(1);
* sensor gain x[0.9, 1.1] (never within 1 % of 1), offset up to +-5 % of the stroke;
* timing: exact, jittered time stamps (|jitter| <= 0.4 % of a sample, written to the file),
  or an unrecorded sampling-clock jitter of the same size; a sensor delay of 0-0.2 samples
  on x in half the records;
* quantisation of x to 12, 14 or 16 bits over 1.5 strokes (or none), of V to 12-16 bits
  over the drive range (or none), and a small noise on the recorded V (0.01-0.05 % of its
  range) in half the records.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import lfilter

from .draws import factor, loguniform


def draw(rng: np.random.Generator) -> dict:
    colour = str(rng.choice(["white", "ar1", "pink", "hum"], p=[0.3, 0.3, 0.25, 0.15]))
    return {
        "level": loguniform(rng, 0.001, 0.02),
        "colour": colour,
        "coloured_share": 0.0 if colour == "white" else rng.uniform(0.2, 0.7),
        "corner": loguniform(rng, 0.5, 50.0),
        "hum": float(rng.choice([50.0, 60.0])),
        "gain": factor(rng, 0.9, 1.1, gap=0.01),
        "offset": rng.uniform(-0.05, 0.05),
        "timing": str(rng.choice(["exact", "stamps", "clock"], p=[0.4, 0.3, 0.3])),
        "jitter": rng.uniform(0.0005, 0.004),
        "delay": 0.0 if rng.uniform() < 0.5 else rng.uniform(0.0, 0.2),
        "x_bits": [None, 16, 14, 12][int(rng.choice(4, p=[0.4, 0.3, 0.2, 0.1]))],
        "v_bits": [None, 16, 14, 12][int(rng.choice(4, p=[0.5, 0.25, 0.15, 0.1]))],
        "v_noise": 0.0 if rng.uniform() < 0.5 else loguniform(rng, 1e-4, 5e-4),
        "seed": int(rng.integers(2**31)),
    }


def _coloured(spec: dict, n: int, fs: float, rng) -> np.ndarray:
    """Unit-RMS coloured noise of the spec's kind."""
    kind = spec["colour"]
    t = np.arange(n) / fs
    if kind == "pink":
        f = np.fft.rfftfreq(n, 1 / fs)
        spec_ = rng.standard_normal(len(f)) + 1j * rng.standard_normal(len(f))
        spec_[1:] /= np.sqrt(f[1:])
        spec_[0] = 0.0
        c = np.fft.irfft(spec_, n)
    else:
        rho = np.exp(-2 * np.pi * spec["corner"] / fs)
        c = lfilter([np.sqrt(1 - rho**2)], [1.0, -rho], rng.standard_normal(n))
        if kind == "hum":
            c = c / max(np.std(c), 1e-30)
            phase = rng.uniform(0, 2 * np.pi, 2)
            hum = np.sin(2 * np.pi * spec["hum"] * t + phase[0]) + 0.3 * np.sin(6 * np.pi * spec["hum"] * t + phase[1])
            c = c + hum / np.std(hum)
    c = c - c.mean()
    return c / max(np.std(c), 1e-30)


def _quantise(x, lsb):
    return np.round(x / lsb) * lsb


def sample(t_fine, V_fine, y_fine, fs: float, n: int, spec: dict, stroke: float, others=()):
    """(t, V, x, noise RMS, [other fine-grid signals at the instants x is taken]) of ``n``
    samples at ``fs`` measured from the fine-grid truth ``y_fine``.

    ``stroke`` is the effect-free peak-to-peak displacement (m) the noise level refers to."""
    rng = np.random.default_rng(spec["seed"])
    k = np.arange(n) / fs
    dt = 1.0 / fs
    jit = spec["jitter"] * dt
    if spec["timing"] == "stamps":
        t = k + rng.uniform(-jit, jit, n)
        t[0] = max(t[0], 0.0)
        instants = t
    elif spec["timing"] == "clock":
        t = k
        instants = np.clip(k + np.clip(rng.normal(0.0, jit / 2, n), -jit, jit), 0.0, None)
    else:
        t = instants = k
    V = np.interp(instants, t_fine, V_fine)
    at = instants + spec["delay"] * dt
    y = CubicSpline(t_fine, y_fine)(at)
    sampled = [CubicSpline(t_fine, o)(at) for o in others]

    gain = spec["gain"]
    sigma = spec["level"] * stroke * gain
    share = spec["coloured_share"]
    noise = sigma * np.sqrt(1 - share) * rng.standard_normal(n)
    if share > 0:
        noise += sigma * np.sqrt(share) * _coloured(spec, n, fs, rng)
    x = gain * y + spec["offset"] * stroke + noise
    if spec["x_bits"]:
        x = _quantise(x, 1.5 * stroke * gain / 2 ** spec["x_bits"])
    v_span = max(float(np.ptp(V_fine)), 1e-9)
    if spec["v_noise"]:
        V = V + spec["v_noise"] * v_span * rng.standard_normal(n)
    if spec["v_bits"]:
        V = _quantise(V, v_span / 2 ** spec["v_bits"])
    return t, V, x, float(np.sqrt(np.mean((x - gain * y - spec["offset"] * stroke) ** 2))), sampled
