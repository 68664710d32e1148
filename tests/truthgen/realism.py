"""Two numbers to compare a record with a real one (e.g. tests/data/p885_bursts.csv).

* :func:`loop_width` — the largest vertical gap between the falling and the rising branch of
  x(V), over the stroke (voltage binned into ``bins`` levels; each branch's mean per level);
* :func:`hold_drift` — the largest change of x over a hold (V within 0.2 % of its range of
  the hold's first value for at least ``min_hold`` seconds), end minus start, over the stroke.
"""

from __future__ import annotations

import numpy as np


def loop_width(V: np.ndarray, x: np.ndarray, bins: int = 20) -> float:
    dV = np.gradient(V)
    edges = np.linspace(V.min(), V.max(), bins + 1)
    gaps = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        inside = (V >= lo) & (V < hi)
        up, down = x[inside & (dV > 0)], x[inside & (dV < 0)]
        if len(up) > 2 and len(down) > 2:
            gaps.append(abs(down.mean() - up.mean()))
    stroke = float(np.ptp(x))
    return float(max(gaps) / stroke) if gaps and stroke > 0 else 0.0


def hold_drift(t: np.ndarray, V: np.ndarray, x: np.ndarray, min_hold: float = 0.5) -> float:
    tol = 2e-3 * float(np.ptp(V))
    best, start, n = 0.0, 0, len(V)
    while start < n - 1:
        stop = start + 1
        while stop < n and abs(V[stop] - V[start]) <= tol:
            stop += 1
        if t[stop - 1] - t[start] >= min_hold:
            k = max(3, (stop - start) // 20)
            best = max(best, abs(x[stop - k : stop].mean() - x[start : start + k].mean()))
        start = stop
    stroke = float(np.ptp(x))
    return best / stroke if stroke > 0 else 0.0
