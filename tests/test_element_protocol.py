"""The element protocol: a new kind of element, defined here and nowhere in the framework,
works end to end (causality, equations, printout, simulation, linearisation); causality does
not depend on the order in which elements and bonds were added."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_properties import Spec, build, graphs

import bondgraph as bg
from bondgraph import config
from bondgraph.linear.linearize import linearize
from bondgraph.model.elements import DISSIPATION, Element, sympify


class CubicDamper(Element):
    """A damper with e = c·f³ (power-in): not an R, a kind of its own.  It prefers to take the
    flow; given the effort it returns the real cube root f = sign(e)·|e/c|^(1/3)."""

    kind = "Rcubic"
    symbolic_attrs = ("c",)
    causal_class = DISSIPATION

    def __init__(self, name, c):
        super().__init__(name)
        self.c = sympify(c, f"Rcubic '{name}' coefficient")

    def preferred_causality(self, port):
        return True

    def equations(self, ports, eqs):
        p = ports["p"]
        if p.sets_effort:
            p.set_effort(self.c * p.f_in**3)
        else:
            p.set_flow_in(sp.sign(p.e) * sp.Abs(p.e / self.c) ** sp.Rational(1, 3))

    def describe(self):
        return f"e = {self.c}·f³"


def mass_on_cubic_damper(m=2.0, c=0.5, k=None, v0=3.0):
    g = bg.Model("cubic")
    F = g.input("F", "N")
    mass = g.parameter("m", m)
    g.add(bg.Se("force", F), bg.J1("v"), bg.I("m", mass, p0=m * v0), CubicDamper("d", g.parameter("c", c)))
    g.bond("force", "v")
    g.bond("v", "m")
    g.bond("v", "d")
    if k is not None:
        g.add(bg.C("k", 1 / g.parameter("k", k)))
        g.bond("v", "k")
    g.output("v", g.flow("m"), "m/s")
    g.output("Fd", g.effort("d"), "N")
    return g


def test_new_kind_derives_prints_and_simulates_against_the_analytic_solution():
    m, c, v0 = 2.0, 0.5, 3.0
    g = mass_on_cubic_damper(m, c, v0=v0)
    eqs = bg.derive(g)
    assert [s.origin for s in eqs.states] == ["m"] and not eqs.causality.derivative
    p = sp.Symbol("p_m", real=True)
    msym, csym, F = sp.symbols("m c F", real=True)
    assert sp.simplify(eqs.state_equations()[p] - (F - csym * (p / msym) ** 3)) == 0
    assert g.elements["d"].describe() == "e = c·f³"
    # m dv/dt = -c v³  ->  v(t) = v0 / sqrt(1 + 2 c v0² t / m)
    t = np.linspace(0.0, 2.0, 401)
    res = bg.simulate(eqs, t, rtol=1e-10)
    exact = v0 / np.sqrt(1 + 2 * c * v0**2 * t / m)
    assert np.max(np.abs(res["v"] - exact)) < 1e-7 * v0
    assert np.max(np.abs(res["Fd"] - c * exact**3)) < 1e-6 * c * v0**3


def test_new_kind_in_its_other_causality_and_in_a_model_file_pipeline():
    """Driven by an effort source directly (through a 0-junction), the damper takes the effort
    and gives the flow: the cube-root branch, checked against the law."""
    g = bg.Model("driven")
    V = g.input("E")
    g.add(bg.Se("src", V), bg.J0("n"), CubicDamper("d", 4.0), bg.C("k", 1.0))
    g.chain("src", "n", "d")
    g.bond("n", "k")
    g.output("f", g.flow("d"))
    eqs = bg.derive(g)
    assert eqs.causality.sets_effort(g.bonds[1], ("n", g.bonds[1].tail[1]))  # the junction gives the effort
    t = np.linspace(0.0, 1.0, 201)
    res = bg.simulate(eqs, t, {"E": bg.Sine(32.0, 1.0)})
    e = 32.0 * np.sin(2 * np.pi * t)
    assert np.allclose(res["f"], np.cbrt(e / 4.0), atol=1e-9)


def test_new_kind_linearizes_to_its_slope_at_the_operating_point():
    m, c, k, v0 = 2.0, 0.5, 50.0, 3.0
    eqs = bg.derive(mass_on_cubic_damper(m, c, k=k, v0=v0))
    lin = linearize(eqs, "F", "v", x_op={"p_m": m * v0, "q_k": 0.0})
    i = lin.states.index("p_m")
    assert lin.A[i, i] == pytest.approx(-3 * c * v0**2 / m)  # d(-c (p/m)³)/dp at p = m v0
    assert lin.A[i, lin.states.index("q_k")] == pytest.approx(-k)


def test_element_kind_without_equations_cannot_be_made():
    class Incomplete(Element):
        kind = "half"

    with pytest.raises(TypeError, match="equations"):
        Incomplete("x")


# ---- causality never depends on insertion order -----------------------------------------------
def parallel_capacitors(nonlinear_first: bool):
    """A flow source feeding a linear and a nonlinear capacitor in parallel: one must take
    derivative causality, and only the linear one can (its law inverts)."""
    g = bg.Model("par")
    g.add(bg.Sf("src", g.input("i")), bg.J0("n"))
    lin = bg.C("lin", 2.0)
    nl = bg.C("nl", law=lambda q: q + q**3)
    g.add(*((nl, lin) if nonlinear_first else (lin, nl)))
    g.bond("src", "n")
    for e in ("nl", "lin") if nonlinear_first else ("lin", "nl"):
        g.bond("n", e)
    g.output("e", g.effort("n"))
    return g


def test_nonlinear_capacitor_in_parallel_is_accepted_in_either_order():
    for first in (True, False):
        eqs = bg.derive(parallel_capacitors(first))
        assert [s.origin for s in eqs.states] == ["nl"]
        assert eqs.causality.derivative == [("lin", "p")]


def test_a_true_conflict_names_the_element_that_refuses():
    g = bg.Model("rigid")
    g.add(bg.Sf("src", 1.0), bg.J0("n"), bg.C("a", law=lambda q: q + q**3), bg.C("b", law=lambda q: q + q**5))
    g.bond("src", "n")
    g.bond("n", "a")
    g.bond("n", "b")
    with pytest.raises(bg.CausalityError, match=r"causal conflict around .*'[ab]'"):
        bg.derive(g)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data())
def test_causality_and_equations_do_not_depend_on_insertion_order(data):
    """Same graph, elements and bonds added in another order: the same states, the same
    derivative-causality set, and the same state equations (up to the names of bond variables)."""
    spec = data.draw(graphs(max_junctions=4, max_attached=2), label="graph")
    shuffled = Spec(
        data.draw(st.permutations(spec.elements), label="elements"),
        data.draw(st.permutations(spec.bonds), label="bonds"),
    )
    try:
        ref = bg.derive(build(spec))
    except bg.BondGraphError as exc:
        with pytest.raises(type(exc)):
            bg.derive(build(shuffled))
        return
    got = bg.derive(build(shuffled))
    assert sorted(map(str, got.state_symbols)) == sorted(map(str, ref.state_symbols))
    assert sorted(got.causality.derivative) == sorted(ref.causality.derivative)
    a, b = ref.state_equations(), got.state_equations()
    assert set(a) == set(b)
    # equal as functions: compared at random values of every symbol (symbolic cancellation of
    # the difference can take minutes on larger random graphs)
    rng = np.random.default_rng(0)
    for s in a:
        syms = sorted(a[s].free_symbols | b[s].free_symbols, key=str)
        for _ in range(3):
            at = {x: float(rng.uniform(0.5, 2.0)) for x in syms}
            va, vb = float(a[s].xreplace(at)), float(b[s].xreplace(at))
            assert va == pytest.approx(vb, rel=1e-9, abs=1e-12), (s, a[s], b[s])


def test_causality_search_budget_is_a_setting():
    from test_properties import SCAP_COUNTEREXAMPLE

    model = build(SCAP_COUNTEREXAMPLE)
    assert bg.derive(model).causality.derivative == [("C4", "p")]
    with config.override({"causality.max_attempts": -10}):
        with pytest.raises(bg.CausalityError, match="causality.max_attempts"):
            bg.derive(model)


# ---- the diagnosis on a model with a kind of its own ---------------------------------------------
class ViscousDamper(Element):
    """e = c·f as a kind of its own (not an R): the diagnosis must work on models that use it."""

    kind = "Rvisc"
    symbolic_attrs = ("c",)
    causal_class = DISSIPATION

    def __init__(self, name, c):
        super().__init__(name)
        self.c = sympify(c, f"Rvisc '{name}' coefficient")

    def preferred_causality(self, port):
        return True

    def equations(self, ports, eqs):
        p = ports["p"]
        if p.sets_effort:
            p.set_effort(self.c * p.f_in)
        else:
            p.set_flow_in(p.e / self.c)


def oscillator(m=0.01, k=400.0, c=0.05, q0=None):
    """Mass, spring, ViscousDamper driven by a force; with ``q0`` the spring saturates as
    k·q0·tanh(q/q0) (a softening that is not the candidates' cubic law)."""
    g = bg.Model("newkind")
    F = g.input("F", "N")
    K = g.parameter("k", k)
    spring = bg.C("k", 1 / K) if q0 is None else bg.C("k", law=lambda q: K * q0 * sp.tanh(q / q0))
    g.add(
        bg.Se("force", F), bg.J1("v"), bg.I("m", g.parameter("m", m)), spring, ViscousDamper("d", g.parameter("c", c))
    )
    g.bond("force", "v")
    for e in ("m", "k", "d"):
        g.bond("v", e)
    g.tag("k", "stiffness")
    g.tag("d", "damping")
    g.tag("m", "inertia")
    g.output("x", g.displacement("k"), "m")
    return g


@pytest.mark.parametrize("q0, cause", [(None, []), (0.006, ["softening"])])
def test_diagnosis_on_a_model_with_a_new_kind(q0, cause):
    """Data from the oscillator with other linear parameters (and a saturating spring or not),
    diagnosed with the softening candidates: none on the effect-free record, softening on the other."""
    from bondgraph.data import Dataset
    from bondgraph.diagnosis import diagnose, load_candidates

    t = np.linspace(0, 2, 4001)
    res = bg.simulate(oscillator(k=440.0, c=0.06, q0=q0), t, {"F": bg.Chirp(0.3, 5.0, 60.0, 2.0)}, rtol=1e-9)
    noise = 1e-3 * np.std(res["x"]) * np.random.default_rng(0).standard_normal(t.size)
    data = Dataset(t, {"F": res["F"], "x": res["x"] + noise})
    report = diagnose(
        oscillator(), data, workers=1, candidates=[c for c in load_candidates(oscillator()) if c.cause == "softening"]
    )
    assert report.causes == cause
