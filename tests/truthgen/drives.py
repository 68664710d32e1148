"""Drive voltages of the truth records: a drive is a small dict (``kind`` and its numbers) that
:func:`signal` turns into V(t) on a uniform grid, and that :func:`draw` draws for a device.

Kinds (every drive starts at 0 V, from rest; offsets are reached by a smooth ramp):

* ``sine``: ``offset + amp sin(2 pi f t + phase)``;
* ``triangle``: the same with a triangle wave;
* ``steps``: a staircase of random levels with holds, edges of finite rise time (raised cosine);
* ``chirp``: a logarithmic sweep ``f0 -> f1`` of amplitude ``amp`` around ``offset``;
* ``noise``: Gaussian noise band-limited to ``[f_lo, f_hi]`` (FFT shaping), RMS ``rms``
  around ``offset``, kept within the device range by a soft clip;
* ``bursts``: sine bursts with amplitude ramps and pauses (holds at the centre voltage), as in
  real stack records driven by a control loop; ``resonant-bursts``: the same at the device's
  resonance, around 0 V;
* ``stepped-sine``: consecutive sine dwells at frequencies ``freqs`` and amplitudes ``amps``
  with continuous phase (resonance testing).

Ranges per device come from :class:`DriveRange`: the device's voltage limits, the frequency band
it is driven in, and the largest frequency the sampling allows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .draws import loguniform

KINDS = ("sine", "triangle", "steps", "chirp", "noise", "bursts", "resonant-bursts", "stepped-sine")


@dataclass(frozen=True)
class DriveRange:
    """What a device is driven with.

    vmin, vmax: voltage limits (V); bipolar: whether drives swing around 0 (else they sit in
    [max(vmin, 0), vmax]); f_slow: (lo, hi) band of the quasi-static drives (sine, triangle,
    bursts), Hz; f_res: a resonance to drive near (Hz) or None; amp_res: (lo, hi) amplitude
    near resonance (V); amp_dyn: (lo, hi) amplitude of broadband drives (chirp, noise, steps)
    of a resonant device (None: a random part of the voltage range)."""

    vmin: float
    vmax: float
    bipolar: bool
    f_slow: tuple
    f_res: float | None = None
    amp_res: tuple = (0.5, 5.0)
    amp_dyn: tuple | None = None


def _ramp(t, t1):
    """Smooth 0 -> 1 over [0, t1] (raised cosine)."""
    if t1 <= 0:
        return np.ones_like(t)
    s = np.clip(t / t1, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * s)


def _triangle(phase):
    """Triangle wave of unit amplitude with the phase convention of sin."""
    return 2 / np.pi * np.arcsin(np.sin(phase))


def signal(spec: dict, t: np.ndarray) -> np.ndarray:
    """V(t) for the drive ``spec`` on the uniform grid ``t`` (starting at 0)."""
    kind = spec["kind"]
    if kind in ("sine", "triangle"):
        wave = np.sin if kind == "sine" else _triangle
        phase = 2 * np.pi * spec["freq"] * t + spec["phase"]
        return spec["offset"] + spec["amp"] * wave(phase)  # starts at 0 V (phase -pi/2 if unipolar)
    if kind == "steps":
        v = np.zeros_like(t)
        prev = 0.0
        for t0, level in zip(spec["times"], spec["levels"]):
            v += (level - prev) * _ramp(t - t0, spec["rise"])
            prev = level
        return v
    if kind == "chirp":
        f0, f1, T = spec["f0"], spec["f1"], spec["sweep"]
        t_start = spec["ramp"]
        tau = np.clip(t - t_start, 0.0, T)
        k = np.log(f1 / f0) / T
        phase = 2 * np.pi * f0 * np.expm1(k * tau) / k
        phase = np.where(t - t_start > T, phase + 2 * np.pi * f1 * (t - t_start - T), phase)
        return spec["offset"] * _ramp(t, t_start) + spec["amp"] * np.sin(phase) * (t >= t_start)
    if kind == "noise":
        rng = np.random.default_rng(spec["seed"])
        n = len(t)
        dt = t[1] - t[0]
        spectrum = rng.standard_normal(n // 2 + 1) + 1j * rng.standard_normal(n // 2 + 1)
        f = np.fft.rfftfreq(n, dt)
        spectrum[(f < spec["f_lo"]) | (f > spec["f_hi"])] = 0.0
        x = np.fft.irfft(spectrum, n)
        x *= spec["rms"] / max(np.std(x), 1e-30)
        x *= _ramp(t, spec["ramp"])
        v = spec["offset"] * _ramp(t, spec["ramp"]) + x
        lo, hi = spec["lo"], spec["hi"]
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        return mid + half * np.tanh((v - mid) / half)
    if kind == "bursts":
        env = np.interp(t, spec["env_t"], spec["env_a"])
        centre = spec["centre"] * _ramp(t, spec["ramp"])
        return centre + env * np.sin(2 * np.pi * spec["freq"] * t)
    if kind == "stepped-sine":
        edges = np.asarray(spec["edges"])  # dwell boundaries, len(freqs) + 1
        idx = np.clip(np.searchsorted(edges, t, "right") - 1, 0, len(spec["freqs"]) - 1)
        freqs = np.asarray(spec["freqs"])
        amps = np.asarray(spec["amps"])
        dt = t[1] - t[0]
        phase = 2 * np.pi * np.concatenate([[0.0], np.cumsum(freqs[idx][:-1]) * dt])
        # amplitude changes smoothly over two periods at each dwell boundary
        amp = amps[idx].astype(float)
        width = 2.0 / freqs.min()
        kernel = max(1, int(width / dt))
        amp = np.convolve(np.pad(amp, (kernel, kernel), mode="edge"), np.ones(kernel) / kernel, "same")[kernel:-kernel]
        return spec["offset"] * _ramp(t, spec["ramp"]) + amp * np.sin(phase) * _ramp(t, spec["ramp"])
    raise ValueError(f"unknown drive kind {kind!r}")


def _window(r: DriveRange, rng, fraction_lo=0.35):
    """(offset, amplitude) of a drive that swings over a random part of the device range."""
    if r.bipolar:
        return 0.0, rng.uniform(fraction_lo, 1.0) * min(r.vmax, -r.vmin)
    lo = max(r.vmin, 0.0)
    span = rng.uniform(fraction_lo, 1.0) * (r.vmax - lo)
    return lo + span / 2, span / 2


def draw(kind: str, r: DriveRange, T: float, fs: float, rng: np.random.Generator) -> dict:
    """A random drive of ``kind`` for a device driven as ``r``, ``T`` seconds sampled at ``fs``.
    ``resonant-bursts`` are bursts at the resonance ``r.f_res``."""
    f_lo, f_hi = r.f_slow
    f_min = max(f_lo, 3.0 / T)  # at least three periods in the record
    f_hi = max(min(f_hi, 0.05 * fs), f_min * 1.01)
    offset, amp = _window(r, rng)
    if r.amp_dyn is not None and kind in ("chirp", "noise", "steps"):
        amp = rng.uniform(*r.amp_dyn)
        offset = 0.0 if r.bipolar else amp
    lo, hi = (
        (offset - amp, offset + amp)
        if r.amp_dyn is not None
        else ((r.vmin, r.vmax) if r.bipolar else (max(r.vmin, 0.0), r.vmax))
    )
    spec: dict = {"kind": kind}
    if kind in ("sine", "triangle"):
        spec.update(freq=loguniform(rng, f_min, f_hi), amp=amp, offset=offset, phase=0.0 if r.bipolar else -np.pi / 2)
    elif kind == "steps":
        hold_hi = min(max(T / 4, 0.02), 2.0)
        hold_lo = min(max(T / 40, 0.005), hold_hi / 2)
        times, levels, t0 = [], [], loguniform(rng, hold_lo, hold_hi) / 2
        while t0 < T * 0.97:
            times.append(t0)
            levels.append(rng.uniform(lo, hi) if rng.uniform() < 0.85 else 0.0)
            t0 += loguniform(rng, hold_lo, hold_hi)
        spec.update(times=times, levels=levels, rise=loguniform(rng, 2.0 / fs, max(4.0 / fs, 3e-3)))
    elif kind == "chirp":
        ramp = min(0.1 * T, 0.2)
        amp_c = amp if r.amp_dyn is not None else rng.uniform(0.1, 0.5) * amp
        spec.update(
            f0=loguniform(rng, max(1.0, 2.0 / T), max(2.02 / T, 50.0)),
            f1=rng.uniform(0.3, 0.45) * fs,
            amp=amp_c,
            offset=offset,
            ramp=ramp,
            sweep=T - ramp,
        )
    elif kind == "noise":
        spec.update(
            seed=int(rng.integers(2**31)),
            f_lo=rng.uniform(0.5, 5.0),
            f_hi=rng.uniform(0.15, 0.45) * fs,
            rms=rng.uniform(0.15, 0.35) * (hi - lo) / 2,
            offset=offset,
            lo=lo,
            hi=hi,
            ramp=min(0.1 * T, 0.2),
        )
    elif kind in ("bursts", "resonant-bursts"):
        if kind == "resonant-bursts":
            freq, full, centre = rng.uniform(0.92, 1.06) * r.f_res, rng.uniform(*r.amp_res), 0.0
        else:
            freq, full = loguniform(rng, min(2 * f_min, f_hi), f_hi), amp
            centre = offset
        period = 1.0 / freq
        env_t, env_a, t0 = [0.0], [0.0], 0.0
        while t0 < T:
            t0 += period * rng.uniform(3, 14)  # amplitude ramp to the next level
            level = full * rng.choice([1.0, rng.uniform(0.2, 0.9), 0.0], p=[0.45, 0.35, 0.2])
            env_t.append(t0)
            env_a.append(level)
            t0 += period * rng.uniform(2, 10)  # plateau at that level (0: a hold)
            env_t.append(t0)
            env_a.append(level)
        if not np.any(np.interp(np.linspace(0.0, T, 1001), env_t, env_a) > 0):
            env_a[1] = env_a[2] = full  # a silent record: its first burst at full level
        spec.update(kind="bursts", freq=freq, centre=centre, env_t=env_t, env_a=env_a, ramp=min(2 * period, T / 10))
    elif kind == "stepped-sine":
        count = int(rng.integers(4, 10))
        edges = np.concatenate([[0.0], np.sort(rng.uniform(0.0, T, count - 1)), [T * 1.01]])
        spec.update(
            freqs=list(r.f_res * rng.uniform(0.9, 1.08, count)),
            amps=list(rng.uniform(*r.amp_res, count)),
            edges=list(edges),
            offset=0.0,
            ramp=min(3.0 / r.f_res, T / 10),
        )
    else:
        raise ValueError(f"unknown drive kind {kind!r}")
    return spec
