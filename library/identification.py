"""Identification helpers that know the physics: the Bouc–Wen seeding procedure of seed 002 §5.2.

The Bouc–Wen polarization law E = kx·P + kw·z with ż = q·(Ṗ − r·|Ṗ|·|z|^(n−1)·z + (r−1)·Ṗ·|z|^n)
is hard to fit from a poor start.  Seed 002 reads the start values off a measured E–P curve:

* kx: the linear part (the known linear capacitor, or the least-squares slope);
* h = E − kx·P = kw·z; on a rising branch (Ṗ > 0) where z = 0, dh/dP = kw·q = α (eq. 18);
* at two points with z > 0 on a rising branch, dh/dP = α·(1 − (h/kw)^n) gives n and kw (eq. 19);
* at a point with z < 0 on a rising branch, dh/dP = α·(1 + (2r − 1)·|h/kw|^n) gives r (eq. 20);
* q = α/kw.
"""
from __future__ import annotations

import math

import numpy as np


def _slope_near(h: np.ndarray, s: np.ndarray, level: float, width: float) -> float | None:
    sel = np.abs(h - level) < width
    return float(np.median(s[sel])) if np.count_nonzero(sel) >= 3 else None


def bouc_wen_seed(P, E, kx: float | None = None) -> dict[str, float]:
    """Start values {kx, kw, q, r, n} from sampled polarization P and field E (seed 002 §5.2).

    ``P`` and ``E`` are in any consistent units (e.g. dipole C·m and V/m); the samples should
    cover at least one full quasi-static loop."""
    P = np.asarray(P, float)
    E = np.asarray(E, float)
    if kx is None:
        Pc = P - P.mean()
        kx = float(Pc @ (E - E.mean()) / max(Pc @ Pc, 1e-300))
    h = E - kx * P
    dP = np.gradient(P)
    dh = np.gradient(h)
    rising = dP > 1e-3 * np.max(np.abs(dP))
    hr, sr = h[rising], dh[rising] / dP[rising]
    hmax = float(np.max(np.abs(hr))) if hr.size else 0.0
    if hmax == 0.0:
        return {"kx": kx, "kw": 0.0, "q": 1.0, "r": 0.5, "n": 1.0}
    w = 0.08 * hmax
    alpha = _slope_near(hr, sr, 0.0, w) or float(np.max(sr))
    s1 = _slope_near(hr, sr, 0.3 * hmax, w)
    s2 = _slope_near(hr, sr, 0.7 * hmax, w)
    n, kw = 1.5, 1.2 * hmax
    if s1 is not None and s2 is not None and 0 < s2 < s1 < alpha:
        n = math.log((1 - s2 / alpha) / (1 - s1 / alpha)) / math.log(0.7 / 0.3)
        n = min(max(n, 1.0), 4.0)
        kw = 0.3 * hmax / (1 - s1 / alpha) ** (1 / n)
    s3 = _slope_near(hr, sr, -0.5 * hmax, w)
    r = 0.5
    if s3 is not None:
        r = ((s3 / alpha - 1) / (0.5 * hmax / kw) ** n + 1) / 2
        r = min(max(r, 0.0), 1.0)
    return {"kx": kx, "kw": kw, "q": alpha / kw, "r": r, "n": n}
