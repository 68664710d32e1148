"""Identification: honest uncertainties, defaults, refusals, and the exact linear route with
time-scale separation.

Coverage protocol: a mass-spring-damper (k = 400 N/m, c = 4 N·s/m, m = 1 kg, a 3.2 Hz mode with
ζ = 0.1) driven by a fixed random multisine, 1000 samples at 200 Hz, white output noise of 2 %
of the response's RMS; 30 noise draws (seeds 0-29), k and c fitted from 30 % off.  The ± of
``FitResult.stderr`` is a standard error conditional on everything held fixed (here m, and the
exactly solved offset), so with white noise and the right model the interval ±1 SE must hold
the true value in about 68 % of the 60 cases, ±2 SE in about 95 %.
"""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import bondgraph as bg
from bondgraph import config
from bondgraph.data import Dataset
from bondgraph.fit.identify import Identification, Spec
from bondgraph.linear.lti import LTI, residualise
from bondgraph.support.errors import DataError

K, C_D = 400.0, 4.0


def msd():
    g = bg.Model("msd")
    F = g.input("F", "N")
    k = g.parameter("k", K, "N/m")
    c = g.parameter("c", C_D, "N*s/m")
    g.add(bg.Se("f", F), bg.J1("v"), bg.I("m", 1.0), bg.C("spring", 1 / k), bg.R("damper", c))
    g.bond("f", "v")
    for e in ("m", "spring", "damper"):
        g.bond("v", e)
    g.output("x", "spring.q", "m")
    return g


def record(seed, noise=0.02):
    t = np.arange(1000) / 200.0
    rng = np.random.default_rng(12345)
    F = sum(np.sin(2 * np.pi * f * t + rng.uniform(0, 6.3)) for f in (0.7, 1.9, 3.2, 4.4, 7.1))
    x = bg.simulate(msd(), t, {"F": bg.PiecewiseLinear(t, F)}, rtol=1e-10)["x"]
    x = x + np.random.default_rng(seed).normal(0, noise * np.std(x), t.size)
    return Dataset(t, {"F": F, "x": x})


def test_standard_errors_cover_the_true_values():
    inside1 = inside2 = 0
    # the records are simulated from rest, and the drive starts at F(0) ≠ 0
    with config.override({"record.start": "rest"}):
        for seed in range(30):
            ident = Identification(msd(), record(seed))
            specs = ident.specs(["k", "c"])
            specs[0].start, specs[1].start = 1.3 * K, 0.7 * C_D
            res = ident.fit(specs)
            assert res.success
            for name, true in (("k", K), ("c", C_D)):
                err = abs(res.values[name] - true)
                inside1 += err <= res.stderr[name]
                inside2 += err <= 2 * res.stderr[name]
    assert 31 <= inside1 <= 50, inside1  # 68 % of 60 = 41 (binomial 99 % band)
    assert inside2 >= 52, inside2  # 95 % of 60 = 57


def test_first_declared_input_and_output_by_default():
    ident = Identification(msd(), record(0))
    assert (ident.input, ident.output) == ("F", "x")


def test_constant_drive_is_refused():
    t = np.arange(100) / 100.0
    with pytest.raises(DataError, match="constant"):
        Identification(msd(), Dataset(t, {"F": np.full(t.size, 3.0), "x": np.sin(t)}))


def test_failed_optimisation_is_reported():
    ident = Identification(msd(), record(0))
    specs = ident.specs(["k", "c"])
    specs[0].start = 3 * K
    res = ident.fit(specs, max_nfev=2, rounds=1)
    assert res.success is False and res.message


def test_residualisation_keeps_slow_poles_and_static_gain():
    """Two masses: a slow mode (~3 Hz) and a stiff one (~3 kHz); with the cut between them the
    reduced model has exactly the slow poles and the full model's static gain, and its response
    to a slow input matches the full model's."""
    g = bg.Model("two")
    F = g.input("F", "N")
    g.add(
        bg.Se("f", F),
        bg.J1("v1"),
        bg.I("m1", 1.0),
        bg.C("k1", 1 / 400.0),
        bg.R("c1", 4.0),
        bg.J0("n"),
        bg.C("k2", 1 / 4e8),
        bg.J1("v2"),
        bg.I("m2", 1e-3),
        bg.R("c2", 10.0),
    )
    g.bond("f", "v1")
    for e in ("m1", "k1", "c1"):
        g.bond("v1", e)
    g.bond("v1", "n")
    g.bond("n", "k2")
    g.bond("n", "v2")
    g.bond("v2", "m2")
    g.bond("v2", "c2")
    g.output("x", "k1.q", "m")
    eqs = bg.derive(g)
    lti = LTI(eqs)
    th = np.array([float(eqs.model.parameter_table().get(p, 0)) for p in eqs.params])
    A, B, Cm, D = lti.matrices(th)
    full = np.linalg.eigvals(A)
    red = residualise(A, B, Cm, D, cut=2 * math.pi * 100)
    assert red.fast == A.shape[0] - red.n and red.n == 2
    slow = np.sort_complex(full[np.abs(full) < 2 * math.pi * 100])
    assert np.allclose(np.sort_complex(red.poles()), slow, rtol=1e-9)
    static_full = (D - Cm @ np.linalg.solve(A, B))[0, 0]
    static_red = (red.D - red.C @ np.linalg.solve(red.A, red.B))[0, 0]
    assert static_red == pytest.approx(static_full, rel=1e-9)
    t = np.arange(2000) / 1000.0
    u = np.sin(2 * np.pi * 2 * t)
    y_full = lti.state_space(th).response(1e-3, u)[:, 0]
    y_red = red.response(1e-3, u)[:, 0]
    assert np.max(np.abs(y_red - y_full)) < 1e-4 * np.max(np.abs(y_full))


def test_the_rate_term_keeps_the_lag_of_the_residualised_modes():
    """A slow first-order lag (1 Hz) beside a fast one (ω_f = 2π·2 kHz), y = x_slow + x_fast,
    the fast state residualised, driven by a 20 Hz sine: without the rate term D1 the reduced
    model misses the fast lag, an error of ω/ω_f = 1 % of the response; with it the error is
    second order ((ω/ω_f)² = 1e-4), in the frequency response and in the sampled response.
    Analytically D1 = −C_f·A_f⁻²·B_f = −1/ω_f for the unit fast lag 1/(1 + s/ω_f)."""
    from bondgraph.linear.lti import StateSpace

    wf, ws = 2 * math.pi * 2000.0, 2 * math.pi * 1.0
    A = np.diag([-wf, -ws])
    B = np.array([[wf], [ws]])
    C = np.array([[1.0, 1.0]])
    D = np.zeros((1, 1))
    red = residualise(A, B, C, D, cut=2 * math.pi * 100)
    assert red.n == 1 and red.fast == 1
    assert red.D1 == pytest.approx(-1 / wf, rel=1e-9)
    w = np.array([2 * math.pi * 20.0])
    H = StateSpace(A, B, C, D).frequency_response(w)
    no_rate = StateSpace(red.A, red.B, red.C, red.D).frequency_response(w)
    assert abs(no_rate - H)[0] == pytest.approx(w[0] / wf, rel=0.01)
    assert abs(red.frequency_response(w) - H)[0] < 1.01 * (w[0] / wf) ** 2
    dt = 1e-4
    t = np.arange(30000) * dt
    u = np.sin(w[0] * t)
    y = StateSpace(A, B, C, D).response(dt, u)[:, 0]
    settled = t > 1.0  # the slow lag's start-up decayed
    err = lambda r: np.max(np.abs(r.response(dt, u)[:, 0] - y)[settled])
    assert err(StateSpace(red.A, red.B, red.C, red.D)) == pytest.approx(w[0] / wf, rel=0.05)
    assert err(red) < 2e-4


@given(rows=st.integers(1, 30), cols=st.integers(1, 12), seed=st.integers(0, 10_000))
@settings(max_examples=60, deadline=None)
def test_bounded_least_squares_on_any_shape(rows, cols, seed):
    """bounded_lstsq against scipy's lsq_linear on the same problem, for tall and wide systems
    (a wide one, fewer rows than columns, indexed past the QR's diagonal before): within the
    bounds, and as good a fit (to rounding) whenever the columns are independent."""
    from scipy.optimize import lsq_linear

    from bondgraph.fit.identify import bounded_lstsq

    rng = np.random.default_rng(seed)
    A, b = rng.normal(size=(rows, cols)), rng.normal(size=rows)
    lower = np.where(rng.random(cols) < 0.5, 0.0, -np.inf)
    upper = np.full(cols, np.inf)
    x = bounded_lstsq(A, b, lower, upper)
    assert np.all(np.isfinite(x)) and np.all(x >= lower - 1e-12)
    if rows > cols:
        ref = lsq_linear(A, b, bounds=(lower, upper)).x
        assert np.linalg.norm(A @ x - b) <= np.linalg.norm(A @ ref - b) * (1 + 1e-6) + 1e-9


@settings(max_examples=60, deadline=None)
@given(
    st.floats(1e-6, 1e6),
    st.sampled_from([-1.0, 1.0]),
    st.floats(0.01, 0.99),
    st.floats(1.01, 100.0),
    st.floats(1e-3, 1e3),
)
def test_a_log_spec_keeps_its_start_sign_and_bounds_the_magnitude(mag, sign, lo, hi, ratio):
    """z = log |v| for a log parameter, the start's sign kept: a value inside the magnitude
    bounds comes back unchanged, one outside comes back clipped to the nearer bound."""
    spec = Spec("p", sign * mag, lo * mag, hi * mag, log=True)
    zl, zu = spec.z_bounds()
    assert zl == pytest.approx(math.log(lo * mag)) and zu == pytest.approx(math.log(hi * mag))
    v = sign * mag * ratio
    back = spec.from_z(spec.to_z(v))
    assert math.copysign(1.0, back) == sign
    assert abs(back) == pytest.approx(min(max(mag * ratio, lo * mag), hi * mag), rel=1e-12)
