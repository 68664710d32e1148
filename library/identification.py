"""Identification helpers that know the physics, after Rodriguez-Fortun, Orus, Buil & Castellanos,
"General bond graph model for piezoelectric actuators and methodology for experimental
identification", Mechatronics 20 (2010) 303-314, Sec. 5.2-5.3.

Bouc-Wen seeding (Sec. 5.2). The polarization law E = kx*P + kw*z with
z' = q*(P' - r*|P'|*|z|^(n-1)*z + (r-1)*P'*|z|^n) is hard to fit from a poor start; the paper
reads the start values off a measured E-P curve:

* kx: the linear part (the known linear capacitor, or the least-squares slope);
* h = E - kx*P = kw*z; on a rising branch (P' > 0) where z = 0, dh/dP = kw*q = alpha (eq. 18);
* at two points with z > 0 on a rising branch, dh/dP = alpha*(1 - (h/kw)^n) gives n and kw (eq. 19);
* at a point with z < 0 on a rising branch, dh/dP = alpha*(1 + (2r - 1)*|h/kw|^n) gives r (eq. 20);
* q = alpha/kw.

Operator models (Sec. 5.3): thresholds on a grid over the input range (r_i = P_i/2), the
weights by non-negative least squares (the "slopes" of the loop), then the dead-zone weights of
the modified PI the same way on the PI sum, with the dead zones measured from the last reversal.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import nnls

from .hysteresis import PrandtlIshlinskii, RelativeModifiedPI, fit_pi_weights, threshold_grid


def _slope_near(h: np.ndarray, s: np.ndarray, level: float, width: float) -> float | None:
    sel = np.abs(h - level) < width
    return float(np.median(s[sel])) if np.count_nonzero(sel) >= 3 else None


def bouc_wen_seed(P, E, kx: float | None = None) -> dict[str, float]:
    """Start values {kx, kw, q, r, n} from sampled polarization P and field E (Sec. 5.2).

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


def fit_pi(v, y, n: int = 10) -> tuple[PrandtlIshlinskii, float]:
    """A PI model y ~ H[v] + c from sampled input v and output y (any units): n thresholds
    0 .. range/2 over v (r_i = P_i/2), non-negative weights and the offset c by least squares.
    Returns (operator, c); the operator runs from rest at v[0] like the data."""
    r = threshold_grid(v, n)
    w, c = fit_pi_weights(v, y, r, offset=True)
    return PrandtlIshlinskii(r, w), c


def fit_relative_modified_pi(v, y, n: int = 10, m: int = 3) -> tuple[RelativeModifiedPI, float]:
    """A modified PI y ~ G[H[v]] + c with dead zones measured from the last reversal (Sec. 5.3):
    the PI stage by :func:`fit_pi`, then m dead zones d_j = 0, D/m, .., (m-1)D/m over the PI sum's
    range D with non-negative weights ws_j (and a new offset) by least squares. The output of
    the dead-zone stage is linear in ws_j for a fixed PI sum, so this is exact least squares."""
    pi, _ = fit_pi(v, y, n)
    v = np.asarray(v, float)
    y = np.asarray(y, float)
    span = float(np.ptp(pi.run(v)))
    d = np.linspace(0.0, span, int(m), endpoint=False)
    cols = [RelativeModifiedPI(pi.thresholds, pi.weights, [dj], [1.0]).run(v) for dj in d]
    a = np.c_[np.array(cols).T, np.ones(v.size), -np.ones(v.size)]
    scale = np.max(np.abs(a), axis=0)
    scale[scale == 0.0] = 1.0
    y_scale = max(float(np.max(np.abs(y))), np.finfo(float).tiny)
    sol = nnls(a / scale, y / y_scale, maxiter=50 * a.shape[1])[0] / scale * y_scale
    return RelativeModifiedPI(pi.thresholds, pi.weights, d, sol[:m]), float(sol[m] - sol[m + 1])


def loop_width(v, y) -> float:
    """Largest vertical gap between the rising and the falling branch of one period of y(v)
    (starting at its minimum), as a fraction of the range of y: the width of a hysteresis
    loop as a piezo engineer reads it (10-15 % of the stroke on a stack). Units-free."""
    v, y = np.asarray(v, float), np.asarray(y, float)
    k = int(np.argmax(v))
    grid = np.linspace(v.min(), v.max(), 400)[5:-5]
    up, dn = np.argsort(v[: k + 1]), np.argsort(v[k:])
    yu = np.interp(grid, v[: k + 1][up], y[: k + 1][up])
    yd = np.interp(grid, v[k:][dn], y[k:][dn])
    return float(np.max(np.abs(yd - yu)) / np.ptp(y))
