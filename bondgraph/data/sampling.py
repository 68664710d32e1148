"""Sampling of time series: the one definition of "uniformly sampled", resampling, decimation.

Functions work on plain arrays (times in seconds, strictly increasing); :class:`Dataset`
methods wrap them.
"""
from __future__ import annotations

import math

import numpy as np

from .. import config
from ..errors import DataError, UsageError


def uniform_step(t, rtol: float | None = None) -> float | None:
    """The mean sample interval (s) if ``t`` is uniformly sampled, else None.

    Uniform means every step is within ``rtol`` of the mean step, by default the setting
    ``data.uniform_rtol`` (1 %: absorbs time stamps printed with few digits)."""
    t = np.asarray(t, dtype=np.float64)
    if t.size < 2:
        return None
    rtol = config.get("data.uniform_rtol") if rtol is None else rtol
    with np.errstate(over="ignore", invalid="ignore"):
        mean = (t[-1] - t[0]) / (t.size - 1)
        ok = np.max(np.abs(np.diff(t) - mean)) <= rtol * mean
    return float(mean) if ok else None


def median_step(t) -> float:
    """Median time step (s)."""
    with np.errstate(over="ignore"):
        return float(np.median(np.diff(t)))


def uniform_grid(t0: float, t1: float, dt: float, where: str, n_have: int) -> np.ndarray:
    """``t0, t0 + dt, ...`` up to ``t1`` (the last point clipped to ``t1``)."""
    if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
        raise UsageError(f"resample step must be a positive number of seconds, not {dt!r}")
    n = int(math.floor((t1 - t0) / dt * (1 + 1e-12))) + 1
    if n < 2:
        raise DataError(f"{where}: a step of {dt:g} s leaves fewer than 2 samples")
    if n > max(100 * n_have, 10_000_000):
        raise UsageError(f"resample step {dt:g} s would make {n} samples from {n_have}; use a larger step")
    t = t0 + dt * np.arange(n)
    t[-1] = min(t[-1], t1)
    if n > 2 and t[-1] <= t[-2]:
        t = t[:-1]
    return t


def decimation_stages(factor: int) -> list[int]:
    """Split ``factor`` into IIR stages of at most 10 (prime factors > 13 stay single)."""
    stages, rest = [], factor
    while rest > 13:
        for q in range(10, 1, -1):
            if rest % q == 0:
                stages.append(q)
                rest //= q
                break
        else:
            break
    stages.append(rest)
    return [q for q in stages if q > 1]


def decimate_columns(columns: dict, factor: int, ftype: str, where: str, n: int) -> dict:
    """Every column low-pass filtered (zero phase) and decimated by ``factor``;
    see :meth:`Dataset.decimate`."""
    from scipy import signal

    stages = decimation_stages(factor) if ftype == "iir" else [factor]
    out = {}
    try:
        for name, values in columns.items():
            y = np.asarray(values)
            for q in stages:
                y = signal.decimate(y, q, ftype=ftype, zero_phase=True)
            out[name] = y
    except ValueError as exc:
        raise DataError(f"{where}: cannot decimate {n} samples by {factor} ({exc}); "
                        f"use more data or a smaller factor") from None
    return out
