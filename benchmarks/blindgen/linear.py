"""Exact simulation of linear state-space models under a piecewise-linear input (first-order
hold: the drive is linear between samples), and the best linear refit used by the
visibility rule.

x' = A x + B u, y = C x, from rest; samples every dt; y in the model's output unit.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.linalg import expm
from scipy.optimize import least_squares


def foh(A: np.ndarray, B: np.ndarray, dt: float):
    """(Phi, Gw, Gs): x[k+1] = Phi x[k] + Gw u[k] + Gs (u[k+1] - u[k]) / dt, exact for an input
    linear over the step."""
    n = A.shape[0]
    F = np.zeros((n + 2, n + 2))
    F[:n, :n] = A
    F[:n, n] = B
    F[n, n + 1] = 1.0
    E = expm(F * dt)
    return (np.ascontiguousarray(E[:n, :n]), np.ascontiguousarray(E[:n, n]), np.ascontiguousarray(E[:n, n + 1]))


@njit(cache=True)
def _run(Phi, Gw, Gs, C, u, inv_dt):
    n = Phi.shape[0]
    x = np.zeros(n)
    xn = np.zeros(n)
    y = np.zeros(u.size)
    for k in range(u.size - 1):
        s = (u[k + 1] - u[k]) * inv_dt
        acc_y = 0.0
        for i in range(n):
            acc = Gw[i] * u[k] + Gs[i] * s
            for j in range(n):
                acc += Phi[i, j] * x[j]
            xn[i] = acc
        for i in range(n):
            x[i] = xn[i]
            acc_y += C[i] * x[i]
        y[k + 1] = acc_y
    return y


def simulate(A, B, C, u, dt) -> np.ndarray:
    """Output samples of (A, B, C) from rest under the sampled input u (first-order hold)."""
    Phi, Gw, Gs = foh(np.asarray(A, float), np.asarray(B, float), dt)
    return _run(Phi, Gw, Gs, np.asarray(C, float), np.asarray(u, float), 1.0 / dt)


def refit(y, predict, theta0, lower, upper, starts=(), enough=0.0):
    """Best linear refit of y: min over theta in [lower, upper] (log-parameters) and a free
    gain and offset of ||y - g * predict(theta) - o||.  Returns (rms, theta).  ``starts`` are
    further start points, tried while the RMS stays above ``enough`` (the best result wins)."""
    y = np.asarray(y, float)
    yc = y - y.mean()

    def resid(theta):
        lc = predict(theta)
        lc = lc - lc.mean()
        return (lc @ yc) / max(lc @ lc, 1e-300) * lc - yc

    best = None
    for t0 in (theta0, *starts):
        t0 = np.clip(np.asarray(t0, float), lower + 1e-9, upper - 1e-9)
        sol = least_squares(resid, t0, bounds=(lower, upper), diff_step=1e-4, xtol=1e-8, ftol=1e-4, max_nfev=100)
        if best is None or sol.cost < best.cost:
            best = sol
        if np.sqrt(2 * best.cost / y.size) <= enough:
            break
    return float(np.sqrt(2 * best.cost / y.size)), best.x
