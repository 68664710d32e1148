"""Hysteresis operators (library/hysteresis/): operator properties, contracts, inverse, fits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bondgraph.support.errors import ParameterError
from library.hysteresis import (
    MaxwellSlip,
    ModifiedPI,
    PIStop,
    PrandtlIshlinskii,
    RelativeModifiedPI,
    fit_pi_weights,
    play_outputs,
    threshold_grid,
)

R = [0.0, 0.1, 0.25, 0.4, 0.6]
W = [1.0, 0.5, 0.3, 0.2, 0.4]


def operators():
    return [
        PrandtlIshlinskii(R, W),
        PIStop(R, W),
        ModifiedPI(R, W, [0.0, 0.5, -0.3], [1.0, 0.8, 0.4]),
        MaxwellSlip([2.0, 1.0, 0.5], [0.2, 0.3, 0.4]),
    ]


def branch_operators():
    """Operators whose memory is the last reversal rather than a return-point memory: the
    relative modified PI and the inverses of both modified PI forms."""
    rel = RelativeModifiedPI(R, W, [0.0, 0.5, 1.0], [1.0, 0.8, 0.4])
    return [rel, rel.inverse(), ModifiedPI(R, W, [0.0, 0.5, -0.3], [1.0, 0.8, 0.4]).inverse()]


OPS = operators()
IDS = [op.kind for op in OPS]
ALL_OPS = OPS + branch_operators()
ALL_IDS = [op.kind for op in ALL_OPS]


def path(knots, per_segment=20):
    """Piecewise-linear sampled input through the given turning points (knots included)."""
    pieces = [np.linspace(a, b, per_segment, endpoint=False) for a, b in zip(knots[:-1], knots[1:])]
    return np.concatenate(pieces + [[knots[-1]]])


def final_memory(op, v):
    prm = op.parameter_values()
    mem = op.initial_memory(float(v[0]), prm)
    for vk in v:
        type(op).commit(float(vk), mem, prm)
    return mem


def lipschitz_bound(op):
    """An upper bound of |dy/dv| for frozen memory."""
    if isinstance(op, MaxwellSlip):
        return np.sum(op.stiffnesses)
    bound = np.sum(np.abs(op.weights))
    return bound * np.sum(np.abs(op.dz_weights)) if hasattr(op, "dz_weights") else bound


finite = dict(allow_nan=False, allow_infinity=False)
inputs = st.lists(st.floats(-2.0, 2.0, **finite), min_size=2, max_size=60)


# --- rate independence, memory properties ---------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    knots=st.lists(st.floats(-1.5, 1.5, **finite), min_size=2, max_size=8),
    power=st.floats(0.3, 3.0),
    n_a=st.integers(2, 30),
    n_b=st.integers(2, 30),
)
@pytest.mark.parametrize("op", ALL_OPS, ids=ALL_IDS)
def test_rate_independence(op, knots, power, n_a, n_b):
    """The same input path under two clocks gives the same output at every shared path point."""
    k = len(knots) - 1
    shared = np.linspace(0.0, k, 8 * k + 1)  # path parameter s, includes all knots
    clock_a = np.linspace(0.0, 1.0, n_a * k) * k  # uniform clock
    clock_b = np.linspace(0.0, 1.0, n_b * k) ** power * k  # time-warped clock
    out = []
    for clock in (clock_a, clock_b):
        s = np.union1d(clock, shared)
        y = op.run(np.interp(s, np.arange(k + 1), knots))
        out.append(y[np.searchsorted(s, shared)])
    np.testing.assert_allclose(out[0], out[1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("op", OPS, ids=IDS)
def test_return_point_memory(op):
    """A minor loop 4 -> -2 -> 4 inside the major loop closes at its return point and leaves the
    memory as it was, so the branch then continues as if the loop had never happened."""
    with_loop = path([0.0, 10.0, -10.0, 4.0, -2.0, 4.0, 10.0]) / 10
    without = path([0.0, 10.0, -10.0, 4.0, 10.0]) / 10
    y1, y2 = op.run(with_loop), op.run(without)
    n = 20  # samples per segment
    assert y1[3 * n] == pytest.approx(y1[5 * n], abs=1e-12)  # loop closes at v = 0.4
    assert y1[4 * n] < y1[3 * n]  # and was a real excursion
    np.testing.assert_allclose(y1[5 * n :], y2[3 * n :], atol=1e-12)  # same branch to v = 1
    np.testing.assert_allclose(final_memory(op, with_loop), final_memory(op, without), atol=1e-12)


@pytest.mark.parametrize("op", OPS, ids=IDS)
def test_wiping_out(op):
    """Exceeding the maximum 0.6 erases it and every later (smaller) extremum."""
    a = path([0.0, 1.0, -1.0, 0.6, -0.4, 0.3, -0.1, 0.8, -0.5])
    b = path([0.0, 1.0, -1.0, 0.8, -0.5])
    np.testing.assert_allclose(final_memory(op, a), final_memory(op, b), atol=1e-12)
    np.testing.assert_allclose(op.run(a)[-21:], op.run(b)[-21:], atol=1e-12)
    # without the wiping excursion the memories differ
    c = path([0.0, 1.0, -1.0, 0.6, -0.4, 0.3, -0.1, 0.5, -0.5])
    assert np.max(np.abs(final_memory(op, c) - final_memory(op, b))) > 1e-3


# --- the output/commit contract -----------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(v=inputs, trials=st.lists(st.floats(-2.5, 2.5, **finite), min_size=1, max_size=5))
@pytest.mark.parametrize("op", ALL_OPS, ids=ALL_IDS)
def test_output_is_pure_and_commit_matches_run(op, v, trials):
    prm = op.parameter_values()
    out_fn, commit_fn = type(op).output, type(op).commit
    lipschitz = lipschitz_bound(op)
    mem = op.initial_memory(v[0], prm)
    y = []
    for vk in v:
        for trial in trials:  # rejected steps: output only
            before = mem.copy()
            y_t = out_fn(trial, mem, prm)
            np.testing.assert_array_equal(mem, before)
            assert out_fn(trial, mem, prm) == y_t
            h = 1e-6  # continuity: Lipschitz in v, up to rounding of the sums
            assert abs(out_fn(trial + h, mem, prm) - y_t) <= lipschitz * h + 1e-12
        y.append(out_fn(vk, mem, prm))
        commit_fn(vk, mem, prm)
    np.testing.assert_allclose(y, op.run(np.array(v)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(mem, final_memory(op, np.array(v)), rtol=0, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(v=inputs)
@pytest.mark.parametrize("op", ALL_OPS, ids=ALL_IDS)
def test_initial_memory_is_monotone_approach_from_zero(op, v):
    """Rest at v0 means: reached monotonically from the demagnetised state at 0."""
    v = np.array(v)
    np.testing.assert_allclose(op.run(v), op.run(np.r_[0.0, v])[1:], rtol=0, atol=1e-12)
    assert op.run(np.zeros(3))[0] == 0.0


def test_parameter_layout_and_gains():
    pi, stop, mpi, ms = operators()
    assert pi.parameter_names == ("r1", "r2", "r3", "r4", "r5", "w1", "w2", "w3", "w4", "w5")
    assert mpi.parameter_names[10:] == ("d1", "d2", "d3", "ws1", "ws2", "ws3")
    assert ms.parameter_names == ("k1", "k2", "k3", "f1", "f2", "f3")
    for op in operators():
        assert len(op.parameter_names) == op.parameter_values().size
    assert (pi.n_memory, mpi.n_memory, ms.n_memory) == (5, 5, 3)
    assert pi.small_signal_gain(pi.parameter_values()) == 1.0
    assert stop.small_signal_gain(stop.parameter_values()) == pytest.approx(1.4)
    assert mpi.small_signal_gain(mpi.parameter_values()) == 1.0
    assert ms.small_signal_gain(ms.parameter_values()) == 3.5
    # measured: slope right after a reversal from rest
    for op in operators():
        v = np.array([0.0, 1e-6, 0.0])
        y = op.run(v)
        assert (y[1] - y[0]) / 1e-6 == pytest.approx(op.small_signal_gain(op.parameter_values()))
        assert (y[1] - y[2]) / 1e-6 == pytest.approx(op.small_signal_gain(op.parameter_values()))
    with pytest.raises(ParameterError):
        PrandtlIshlinskii([0.0, -1.0], [1.0, 1.0])
    with pytest.raises(ParameterError):
        PrandtlIshlinskii([0.0, 1.0], [1.0])
    with pytest.raises(ParameterError):
        MaxwellSlip([0.0], [1.0])


# --- equivalences ------------------------------------------------------------------------


@settings(max_examples=50, deadline=None)
@given(kf=st.lists(st.tuples(st.floats(0.1, 10.0), st.floats(0.0, 5.0)), min_size=1, max_size=6), v=inputs)
def test_maxwell_slip_equals_pi_stop(kf, v):
    k, f = map(list, zip(*kf))
    ms = MaxwellSlip(k, f)
    stop = ms.to_pi_stop()
    np.testing.assert_allclose(stop.thresholds, np.array(f) / np.array(k))
    y_ms, y_stop = ms.run(v), stop.run(v)
    np.testing.assert_allclose(y_ms, y_stop, rtol=1e-12, atol=1e-12 * np.sum(k))
    # the forces respect the break-away limits
    assert np.all(np.abs(y_ms) <= np.sum(f) * (1 + 1e-12) + 1e-12)


@settings(max_examples=40, deadline=None)
@given(v=inputs)
def test_stop_play_identity(v):
    v = np.array(v)
    lhs = PIStop(R, W).run(v)
    rhs = np.sum(W) * v - PrandtlIshlinskii(R, W).run(v)
    np.testing.assert_allclose(lhs, rhs, atol=1e-12)
    # each stop saturates at +-r
    for r in R:
        assert np.all(np.abs(PIStop([r], [1.0]).run(v)) <= r + 1e-15)


# --- inverse and feed-forward compensation ------------------------------------------------


@st.composite
def invertible_pi(draw):
    n = draw(st.integers(1, 8))
    r = np.sort(np.array(draw(st.lists(st.floats(0.0, 1.0), min_size=n - 1, max_size=n - 1))))
    w = draw(st.lists(st.floats(0.0, 2.0), min_size=n - 1, max_size=n - 1))
    w1 = draw(st.floats(0.05, 3.0))
    return PrandtlIshlinskii(np.r_[0.0, r], np.r_[w1, w])


@settings(max_examples=80, deadline=None)
@given(pi=invertible_pi(), v=inputs)
def test_pi_inverse_is_exact(pi, v):
    v = np.array(v)
    inv = pi.inverse()
    scale = max(np.max(np.abs(v)), 1e-300)
    np.testing.assert_allclose(inv.run(pi.run(v)), v, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(pi.run(inv.run(v)), v, rtol=0, atol=1e-9 * scale)


def test_pi_inverse_requires_increasing_loading_curve():
    with pytest.raises(ParameterError):
        PrandtlIshlinskii([0.1, 0.2], [1.0, 1.0]).inverse()  # no threshold-0 play
    with pytest.raises(ParameterError):
        PrandtlIshlinskii([0.0, 0.2], [1.0, -1.5]).inverse()  # loading curve turns down
    # unsorted input is fine: the sum does not depend on the order of the plays
    inv = PrandtlIshlinskii([0.3, 0.0, 0.1], [0.2, 1.0, 0.5]).inverse()
    assert inv.thresholds[0] == 0.0 and inv.weights[0] == 1.0


def _compensation_ratio(plant, model, y_ref):
    """max|y - y_ref| / range: direct (gain-scaled) drive over drive through model.inverse()."""
    v_ff = model.inverse().run(y_ref)
    err_ff = np.max(np.abs(plant.run(v_ff) - y_ref))
    v_lin = y_ref * (np.ptp(v_ff) / np.ptp(y_ref))  # same input range, no compensation
    err_lin = np.max(np.abs(plant.run(v_lin) - y_ref))
    span = np.ptp(y_ref)
    return (err_lin / span) / max(err_ff / span, 1e-300), err_lin / span, err_ff / span


def test_feedforward_compensation():
    t = np.linspace(0.0, 3.0, 1501)
    y_ref = 5.0 * np.sin(2 * np.pi * t) * (1.0 - 0.25 * t)  # decaying: minor loops too
    r = threshold_grid(y_ref, 10)
    plant = PrandtlIshlinskii(r, np.r_[1.0, np.linspace(0.6, 0.1, 9)])
    ratio, err_lin, err_ff = _compensation_ratio(plant, plant, y_ref)
    print(f"\nexact model: uncompensated {err_lin:.3%}, compensated {err_ff:.2e}, ratio {ratio:.3g}")
    assert err_lin > 0.05 and ratio > 1e6

    # realistic case: the plant has a continuum-like threshold density, the compensator uses
    # a 10-play model identified by NNLS from one excitation and is tested on another
    plant = PrandtlIshlinskii(np.linspace(0.0, 4.0, 100, endpoint=False), np.r_[1.0, np.full(99, 0.06)])
    v_id = 5.0 * np.sin(2 * np.pi * 2 * t) * np.exp(-0.5 * t)
    r_id = threshold_grid(np.r_[v_id, -v_id], 10)
    model = PrandtlIshlinskii(r_id, fit_pi_weights(v_id, plant.run(v_id), r_id))
    y_ref = 0.8 * plant.run(np.array([0.0, 5.0, 0.0]))[1] * np.sin(2 * np.pi * t) * (1 - 0.25 * t)
    ratio, err_lin, err_ff = _compensation_ratio(plant, model, y_ref)
    print(f"identified model: uncompensated {err_lin:.3%}, compensated {err_ff:.3%}, ratio {ratio:.1f}")
    assert ratio >= 10.0


# --- modified PI ---------------------------------------------------------------------------


def test_modified_pi_dead_zones():
    r, w = [0.0, 0.5], [1.0, 0.5]
    pi = PrandtlIshlinskii(r, w)
    v = np.linspace(0.0, 2.0, 201)  # virgin ramp: x = v + 0.5 max(v - 0.5, 0)
    x = pi.run(v)
    y = ModifiedPI(r, w, [0.0, 1.0, -0.5], [1.0, 2.0, 3.0]).run(v)
    np.testing.assert_allclose(y, x + 2.0 * np.maximum(x - 1.0, 0.0), atol=1e-12)
    y_neg = ModifiedPI(r, w, [0.0, 1.0, -0.5], [1.0, 2.0, 3.0]).run(-v)
    x_neg = pi.run(-v)
    np.testing.assert_allclose(y_neg, x_neg + 3.0 * np.minimum(x_neg + 0.5, 0.0), atol=1e-12)
    # the d > 0 dead zone is silent until x passes d, then adds its slope
    below = x < 1.0
    np.testing.assert_allclose(y[below], x[below], atol=1e-12)
    assert np.all(np.diff(y)[~below[1:]] > np.diff(x)[~below[1:]])


@settings(max_examples=30, deadline=None)
@given(v=inputs, c=st.floats(0.1, 3.0))
def test_modified_pi_zero_dead_zones_reduce_to_pi(v, c):
    v = np.array(v)
    pi = PrandtlIshlinskii(R, W).run(v)
    np.testing.assert_allclose(ModifiedPI(R, W, [0.0], [1.0]).run(v), pi, atol=1e-12)
    np.testing.assert_allclose(ModifiedPI(R, W, [0.0, 0.0], [c, 1.0]).run(v), (c + 1) * pi, atol=1e-12)


def test_modified_pi_loop_is_not_point_symmetric():
    t = np.linspace(0.0, 3.0, 3001)  # three periods; compare the two halves of the last one
    v = np.sin(2 * np.pi * t)

    def asymmetry(op):
        y = op.run(v)
        return np.max(np.abs(y[2000:2500] + y[2500:3000])) / np.ptp(y[2000:])

    assert asymmetry(PrandtlIshlinskii(R, W)) < 1e-12  # PI loops are point-symmetric
    assert asymmetry(ModifiedPI(R, W, [0.0, 0.8], [1.0, 1.5])) > 0.05


# --- numba kernels ---------------------------------------------------------------------------


def python_reference(op):
    """The operator's output/commit loop in pure Python (run() uses the numba-compiled kernels)."""
    out, commit = type(op).output, type(op).commit

    def drive(v, mem, prm):
        y = np.empty(v.size)
        for k in range(v.size):
            y[k] = out(v[k], mem, prm)
            commit(v[k], mem, prm)
        return y

    return drive


@pytest.mark.parametrize("op", ALL_OPS, ids=ALL_IDS)
def test_numba_kernels_match_python(op):
    drive = python_reference(op)
    rng = np.random.default_rng(1)
    scale = 1.5
    v = scale * np.cumsum(rng.normal(0.0, 0.05, 2000))
    prm = op.parameter_values()
    y = drive(v, op.initial_memory(v[0], prm), prm)
    np.testing.assert_allclose(y, op.run(v), rtol=1e-13, atol=0)


# --- identification ----------------------------------------------------------------------------


def test_play_outputs_matrix():
    rng = np.random.default_rng(2)
    v = np.cumsum(rng.normal(0, 0.1, 500))
    r = threshold_grid(v, 7)
    assert r[0] == 0.0 and r[-1] < np.ptp(v) / 2 and r.size == 7
    a = play_outputs(v, r)
    assert a.shape == (500, 7)
    np.testing.assert_array_equal(a[:, 0], v)
    for i, ri in enumerate(r):
        np.testing.assert_allclose(a[:, i], PrandtlIshlinskii([ri], [1.0]).run(v), atol=1e-15)


def test_nnls_recovers_weights():
    t = np.linspace(0.0, 4.0, 4001)
    v = 2.0 * np.sin(2 * np.pi * 3 * t) * np.exp(-0.6 * t) + 0.5 * np.sin(2 * np.pi * 0.5 * t)
    r = threshold_grid(v, 12)
    w_true = np.array([1.2, 0.0, 0.5, 0.3, 0.0, 0.2, 0.7, 0.1, 0.0, 0.05, 0.3, 0.15])
    y = PrandtlIshlinskii(r, w_true).run(v)
    np.testing.assert_allclose(fit_pi_weights(v, y, r), w_true, rtol=0, atol=1e-6)
    w, c = fit_pi_weights(v, y - 0.75, r, offset=True)
    np.testing.assert_allclose(w, w_true, rtol=0, atol=1e-6)
    assert c == pytest.approx(-0.75, abs=1e-6)
    # units do not matter: dipole-sized input, field-sized output
    np.testing.assert_allclose(fit_pi_weights(v * 1e-7, y * 1e6, r * 1e-7) / 1e13, w_true, rtol=0, atol=1e-6)


# --- the device's history: where the plays start ----------------------------------------------


@settings(max_examples=30, deadline=None)
@given(v=inputs, prior=st.floats(-3.0, 3.0, **finite))
def test_prior_is_a_monotone_approach_from_it(v, prior):
    """With ``prior`` the plays start as if the input had come to v[0] from ``prior``: the run
    equals the run of the path prior → v[0] → ... from rest at ``prior``; play_outputs agrees;
    without a prior the convention is an approach from 0."""
    v = np.array(v)
    op = PrandtlIshlinskii(R, W, prior)
    assert op.parameter_names[-1] == "prior"
    ramp = np.linspace(prior, v[0], 50)
    from_prior = PrandtlIshlinskii(R, W, prior).run(np.r_[ramp, v[1:]])[len(ramp) - 1 :]
    np.testing.assert_allclose(op.run(v), from_prior, rtol=0, atol=1e-12)
    np.testing.assert_allclose(play_outputs(v, R, prior) @ np.array(W), op.run(v), rtol=0, atol=1e-12)
    np.testing.assert_allclose(PrandtlIshlinskii(R, W, 0.0).run(v), PrandtlIshlinskii(R, W).run(v), atol=1e-15)


def test_a_device_last_driven_to_its_maximum_starts_on_the_descending_branch():
    """From rest at 0 after the maximum 1, every play sits r above the input: the first
    rise moves nothing but the r = 0 play until the input climbs by 2r."""
    op = PrandtlIshlinskii(R, W, prior=1.0)
    v = np.linspace(0.0, 0.2, 11)
    expected = W[0] * v + sum(w * min(r, 1.0) for r, w in zip(R[1:], W[1:]))
    np.testing.assert_allclose(op.run(v)[:3], expected[:3], atol=1e-12)
    assert repr(op) == "PrandtlIshlinskii([0.0, 0.1, 0.25, 0.4, 0.6], [1.0, 0.5, 0.3, 0.2, 0.4], [1.0])"
