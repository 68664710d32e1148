"""Analytic solutions: driven mass-spring-damper, RC circuit, energy balance."""

import numpy as np
import pytest
import sympy as sp

import bondgraph as bg


def msd(m=1.0, k=100.0, c=2.0):
    g = bg.Model("msd")
    F = g.input("F", "N")
    ms, ks, cs = g.parameter("m", m), g.parameter("k", k), g.parameter("c", c)
    g.add(bg.Se("force", F), bg.J1("v"), bg.I("mass", ms), bg.C("spring", 1 / ks), bg.R("damper", cs))
    for e in ("force", "mass", "spring", "damper"):
        g.bond(e, "v") if e == "force" else g.bond("v", e)
    g.output("x", g.displacement("spring"), "m")
    g.output("v", g.flow("mass"), "m/s")
    return g


def test_mass_spring_damper_step_matches_analytic():
    m, k, c, F0 = 0.5, 200.0, 3.0, 2.5
    res = bg.simulate(msd(m, k, c), np.linspace(0, 3, 3001), {"F": bg.Step(F0)}, rtol=1e-10)
    wn = np.sqrt(k / m)
    z = c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - z * z)
    t = res.t
    xa = F0 / k * (1 - np.exp(-z * wn * t) * (np.cos(wd * t) + z / np.sqrt(1 - z * z) * np.sin(wd * t)))
    assert np.max(np.abs(res["x"] - xa)) / np.max(np.abs(xa)) < 1e-6
    va = np.gradient(xa, t)
    assert np.max(np.abs(res["v"] - va)[5:-5]) / np.max(np.abs(va)) < 1e-4


def test_a_number_as_an_input_is_a_constant_and_anything_else_is_refused():
    """F = 2.5 given as a number is the step of 2.5 from t = 0 (the static deflection F/k after
    the transient); a list is refused with a SignalError that names the input."""
    t = np.linspace(0, 10, 1001)
    as_number = bg.simulate(msd(), t, {"F": 2.5})
    as_signal = bg.simulate(msd(), t, {"F": bg.Constant(2.5)})
    assert np.array_equal(as_number["x"], as_signal["x"])
    assert as_number["x"][-1] == pytest.approx(2.5 / 100.0, rel=1e-3)
    with pytest.raises(bg.SignalError, match="input 'F'"):
        bg.simulate(msd(), t, {"F": [1.0, 2.0]})


def test_rc_circuit_step_and_sine():
    g = bg.Model("rc")
    V = g.input("V", "V")
    Rs, Cs = g.parameter("R", 1e3), g.parameter("Cap", 1e-6)
    g.add(bg.Se("src", V), bg.J1("loop"), bg.R("R", Rs), bg.C("C", Cs))
    g.chain("src", "loop", "R")
    g.bond("loop", "C")
    g.output("vc", g.effort("C"), "V")
    g.output("i", g.flow("C"), "A")
    tau = 1e-3
    t = np.linspace(0, 5e-3, 2001)
    res = bg.simulate(g, t, {"V": bg.Step(10.0, t0=1e-3)}, rtol=1e-10)
    va = np.where(t >= 1e-3, 10 * (1 - np.exp(-(t - 1e-3) / tau)), 0.0)
    assert np.max(np.abs(res["vc"] - va)) / 10 < 1e-6
    # sine steady state amplitude |1/(1 + j w tau)|
    f = 500.0
    t = np.linspace(0, 20e-3, 4001)
    res = bg.simulate(g, t, {"V": bg.Sine(1.0, f)}, rtol=1e-10)
    w = 2 * np.pi * f
    H = 1 / (1 + 1j * w * tau)
    va = np.abs(H) * np.sin(w * t + np.angle(H)) + np.exp(-t / tau) * np.abs(H) * np.sin(-np.angle(H))
    assert np.max(np.abs(res["vc"] - va)) < 1e-6


@pytest.mark.parametrize("method", ["dopri5", "radau"])
def test_sampled_pulse_reaches_a_model_at_rest(method):
    """A 2 ms pulse in a 10 kHz table, 1 s into the record: at rest the error estimate is zero
    and the step would grow past the pulse; the step cap (10 table intervals) keeps it in view.
    RC with tau = 0.1 ms: the pulse charges C to 1 - exp(-20) and it decays after."""
    g = bg.Model("rc")
    V = g.input("V", "V")
    g.add(bg.Se("src", V), bg.J1("loop"), bg.R("R", 1e2), bg.C("C", 1e-6))
    g.chain("src", "loop", "R")
    g.bond("loop", "C")
    g.output("vc", g.effort("C"), "V")
    t = np.linspace(0, 2, 20001)
    v = np.where((t > 1.0) & (t < 1.002), 1.0, 0.0)
    res = bg.simulate(g, t, {"V": bg.PiecewiseLinear(t, v)}, method=method, rtol=1e-6)
    assert res["vc"].max() == pytest.approx(1.0, abs=1e-3)
    assert abs(res["vc"][-1]) < 1e-6


@pytest.mark.parametrize("method", ["radau", "bdf", "lsoda"])
def test_a_stiff_run_stops_at_its_deadline(method):
    """A deadline already passed stops the stiff solvers at their first step with a
    SimulationTimeout (a SimulationError); one in the future changes nothing."""
    import time

    from bondgraph.numerics.simulate import SimulationError, SimulationTimeout

    t = np.linspace(0, 3, 3001)
    free = bg.simulate(msd(), t, {"F": bg.Step(1.0)}, method=method)
    with pytest.raises(SimulationTimeout, match="deadline") as err:
        bg.simulate(msd(), t, {"F": bg.Step(1.0)}, method=method, deadline=time.monotonic() - 1.0)
    assert isinstance(err.value, SimulationError)
    timed = bg.simulate(msd(), t, {"F": bg.Step(1.0)}, method=method, deadline=time.monotonic() + 600.0)
    assert np.array_equal(timed["x"], free["x"])


def test_energy_balance_of_driven_msd():
    """Work done by the source = stored energy + dissipated energy (to integration accuracy)."""
    g = msd()
    eqs = bg.derive(g)
    res = bg.simulate(eqs, np.linspace(0, 2, 20001), {"F": bg.Sine(1.0, 1.3)}, rtol=1e-10)
    p, q = res.states["p_mass"], res.states["q_spring"]
    v = res["v"]
    H = p**2 / 2 + 100.0 * q**2 / 2
    work = np.concatenate([[0], np.cumsum(0.5 * (res["F"][1:] * v[1:] + res["F"][:-1] * v[:-1]) * np.diff(res.t))])
    diss = np.concatenate([[0], np.cumsum(0.5 * (2.0 * v[1:] ** 2 + 2.0 * v[:-1] ** 2) * np.diff(res.t))])
    assert np.max(np.abs(work - diss - H)) < 1e-6 * np.max(H)


def test_state_equations_symbolic_form():
    eqs = bg.derive(msd())
    m, k, c, F = sp.symbols("m k c F", real=True)
    p, q = sp.symbols("p_mass q_spring", real=True)
    se = eqs.state_equations()
    assert sp.simplify(se[p] - (F - c * p / m - k * q)) == 0
    assert sp.simplify(se[q] - p / m) == 0
