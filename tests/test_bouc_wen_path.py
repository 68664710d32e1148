"""The Bouc–Wen variable along a sampled path (exponent 1, solved in closed form between
samples) against the analytic ramp response and against a tight ODE integration of
dz/dt = v̇ − β|v̇|z − γv̇|z| in time."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from library.hysteresis import bouc_wen_response


def test_a_rising_ramp_from_rest_saturates_exponentially():
    beta, gamma = 7.0, 3.0
    v = np.linspace(0.0, 0.8, 9)  # any sampling of a monotone path
    z = bouc_wen_response(v, beta, gamma, 1.0)
    assert np.allclose(z, -np.expm1(-(beta + gamma) * v) / (beta + gamma), rtol=1e-13, atol=0)


def test_a_falling_ramp_from_a_positive_state_crosses_zero_once():
    # v falls by U from z0 > 0: ζ = −z rises from −z0 under dζ/du = 1 − (β − γ)ζ, then from 0
    # under 1 − (β + γ)ζ; the crossing at u0 = ln(1 + (β − γ)z0)/(β − γ)
    beta, gamma, z0, U = 4.0, 1.5, 0.2, 0.5
    a, b = beta - gamma, beta + gamma
    u0 = math.log1p(a * z0) / a
    z = bouc_wen_response(np.array([0.0, -U]), beta, gamma, 1.0, z0)
    assert z[1] == pytest.approx(-(-math.expm1(-b * (U - u0)) / b), rel=1e-13)


@pytest.mark.parametrize(
    "beta, gamma, z0", [(3.0, 0.5, 0.0), (30.0, -10.0, 0.02), (0.5, 2.0, -0.3), (100.0, 100.0, 0.004)]
)
def test_the_path_is_the_ode_solution(beta, gamma, z0):
    t = np.linspace(0.0, 1.0, 40001)
    w1, w2 = 2 * math.pi * 3, 2 * math.pi * 0.7

    def v(t):
        return np.sin(w1 * t) * (1 + 0.5 * np.sin(w2 * t))

    def vdot(t):
        return w1 * np.cos(w1 * t) * (1 + 0.5 * np.sin(w2 * t)) + 0.5 * w2 * np.sin(w1 * t) * np.cos(w2 * t)

    def rate(t, z):
        d = vdot(t)
        return d - beta * abs(d) * z - gamma * d * abs(z)

    ode = solve_ivp(rate, (0.0, 1.0), [z0], t_eval=t, rtol=1e-10, atol=1e-13, method="LSODA").y[0]
    z = bouc_wen_response(v(t), beta, gamma, 1.0, z0)
    assert np.max(np.abs(z - ode)) < 2e-5 * np.max(np.abs(ode))  # explicit sub-steps: 4e-4 to 4e-3
