"""Elements with memory: the integrator commits operator memory on accepted steps only, so the
result does not depend on its step pattern (rejections, reversals) beyond the tolerance."""

import numpy as np
import pytest

import bondgraph as bg
from library.hysteresis import PrandtlIshlinskii

PI = PrandtlIshlinskii([0.0, 0.2, 0.5, 0.9], [1.0, 0.6, 0.4, 0.3])


def lag_after_operator():
    """τ·ẋ = H[V] − x: the operator acts on the input."""
    g = bg.Model("lag")
    V = g.input("V")
    h = g.operator("H", PI, V)
    g.add(bg.Se("s", h), bg.J1("j"), bg.R("r", 0.05), bg.C("c", 1.0))
    g.chain("s", "j", "r")
    g.bond("j", "c")
    g.output("x", g.displacement("c"))
    return g


def hysteretic_spring():
    """A mass on a spring whose force is k·q + H[q]: the operator acts on a state."""
    g = bg.Model("spring")
    F = g.input("F")
    h = g.operator("H", PI, bg.Quantity("q", "k"))
    g.add(bg.Se("f", F), bg.J1("v"), bg.I("m", 0.01), bg.R("c", 0.3), bg.C("k", law=lambda q: 2.0 * q + h))
    g.bond("f", "v")
    for e in ("m", "c", "k"):
        g.bond("v", e)
    g.output("x", g.displacement("k"))
    return g


def reference(model, t, signal, substeps=200):
    """Classical RK4 on a fine fixed grid, memory committed after every (always accepted) step."""
    sim = bg.Simulator(model)
    th = sim.theta()
    x = sim.initial_state(th)
    bank = sim.signal_bank({sim.input_names[0]: signal})
    mem = sim.initial_memory(t[0], x, th, bank)
    c = sim.compiled
    u, du = np.zeros(1), np.zeros(1)
    args = bank.args()
    from bondgraph.numerics.integrators import eval_inputs

    def f(tt, xx):
        out = np.zeros_like(xx)
        eval_inputs(tt, *args, u, du, True)
        c.rhs(tt, xx, u, du, th, mem, c.aux, out)
        return out

    ys = [x.copy()]
    v = np.zeros(len(sim.eqs.operators))
    for a, b in zip(t[:-1], t[1:]):
        h = (b - a) / substeps
        for k in range(substeps):
            tt = a + k * h
            k1 = f(tt, x)
            k2 = f(tt + h / 2, x + h / 2 * k1)
            k3 = f(tt + h / 2, x + h / 2 * k2)
            k4 = f(tt + h, x + h * k3)
            x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            eval_inputs(tt + h, *args, u, du, True)
            c.commit(tt + h, x, u, du, th, mem, c.aux, v)
        ys.append(x.copy())
    return np.array(ys)


@pytest.mark.parametrize("build,inp", [(lag_after_operator, "V"), (hysteretic_spring, "F")])
def test_adaptive_steps_with_rejections_match_a_fine_fixed_step_reference(build, inp):
    model = build()
    t = np.linspace(0, 2.0, 201)
    sig = bg.Sine(1.5, 2.0)  # eight reversals inside steps, each one a memory event
    res = bg.simulate(model, t, {inp: sig}, rtol=1e-8, method="dopri5")
    assert res.stats["rejected"] > 0 and res.stats["reversal_rejections"] > 0
    ref = reference(model, t, sig)
    x = res.states[bg.Simulator(model).state_names[0]]
    assert np.max(np.abs(x - ref[:, 0])) < 1e-5 * np.ptp(ref[:, 0])


def test_operator_memory_survives_rejected_steps_unchanged():
    """A large first step is rejected several times; the loop must still match the reference."""
    model = lag_after_operator()
    t = np.array([0.0, 0.5, 1.0, 1.5, 2.0])
    sig = bg.Sine(1.5, 3.0)
    loose = bg.simulate(model, t, {"V": sig}, rtol=1e-3, method="dopri5")
    tight = bg.simulate(model, t, {"V": sig}, rtol=1e-9, method="dopri5")
    assert loose.stats["rejected"] > 0
    assert np.max(np.abs(loose["x"] - tight["x"])) < 2e-3 * np.ptp(tight["x"])


def test_triangle_corners_are_breakpoints_for_operators():
    """A memory operator reverses exactly at a triangle corner: the integrator stops there."""
    model = lag_after_operator()
    t = np.linspace(0, 2.0, 201)
    sig = bg.Triangle(1.5, 2.0)
    res = bg.simulate(model, t, {"V": sig}, rtol=1e-9, method="dopri5")
    ref = reference(model, t, sig, substeps=100)
    assert np.max(np.abs(res["x"] - ref[:, 0])) < 1e-6 * np.ptp(ref[:, 0])
