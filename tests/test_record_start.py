"""Runs against a record start at the steady state at the record's first drive value.

A mass-spring-damper (k = 400 N/m, c = 4 N·s/m, m = 1 kg: a 3.2 Hz mode, ζ = 0.1) is driven by
a force that starts at F0 = 2 N.  The record is the model's own response from its steady
state at F0 (spring at F0/k = 5 mm, mass at rest), integrated at rtol 1e-10.  With setting
``record.start = "rest"`` the model starts at x = 0 and rings for seconds (a start-up
transient of F0/k); with ``"steady"`` (the default) it must reproduce the record to the
integration tolerance, on the exact linear route, on the integrator, in the diagnosis and in
``simulate`` driven by the record's csv column alike.  A hardening spring checks the nonlinear root solve against the analytic equilibrium;
a drive starting at zero must leave everything exactly as it was.
"""

import numpy as np
import pytest
import scipy.optimize

import bondgraph as bg
from bondgraph import config
from bondgraph.data import Dataset
from bondgraph.diagnosis import diagnose
from bondgraph.fit.compensate import feedforward
from bondgraph.fit.identify import Identification
from bondgraph.linear.lti import LTI
from bondgraph.numerics.steady import record_start, steady_state
from bondgraph.support.errors import UsageError

K, C_D, F0 = 400.0, 4.0, 2.0


def msd(hardening: float = 0.0):
    g = bg.Model("msd")
    F = g.input("F", "N")
    k = g.parameter("k", K, "N/m")
    c = g.parameter("c", C_D, "N*s/m")
    law = (lambda q: k * q + hardening * q**3) if hardening else None
    spring = bg.C("spring", law=law) if hardening else bg.C("spring", 1 / k)
    g.add(bg.Se("f", F), bg.J1("v"), bg.I("m", 1.0), spring, bg.R("damper", c))
    g.bond("f", "v")
    for e in ("m", "spring", "damper"):
        g.bond("v", e)
    g.output("x", "spring.q", "m")
    return g


def drive(t, f0=F0):
    return f0 + 0.5 * np.sin(2 * np.pi * 0.7 * t) + 0.3 * np.sin(2 * np.pi * 1.9 * t)


def steady_record(f0=F0, n=800, fs=200.0):
    t = np.arange(n) / fs
    F = drive(t, f0)
    sim = bg.Simulator(msd())
    x0 = np.array([f0 / K if s == "q_spring" else 0.0 for s in sim.state_names])
    x = sim.run(t, {"F": bg.PiecewiseLinear(t, F)}, x0=x0, rtol=1e-10, atol=1e-16)["x"]
    return Dataset(t, {"F": F, "x": x})


def test_steady_state_of_a_linear_and_a_hardening_spring():
    sim = bg.Simulator(msd())
    x = steady_state(sim, sim.theta(), {"F": F0})
    assert dict(zip(sim.state_names, x)) == pytest.approx({"q_spring": F0 / K, "p_m": 0.0}, abs=1e-15)
    eps = 4e7  # N/m³: at 5 mm the cubic adds 1.25 times the linear force
    hard = bg.Simulator(msd(hardening=eps))
    q = scipy.optimize.brentq(lambda q: K * q + eps * q**3 - F0, 0, F0 / K)
    xh = dict(zip(hard.state_names, steady_state(hard, hard.theta(), {"F": F0})))
    assert xh["q_spring"] == pytest.approx(q, rel=1e-9) and abs(xh["p_m"]) < 1e-12
    with config.override({"record.start": "rest"}):
        assert not np.any(record_start(sim, sim.theta(), {"F": F0}))
    with config.override({"record.start": "sideways"}), pytest.raises(UsageError, match="record.start"):
        record_start(sim, sim.theta(), {"F": F0})


@pytest.mark.parametrize("route", ["exact linear", "integrator"])
def test_fit_reproduces_a_record_that_starts_at_a_steady_state(route):
    data = steady_record()
    span = np.ptp(data.column("x"))
    rms = {}
    for start in ("rest", "steady"):
        with config.override({"record.start": start}):
            ident = Identification(msd(), data, rtol=1e-10)
            if route == "integrator":
                ident.lti = None
            else:
                assert ident.lti is not None
            res = ident.evaluate()
            rms[start] = max(res.rms_fit, res.rms_validation)
    assert rms["rest"] > 0.02 * span  # the start-up transient: F0/k rings down for seconds
    assert rms["steady"] < 1e-6 * span  # the record, to the integration tolerance


def test_fit_recovers_the_stiffness_from_a_steady_start():
    data = steady_record()
    ident = Identification(msd(), data)
    specs = ident.specs(["k", "c"])
    specs[0].start, specs[1].start = 1.3 * K, 0.7 * C_D
    res = ident.fit(specs)
    assert res.values["k"] == pytest.approx(K, rel=1e-5) and res.values["c"] == pytest.approx(C_D, rel=1e-4)


def test_sensitivities_start_where_the_prediction_starts():
    data = steady_record()
    ident = Identification(msd(), data)
    Y, dY = ident.sensitivities({"k": 380.0}, ["k"])
    assert Y[:, 0] == pytest.approx(ident.predict({"k": 380.0}), abs=1e-9 * F0 / K)
    h = 1e-3
    fd = (ident.predict({"k": 380.0 + h}) - ident.predict({"k": 380.0 - h})) / (2 * h)
    assert dY[0, :, 0] == pytest.approx(fd, rel=1e-5, abs=1e-7 * np.max(np.abs(fd)))


def test_a_drive_from_zero_gives_exactly_the_results_from_rest():
    data = steady_record(f0=0.0)
    assert data.column("F")[0] == 0.0
    preds = {}
    for start in ("rest", "steady"):
        with config.override({"record.start": start}):
            ident = Identification(msd(), data)
            lin = ident.predict()
            ident.lti = None
            preds[start] = (lin, ident.predict())
    assert np.array_equal(preds["rest"][0], preds["steady"][0])
    assert np.array_equal(preds["rest"][1], preds["steady"][1])


def test_exact_linear_route_and_integrator_agree_from_a_steady_start():
    data = steady_record()
    ss = LTI(bg.derive(msd()), "F", "x").state_space(bg.Simulator(msd()).theta())
    y = ss.response(data.t[1] - data.t[0], data.column("F"), steady=True)[:, 0]
    assert y == pytest.approx(data.column("x"), abs=1e-7 * F0 / K)  # the integrator's tolerance


def test_compensation_follows_a_reference_that_starts_away_from_zero():
    t = np.arange(600) / 200.0
    ref = F0 / K + 1e-3 * (1 - np.cos(2 * np.pi * 0.5 * t))  # from 5 mm at rest, slow against the mode
    err = {}
    for start in ("rest", "steady"):
        with config.override({"record.start": start}):
            comp = feedforward(msd(), t, ref, input="F", output="x", iterations=8)
            err[start] = np.abs(comp.predicted - ref)
    assert err["rest"][0] == pytest.approx(F0 / K)  # from rest the output starts 5 mm off
    assert np.max(err["steady"]) < 0.05 * np.ptp(ref)  # what 8 iterations on the static gain leave


def test_diagnosis_calibration_sees_no_transient():
    data = steady_record()
    noise = np.random.default_rng(0).normal(0, 1e-3 * np.std(data.column("x")), data.t.size)
    noisy = Dataset(data.t, {"F": data.column("F"), "x": data.column("x") + noise})
    rms = {}
    for start in ("rest", "steady"):
        with config.override({"record.start": start}):
            rep = diagnose(msd(), noisy, candidates=[], workers=1, chain=False, equations=False)
            rms[start] = rep.baseline_rms
    assert rms["steady"] < 2e-3 * np.std(data.column("x"))  # the noise, nothing more
    assert rms["rest"] > 10 * rms["steady"]


MODEL_FILE = """
from bondgraph import C, I, J1, Model, Parameter, R, Se

PARAMETERS = [Parameter("k", 400.0, "N/m", "stiffness"), Parameter("c", 4.0, "N*s/m", "damping")]


def build(p):
    g = Model("msd")
    F = g.input("F", "N")
    g.add(Se("f", F), J1("v"), I("m", 1.0), C("spring", 1 / p.k), R("damper", p.c))
    g.bond("f", "v")
    for e in ("m", "spring", "damper"):
        g.bond("v", e)
    g.output("x", "spring.q", "m")
    return g
"""


def test_simulate_driven_by_a_record_starts_where_fit_does(tmp_path):
    from bondgraph.cli import main
    from bondgraph.data import read_csv, write_csv

    data = steady_record()
    (tmp_path / "msd.py").write_text(MODEL_FILE)
    write_csv(tmp_path / "rec.csv", data.t, {"F": data.column("F"), "x": data.column("x")})
    args = ["simulate", str(tmp_path / "msd.py"), "--input", f"F=csv(file={tmp_path / 'rec.csv'}, column=F)"]
    assert main([*args, "--rtol", "1e-9", "--out", str(tmp_path / "sim.csv"), "--quiet"]) == 0
    x = read_csv(tmp_path / "sim.csv").column("x")
    assert x == pytest.approx(data.column("x"), abs=1e-6 * F0 / K)  # no start-up transient


def test_a_declared_start_is_kept_and_both_routes_agree_on_it():
    g = msd()
    g.add(bg.J1("cell"), bg.C("cell.C", 1.0, q0=0.5), bg.R("cell.R", 0.2))  # a lag that starts at 0.5
    g.bond("cell", "cell.C")
    g.bond("cell", "cell.R")
    g.output("lag", "cell.C.q", "C")
    sim = bg.Simulator(g)
    x = dict(zip(sim.state_names, steady_state(sim, sim.theta(), {"F": F0})))
    assert x["q_cell.C"] == 0.5 and x["q_spring"] == pytest.approx(F0 / K, rel=1e-12)
    data = steady_record()
    for output, truth in (("x", data.column("x")), ("lag", 0.5 * np.exp(-data.t / 0.2))):
        ident = Identification(g, data, output=output, data_output="x", rtol=1e-10)
        assert ident.predict() == pytest.approx(truth, abs=1e-7 * np.max(np.abs(truth)))  # exact route
        ident.lti = None
        assert ident.predict() == pytest.approx(truth, abs=1e-7 * np.max(np.abs(truth)))  # integrator


def test_lure_route_starts_at_the_nonlinear_equilibrium():
    """The diagnosis' Lur'e stepping (a softening term on the spring) against the rewritten
    bond graph integrated from its steady state (the root solve), on a drive that starts at
    half its amplitude; as tests/test_lure.py, but not from rest."""
    from test_lure import resonator, softening

    from bondgraph.diagnosis.lure import Lure
    from bondgraph.diagnosis.rewrite import modify_law

    t = np.arange(2000) / 2000.0
    u = 0.5 + np.sin(2 * np.pi * (10 * t + 15 * t**2))
    lure = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0])
    q = lure.linear_responses({}, u, softening)["diag.x:k"]
    coef, r2 = 0.3 * (2 * np.pi * 40.0) ** 2 / float(np.max(np.abs(q))) ** 2, 0.5 * float(np.mean(q**2))
    y = lure.simulate({}, u, softening, [(coef, r2)])
    rewritten = resonator()
    modify_law(rewritten, "k", lambda x, old: old + softening(coef, r2, x, None))
    sim = bg.Simulator(rewritten)
    drive = {"F": bg.PiecewiseLinear(t, u)}
    x0 = steady_state(sim, sim.theta(), drive)
    ref = sim.run(t, drive, x0=x0, rtol=1e-10, atol=1e-14)["x"]
    rest = sim.run(t, drive, rtol=1e-10, atol=1e-14)["x"]
    early = slice(0, 200)  # the first 0.1 s: the transient from rest, the resonance not yet reached
    assert np.max(np.abs(rest - ref)[early]) > 0.5 * abs(ref[0])  # the start matters
    assert np.max(np.abs(y - ref)[early]) < 1e-3 * abs(ref[0])  # both routes start at one equilibrium
    assert np.std(y - ref) < 5e-3 * np.std(ref)  # and agree through the resonance
