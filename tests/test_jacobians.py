"""Analytic Jacobians against finite differences, and the recursion's subnormal guard.

Truths: central finite differences (relative step 1e-6) of the exact first-order-hold
response (:meth:`StateSpace.response`) and of the frequency response, on three models: a
three-state one with a lightly damped pair and a real mode, the same with its fast modes
residualised, and the APA-120ML model file at its values (eight parameters, three states);
the variable projection's Jacobian against finite differences of its residual, with a bound
active and a column that the rows cannot tell apart; the Jacobians the diagnosis' fitting
services hand to the optimiser (``View.fit_drive`` with a basis and direct columns of their
own parameters, ``View.fit_model`` on an extended linear model) against finite differences
of their columns.  The guard: a response that decays for 40 000 samples after its drive stops
equals, within 1e-140 of its peak, the plain recursion written here in numpy, which ends in
subnormal numbers where the guarded one ends at exactly zero.
"""

import math
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from test_diagnosis_friction import resonator
from test_parallel_fits import decaying_sine

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis import View
from bondgraph.diagnosis import view as view_module
from bondgraph.diagnosis.calibration import calibrate
from bondgraph.diagnosis.context import Context
from bondgraph.diagnosis.projection import projected_fit, projection_jacobian
from bondgraph.fit.identify import Identification, Spec, bounded_lstsq_free
from bondgraph.linear.lti import LTI, StateSpace, foh, residualise
from bondgraph.linear.sensitivity import modal_sensitivity, sensitivity
from bondgraph.model.modelfile import load_model

ROOT = Path(__file__).resolve().parents[1]


def three_states(th):
    """A lightly damped pair (ω = th[0], ζ = th[1]) fed through a first-order stage (pole
    th[2]); output the pair's displacement plus th[3] of the stage."""
    w, z, p, g = th
    A = np.array([[0.0, 1.0, 0.0], [-(w**2), -2 * z * w, w**2], [0.0, 0.0, -p]])
    return A, np.array([[0.0], [0.0], [p]]), np.array([[1.0, 0.0, g]]), np.array([[0.05]])


def derivative_matrices(f, th, h=1e-7):
    """∂(A, B, C, D)/∂θ of ``f`` (affine or smooth in θ) by central differences, stacked."""
    out = [[], [], [], []]
    for i in range(len(th)):
        up, dn = np.array(th, float), np.array(th, float)
        up[i] += h * abs(th[i])
        dn[i] -= h * abs(th[i])
        for k, (a, b) in enumerate(zip(f(up), f(dn))):
            out[k].append((a - b) / (up[i] - dn[i]))
    return [np.array(o) for o in out]


def central(fn, th, i, rel=1e-6):
    up, dn = np.array(th, float), np.array(th, float)
    up[i] *= 1 + rel
    dn[i] *= 1 - rel
    return (fn(up) - fn(dn)) / (up[i] - dn[i])


def drive(n=6000, seed=4):
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    return np.column_stack([np.cumsum(rng.normal(size=n)) * 0.05, np.sin(0.013 * t) * (t < n // 3)])


@pytest.mark.parametrize("cut", [None, 300.0])
def test_modal_sensitivities_are_the_derivatives_of_the_exact_response(cut):
    th = np.array([2 * math.pi * 40.0, 0.03, 900.0, 0.4])
    dt, U = 5e-4, drive()
    rows = np.arange(7, U.shape[0], 3)
    modal = modal_sensitivity(*three_states(th), *derivative_matrices(three_states, th), cut)
    Y, dY = modal.time(dt, U, rows)

    def state_space(t):
        A, B, C, D = three_states(t)
        return residualise(A, B, C, D, cut) if cut is not None else StateSpace(A, B, C, D)

    def response(t):
        return state_space(t).response(dt, U, rows=rows)

    assert state_space(th).fast == (1 if cut is not None else 0)  # the first-order stage is residualised
    np.testing.assert_allclose(Y, response(th), rtol=0, atol=1e-10 * np.abs(Y).max())
    for i in range(th.size):
        fd = central(response, th, i)
        np.testing.assert_allclose(dY[i], fd, rtol=0, atol=2e-6 * np.abs(fd).max())
    w = np.geomspace(1.0, 2e4, 40)
    H, dH = modal.frequency(w)

    def frf(t):
        return state_space(t).frequency_response(w)

    np.testing.assert_allclose(H, frf(th), rtol=1e-10)
    for i in range(th.size):
        np.testing.assert_allclose(dH[i], central(frf, th, i), rtol=1e-5, atol=1e-9 * np.abs(dH[i]).max())


def test_the_apa_models_sensitivities_through_its_symbolic_derivatives():
    model = load_model(ROOT / "models" / "apa120ml.py").model
    eqs = bg.derive(model)
    lti = LTI(eqs)
    th = bg.Simulator(eqs).theta()
    names = lti.parameters
    dt, U = 1e-4, drive(4000) * 50.0
    Y, dY = sensitivity(lti, th, names).time(dt, U)
    index = {p.name: i for i, p in enumerate(eqs.params)}
    np.testing.assert_allclose(Y, lti.state_space(th).response(dt, U), rtol=0, atol=1e-11 * np.abs(Y).max())
    for k, n in enumerate(names):
        fd = central(lambda t: lti.state_space(t).response(dt, U), th, index[n])
        np.testing.assert_allclose(dY[k], fd, rtol=0, atol=1e-5 * np.abs(fd).max() + 1e-30)
    with pytest.raises(bg.ParameterError, match="no_such"):
        lti.derivatives(th, ["no_such"])


def spring_mass(compliance):
    """A mass on a spring (compliance ``compliance(kk)``) and a damper, force in, x out."""
    g = bg.Model("spring_mass")
    F = g.input("F", "N")
    kk, cc = g.parameter("kk", 1e-4, "m/N"), g.parameter("cc", 2.0, "N*s/m")
    g.add(bg.Se("src", F), bg.J1("v"), bg.I("m", 1.0), bg.C("k", compliance(kk)), bg.R("c", cc))
    g.chain("src", "v", "m")
    g.bond("v", "k")
    g.bond("v", "c")
    g.output("x", "k.q", "m")
    return g


def test_the_complex_step_and_the_symbolic_derivatives_agree():
    """Matrices analytic in θ take the complex step; an |·| (not analytic) the symbolic route."""
    out = []
    for compliance, analytic in ((lambda k: k, True), (lambda k: sp.Abs(k), False)):
        eqs = bg.derive(spring_mass(compliance))
        lti = LTI(eqs)
        out.append(lti.derivatives(bg.Simulator(eqs).theta(), ["kk", "cc"]))
        assert lti._analytic is analytic
    for a, b in zip(*out):
        np.testing.assert_allclose(a, b, rtol=1e-14)
    np.testing.assert_allclose(out[0][0][0], [[0.0, 1e8], [0.0, 0.0]], rtol=1e-14)  # ∂(1/kk)/∂kk = −1/kk²


def test_a_near_defective_model_has_no_modal_sensitivities():
    a = 30.0
    A = np.array([[-a, 1.0], [0.0, -a]])  # a Jordan block
    B, C, D = np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]]), np.zeros((1, 1))
    z = np.zeros((1, 2, 2))
    assert modal_sensitivity(A, B, C, D, z, np.zeros((1, 2, 1)), np.zeros((1, 1, 2)), np.zeros((1, 1, 1))) is None


def test_identification_sensitivities_from_rest_only():
    t = np.arange(3000) / 2000.0
    u = np.sin(2 * np.pi * (5 * t + 30 * t**2))
    ident = Identification(resonator(), Dataset(t, {"F": u, "x": np.zeros_like(u)}))
    values = {"kk": 1.7e-5, "cc": 4.0}
    rows = ident.fit_idx
    Y, dY = ident.sensitivities(values, ["kk", "cc"], rows=rows)
    np.testing.assert_allclose(Y[:, 0], ident.predict(values)[rows], rtol=0, atol=1e-10 * np.abs(Y).max())
    for k, n in enumerate(["kk", "cc"]):
        h = 1e-6 * values[n]
        fd = (ident.predict({**values, n: values[n] + h}) - ident.predict({**values, n: values[n] - h}))[rows] / (2 * h)
        np.testing.assert_allclose(dY[k][:, 0], fd, rtol=0, atol=1e-5 * np.abs(fd).max())


def test_the_projection_jacobian_is_the_derivative_of_the_projected_residual():
    t = np.linspace(0.0, 2.0, 3000)
    y = 0.7 * np.exp(-1.3 * t) * np.sin(2 * math.pi * 3.1 * t) + 0.05 + 0.2 * t
    idx = np.arange(0, t.size, 2)

    def columns(z):
        a, f = math.exp(z[0]), math.exp(z[1])
        tt = t[idx]
        # the last column repeats the second: the rows cannot tell them apart
        return np.column_stack([np.exp(-a * tt) * np.sin(2 * math.pi * f * tt), np.ones(tt.size), tt, np.ones(tt.size)])

    def derivatives(z):
        h = 1e-7
        return np.stack([(columns(z + h * e) - columns(z - h * e)) / (2 * h) for e in np.eye(2)])

    for lo, hi in (
        ([-np.inf] * 4, [np.inf] * 4),
        ([-np.inf, -np.inf, 0.0, -np.inf], [np.inf, 0.0, np.inf, np.inf]),  # the offset on its bound
        ([0.8, -1, -1, -1], [0.9, 1, 1, 1]),  # the amplitude on its bound
    ):

        def resid(z):
            A = columns(z)
            return A @ bounded_lstsq_free(A, y[idx], lo, hi)[0] - y[idx]

        z = np.array([0.1, math.log(3.0)])
        A = columns(z)
        c, free = bounded_lstsq_free(A, y[idx], lo, hi)
        J = projection_jacobian(A, c, free, A @ c - y[idx], derivatives(z))
        fd = np.column_stack([(resid(z + 1e-6 * e) - resid(z - 1e-6 * e)) / 2e-6 for e in np.eye(2)])
        np.testing.assert_allclose(J, fd, rtol=0, atol=1e-6 * np.abs(fd).max())


def test_a_fit_with_the_analytic_jacobian_is_the_finite_difference_fit():
    t, y, idx, columns = decaying_sine()

    def derivatives(z, rows):
        a, f = math.exp(z[0]), math.exp(z[1])
        tt = t[rows]
        e, s, c = np.exp(-a * tt), np.sin(2 * math.pi * f * tt), np.cos(2 * math.pi * f * tt)
        zero = np.zeros(tt.size)
        return np.stack(
            [np.column_stack([-a * tt * e * s, zero]), np.column_stack([2 * math.pi * f * tt * e * c, zero])]
        )

    fits = [
        projected_fit(
            columns, y, idx, [0.0, math.log(2.5)], [-3, 0], [3, 2], [-np.inf] * 2, [np.inf] * 2, derivatives=d
        )
        for d in (None, derivatives)
    ]
    np.testing.assert_allclose(fits[1].z, fits[0].z, atol=1e-5)
    assert fits[1].cost == pytest.approx(fits[0].cost, rel=1e-8)
    assert math.exp(fits[1].z[0]) == pytest.approx(1.3, rel=0.02)
    # derivatives that are not available anywhere: forward differences, the same fit
    none = projected_fit(
        columns,
        y,
        idx,
        [0.0, math.log(2.5)],
        [-3, 0],
        [3, 2],
        [-np.inf] * 2,
        [np.inf] * 2,
        derivatives=lambda z, r: None,
    )
    np.testing.assert_allclose(none.z, fits[0].z, atol=1e-5)


@pytest.fixture(scope="module")
def resonator_view():
    t = np.arange(4000) / 2000.0
    u = np.sin(2 * np.pi * (5 * t + 20 * t**2))
    y = bg.simulate(resonator(), t, {"F": bg.PiecewiseLinear(t, u)}, rtol=1e-9)["x"]
    ctx = Context(resonator(), Dataset(t, {"F": u, "x": y * (1 + 0.02 * np.tanh(30 * u))}))
    state, cal, _ = calibrate(ctx)
    return View(ctx, state, cal.free)


def captured(monkeypatch, call):
    """The (columns, derivatives, z0) a fitting service hands to projected_fit."""
    seen = {}

    def fake(columns, y, idx, z0, *args, derivatives=None, **kw):
        seen.update(columns=columns, derivatives=derivatives, z0=np.asarray(z0, float), idx=idx)
        return projected_fit(columns, y, idx, z0, *args, max_nfev=1, derivatives=derivatives)

    monkeypatch.setattr(view_module, "projected_fit", fake)
    call()
    return seen


def assert_columns_derivatives(seen, own=0, zero=()):
    """The derivatives agree with central differences of the columns: within 1e-5 for the
    linear parameters (output sensitivities), within 1e-3 for the first ``own`` (forward
    differences of the basis, step 1e-4); those of the parameters ``zero`` vanish."""
    columns, derivatives, z = seen["columns"], seen["derivatives"], seen["z0"] + 0.01
    rows = seen["idx"][::5]
    dA = derivatives(z, rows)
    assert dA is not None and dA.shape[0] == z.size
    for i in range(z.size):
        h = 1e-6
        e = np.zeros(z.size)
        e[i] = h
        fd = (columns(z + e, rows) - columns(z - e, rows)) / (2 * h)
        if i in zero:
            assert not np.any(fd) and not np.any(dA[i])
            continue
        assert np.abs(fd).max() > 0
        np.testing.assert_allclose(dA[i], fd, rtol=0, atol=(1e-3 if i < own else 1e-5) * np.abs(fd).max())


def test_fit_drive_hands_the_optimiser_the_derivatives_of_its_columns(resonator_view, monkeypatch):
    view = resonator_view
    d = np.asarray(view.current.drive)

    def lowpass(zb):  # the drive through a first-order lag of time constant exp(zb[0]) s
        tau = math.exp(zb[0])
        Phi, Gam, G1 = foh(np.array([[-1 / tau]]), np.array([[1 / tau]]), view.record.dt)
        x = StateSpace(np.array([[-1 / tau]]), np.array([[1 / tau]]), np.eye(1), np.zeros((1, 1)))
        return [x.response(view.record.dt, d)[:, 0]]

    def direct(zb):
        return [np.tanh(math.exp(zb[0]) * 30 * d)]

    seen = captured(
        monkeypatch,
        lambda: view.fit_drive(
            lowpass, [-np.inf], [np.inf], direct=direct, z0=[math.log(0.01)], z_bounds=[(math.log(1e-3), 0.0)]
        ),
    )
    assert seen["z0"].size == 1 + len(view.current.calibrated)
    assert_columns_derivatives(seen, own=1)


def test_fit_model_hands_the_optimiser_the_derivatives_of_its_columns(resonator_view, monkeypatch):
    """A second damper in parallel (a new parameter) and a spec of a calibrated parameter,
    which the refitted linear parameters override: its column is zero."""
    view = resonator_view
    model = view.rewrite()
    model.add(bg.R("c2", model.parameter("cc2", 0.5, "N*s/m")))
    model.bond("v", "c2")
    specs = [
        Spec("cc2", 0.5, 0.05, 5.0, log=True),
        Spec("cc", view.current.values["cc"], view.current.values["cc"] / 3, view.current.values["cc"] * 3, log=True),
    ]
    seen = captured(monkeypatch, lambda: view.fit_model(model, specs, refit=True))
    assert seen["derivatives"] is not None and seen["z0"].size == 2 + len(view.current.calibrated)
    assert_columns_derivatives(seen, zero=[1])


def plain_recursion(Phi, Gam, C, D, u):
    """x[k+1] = Φx[k] + Γu[k], y = Cx + Du, from rest, without the guard: the compiled loop's
    arithmetic in its order, in Python floats."""
    n = Phi.shape[0]
    Phi, Gam, C, d = Phi.tolist(), Gam[:, 0].tolist(), C[0].tolist(), float(D[0, 0])
    x = [0.0] * n
    y = np.empty(u.size)
    for k, uk in enumerate(u.tolist()):
        acc = d * uk
        for i in range(n):
            acc += C[i] * x[i]
        y[k] = acc
        xn = []
        for i in range(n):
            s = Gam[i] * uk
            for j in range(n):
                s += Phi[i][j] * x[j]
            xn.append(s)
        x = xn
    return y, np.array(x)


def test_the_subnormal_guard_changes_the_response_by_less_than_1e_140_of_its_scale():
    A = np.array([[0.0, 1.0], [-4e4, -60.0]])  # 32 Hz, decays by e^-30 a second
    B, C, D = np.array([[0.0], [4e4]]), np.array([[1.0, 0.0]]), np.zeros((1, 1))
    dt, n = 1e-3, 40_000
    u = np.zeros(n)
    u[:300] = np.sin(np.arange(300) * 0.2)
    ss = StateSpace(A, B, C, D)
    guarded = ss.response(dt, u)[:, 0]
    Phi, Gam, G1 = foh(A, B, dt)
    plain, x_end = plain_recursion(Phi, Gam, C, D + C @ G1, u)
    assert 0 < np.max(np.abs(x_end)) < np.finfo(float).tiny  # the plain recursion ends in subnormals
    assert np.all(guarded[-1000:] == 0.0)  # the guarded one at zero
    assert np.max(np.abs(guarded - plain)) <= 1e-140 * np.max(np.abs(plain))
    np.testing.assert_array_equal(guarded[:5000], plain[:5000])  # before the floor: the same arithmetic
    two = ss.response(dt, np.column_stack([u, 0.5 * u]))  # the many-column loop guards alike
    np.testing.assert_array_equal(two[:, 0], guarded)
    np.testing.assert_array_equal(two[:, 1], ss.response(dt, 0.5 * u)[:, 0])
