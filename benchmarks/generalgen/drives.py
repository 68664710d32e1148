"""Drives: broadband (random-phase multisine, filtered noise), periodic (sine, stepped sine,
triangle), chirps and steps with holds.

Every drive is a function of continuous time, evaluated on any grid ``dt/q`` (the truth's
integrator needs it at every half step, the CSV at the samples): the broadband ones are
sums of sinusoids on the record's (or one period's) harmonic grid, evaluated exactly by an
inverse FFT; steps rise along a raised cosine over several samples, as an amplifier's slew
would, so the samples say what the drive does between them.  Every drive but the steps fades
in from zero along a raised cosine: the system starts at rest, as the model does.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.fft
import scipy.signal

KINDS = ("multisine", "noise", "sine", "stepped-sine", "triangle", "chirp", "steps")


def _raised_step(x: np.ndarray) -> np.ndarray:
    """0 before 0, 1 after 1, a raised cosine between."""
    x = np.clip(x, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * x))


@dataclass
class Drive:
    """A drawn drive (N or V).

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    amplitude : float
        The scale: the peak of a sine, triangle or chirp, the peak of the equivalent sine of
        the same RMS for broadband drives, the largest step level.
    offset : float
        A constant added to periodic and broadband drives (faded in with them).
    T : float
        The record's duration (s).
    fade : float
        The fade-in time (s).
    par : dict
        Kind-specific parameters (frequencies in Hz, times in s, harmonic numbers, phases).
    """

    kind: str
    amplitude: float
    offset: float
    T: float
    fade: float
    par: dict = field(default_factory=dict)

    def describe(self) -> str:
        """A short label, e.g. ``multisine 2-180 Hz``."""
        p = self.par
        if self.kind in ("multisine", "noise", "chirp"):
            return f"{self.kind} {p['f_lo']:.3g}-{p['f_hi']:.3g} Hz"
        if self.kind in ("sine", "triangle"):
            return f"{self.kind} {p['f']:.3g} Hz"
        if self.kind == "stepped-sine":
            return f"stepped-sine {len(p['freqs'])}x {min(p['freqs']):.3g}-{max(p['freqs']):.3g} Hz"
        return f"steps {len(p['times'])} holds"

    def top_frequency(self) -> float:
        """The highest frequency the drive means to excite (Hz); for steps, the inverse rise time."""
        p = self.par
        if self.kind in ("sine", "triangle"):
            return p["f"]
        if self.kind == "stepped-sine":
            return float(max(p["freqs"]))
        if self.kind == "steps":
            return 1.0 / p["rise"]
        return p["f_hi"]

    def summary(self) -> dict:
        """The drive's description for the truth file (scalars only)."""
        out = {"kind": self.kind, "amplitude": self.amplitude, "offset": self.offset, "fade_s": self.fade}
        for k, v in self.par.items():
            if np.isscalar(v):
                out[k] = v
        if self.kind == "stepped-sine":
            out["freqs"] = [float(f) for f in self.par["freqs"]]
        return out

    def evaluate(self, dt: float, n: int, q: int) -> np.ndarray:
        """The drive at ``t = j dt / q`` for ``j = 0 .. n q`` (``n`` samples of step ``dt``)."""
        t = np.arange(n * q + 1) * (dt / q)
        if self.kind == "steps":
            p = self.par
            u = np.zeros_like(t)
            prev = 0.0
            for t0, level in zip(p["times"], p["levels"]):
                u += (level - prev) * _raised_step((t - t0) / p["rise"])
                prev = level
            return u
        if self.kind in ("multisine", "noise"):
            wave = self._harmonics(dt, n, q)
        elif self.kind == "sine":
            wave = self.amplitude * np.sin(2 * np.pi * self.par["f"] * t + self.par["phase"])
        elif self.kind == "triangle":
            wave = self.amplitude * scipy.signal.sawtooth(2 * np.pi * self.par["f"] * t + self.par["phase"], 0.5)
        elif self.kind == "chirp":
            f0, f1 = self.par["f_lo"], self.par["f_hi"]
            if self.par["log"]:
                rate = np.log(f1 / f0) / self.T
                phase = 2 * np.pi * f0 * np.expm1(rate * t) / rate
            else:
                phase = 2 * np.pi * (f0 * t + 0.5 * (f1 - f0) * t * t / self.T)
            if self.par["down"]:  # the same sweep from the top
                phase = -phase[::-1] + phase[-1]
            wave = self.amplitude * np.sin(phase)
        else:  # stepped sine: bursts that rise and fall with raised cosines
            freqs = self.par["freqs"]
            seg = self.T / len(freqs)
            ramp = 0.1 * seg
            wave = np.zeros_like(t)
            for j, f in enumerate(freqs):
                tau = t - j * seg
                env = _raised_step(tau / ramp) * _raised_step((seg - tau) / ramp)
                wave += env * np.sin(2 * np.pi * f * tau)
            wave *= self.amplitude
        return (self.offset + wave) * _raised_step(t / self.fade)

    def _harmonics(self, dt: float, n: int, q: int) -> np.ndarray:
        """Sum of ``amps[k] cos(2 pi h[k] t / Tp + phases[k])`` over one period ``Tp = T/periods``,
        evaluated by an inverse FFT on the grid ``dt/q`` (which divides ``Tp``: ``T`` is a whole
        number of samples, a multiple of 8) and repeated."""
        p = self.par
        L = int(round(self.T / p["periods"] / (dt / q)))
        X = np.zeros(L // 2 + 1, complex)
        X[p["harmonics"]] = p["amps"] * np.exp(1j * p["phases"]) * (L / 2)
        one = scipy.fft.irfft(X, n=L)
        reps = -(-(n * q + 1) // L)
        return np.tile(one, reps)[: n * q + 1]


def _log_uniform(rng, lo, hi):
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def draw_drive(rng: np.random.Generator, level: float, f1: float, f_top: float, fs: float, n: int) -> Drive:
    """Draw a drive for a system whose modes span ``f1 .. f_top`` (Hz), sampled at ``fs`` for ``n`` samples.

    Parameters
    ----------
    rng : numpy.random.Generator
        The drive's own random stream.
    level : float
        The system's typical drive amplitude (N or V); the drawn amplitude is 0.3-3 times it.
    f1, f_top : float
        The model's lowest and highest natural frequencies (Hz).
    fs : float
        The sample rate (Hz).
    n : int
        The number of samples (a multiple of 8).

    Returns
    -------
    Drive
    """
    T = n / fs
    kind = KINDS[rng.integers(len(KINDS))]
    amplitude = level * _log_uniform(rng, 0.3, 3.0)
    offset = amplitude * rng.uniform(0.2, 1.0) if rng.random() < 0.3 else 0.0
    fade = max(rng.uniform(0.02, 0.06) * T, 8 / fs)
    f_hi = min(fs / 10, f_top * rng.uniform(1.3, 4.0))
    f_lo = max(f1 * rng.uniform(0.03, 0.5), 4.0 / T)
    par: dict = {}
    if kind == "multisine":
        periods = int(rng.choice([1, 2, 4, 8]))
        base = periods / T
        h = np.arange(max(1, int(np.ceil(f_lo / base))), int(f_hi / base) + 1)
        if rng.random() < 0.5 and h.size > 60:  # a log-spaced subset
            h = np.unique(np.geomspace(h[0], h[-1], 60).round().astype(int))
        amps = np.ones(h.size)
        par = dict(
            periods=periods, harmonics=h, phases=rng.uniform(0, 2 * np.pi, h.size), f_lo=h[0] * base, f_hi=h[-1] * base
        )
    elif kind == "noise":
        order = int(rng.integers(2, 5))
        stop = min(fs / 4, 2 * f_hi)
        h = np.arange(1, int(stop * T) + 1)
        b, a = scipy.signal.butter(order, [2 * np.pi * f_lo, 2 * np.pi * f_hi], "bandpass", analog=True)
        mag = np.abs(scipy.signal.freqs(b, a, 2 * np.pi * h / T)[1])
        amps = rng.rayleigh(1.0, h.size) * mag
        par = dict(periods=1, harmonics=h, phases=rng.uniform(0, 2 * np.pi, h.size), f_lo=f_lo, f_hi=f_hi, order=order)
    elif kind == "sine":
        par = dict(
            f=_log_uniform(rng, max(0.2 * f1, 4 / T), min(2.0 * f_top, fs / 10)), phase=rng.uniform(0, 2 * np.pi)
        )
    elif kind == "triangle":
        par = dict(f=max(_log_uniform(rng, 0.02, 0.3) * f1, 3.0 / T), phase=rng.uniform(0, 2 * np.pi))
    elif kind == "chirp":
        par = dict(f_lo=f_lo, f_hi=f_hi, log=bool(rng.random() < 0.5), down=bool(rng.random() < 0.25))
    elif kind == "stepped-sine":
        k = int(rng.integers(3, 9))
        lo = max(0.3 * f1, 10 * k / T)
        freqs = np.geomspace(lo, max(lo * 1.5, f_hi), k)
        if rng.random() < 0.3:
            freqs = freqs[::-1]
        par = dict(freqs=freqs)
    else:  # steps and holds: random levels, or a staircase up and down
        j = int(rng.integers(4, 16))
        times = np.sort(rng.uniform(0.03 * T, 0.95 * T, j))
        if rng.random() < 0.5:
            levels = amplitude * rng.uniform(-1.0, 1.0, j)
        else:
            up = np.linspace(1, j // 2 + 1, j // 2 + 1)
            stair = np.concatenate([up, up[-2::-1]])[:j] / up[-1]
            levels = amplitude * stair
        rise = max(8 / fs, rng.uniform(0.05, 0.4) / f_top)
        par = dict(times=times, levels=levels, rise=rise)
    if kind in ("multisine", "noise"):
        par["amps"] = amps * (amplitude / np.sqrt(np.sum(amps**2)))  # RMS = amplitude / sqrt(2)
    return Drive(kind, amplitude, offset, T, fade, par)
