"""Textbook causality cases: derivative causality, algebraic loops, C-fields, conflicts."""

import numpy as np
import pytest
import sympy as sp

import bondgraph as bg


def coupled_masses(n=3.0, m1=2.0, m2=0.5, k=50.0, c=1.0):
    """Force on mass m1, rigidly coupled through a lever (TF, ratio n) to m2; m1 on a spring."""
    g = bg.Model("lever")
    F = g.input("F", "N")
    g.add(
        bg.Se("force", F),
        bg.J1("v1"),
        bg.I("m1", g.parameter("m1", m1)),
        bg.C("k", 1 / g.parameter("k", k)),
        bg.R("c", g.parameter("c", c)),
        bg.TF("lever", g.parameter("n", n)),
        bg.J1("v2"),
        bg.I("m2", g.parameter("m2", m2)),
    )
    g.bond("force", "v1")
    for e in ("m1", "k", "c"):
        g.bond("v1", e)
    g.bond("v1", "lever.p1")
    g.bond("lever.p2", "v2")
    g.bond("v2", "m2")
    g.output("x", g.displacement("k"), "m")
    return g


def test_rigidly_coupled_inertias_reduce_to_one():
    g = coupled_masses()
    eqs = bg.derive(g)
    assert len(eqs.states) == 2  # p_m1 and q_k; m2 eliminated
    assert [n for n in eqs.causality.derivative] == [("m2", "p")]
    assert any("m2" in note and "derivative causality" in note for note in eqs.eliminated)
    # hand-reduced model: effective mass m1 + n^2 m2 on the spring and damper
    m_eff = 2.0 + 9.0 * 0.5
    h = bg.Model("reduced")
    F = h.input("F")
    h.add(bg.Se("force", F), bg.J1("v"), bg.I("m", m_eff), bg.C("k", 1 / 50.0), bg.R("c", 1.0))
    h.bond("force", "v")
    for e in ("m", "k", "c"):
        h.bond("v", e)
    h.output("x", h.displacement("k"))
    t = np.linspace(0, 2, 801)
    u = {"F": bg.Sine(1.0, 1.7)}
    a = bg.simulate(g, t, u, rtol=1e-10)["x"]
    b = bg.simulate(h, t, u, rtol=1e-10)["x"]
    assert np.max(np.abs(a - b)) < 1e-8 * np.max(np.abs(b))
    # printed equations show the effective inertia: the force on m1 is shared in the
    # ratio m1 : n^2 m2, i.e. dp_m1/dt = m1/(m1 + n^2 m2) * (F - ...)
    se = eqs.state_equations()
    p = sp.Symbol("p_m1", real=True)
    m1, m2, n, F = sp.symbols("m1 m2 n F", real=True)
    assert sp.simplify(sp.diff(se[p], F) - m1 / (m1 + n**2 * m2)) == 0


def test_flow_source_driving_a_mass_uses_input_derivative():
    g = bg.Model("driven")
    v = g.input("v", "m/s")
    g.add(bg.Sf("shaker", v), bg.J1("j"), bg.I("m", 2.0), bg.C("k", 0.1))
    g.bond("shaker", "j")
    g.bond("j", "m")
    g.bond("j", "k")
    g.output("F", g.effort("shaker"))
    eqs = bg.derive(g)
    assert len(eqs.states) == 1
    t = np.linspace(0, 1, 201)
    r = bg.simulate(eqs, t, {"v": bg.Sine(0.5, 2.0)}, rtol=1e-10)
    # F = m dv/dt + q/C, q = ∫ v
    w = 2 * np.pi * 2.0
    F = 2.0 * 0.5 * w * np.cos(w * t) + (0.5 / w) * (1 - np.cos(w * t)) / 0.1
    assert np.max(np.abs(r["F"] - F)) < 1e-6 * np.max(np.abs(F))


def two_resistor_loop():
    """Effort source feeding R1 in series with the parallel pair (R2 || C): with both
    resistors' causality free, SCAP leaves an algebraic loop between them."""
    g = bg.Model("loop")
    V = g.input("V")
    g.add(
        bg.Se("src", V),
        bg.J0("n0"),
        bg.J1("s1"),
        bg.R("R1", g.parameter("R1", 100.0)),
        bg.J0("n1"),
        bg.R("R2", g.parameter("R2", 300.0)),
        bg.I("L", g.parameter("L", 1e-3)),
        bg.R("R3", g.parameter("R3", 50.0)),
    )
    g.bond("src", "n0")
    g.bond("n0", "R3")
    g.bond("n0", "s1")
    g.bond("s1", "R1")
    g.bond("s1", "n1")
    g.bond("n1", "R2")
    g.bond("n1", "L")
    g.output("iL", g.flow("L"))
    return g


def test_algebraic_loop_between_resistors_is_solved():
    g = two_resistor_loop()
    eqs = bg.derive(g)
    assert eqs.loops, "expected an algebraic loop"
    # L di/dt = v_n1 with v_n1 = V*R2/(R1+R2) - i*R1*R2/(R1+R2)  (Thevenin)
    se = eqs.state_equations()
    p = sp.Symbol("p_L", real=True)
    V, R1, R2, L = sp.symbols("V R1 R2 L", real=True)
    expect = V * R2 / (R1 + R2) - (p / L) * R1 * R2 / (R1 + R2)
    assert sp.simplify(se[p] - expect) == 0


def test_cfield_energy_equals_matrix_form():
    K1, a1, C1 = sp.symbols("K1 a1 C1", positive=True)
    Kmat = [[K1, -K1 * a1], [-K1 * a1, K1 * a1**2 + 1 / C1]]

    def build(field):
        g = bg.Model("layer")
        V = g.input("V")
        g.add(bg.Se("src", V), bg.R("Re", 4.7), field, bg.J1("e"), bg.J1("mech"), bg.I("M", 0.16), bg.R("c", 3000.0))
        g.bond("src", "e")
        g.bond("e", "Re")
        g.bond("e", "layer.Q")
        g.bond("mech", "layer.x")
        g.bond("mech", "M")
        g.bond("mech", "c")
        g.output("x", g.displacement("layer.x"))
        return bg.derive(g)

    by_matrix = build(bg.CField("layer", ["x", "Q"], stiffness=Kmat))
    by_energy = build(
        bg.CField("layer", ["x", "Q"], energy=lambda q: K1 * (q["x"] - a1 * q["Q"]) ** 2 / 2 + q["Q"] ** 2 / (2 * C1))
    )
    se1, se2 = by_matrix.state_equations(), by_energy.state_equations()
    assert set(se1) == set(se2)
    for s in se1:
        assert sp.expand(se1[s] - se2[s]) == 0


def test_two_effort_sources_on_a_zero_junction_is_a_named_conflict():
    g = bg.Model("bad")
    g.add(bg.Se("a", 1.0), bg.Se("b", 2.0), bg.J0("n"), bg.C("c", 1.0))
    g.bond("a", "n")
    g.bond("b", "n")
    g.bond("n", "c")
    with pytest.raises(bg.CausalityError, match="'a'.*'n'.*'b'"):
        bg.derive(g)


def test_unresolvable_derivative_causality_names_elements():
    g = bg.Model("nl")
    g.add(bg.Sf("s", 1.0), bg.J1("j"), bg.I("m", law=lambda p: p + p**3), bg.C("k", 1.0))
    g.bond("s", "j")
    g.bond("j", "m")
    g.bond("j", "k")
    with pytest.raises(bg.CausalityError, match="m"):
        bg.derive(g)
