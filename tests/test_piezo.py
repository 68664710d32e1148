"""Rodriguez-Fortun et al. 2010, (Rodriguez-Fortun et al. 2010): layers, stacks, the APA-120ML."""

import numpy as np
import pytest
import sympy as sp
from conftest import MODELS

import bondgraph as bg
from bondgraph.model.modelfile import load_model
from library.piezo import (
    layer_extension,
    linear_polarization,
    model1_cfield,
    model2_cfield,
    model2_from_model1,
    piezo_layer,
)

K1, A1, C1 = 2.0e7, 0.05, 2.0e-6


def cfield_actuator(field):
    """Amplifier (Re) → C-field layer → moving mass with damper."""
    g = bg.Model("layer")
    V = g.input("V")
    g.add(bg.Se("amp", V), bg.J1("i"), bg.R("Re", 10.0), field, bg.J1("v"), bg.I("M", 0.01), bg.R("c", 50.0))
    g.chain("amp", "i", "layer.Q")
    g.bond("i", "Re")
    g.bond("layer.x", "v")
    g.bond("v", "M")
    g.bond("v", "c")
    g.output("x", g.displacement("layer.x"))
    return g


def test_model1_and_model2_layers_give_the_same_response():
    K2, a2, C2 = model2_from_model1(K1, A1, C1)
    t = np.linspace(0, 5e-3, 501)
    u = {"V": bg.Sine(10.0, 400.0)}
    r1 = bg.simulate(cfield_actuator(model1_cfield("layer", K1=K1, a1=A1, C1=C1)), t, u, rtol=1e-10)
    r2 = bg.simulate(cfield_actuator(model2_cfield("layer", K2=K2, a2=a2, C2=C2)), t, u, rtol=1e-10)
    assert np.max(np.abs(r1["x"] - r2["x"])) < 1e-8 * np.max(np.abs(r1["x"]))
    # both stiffness matrices equal the model-1 matrix of eq. 5
    f1 = model1_cfield("f", K1=K1, a1=A1, C1=C1).stiffness_matrix()
    f2 = model2_cfield("f", K2=K2, a2=a2, C2=C2).stiffness_matrix()
    expect = sp.Matrix([[K1, -K1 * A1], [-K1 * A1, K1 * A1**2 + 1 / C1]])
    assert np.allclose(np.array(f1 - expect, float), 0, atol=1e-6 * K1)
    assert np.allclose(np.array(f2 - expect, float), 0, atol=1e-6 * K1)


def test_three_domain_layer_equals_model1_cfield():
    """E = kx·p with p = Q·l and x_p = a·p/l store U = ½K(x − aQ)² + Q²/(2C): model 1 with C = 1/(kx·l²)."""
    l, kx = 1e-4, 1.0 / (C1 * 1e-8)
    g = bg.Model("three-domain")
    V = g.input("V")
    g.add(piezo_layer("layer", l=l, a=A1, K=K1, polarization=lambda c, n: linear_polarization(c, n, kx)))
    g.add(bg.Se("amp", V), bg.J1("i"), bg.R("Re", 10.0), bg.I("M", 0.01), bg.R("c", 50.0))
    g.chain("amp", "i", "layer.elec")
    g.bond("i", "Re")
    g.bond("layer.mech", "M")
    g.bond("layer.mech", "c")
    g.output("x", layer_extension("layer", A1, l))
    t = np.linspace(0, 5e-3, 501)
    u = {"V": bg.Sine(10.0, 400.0)}
    a = bg.simulate(g, t, u, rtol=1e-10)["x"]
    b = bg.simulate(cfield_actuator(model1_cfield("layer", K1=K1, a1=A1, C1=C1)), t, u, rtol=1e-10)["x"]
    assert np.max(np.abs(a - b)) < 1e-7 * np.max(np.abs(b))


def test_lumped_and_n_layer_stack_agree_quasi_statically():
    t = np.linspace(0, 0.05, 501)
    u = {"V": bg.Sine(50.0, 20.0, phase=-90, offset=50.0)}  # slow compared with the ~35 kHz mode
    full = bg.simulate(load_model(MODELS / "stack.py", {"layers": 8}).model, t, u, rtol=1e-8)["x"]
    lumped = bg.simulate(load_model(MODELS / "stack.py", {"layers": 8, "lumped": True}).model, t, u, rtol=1e-8)["x"]
    assert np.max(np.abs(full - lumped)) < 2e-3 * np.max(np.abs(lumped))
    assert np.max(lumped) == pytest.approx(100 * 0.0474 / (5e12 * 1e-8), rel=1e-3)  # x/V = a/(kx·l²)


def test_lumped_stack_equations_match_eq14():
    """Compare the printed state equations of the lumped stack with Rodriguez-Fortun et al. 2010, eq. (14):
    Ve = i·Re + V, V = (E2 − E3)·l, E2 = p/C_NL, ṗ = i·l, E3·l = a·F1, F1 = K_NL·(x − a·p/l),
    F = M·ẍ + K_NL·(x − a·p/l) + c·ẋ.  Our states are p, the spring compression
    s = a·p/l − x and the momentum P = M·ẋ."""
    lm = load_model(MODELS / "stack.py", {"lumped": True})
    eqs = bg.derive(lm.model)
    se = eqs.state_equations()
    p, s, P = (sp.Symbol(n, real=True) for n in ("q_stack.C_NL", "q_stack.K", "p_M"))
    Ve, F, Re, l, a, K, kx, c, Mw = sp.symbols("V F Re l a K kx c M_layer", real=True)
    M = sp.Rational(21, 2) * Mw  # (N+1)/2·M_w with N = 20
    x = a * p / l - s
    xdot = P / M
    F1 = K * (x - a * p / l)
    E2, E3 = kx * p, a * F1 / l
    i = (Ve - (E2 - E3) * l) / Re
    paper = {p: i * l, s: sp.diff(a * p / l, p) * i * l - xdot, P: F - F1 - c * xdot}
    for sym, rhs in paper.items():
        assert sp.simplify(se[sym] - rhs) == 0, sym
    assert sp.simplify(eqs.output_equations()["x"] - x) == 0


def test_apa_bouc_wen_produces_a_closed_e_p_loop():
    lm = load_model(MODELS / "apa120ml.py", {"hysteresis": "bouc-wen"})
    f, cycles, n = 5.0, 8, 500  # n samples per period
    t = np.linspace(0, cycles / f, cycles * n + 1)
    res = bg.simulate(lm.model, t, {"V": bg.Sine(60.0, f, phase=-90, offset=60.0)}, rtol=1e-8)
    p, E = res["p"], res["E"]
    last = slice((cycles - 1) * n, cycles * n + 1)
    # the loop closes: the last cycle retraces the one before
    gap = [np.max(np.abs(p[k * n : (k + 1) * n + 1] - p[(k - 1) * n : k * n + 1])) for k in range(1, cycles)]
    assert gap[-1] < 1e-3 * np.ptp(p) and gap[-1] < 0.2 * gap[0]
    # and it encloses area: the hysteresis loss per cycle ∮E dp is positive and a sizeable
    # fraction of the stored-energy scale
    area = np.trapezoid(E[last], p[last])
    assert area > 0.02 * np.ptp(E[last]) * np.ptp(p[last])
    # the linear model has no loop
    lin = bg.simulate(
        load_model(MODELS / "apa120ml.py").model, t, {"V": bg.Sine(60.0, f, phase=-90, offset=60.0)}, rtol=1e-8
    )
    assert abs(np.trapezoid(lin["E"][last], lin["p"][last])) < 1e-6 * np.ptp(lin["E"]) * np.ptp(lin["p"])


def test_apa_static_gain_from_table1():
    lin = bg.linearize(bg.derive(load_model(MODELS / "apa120ml.py").model))
    assert lin.dc_gain() == pytest.approx(0.0474 / (5e12 * 1e-8), rel=1e-9)
    # overdamped mechanical mode (c = 3000 N·s/m on 160 g): real poles
    assert np.all(np.abs(lin.poles.imag) < 0.5 * np.abs(lin.poles.real))
