"""Exact responses of small linear filters to sampled signals (linear between samples):
the bases that drive-side candidates and the flexible linear reference are built from."""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import signal

from ..linear.lti import StateSpace


def lowpass(u: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """First-order lag 1/(τs + 1) of ``u`` (sampled every ``dt`` s, linear in between),
    starting in equilibrium with u[0].

    Parameters
    ----------
    u : numpy.ndarray
        The samples, any unit.
    tau : float
        Time constant τ, s (> 0).
    dt : float
        Sample interval, s.

    Returns
    -------
    numpy.ndarray
        The lag's output at the samples, units of ``u`` (unit static gain).
    """
    a = math.exp(-dt / tau)
    b1 = 1.0 - tau / dt * (1.0 - a)
    b0 = tau / dt * (1.0 - a) - a
    zi = signal.lfiltic([b1, b0], [1.0, -a], [u[0]], [u[0]])
    return signal.lfilter([b1, b0], [1.0, -a], u, zi=zi)[0]


@njit(cache=True)
def _rate_limited(u, tau, rate, dt):
    v = np.empty(u.size)
    v[0] = u[0]
    h = dt / tau
    for k in range(1, u.size):
        # backward Euler: g(x) = x − v[k−1] − dt·rate·tanh((u[k] − x)/(τ·rate)) = 0 is increasing
        # in x and changes sign between v[k−1] and u[k]: Newton kept inside that bracket
        lo, hi = min(v[k - 1], u[k]), max(v[k - 1], u[k])
        x = v[k - 1]
        for _ in range(60):
            t = math.tanh((u[k] - x) / (tau * rate))
            g = x - v[k - 1] - dt * rate * t
            if g > 0.0:
                hi = x
            else:
                lo = x
            step = g / (1.0 + h * (1.0 - t * t))
            nx = x - step
            if not lo <= nx <= hi:
                nx = 0.5 * (lo + hi)
            if abs(nx - x) <= 1e-13 * (abs(x) + abs(u[k]) + 1e-300):
                x = nx
                break
            x = nx
        v[k] = x
    return v


def rate_limited(u: np.ndarray, tau: float, rate: float, dt: float) -> np.ndarray:
    """A first-order stage whose rate saturates: v̇ = S·tanh((u − v)/(τ·S)), the voltage on a
    capacitance charged through a series resistance by a source whose current saturates (a
    lag 1/(τs + 1) for small steps, a slew rate S for large ones), by the backward Euler rule
    per sample from v = u[0].

    Parameters
    ----------
    u : numpy.ndarray
        The samples, any unit.
    tau : float
        Time constant τ of the unsaturated stage, s (> 0).
    rate : float
        The largest rate S, units of u per s (> 0).
    dt : float
        Sample interval, s.

    Returns
    -------
    numpy.ndarray
        The stage's output at the samples, units of ``u`` (unit static gain).
    """
    return _rate_limited(np.ascontiguousarray(u, dtype=np.float64), float(tau), float(rate), float(dt))


def resonator(u: np.ndarray, dt: float, omega: float, zeta: float, velocity: bool = False) -> np.ndarray:
    """Displacement q of q̈ + 2ζω·q̇ + ω²·q = u, from rest (units of u·s²), or (q, q̇).

    ``u`` is taken as linear between samples (exact first-order-hold discretisation).

    Parameters
    ----------
    u : numpy.ndarray
        The forcing samples.
    dt : float
        Sample interval, s.
    omega : float
        Natural angular frequency ω, rad/s.
    zeta : float
        Damping ratio ζ (dimensionless).
    velocity : bool, optional
        Return the velocity q̇ too (units of u·s), as a second column.

    Returns
    -------
    numpy.ndarray
        q at the samples, units of u·s² (static gain 1/ω²); with ``velocity``, an
        (samples, 2) array of q and q̇.
    """
    A = np.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    B, D = np.array([[0.0], [1.0]]), np.zeros((1, 1))
    q = StateSpace(A, B, np.array([[1.0, 0.0]]), D).response(dt, u)[:, 0]
    if not velocity:
        return q
    return np.column_stack([q, StateSpace(A, B, np.array([[0.0, 1.0]]), D).response(dt, u)[:, 0]])
