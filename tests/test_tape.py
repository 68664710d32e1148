"""The tape interpreter (large models) gives the same results as numba-compiled code."""

import numpy as np
import pytest
import sympy as sp
from conftest import MODELS

import bondgraph as bg
from bondgraph import config
from bondgraph.model.modelfile import load_model


@pytest.mark.parametrize("settings", [{"layers": 3}, {"layers": 3, "lumped": True}])
def test_tape_equals_compiled(settings):
    t = np.linspace(0, 2e-3, 101)
    u = {"V": bg.Sine(50.0, 2000.0, offset=50.0)}
    eqs = bg.derive(load_model(MODELS / "stack.py", settings).model)
    with config.override({"codegen.tape_threshold": 10**9}):
        compiled = bg.Simulator(eqs)
    with config.override({"codegen.tape_threshold": 0}):
        taped = bg.Simulator(eqs)
    assert taped.compiled.route == "tape" and compiled.compiled.route != "tape"
    a = compiled.run(t, u, rtol=1e-9)["x"]
    b = taped.run(t, u, rtol=1e-9)["x"]
    assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))


def nonlinear_oscillator():
    g = bg.Model("nl")
    V = g.input("V")
    g.add(
        bg.Se("s", V),
        bg.J1("j"),
        bg.I("m", 1.0),
        bg.C("k", law=lambda q: q + q**3 + sp.sin(q)),
        bg.R("r", law=lambda f: 0.5 * f + 0.1 * sp.Abs(f) * f),
    )
    g.bond("s", "j")
    for e in ("m", "k", "r"):
        g.bond("j", e)
    g.output("x", g.displacement("k"))
    return g


def test_tape_evaluates_nonlinear_functions():
    g = nonlinear_oscillator()
    t = np.linspace(0, 3, 301)
    with config.override({"codegen.tape_threshold": 10**9}):
        a = bg.simulate(g, t, {"V": bg.Sine(1.0, 0.5)}, rtol=1e-10)["x"]
    with config.override({"codegen.tape_threshold": 0}):
        b = bg.simulate(g, t, {"V": bg.Sine(1.0, 0.5)}, rtol=1e-10)["x"]
    assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(a))
