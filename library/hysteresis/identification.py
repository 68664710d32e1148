"""Identification helpers: play outputs along a sampled path, threshold grids, non-negative PI
weights, the Bouc–Wen variable along a path."""

from __future__ import annotations

import math

import numba
import numpy as np
from scipy.optimize import nnls

from bondgraph import ParameterError

from .base import _vector, _virgin_plays
from .play import _PlayBank

_commit_plays = numba.njit(cache=True)(_PlayBank.commit)


@numba.njit(cache=True)
def _play_matrix(v, r, h):
    out = np.empty((v.size, r.size))
    for k in range(v.size):
        _commit_plays(v[k], h, r)
        out[k, :] = h
    return out


def play_outputs(v, thresholds, prior: float | None = None) -> np.ndarray:
    """Outputs of plays with the given thresholds for a sampled input, from rest at v[0]
    (after a monotone approach from ``prior``, as :class:`PrandtlIshlinskii` with that
    ``prior`` starts; from 0 without it).

    Returns an (n_samples, n_plays) array in units of v.
    """
    v = np.ascontiguousarray(v, dtype=np.float64).ravel()
    r = np.ascontiguousarray(_vector("thresholds", thresholds, nonneg=True))
    if v.size == 0:
        raise ParameterError("input sequence is empty")
    h = (
        _virgin_plays(v[0], r)
        if prior is None
        else np.ascontiguousarray(np.clip(float(prior), v[0] - r, v[0] + r), dtype=np.float64)
    )
    return _play_matrix(v, r, h)


def threshold_grid(v, n: int) -> np.ndarray:
    """n equally spaced thresholds 0, R/n, ..., (n-1)R/n with R = (max v - min v)/2, units of v.

    A play only opens a loop when the input swings by more than 2r, so R is the largest useful
    threshold (Rodriguez-Fortun et al. 2010: r_i = P_i / 2 over the input range).
    """
    v = np.asarray(v, dtype=np.float64)
    return np.linspace(0.0, 0.5 * float(np.ptp(v)), int(n), endpoint=False)


def fit_pi_weights(v, y, thresholds, offset: bool = False):
    """Non-negative least-squares PI weights w (units of y/v) for y ~ sum_i w_i H_{r_i}[v].

    The r = 0 play is v itself, so a threshold 0 gives the linear term. With ``offset`` an
    additive constant c (units of y, either sign) is fitted too and ``(w, c)`` is returned.
    Columns are scaled internally so NNLS is insensitive to the units of v and y.
    """
    a = play_outputs(v, thresholds)
    y = np.asarray(y, dtype=np.float64).ravel()
    if y.size != a.shape[0]:
        raise ParameterError(f"y has {y.size} samples, v has {a.shape[0]}")
    n = a.shape[1]
    if offset:
        a = np.hstack([a, np.ones((a.shape[0], 1)), -np.ones((a.shape[0], 1))])
    scale = np.max(np.abs(a), axis=0)
    scale[scale == 0.0] = 1.0
    y_scale = max(float(np.max(np.abs(y))), np.finfo(float).tiny)
    sol = nnls(a / scale, y / y_scale, maxiter=50 * a.shape[1])[0] / scale * y_scale
    if offset:
        return sol[:n], float(sol[n] - sol[n + 1])
    return sol[:n]


@numba.njit(cache=True)
def _relax(x):
    """(1 − e^(−x))/x, 1 at x = 0."""
    return -math.expm1(-x) / x if abs(x) > 1e-8 else 1.0 - 0.5 * x


@numba.njit(cache=True)
def _log_ratio(x):
    """ln(1 + x)/x, 1 at x = 0."""
    return math.log1p(x) / x if abs(x) > 1e-8 else 1.0 - 0.5 * x


@numba.njit(cache=True)
def _bouc_wen_exact(v, beta, gamma, z0, out):
    """Exponent 1: along a monotone piece of the path (|Δv| = U, σ = sign Δv) ζ = σz obeys
    dζ/du = 1 − (β ± γ)·ζ (+ for ζ ≥ 0), a linear law on each side of ζ = 0, solved in closed form;
    ζ crosses 0 at most once, upwards."""
    z = z0
    out[0] = z
    b = beta + gamma
    a = beta - gamma
    for k in range(1, v.shape[0]):
        dv = v[k] - v[k - 1]
        if dv != 0.0:
            sg = 1.0 if dv > 0 else -1.0
            zeta = sg * z
            U = abs(dv)
            if zeta < 0.0:
                x = -a * zeta
                u0 = -zeta * _log_ratio(x) if x > -1.0 else math.inf
                if u0 >= U:
                    zeta = zeta * math.exp(-a * U) + U * _relax(a * U)
                else:
                    rem = U - u0
                    zeta = rem * _relax(b * rem)
            else:
                zeta = zeta * math.exp(-b * U) + U * _relax(b * U)
            z = sg * zeta
        out[k] = z


@numba.njit(cache=True)
def _bouc_wen_path(v, beta, gamma, n, z0, out):
    z = z0
    out[0] = z
    for k in range(1, v.shape[0]):
        dv = v[k] - v[k - 1]
        # sub-steps keep each explicit update small against the loop's curvature
        m = 1 + int(abs(dv) * (abs(beta) + abs(gamma) + 1.0) * 8.0)
        h = dv / m
        for _ in range(m):
            az = abs(z)
            z += h - beta * abs(h) * az ** (n - 1.0) * z - gamma * h * az**n
        out[k] = z


def bouc_wen_response(v, beta: float, gamma: float, n: float, z0: float = 0.0) -> np.ndarray:
    """Bouc–Wen variable z along a sampled input path (rate independent):
    dz = dv − β·|dv|·|z|^(n−1)·z − γ·dv·|z|^n, from z0 (units of v; z saturates near
    (β + γ)^(−1/n)).  For identification: z depends on the path only, not on time.  Exponent 1
    (the usual one): exact between samples, the path being linear there; others: explicit
    sub-steps small against the loop's curvature."""
    v = np.ascontiguousarray(v, dtype=np.float64)
    out = np.empty_like(v)
    if n == 1.0:
        _bouc_wen_exact(v, float(beta), float(gamma), float(z0), out)
    else:
        _bouc_wen_path(v, float(beta), float(gamma), float(n), float(z0), out)
    return out
