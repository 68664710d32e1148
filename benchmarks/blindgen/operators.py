"""Input-side operators of the bimorph (the drive reaches the beam as an equivalent voltage
u = H[V], Ghafarirad et al. 2015, eq. 25), evaluated on a fine time grid where V is linear
between nominal samples.  All take and return volts.

* Preisach (Mayergoyz 1991) with a random density on the (alpha, beta) half-plane, through a
  tabulated Everett function and the wiping-out memory of turning points; the output is
  continuous (bilinear in the thresholds), lags the input (counter-clockwise loop) and starts
  from an AC-demagnetised state.
* Bouc-Wen at the input (as Low & Guo 1995 for a bimorph): u = V - H Vr z, with the
  rate-independent dz/dV = (1/(w Vr)) (1 - (b sgn(dV z) + 1 - b) |z|^n).
* Creep cells (generalised Kelvin-Voigt in the polarization): u = V + sum r_n c_n,
  tau_n c_n' = V - c_n, exact for V linear between grid points.
"""

from __future__ import annotations

import numpy as np
from numba import njit

EDGE = 1.5  # Preisach thresholds span [-EDGE, EDGE] Vr


def preisach_table(rng, n=241):
    """A random Preisach density in units of Vr and its Everett table E[i, j] = weighted area of
    {beta_j <= beta' <= alpha' <= alpha_i}; normalised so that a full sweep changes the output by
    2 * EDGE (slope about 1 over the threshold range).  Returns (grid, E, description)."""
    g = np.linspace(-EDGE, EDGE, n)
    al, be = np.meshgrid(g, g, indexing="ij")
    c, r = (al + be) / 2, (al - be) / 2
    mu = np.zeros_like(c)
    bumps = []
    for _ in range(int(rng.integers(2, 4))):
        cc, sc = rng.uniform(-0.6, 0.6), rng.uniform(0.5, 1.2)
        rc, sr = rng.uniform(0.0, 0.3), rng.uniform(0.08, 0.3)
        a = rng.uniform(0.5, 1.0)
        mu += a * np.exp(-0.5 * ((c - cc) / sc) ** 2 - 0.5 * ((r - rc) / sr) ** 2)
        bumps.append({"c": cc, "sc": sc, "r": rc, "sr": sr, "a": a})
    mu += 0.05 * np.exp(-r / 0.5)  # broad background: no flat dead spots
    mu[al < be] = 0.0
    # cumulative over alpha ascending and beta descending
    E = np.cumsum(np.cumsum(mu[:, ::-1], axis=1)[:, ::-1], axis=0)
    E *= EDGE / E[-1, 0]
    return g, E, bumps


@njit(cache=True)
def _everett(g, E, a, b):
    n = g.size
    h = g[1] - g[0]
    fa = min(max((a - g[0]) / h, 0.0), n - 1.000001)
    fb = min(max((b - g[0]) / h, 0.0), n - 1.000001)
    i, j = int(fa), int(fb)
    u, v = fa - i, fb - j
    return (1 - u) * (1 - v) * E[i, j] + u * (1 - v) * E[i + 1, j] + (1 - u) * v * E[i, j + 1] + u * v * E[i + 1, j + 1]


@njit(cache=True)
def _preisach(x, g, E):
    """Output (in Vr) for the input sequence x (in Vr) from negative saturation.  Memory: turning
    points tp[0..m), tp[0] the lower edge, alternating min, max, min...; ps[i] the sum of
    2 (E(M_k, m_k-1) - E(M_k, m_k)) over the max-min pairs that end at or before index i."""
    lo = g[0]
    tp = np.zeros(x.size + 2)
    ps = np.zeros(x.size + 2)
    tp[0] = lo
    m = 1
    E0 = _everett(g, E, g[-1], lo)
    out = np.zeros(x.size)
    prev = lo
    for t in range(x.size):
        xt = min(max(x[t], g[0]), g[-1])
        if m % 2 == 1 and xt < prev:  # rising -> falling: prev is a maximum
            tp[m] = prev
            ps[m] = ps[m - 1]
            m += 1
        elif m % 2 == 0 and xt > prev:  # falling -> rising: prev is a minimum
            tp[m] = prev
            ps[m] = ps[m - 1] + 2 * (_everett(g, E, tp[m - 1], tp[m - 2]) - _everett(g, E, tp[m - 1], prev))
            m += 1
        if m % 2 == 1:  # wiping out
            while m >= 3 and xt >= tp[m - 2]:
                m -= 2
        else:
            while m >= 4 and xt <= tp[m - 2]:
                m -= 2
        if m % 2 == 1:
            out[t] = -E0 + ps[m - 1] + 2 * _everett(g, E, xt, tp[m - 1])
        else:
            out[t] = -E0 + ps[m - 2] + 2 * (_everett(g, E, tp[m - 1], tp[m - 2]) - _everett(g, E, tp[m - 1], xt))
        prev = xt
    return out


_DEMAG = EDGE * np.array([(1.0 if k % 2 == 0 else -1.0) * (1 - k / 60) for k in range(60)] + [0.0])


def preisach(V, Vr, h, table):
    """u = (1 - h) V + h Vr (P[V/Vr] - P at rest): a fraction h of the drive passes the
    Preisach operator; V starts at 0 (the demagnetised rest)."""
    g, E, _ = table
    V = np.asarray(V, float)
    p = _preisach(np.concatenate([_DEMAG, V / Vr]), g, E)[_DEMAG.size :]
    return (1 - h) * V + h * Vr * (p - p[0])


@njit(cache=True)
def _bouc_wen(V, Vr, w, b, n):
    z = 0.0
    out = np.zeros(V.size)
    for k in range(1, V.size):
        dv = (V[k] - V[k - 1]) / Vr
        m = 1 + int(abs(dv) / (0.01 * w))
        s = dv / m
        for _ in range(m):
            zz = z
            d = 0.0
            for stage in range(2):  # Heun in V
                sg = 1.0 if s * zz > 0 else -1.0
                f = (1.0 - (b * sg + 1.0 - b) * abs(zz) ** n) / w
                d += f * s / 2.0
                zz = z + f * s
            z += d
        out[k] = z
    return out


def bouc_wen(V, Vr, H, w, b, n):
    """u = V - H Vr z, z the rate-independent Bouc-Wen variable of V/Vr (stop-like, |z| <= 1)."""
    V = np.asarray(V, float)
    return V - H * Vr * _bouc_wen(V, Vr, w, b, n)


@njit(cache=True)
def _cells(V, h, r, tau):
    out = V.copy()
    for n in range(r.size):
        e = np.exp(-h / tau[n])
        c = 0.0
        for k in range(V.size - 1):
            m = (V[k + 1] - V[k]) / h
            c = V[k] + m * (h - tau[n]) + (c - V[k] + m * tau[n]) * e
            out[k + 1] += r[n] * c
    return out


def creep(V, h, r, tau):
    """u = V + sum r_n c_n, tau_n c_n' = V - c_n, from rest; grid step h (s)."""
    return _cells(np.asarray(V, float), h, np.asarray(r, float), np.asarray(tau, float))
