"""Dimensional analysis: unit strings as written, the check of every equation at derive time
(the element, its equation and both units named), ``bondgraph check``, every model file and
library component consistent, and random consistent chains pass while any single swap fails."""

from __future__ import annotations

import contextlib
import io
import math
import re
from fractions import Fraction

import pytest
import sympy as sp
from conftest import MODELS, ROOT
from hypothesis import given, settings
from hypothesis import strategies as st

import bondgraph as bg
from bondgraph import config
from bondgraph.cli import main
from bondgraph.model.modelfile import load_model
from bondgraph.model.units import BASE, DENOM, ONE, format_dim, parse_unit

OSCILLATOR = """
from bondgraph import C, I, J1, Model, Parameter, R, Se

PARAMETERS = [
    Parameter("m", 1.0, "kg", "mass"),
    Parameter("k", 100.0, "N/m", "stiffness"),
    Parameter("c", 2.0, "N*s/m", "damping"),
]


def build(p):
    g = Model("oscillator")
    F = g.input("F", "N", "applied force")
    g.add(Se("force", F), J1("v"), I("mass", p.m), C("spring", SPRING), R("damper", p.c))
    g.bond("force", "v")
    for e in ("mass", "spring", "damper"):
        g.bond("v", e)
    OUTPUT
    return g
"""


def oscillator_file(tmp_path, spring="1 / p.k", output='g.output("x", g.displacement("spring"), "m")', name="osc"):
    path = tmp_path / f"{name}.py"
    path.write_text(OSCILLATOR.replace("SPRING", spring).replace("OUTPUT", output))
    return path


def dim(**exps) -> tuple:
    """A dimension from exponents of the SI base units, e.g. dim(kg=1, s=-2)."""
    return tuple(int(Fraction(exps.get(b, 0)) * DENOM) for b in BASE)


# ---- unit strings ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, expected, scale",
    [
        ("N/m", dim(kg=1, s=-2), 1.0),
        ("N*s/m", dim(kg=1, s=-1), 1.0),
        ("N·s/m", dim(kg=1, s=-1), 1.0),
        ("m/V", dim(kg=-1, m=-1, s=3, A=1), 1.0),
        ("C/m^2", dim(A=1, s=1, m=-2), 1.0),
        ("V/m", dim(kg=1, m=1, s=-3, A=-1), 1.0),
        ("V/(C*m^2)", dim(kg=1, m=0, s=-4, A=-2), 1.0),
        ("1/(kg m^2 s^2)", dim(kg=-1, m=-2, s=-2), 1.0),
        ("kg^1/2 m", dim(kg=Fraction(1, 2), m=1), 1.0),
        ("kg^-1/2", dim(kg=Fraction(-1, 2)), 1.0),
        ("N/(kg^1/2 V)", dim(kg=Fraction(-1, 2), m=-1, s=1, A=1), 1.0),
        ("m²", dim(m=2), 1.0),
        ("rad/s", dim(s=-1), 1.0),
        ("1", ONE, 1.0),
        ("µm", dim(m=1), 1e-6),
        ("um", dim(m=1), 1e-6),
        ("V/um", dim(kg=1, m=1, s=-3, A=-1), 1e6),
        ("deg", ONE, math.pi / 180),
        ("Ω", dim(kg=1, m=2, s=-3, A=-2), 1.0),
        ("kg/m^3", dim(kg=1, m=-3), 1.0),
        ("F/m", dim(kg=-1, m=-3, s=4, A=2), 1.0),
    ],
)
def test_unit_strings_read_as_engineers_write_them(text, expected, scale):
    u = parse_unit(text)
    assert u.dim == expected
    assert u.scale == pytest.approx(scale, rel=1e-12)


def test_an_empty_unit_is_undeclared_and_1_is_a_pure_number():
    assert parse_unit("") is None and parse_unit("  ") is None
    assert parse_unit("1").dim == ONE


@pytest.mark.parametrize("text", ["N/mx", "m2", "N/(m", "foo", "10 m", "kg^x", "N m)"])
def test_unreadable_unit_strings_are_refused_where_declared(text):
    with pytest.raises(bg.ParameterError, match=rf"^parameter 'K': cannot read unit {re.escape(repr(text))} \("):
        bg.Parameter("K", 1.0, text)
    m = bg.Model("m")
    with pytest.raises(bg.ParameterError, match="parameter 'k'"):
        m.parameter("k", 1.0, text)
    with pytest.raises(bg.ModelError, match=r"^m: input 'V': cannot read unit"):
        m.input("V", text)
    with pytest.raises(bg.ModelError, match=r"^m: internal state 'z': cannot read unit"):
        m.state("z", 0, unit=text)
    m.add(bg.Se("s", 1.0), bg.J1("j"), bg.R("r", 1.0))
    m.chain("s", "j", "r")
    with pytest.raises(bg.ModelError, match=r"^m: output 'y': cannot read unit"):
        m.output("y", "r.e", text)


def test_a_power_written_without_a_caret_gets_the_fix():
    with pytest.raises(bg.ParameterError, match=r"write mm\^2 for a power"):
        bg.Parameter("K", 1e7, "N/mm2")


@settings(deadline=None)  # the first call reads sympy's unit tables
@given(st.lists(st.integers(-8, 8), min_size=len(BASE), max_size=len(BASE)))
def test_a_written_out_unit_reads_back_as_the_same_dimension(halves):
    d = tuple(h * DENOM // 2 for h in halves)
    assert parse_unit(format_dim(d)).dim == d


# ---- the check at derive time ------------------------------------------------------------------
def test_a_stiffness_where_the_compliance_belongs_names_the_element_the_equation_and_both_units(tmp_path):
    good = load_model(oscillator_file(tmp_path))
    assert bg.derive(good.model).units.lines()[0] == "units: consistent"
    bad = load_model(oscillator_file(tmp_path, spring="p.k", name="swapped"))
    with pytest.raises(bg.ModelError) as err:
        bg.derive(bad.model)
    assert str(err.value) == (
        "oscillator: units do not match in C 'spring' (e = q/k): e_spring = q_spring/k: the left side is N, "
        "the right side is m^2/N (k is declared N/m; this equation needs m/N)"
    )


def test_the_element_to_blame_is_found_where_the_contradiction_shows_elsewhere(tmp_path):
    """Without the displacement output, the flows follow from the elements alone: the spring is
    met first; without the damper too, mass and spring contradict each other and the power
    convention tells the swapped one."""
    for spring_first in (False, True):
        text = OSCILLATOR.replace("SPRING", "p.k").replace("OUTPUT", "")
        if spring_first:
            text = text.replace('("mass", "spring", "damper")', '("spring", "mass")').replace(', R("damper", p.c)', "")
        path = tmp_path / f"blame{spring_first}.py"
        path.write_text(text)
        with pytest.raises(bg.ModelError, match=r"in C 'spring' \(e = q/k\): e_spring = q_spring/k: "):
            bg.derive(load_model(path).model)


def test_a_transformer_with_a_pure_number_between_two_domains_is_caught():
    def drive(unit):
        g = bg.Model("drive")
        V, F = g.input("V", "V"), g.input("F", "N")
        g.add(bg.Se("amp", V), bg.J1("i"), bg.R("Re", g.parameter("Re", 10.0, "ohm")))
        g.add(bg.TF("tf", g.parameter("n", 2.0, unit)), bg.J1("v"), bg.I("mass", g.parameter("m", 0.1, "kg")))
        g.add(bg.C("spring", 1 / g.parameter("k", 1e4, "N/m")), bg.Se("load", F))
        g.chain("amp", "i", "tf.p1")
        g.bond("i", "Re")
        g.chain("tf.p2", "v", "mass")
        g.bond("v", "spring")
        g.bond("load", "v")
        g.output("x", g.displacement("spring"), "m")
        return g

    with pytest.raises(
        bg.ModelError, match=r"in TF 'tf' .*the left side is N, the right side is V \(n is declared 1; "
    ):
        bg.derive(drive("1"))
    assert bg.derive(drive("V/N")).units.lines()[0] == "units: consistent"
    assert bg.derive(drive("m/C")).units.lines()[0] == "units: consistent"  # the same unit


def test_a_gyrator_relates_effort_to_flow():
    def motor(unit):
        g = bg.Model("motor")
        g.add(bg.Se("amp", g.input("V", "V")), bg.J1("i"), bg.R("Re", g.parameter("Re", 1.0, "ohm")))
        g.add(bg.GY("gy", g.parameter("Kt", 0.1, unit)), bg.J1("w"), bg.I("J", g.parameter("J", 1e-4, "kg*m^2")))
        g.chain("amp", "i", "gy.p1")
        g.bond("i", "Re")
        g.chain("gy.p2", "w", "J")
        g.output("speed", g.flow("J"), "rad/s")
        return g

    assert bg.derive(motor("N*m/A")).units.lines()[0] == "units: consistent"
    with pytest.raises(bg.ModelError, match=r"in GY 'gy'"):
        bg.derive(motor("N/A"))


def test_undeclared_units_are_inferred_and_numbers_take_the_unit_their_place_needs():
    g = bg.Model("m")
    F = g.input("F", "N")
    g.add(bg.Se("force", F), bg.J1("v"), bg.I("mass", 0.5), bg.C("spring", 1e-3), bg.R("damper", g.parameter("c", 2.0)))
    g.bond("force", "v")
    for e in ("mass", "spring", "damper"):
        g.bond("v", e)
    g.output("x", g.displacement("spring"), "m")
    rep = bg.derive(g).units
    (c,) = rep.parameters
    assert (c.name, c.unit, c.status) == ("c", "kg/s", "inferred")
    assert ("spring", "1000", "N/m") in rep.constants and ("mass", "2", "1/kg") in rep.constants
    assert not rep.notes  # power bonds


def test_an_element_given_only_numbers_takes_the_units_of_its_place():
    """I("mass", 1) writes f = p: the number is gone from its relation, which says nothing."""
    g = bg.Model("m")
    g.add(bg.Se("force", g.input("F", "N")), bg.J1("v"), bg.I("mass", 1), bg.R("damper", 1), bg.C("spring", 1))
    g.bond("force", "v")
    for e in ("mass", "spring", "damper"):
        g.bond("v", e)
    g.output("x", g.displacement("spring"), "m")
    assert bg.derive(g).units.lines()[0] == "units: consistent"


def test_the_check_can_be_turned_off(tmp_path):
    bad = load_model(oscillator_file(tmp_path, spring="p.k"))
    with config.override({"units.check": False}):
        assert bg.derive(bad.model).units is None
    assert bg.derive(bad.model, units=False).units is None
    with pytest.raises(bg.ModelError):
        bg.derive(bad.model)


def test_inside_a_law_a_sum_of_unlike_terms_and_a_function_of_a_unit_are_caught():
    def model(law):
        g = bg.Model("m")
        g.add(bg.Se("force", g.input("F", "N")), bg.J1("v"), bg.I("mass", g.parameter("M", 1.0, "kg")))
        k = g.parameter("k", 1e3, "N/m")
        g.add(bg.C("spring", law=lambda q: law(k, q)))
        g.bond("force", "v")
        g.bond("v", "mass")
        g.bond("v", "spring")
        g.output("x", g.displacement("spring"), "m")
        return g

    rep = bg.derive(model(lambda k, q: k * q + 2.5e9 * k * q**3)).units  # the float takes 1/m^2
    assert ("spring", "2.5e+09", "1/m^2") in rep.constants
    with pytest.raises(bg.ModelError, match=r"the terms of a sum are N \(k\*q_spring\) and N\*m \(k\*q_spring\*\*2\)"):
        bg.derive(model(lambda k, q: k * q + k * q**2))
    with pytest.raises(bg.ModelError, match=r"the argument of tanh is m where a pure number is needed"):
        bg.derive(model(lambda k, q: k * sp.tanh(q)))


def test_an_internal_state_with_a_wrongly_declared_unit_is_named():
    from library.piezo import bouc_wen_polarization

    def model(r_unit):
        g = bg.Model("bw")
        g.add(bg.Se("amp", g.input("V", "V")), bg.J1("i"), bg.R("Re", g.parameter("Re", 1.0, "ohm")), bg.J1("pol"))
        g.add(bg.TF("l", g.parameter("l", 1e-4, "m")))
        p = {n: g.parameter(n, v, u) for n, v, u in (("kx", 5e12, "V/(C*m^2)"), ("kw", 2e5, "V/m"))}
        q = g.parameter("q", 1.6e7, "1/(C*m)")
        bouc_wen_polarization(g, "C_NL", p["kx"], p["kw"], q, g.parameter("r", 0.56, r_unit), 1.0)
        g.chain("amp", "i", "l.p1")
        g.bond("i", "Re")
        g.chain("l.p2", "pol", "C_NL")
        return g

    assert bg.derive(model("1")).units.states[0].unit == "1"
    with pytest.raises(bg.ModelError, match=r"in internal state 'C_NL.z': "):
        bg.derive(model("m"))


def test_memory_operators_give_their_parameters_units_through_their_input_and_output():
    lm = load_model(MODELS / "apa120ml.py", {"hysteresis": "pi"})
    rep = bg.derive(lm.model).units
    units = {e.name: e for e in rep.parameters}
    assert parse_unit(units["stack.C_NL.H.r2"].unit).dim == parse_unit("C*m").dim
    assert parse_unit(units["stack.C_NL.H.w2"].unit).dim == parse_unit("V/(C*m^2)").dim
    assert parse_unit(units["stack.C_NL.H.d1"].unit).dim == parse_unit("V/m").dim
    assert units["stack.C_NL.H.ws1"].unit == "1" and units["stack.C_NL.H.r2"].status == "inferred"
    assert rep.operators == [("stack.C_NL.H", "C*m", "V/m")]


# ---- every model file and library component ----------------------------------------------------
MODEL_CASES = [
    ("stack.py", {}),
    ("stack.py", {"lumped": "true"}),
    ("apa120ml.py", {}),
    ("apa120ml.py", {"hysteresis": "bouc-wen"}),
    ("apa120ml.py", {"hysteresis": "pi"}),
    ("apa120ml.py", {"hysteresis": "pi", "table3": "absolute-positive"}),
    ("bimorph_t215.py", {}),
    ("bimorph_t215.py", {"hysteresis": "pi", "modes": "3"}),
    ("bimorph_t226.py", {}),
    ("bimorph_t226.py", {"nonlinear": "true"}),
    ("bimorph_t226.py", {"nonlinear": "true", "coefficients": "modal", "frequency": "computed"}),
    ("bender_highfield.py", {}),
    ("bender_highfield.py", {"saturation": "true", "creep": "false"}),
    ("triangular_drive.py", {}),
    ("triangular_drive.py", {"formulation": "layers"}),
    ("triangular_drive.py", {"stroke": "hysteretic"}),
    ("triangular_drive.py", {"stroke": "measured", "formulation": "layers"}),
    ("p885_stack.py", {}),
    ("p885_stack.py", {"hysteresis": "none"}),
]


def test_the_cases_cover_every_model_file():
    assert {f for f, _ in MODEL_CASES} == {p.name for p in MODELS.glob("*.py")}


@pytest.mark.parametrize("name, options", MODEL_CASES, ids=[f"{f}-{'-'.join(o.values())}" for f, o in MODEL_CASES])
def test_every_model_file_is_consistent_and_declares_its_units(name, options):
    lm = load_model(MODELS / name, options)
    rep = bg.derive(lm.model).units
    assert all(e.status == "declared" for e in rep.outputs + rep.inputs), rep.lines()
    undeclared = [d.name for d in lm.declared if d.symbolic and d.kind == "real" and not d.unit]
    assert not undeclared
    assert not rep.notes, rep.notes  # power bonds throughout


def test_the_piezo_c_fields_are_consistent():
    from library.piezo import model1_cfield, model2_cfield, model2_from_model1

    g = bg.Model("fields")
    K1, a1, C1 = g.parameter("K1", 1e7, "N/m"), g.parameter("a1", 0.05, "m/C"), g.parameter("C1", 1e-6, "F")
    K2, a2, C2 = model2_from_model1(K1, a1, C1)
    V, Re, M = g.input("V", "V"), g.parameter("Re", 1.0, "ohm"), g.parameter("M", 0.1, "kg")
    for name, field in (
        ("f1", model1_cfield("f1", K1=K1, a1=a1, C1=C1)),
        ("f2", model2_cfield("f2", K2=K2, a2=a2, C2=C2)),
    ):
        g.add(field, bg.Se(f"amp{name}", V), bg.J1(f"i{name}"), bg.R(f"Re{name}", Re))
        g.add(bg.J1(f"v{name}"), bg.I(f"M{name}", M))
        g.chain(f"amp{name}", f"i{name}", f"{name}.Q")
        g.bond(f"i{name}", f"Re{name}")
        g.chain(f"v{name}", f"{name}.x")
        g.bond(f"v{name}", f"M{name}")
        g.output(f"x{name}", g.displacement(f"{name}.x"), "m")
    rep = bg.derive(g).units
    assert rep.lines()[0] == "units: consistent" and not rep.notes
    h = bg.Model("bad")
    wrong = h.parameter("a1", 0.05, "m/V")
    h.add(model1_cfield("f1", K1=h.parameter("K1", 1e7, "N/m"), a1=wrong, C1=h.parameter("C1", 1e-6, "F")))
    h.add(bg.Se("amp", h.input("V", "V")), bg.Se("load", h.input("F", "N")))
    h.bond("amp", "f1.Q")
    h.bond("load", "f1.x")
    with pytest.raises(bg.ModelError, match=r"in C-field 'f1'"):
        bg.derive(h)


# ---- bondgraph check ---------------------------------------------------------------------------
def test_check_prints_causality_and_units_and_marks_inferred_ones(tmp_path, capsys):
    path = tmp_path / "rc.py"
    path.write_text(
        "from bondgraph import C, J1, Model, Parameter, R, Se\n"
        'PARAMETERS = [Parameter("R", 1e3, "ohm"), Parameter("C", 1e-6)]\n'
        "def build(p):\n"
        '    g = Model("rc")\n'
        '    g.add(Se("src", g.input("V", "V")), J1("i"), R("r", p.R), C("cap", p.C))\n'
        '    g.chain("src", "i", "cap")\n'
        '    g.bond("i", "r")\n'
        '    g.output("q", "cap.q")\n'
        "    return g\n"
    )
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "model: rc" and out[1].startswith("causality: 3 bonds, 4 elements; 1 states")
    assert "units: consistent" in out
    assert re.search(r"^ +C +F +\(inferred\)$", "\n".join(out), re.M)
    assert re.search(r"^ +q +C +\(inferred\)$", "\n".join(out), re.M)


def test_check_summarises_an_algebraic_loop_by_its_first_elements(capsys):
    assert main(["check", str(MODELS / "stack.py"), "--set", "layers=8"]) == 0
    out = capsys.readouterr().out.splitlines()
    (loop,) = [line for line in out if "algebraic loop" in line]
    assert re.fullmatch(
        r"  algebraic loop through (L\d\.\w+, ){5}L\d\.\w+ and 13 more \(36 variables, torn at \S+\) solved symbolically",
        loop,
    ), loop


def test_check_exits_2_with_one_line_when_units_do_not_match(tmp_path, capsys):
    assert main(["check", str(oscillator_file(tmp_path, spring="p.k"))]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.count("\n") == 1 and "units do not match in C 'spring'" in captured.err


# ---- random chains -----------------------------------------------------------------------------
@st.composite
def chains(draw):
    """A chain of masses joined by springs and dampers (Kelvin-Voigt pairs on 0-junctions),
    driven by a force or through a transformer or gyrator from a voltage, every parameter
    declared in its unit: (the parameter choices, which elements each gap holds, the front end)."""
    n = draw(st.integers(1, 3))
    gaps = [draw(st.sampled_from(["C", "R", "CR"])) for _ in range(n - 1)]
    ground = draw(st.sampled_from(["C", "R", "CR", ""]))
    front = draw(st.sampled_from(["force", "TF", "GY"]))
    return n, gaps, ground, front


SWAPPABLE = {"C": ("N/m", lambda k: 1 / k, lambda k: k), "I": ("kg", lambda m: m, lambda m: 1 / m)}


def chain_model(n, gaps, ground, front, swap=None):
    """The model of :func:`chains`; ``swap`` names one element whose modulus is inverted."""
    g = bg.Model("chain")

    def modulus(name, unit, value):
        p = g.parameter(f"p_{name}", value, unit)
        return 1 / p if name == swap else p

    F = g.input("F", "N")
    for i in range(1, n + 1):
        g.add(bg.J1(f"v{i}"), bg.I(f"m{i}", modulus(f"m{i}", "kg", 0.1)))
        g.bond(f"v{i}", f"m{i}")
    for i, kinds in enumerate(gaps, 1):
        g.add(bg.J0(f"gap{i}"))
        g.bond(f"v{i}", f"gap{i}")
        g.bond(f"gap{i}", f"v{i + 1}")
        if "C" in kinds:
            g.add(bg.C(f"k{i}", 1 / modulus(f"k{i}", "N/m", 1e4)))
            g.bond(f"gap{i}", f"k{i}")
        if "R" in kinds:
            g.add(bg.R(f"c{i}", modulus(f"c{i}", "N*s/m", 5.0)))
            g.bond(f"gap{i}", f"c{i}")
    if "C" in ground:
        g.add(bg.C("k0", 1 / modulus("k0", "N/m", 1e4)))
        g.bond("v1", "k0")
    if "R" in ground:
        g.add(bg.R("c0", modulus("c0", "N*s/m", 5.0)))
        g.bond("v1", "c0")
    if front == "force":
        g.add(bg.Se("drive", F))
        g.bond("drive", "v1")
    else:
        unit = "V/N" if front == "TF" else "N/A"
        two = bg.TF("tr", modulus("tr", unit, 2.0)) if front == "TF" else bg.GY("tr", modulus("tr", unit, 2.0))
        g.add(bg.Se("amp", g.input("V", "V")), bg.J1("i"), bg.R("Re", modulus("Re", "ohm", 1.0)), two)
        g.chain("amp", "i", "tr.p1")
        g.bond("i", "Re")
        g.bond("tr.p2", "v1")
        g.add(bg.Se("load", F))
        g.bond("load", f"v{n}")
    g.output("v", g.flow(f"m{n}"), "m/s")
    return g


def elements_of(g) -> list[str]:
    return [name for name, el in g.elements.items() if el.kind in ("C", "I", "R", "TF", "GY")]


@settings(max_examples=25, deadline=None)
@given(chains(), st.data())
def test_random_consistent_chains_pass_and_any_single_swap_fails(chain, data):
    g = chain_model(*chain)
    assert bg.derive(g).units.lines()[0] == "units: consistent"
    swap = data.draw(st.sampled_from(elements_of(g)))
    with pytest.raises(bg.ModelError, match=r"units do not match in (\S+) '(\S+)'") as err:
        bg.derive(chain_model(*chain, swap=swap))
    if g.elements[swap].kind in ("C", "I", "R"):  # on the anchored mechanical chain: named exactly
        assert f" '{swap}' (" in str(err.value), str(err.value)


# ---- the examples of docs/units.md -------------------------------------------------------------
def _blocks(page: str) -> list[tuple[str, str]]:
    return re.findall(r"```(python|text)\n(.*?)```", (ROOT / "docs" / page).read_text(), re.S)


def test_the_examples_of_the_units_page_print_what_it_shows():
    blocks = _blocks("units.md")
    pairs = [(code, shown) for (k1, code), (k2, shown) in zip(blocks, blocks[1:]) if k1 == "python" and k2 == "text"]
    assert len(pairs) == 4
    for code, shown in pairs:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(code, "docs/units.md", "exec"), {})
        assert out.getvalue() == shown


def test_the_check_output_shown_on_the_units_page_is_the_oscillators(tmp_path, capsys):
    model_file = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "model-files.md").read_text(), re.S)[0]
    (tmp_path / "oscillator.py").write_text(model_file)
    assert main(["check", str(tmp_path / "oscillator.py")]) == 0
    shown = [text for kind, text in _blocks("units.md") if kind == "text" and text.startswith("model: oscillator")]
    assert shown == [capsys.readouterr().out]
