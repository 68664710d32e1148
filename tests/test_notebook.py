"""Notebook display: the bond graph as SVG (with its causal strokes once assigned), the state
equations as LaTeX, a linear model's poles and zeros as a table, a diagnosis as its tables;
and docs/notebook.ipynb executed by a Jupyter kernel (nbclient), its shown numbers checked.

The oscillator is the one of docs/model-files.md: m = 1 kg, k = 100 N/m, c = 2 N·s/m, so
ω = √(k/m) = 10 rad/s, ζ = c / (2√(km)) = 0.1 and a static gain 1/k = 0.01 m/N.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import sympy as sp
from conftest import ROOT

import bondgraph as bg
from bondgraph.model.drawing import MAX_ELEMENTS
from bondgraph.model.drawing import svg as bond_graph_svg

SVG = "{http://www.w3.org/2000/svg}"


def oscillator() -> bg.Model:
    g = bg.Model("oscillator")
    F = g.input("F", "N", "applied force")
    g.add(
        bg.Se("force", F),
        bg.J1("v"),
        bg.I("mass", g.parameter("m", 1.0, "kg")),
        bg.C("spring", 1 / g.parameter("k", 100.0, "N/m")),
        bg.R("damper", g.parameter("c", 2.0, "N*s/m")),
    )
    g.bond("force", "v")
    for e in ("mass", "spring", "damper"):
        g.bond("v", e)
    g.output("x", g.displacement("spring"), "m", "displacement")
    return g


def two_springs() -> bg.Model:
    """A force on two springs in parallel: one of them must take derivative causality."""
    g = bg.Model("two springs")
    g.add(bg.Se("force", g.input("F", "N")), bg.J1("v"), bg.I("mass", 1.0), bg.J0("p"))
    g.add(bg.J1("a"), bg.J1("b"), bg.C("k1", 0.01), bg.C("k2", 0.02), bg.R("d", 1.0))
    g.chain("force", "v", "mass")
    g.bond("v", "d")
    g.bond("v", "p")
    g.bond("p", "a")
    g.bond("p", "b")
    g.bond("a", "k1")
    g.bond("b", "k2")
    g.output("x", g.displacement("k1"))
    return g


def centres(root) -> dict[str, np.ndarray]:
    return {
        g.get("data-element"): np.array([float(g.find(f"{SVG}text").get(a)) for a in ("x", "y")])
        for g in root.iter(f"{SVG}g")
        if g.get("class") == "element"
    }


def test_the_model_draws_its_bonds_and_the_causality_its_strokes_where_the_effort_arrives():
    g = oscillator()
    plain = ET.fromstring(g._repr_svg_())
    assert sum(1 for e in plain.iter(f"{SVG}g") if e.get("class") == "bond") == len(g.bonds)
    assert not [e for e in plain.iter(f"{SVG}line") if e.get("class") == "stroke"]
    assert "causality not assigned" in "".join(plain.itertext())
    c = bg.assign_causality(g)
    root = ET.fromstring(c._repr_svg_())
    at = centres(root)
    bonds = {b.index: b for b in g.bonds}
    for e in root.iter(f"{SVG}g"):
        if e.get("class") != "bond":
            continue
        b = bonds[int(e.get("data-bond"))]
        (stroke,) = [ln for ln in e.iter(f"{SVG}line") if ln.get("class") == "stroke"]
        mid = np.array(
            [
                (float(stroke.get("x1")) + float(stroke.get("x2"))) / 2,
                (float(stroke.get("y1")) + float(stroke.get("y2"))) / 2,
            ]
        )
        end, other = c.stroke_end(b)[0], ({b.tail[0], b.head[0]} - {c.stroke_end(b)[0]}).pop()
        assert np.hypot(*(mid - at[end])) < np.hypot(*(mid - at[other])), b.index
    # integral causality: the junction sets the mass's effort, the spring sets the junction's
    assert c.stroke_end(bonds[2])[0] == "mass" and c.stroke_end(bonds[3])[0] == "v"


def test_derivative_causality_is_drawn_highlighted():
    c = bg.assign_causality(two_springs())
    (name,) = {e for e, _ in c.derivative}
    root = ET.fromstring(c._repr_svg_())
    fills = {
        g.get("data-element"): g.find(f"{SVG}rect").get("fill")
        for g in root.iter(f"{SVG}g")
        if g.get("class") == "element"
    }
    assert fills[name] == "mistyrose" and sum(f == "mistyrose" for f in fills.values()) == 1
    assert "derivative causality" in "".join(root.itertext())


def test_a_graph_too_big_to_draw_says_so():
    g = bg.Model("chain")
    g.add(bg.Se("s", 1.0), *(bg.J1(f"j{k}") for k in range(MAX_ELEMENTS)))
    g.chain("s", *(f"j{k}" for k in range(MAX_ELEMENTS)))
    text = "".join(ET.fromstring(bond_graph_svg(g)).itertext())
    assert f"{MAX_ELEMENTS + 1} elements" in text and "not drawn" in text


def test_the_equations_display_as_latex_that_reads_back_as_the_state_equations():
    eqs = bg.derive(oscillator())
    tex = eqs._repr_latex_()
    assert tex.startswith(r"\begin{align}") and tex.rstrip().endswith(r"\end{align}")
    rows = dict(re.match(r"\s*(.*?) &= (.*?)(?: \\\\)?$", line).groups() for line in tex.splitlines()[1:-1])
    assert rows[r"\frac{d}{dt}p_{mass}"] == sp.latex(eqs.state_equations()[sp.Symbol("p_mass", real=True)])
    p, q, F, m, k, c = sp.symbols("p_mass q_spring F m k c", real=True)
    assert sp.simplify(eqs.state_equations()[p] - (F - k * q - c * p / m)) == 0  # m p'' = F − k x − c x'
    assert rows["x"] == "q_{spring}"


def test_the_latex_of_a_huge_system_is_replaced_by_a_note():
    from bondgraph.equations.printing import latex_display

    note = latex_display(bg.derive(oscillator()), limit=50)
    assert "2 state equations" in note and "too long to typeset" in note


def test_the_linear_model_shows_its_natural_frequency_and_damping():
    lin = bg.linearize(bg.derive(oscillator()), "F", "x")
    html = lin._repr_html_()
    row = re.search(
        r"<tr><td>(-?[\d.]+) ± ([\d.]+)j</td><td>([\d.]+)</td><td>([\d.]+)</td><td>([\d.]+)</td></tr>", html
    )
    re_, im, w, f, zeta = map(float, row.groups())
    assert (re_, im) == pytest.approx((-1.0, math.sqrt(99.0)), rel=1e-4)
    assert w == pytest.approx(10.0, rel=1e-4) and f == pytest.approx(10 / (2 * math.pi), rel=1e-4)
    assert zeta == pytest.approx(0.1, rel=1e-4)
    assert "static gain 0.01;" in html and "no finite zeros" in html


def test_the_example_notebook_runs_and_shows_what_it_says():
    """docs/notebook.ipynb executed by a Jupyter kernel, in docs/ (its relative paths)."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(ROOT / "docs" / "notebook.ipynb", as_version=4)
    nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(ROOT / "docs")}}
    ).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    shown = [o.get("data", {}) for o in outputs if o.output_type == "execute_result"]
    model_svg, causal_svg, eqs_tex, lin_html, report_html = shown
    assert 'class="stroke"' not in model_svg["image/svg+xml"]
    assert causal_svg["image/svg+xml"].count('class="stroke"') == 4  # one stroke per bond
    assert r"\frac{d}{dt}q_{spring} &= \frac{p_{mass}}{m}" in eqs_tex["text/latex"]
    # the step response's peak: (1 + exp(−ζπ/√(1−ζ²)))/k at t = π/ω_d
    (printed,) = [o["text"] for o in outputs if o.output_type == "stream"]
    peak, at = map(float, re.search(r"peak displacement ([\d.]+) mm at t = ([\d.]+) s", printed).groups())
    zeta, wn = 0.1, 10.0
    assert peak == pytest.approx(1e3 * (1 + math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))) / 100, abs=1e-4)
    assert at == pytest.approx(math.pi / (wn * math.sqrt(1 - zeta**2)), abs=1e-3)
    assert "<td>10</td>" in lin_html["text/html"] and "<td>0.1</td>" in lin_html["text/html"]
    # the real record's diagnosis (tests/test_diagnose.py asserts hysteresis first on it)
    chain = re.search(r'id="chain">Chain: <b>(.*?)</b>', report_html["text/html"]).group(1)
    assert chain.startswith("hysteresis ×")
