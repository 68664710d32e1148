"""Drive voltages (V), sampled on the nominal grid and linear between samples (the amplifier
output of a DAC with first-order hold).  Every segment starts and ends at 0 V, so segments
chain without jumps and the device starts from rest.

Kinds: ``sine`` and ``triangle`` (quasi-static, stepped amplitude envelope), ``steps`` (fast
edges, long holds), ``ramp-hold`` (slow ramps, holds), ``chirp`` (log sweep), ``noise``
(low-pass Gaussian noise), ``bursts`` (Hann-windowed sine bursts over the band),
``ringdown`` (bursts at the nominal resonance, then free decay), ``stepped-sine`` (dwells on a
frequency grid, swept up then down, at one to three levels); ``hi-chirp`` and ``hi-noise``
are high-band tests that start above the first resonance (at lim.hi_band).  Frequencies come
from the model file's nominal device, never from the drawn one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfilt

from .spread import logu

QUASI_STATIC = ("sine", "triangle", "steps", "ramp-hold")
DYNAMIC = ("chirp", "noise", "hi-chirp", "hi-noise", "bursts", "ringdown", "stepped-sine")


@dataclass(frozen=True)
class Limits:
    """Drive limits of a family: unipolar range 0..vmax (None: bipolar only), bipolar +-vbip (V);
    quasi-static frequencies qs_f, dynamic band dyn_f (Hz); nominal resonance f_res (Hz) and
    damping ratio; holds (s); ramp time of slow ramps (s); dynamic amplitude (V); probability of
    a unipolar large-signal segment; lower edges (Hz) of high-band chirps and noise."""

    vmax: float | None
    vbip: float
    qs_f: tuple
    dyn_f: tuple
    f_res: float
    zeta_res: float
    holds: tuple
    ramps: tuple
    dyn_amp: tuple
    p_unipolar: float
    hi_band: tuple


def _range(rng, lim: Limits):
    """(low, high) voltage of a large-signal segment: unipolar 0..s*vmax or bipolar +-s*vbip."""
    s = rng.uniform(0.6, 1.0)
    if lim.vmax is not None and rng.random() < lim.p_unipolar:
        return 0.0, s * lim.vmax
    return -s * lim.vbip, s * lim.vbip


def _periodic(rng, n, dt, lim, wave):
    """Quasi-static periodic drive with 1-4 amplitude levels switched at whole cycles."""
    f = logu(rng, *lim.qs_f)
    lo, hi = _range(rng, lim)
    cycles = int(n * dt * f)
    if cycles < 1:
        f, cycles = 1.0 / (n * dt), 1
    levels = rng.uniform(0.3, 1.0, size=rng.integers(1, 5))
    levels[rng.integers(levels.size)] = 1.0
    t = np.arange(n) * dt
    phase = 2 * np.pi * f * t
    k = (f * t).astype(int)
    amp = np.where(k < cycles, levels[np.minimum(k * levels.size // cycles, levels.size - 1)], 0.0)
    frac = (f * t) % 1.0
    if lo == 0.0:  # unipolar, 0..hi
        w = (1 - np.cos(phase)) / 2 if wave == "sine" else 1 - np.abs(2 * frac - 1)
        return hi * amp * w
    w = np.sin(phase) if wave == "sine" else 2 / np.pi * np.arcsin(np.sin(phase))
    return hi * amp * w


def _staircase(rng, n, dt, lim, ramp_range):
    """Levels held for lim.holds seconds, joined by ramps of ramp_range seconds; ends at 0."""
    lo, hi = _range(rng, lim)
    v = np.zeros(n)
    i = int(rng.uniform(0.02, 0.1) * n)
    level = 0.0
    while i < n:
        ramp = max(1, int(logu(rng, *ramp_range) / dt))
        hold = int(rng.uniform(*lim.holds) / dt)
        new = rng.uniform(lo, hi) if rng.random() < 0.8 else 0.0
        end = min(n, i + ramp)
        v[i:end] = level + (new - level) * np.arange(1, end - i + 1) / ramp
        v[end : end + hold] = new
        level, i = new, end + hold
    return _to_zero(v, max(1, int(ramp_range[1] / dt)))


def _to_zero(v, m):
    """Ramp the last m samples linearly from their value to 0."""
    m = min(m, v.size - 1)
    v = v.copy()
    v[-m:] = v[-m - 1] * np.linspace(1, 0, m)
    return v


def _offset(rng, lim, amp):
    """Bias around which a small-signal drive runs: 0 on a bipolar device and, half the time, on
    a unipolar one too (small negative voltages are allowed); else just enough to keep it
    positive."""
    if lim.vmax is None or rng.random() < 0.5:
        return 0.0
    return min(amp * rng.uniform(1.05, 1.5), lim.vmax - amp)


def _with_bias(x, bias, dt):
    """x riding on a bias: the bias rises and falls in raised-cosine ramps of m samples (0.2 s,
    20 ms without bias), x is faded in and out over the next m samples."""
    n = x.size
    m = max(2, min(int((0.2 if bias else 0.02) / dt), n // 20))
    rise = (1 - np.cos(np.linspace(0, np.pi, m))) / 2
    b = np.full(n, bias)
    b[:m] *= rise
    b[-m:] *= rise[::-1]
    w = np.ones(n)
    w[:m] = w[-m:] = 0.0
    w[m : 2 * m] = rise
    w[-2 * m : -m] = rise[::-1]
    return b + x * w


def chirp(rng, n, dt, lim, high=False):
    amp = rng.uniform(*lim.dyn_amp)
    f0 = logu(rng, *lim.hi_band) if high else lim.dyn_f[0]
    f1 = logu(rng, 0.5 * lim.dyn_f[1], lim.dyn_f[1])
    t = np.arange(n) * dt
    T = n * dt
    k = np.log(f1 / f0) / T
    x = amp * np.sin(2 * np.pi * f0 * (np.exp(k * t) - 1) / k)
    return _with_bias(x, _offset(rng, lim, amp), dt)


def noise(rng, n, dt, lim, high=False):
    amp = rng.uniform(*lim.dyn_amp)
    fc = min(logu(rng, 0.3 * lim.dyn_f[1], lim.dyn_f[1]), 0.45 / dt)
    band = (
        butter(4, [logu(rng, *lim.hi_band), fc], "bandpass", fs=1 / dt, output="sos")
        if high
        else butter(4, fc, fs=1 / dt, output="sos")
    )
    x = sosfilt(band, rng.standard_normal(n))
    x *= amp / 2.5 / np.std(x)  # peaks near amp
    return _with_bias(x, _offset(rng, lim, amp), dt)


def _burst_train(rng, n, dt, lim, freqs, cycles, gap):
    amp = rng.uniform(*lim.dyn_amp)
    x = np.zeros(n)
    i = int((0.45 if lim.vmax is not None else 0.05) / dt)
    while True:
        f = freqs()
        m = int(cycles() / f / dt)
        if i + m >= n - int((0.45 if lim.vmax is not None else 0.05) / dt):
            break
        s = np.arange(m)
        x[i : i + m] = amp * np.sin(2 * np.pi * f * s * dt) * np.hanning(m) ** 0.5
        i += m + int(gap(m))
    return _with_bias(x, _offset(rng, lim, amp), dt)


def bursts(rng, n, dt, lim):
    return _burst_train(
        rng,
        n,
        dt,
        lim,
        lambda: logu(rng, 20 * lim.dyn_f[0], lim.dyn_f[1]),
        lambda: rng.integers(5, 40),
        lambda m: m * rng.uniform(1, 4),
    )


def ringdown(rng, n, dt, lim):
    decay = 1 / (2 * np.pi * lim.f_res * lim.zeta_res)
    return _burst_train(
        rng,
        n,
        dt,
        lim,
        lambda: lim.f_res * rng.uniform(0.94, 1.06),
        lambda: rng.integers(20, 120),
        lambda m: 6 * decay / dt * rng.uniform(1, 2),
    )


def stepped_sine(rng, n, dt, lim):
    """Dwells on a frequency grid (near the nominal resonance when it is lightly damped, else
    log-spaced over the band), up then down, phase-continuous, at 1-3 levels."""
    if lim.zeta_res < 0.1:
        grid = lim.f_res * np.linspace(0.9, 1.1, rng.integers(15, 30))
    else:
        grid = np.geomspace(10 * lim.dyn_f[0], lim.dyn_f[1], rng.integers(15, 30))
    levels = np.sort(rng.uniform(0.3, 1.0, size=rng.integers(1, 4)))
    levels[-1] = 1.0
    plan = [(f, lev) for lev in levels for f in np.concatenate([grid, grid[::-1]])]
    amp = rng.uniform(*lim.dyn_amp)
    dwell = n // len(plan)
    f = np.repeat([p[0] for p in plan], dwell)
    a = np.repeat([p[1] for p in plan], dwell)
    f = np.concatenate([f, np.full(n - f.size, f[-1])])
    a = np.concatenate([a, np.full(n - a.size, a[-1])])
    m = max(1, int(0.005 / dt))
    a = np.convolve(np.pad(a, m, mode="edge"), np.ones(m) / m, mode="same")[m:-m]
    x = amp * a * np.sin(2 * np.pi * np.cumsum(f) * dt)
    return _with_bias(x, _offset(rng, lim, amp), dt)


def segment(kind, rng, n, dt, lim: Limits) -> np.ndarray:
    """One drive segment of n samples."""
    if kind in ("sine", "triangle"):
        v = _periodic(rng, n, dt, lim, kind)
    elif kind == "steps":
        v = _staircase(rng, n, dt, lim, (2 * dt, 20 * dt))
    elif kind == "ramp-hold":
        v = _staircase(rng, n, dt, lim, lim.ramps)
    elif kind in ("hi-chirp", "hi-noise"):
        v = (chirp if kind == "hi-chirp" else noise)(rng, n, dt, lim, high=True)
    else:
        v = {"chirp": chirp, "noise": noise, "bursts": bursts, "ringdown": ringdown, "stepped-sine": stepped_sine}[
            kind
        ](rng, n, dt, lim)
    v[0] = 0.0
    return _to_zero(v, max(2, n // 200)) if abs(v[-1]) > 0 else v
