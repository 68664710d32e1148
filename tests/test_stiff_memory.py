"""Memory models on every solver: the Bouc–Wen APA (a state with |z|^(n-1)·z terms) and
play-operator models run on radau, bdf, lsoda and the compiled implicit route, and their
Jacobian is defined at rest."""

import numpy as np
import pytest
from conftest import MODELS
from test_memory_contract import hysteretic_spring, lag_after_operator, reference

import bondgraph as bg
from bondgraph.model.modelfile import load_model


@pytest.fixture(scope="module")
def bouc_wen():
    return bg.Simulator(load_model(MODELS / "apa120ml.py", {"hysteresis": "bouc-wen"}).model)


@pytest.mark.parametrize("method", ["radau", "bdf"])
def test_bouc_wen_runs_on_the_stiff_scipy_solvers_from_rest(bouc_wen, method):
    """The crash of the issue: the Jacobian at z = 0 divided by zero (|z|^(n-2)·z·sign(z))."""
    t = np.linspace(0.0, 0.02, 201)
    res = bouc_wen.run(t, {"V": bg.Sine(60.0, 5.0, phase=-90.0, offset=60.0)}, method=method)
    assert np.all(np.isfinite(res["x"])) and res["x"][-1] > 0


@pytest.mark.parametrize("method", ["lsoda", "radau5"])
def test_bouc_wen_runs_on_lsoda_and_the_compiled_implicit_route(bouc_wen, method):
    t = np.linspace(0.0, 0.02, 201)
    drive = {"V": bg.Sine(60.0, 5.0, phase=-90.0, offset=60.0)}
    res = bouc_wen.run(t, drive, method=method)
    ref = bouc_wen.run(t, drive, method="dopri5", rtol=1e-9)
    assert np.max(np.abs(res["x"] - ref["x"])) <= 2e-5 * np.max(np.abs(ref["x"]))


def test_bouc_wen_jacobian_at_rest_is_the_right_derivative(bouc_wen):
    """At z = 0 and zero drive every entry is finite and equals the right difference quotient
    (the convention of bondgraph.numerics.jacobian: derivatives from the right at kinks)."""
    sim = bouc_wen
    th = sim.theta()
    x = sim.initial_state(th)
    bank = sim.signal_bank({})
    J = sim.jacobian_at(0.0, x, th, np.zeros(1), bank)
    assert np.all(np.isfinite(J))
    u, du, aux = np.zeros(2), np.zeros(2), sim.compiled.aux.copy()
    f0, f1 = np.zeros(x.size), np.zeros(x.size)
    sim.compiled.rhs(0.0, x, u, du, th, np.zeros(1), aux, f0)
    for j in range(x.size):
        d = 1e-9 * max(1.0, np.abs(J[:, j]).max()) ** -1
        xp = x.copy()
        xp[j] += d
        sim.compiled.rhs(0.0, xp, u, du, th, np.zeros(1), aux, f1)
        fd = (f1 - f0) / d
        assert np.allclose(J[:, j], fd, rtol=1e-5, atol=1e-9 * np.abs(J).max())


class CommitCounter(bg.MemoryOperator):
    """Counts its commits: the output is the number of commits so far (constant in v)."""

    kind = "counter"
    parameter_names = ("unit",)

    def parameter_values(self):
        return np.array([1.0])

    @property
    def n_memory(self):
        return 1

    def initial_memory(self, v0, prm):
        return np.zeros(1)

    def small_signal_gain(self, prm):
        return 0.0

    @staticmethod
    def output(v, mem, prm):
        return mem[0]

    @staticmethod
    def commit(v, mem, prm):
        mem[0] += prm[0]


def counted_hysteretic_spring():
    g = hysteretic_spring()
    n = g.operator("N", CommitCounter(), bg.Quantity("q", "k"))
    g.output("commits", n)
    return g


@pytest.mark.parametrize("method", ["dopri5", "radau5"])
def test_memory_is_committed_once_per_accepted_step_and_never_on_a_rejected_one(method):
    """The memory contract on both compiled routes: after the start's commit, one commit per
    accepted step (the output at the end is sampled before the last step's commit), however
    many steps were rejected by the error test, the Newton iteration or a reversal."""
    t = np.linspace(0, 2.0, 201)
    res = bg.simulate(counted_hysteretic_spring(), t, {"F": bg.Sine(1.5, 2.0)}, rtol=1e-8, method=method)
    assert res.stats["rejected"] > 0 and res.stats["reversal_rejections"] > 0
    assert res["commits"][-1] == res.stats["steps"]


@pytest.mark.parametrize("build,inp", [(lag_after_operator, "V"), (hysteretic_spring, "F")])
def test_radau5_with_memory_matches_a_fine_fixed_step_reference(build, inp):
    model = build()
    t = np.linspace(0, 2.0, 201)
    sig = bg.Sine(1.5, 2.0)
    res = bg.simulate(model, t, {inp: sig}, rtol=1e-8, method="radau5")
    ref = reference(model, t, sig)
    x = res.states[bg.Simulator(model).state_names[0]]
    assert np.max(np.abs(x - ref[:, 0])) < 1e-5 * np.ptp(ref[:, 0])
