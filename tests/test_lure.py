"""The Lur'e route of the diagnosis (bondgraph.diagnosis.lure): a linear bond graph with
polynomial terms (and a smoothed Coulomb force, or a Bouc–Wen restoring force) added to some
elements' laws, stepped sample by sample on the exact
first-order-hold discretisation, against the same rewritten bond graph integrated by the
compiled Dormand–Prince solver (two independent routes to one answer).

The test model is a mass on a spring and a damper driven by a force, x the spring's
displacement (m = 1 kg, k = (2π·40 Hz)² N/m, c = 2·0.02·√(km)); the drive is a chirp through
the resonance, sampled at 2 kHz, linear between samples for both routes.  A term's partner is
another element's displacement or the drive itself (a law that moves with the field).
"""

import math

import numpy as np
import pytest
import sympy as sp

import bondgraph as bg
from bondgraph.diagnosis.lure import DRIVE, Lure, NotConverged, polynomial_term
from bondgraph.diagnosis.rewrite import modify_law

K = (2 * math.pi * 40.0) ** 2
CD = 2 * 0.02 * math.sqrt(K)


def resonator():
    g = bg.Model("resonator", "mass, spring, damper")
    F = g.input("F", "N")
    g.add(bg.Se("src", F), bg.J1("v"), bg.I("m", 1.0), bg.C("k", 1 / K), bg.R("c", CD))
    g.chain("src", "v", "m")
    g.bond("v", "k")
    g.bond("v", "c")
    g.output("x", "k.q", "m")
    return g


def softening(c, r2, x, a):
    return -c * x * (x**2 - r2)


def stanton(c, r2, x, a):
    return c * ((x if a is None else a) ** 2 - r2) * x


def drive():
    t = np.arange(4000) / 2000.0
    u = np.sin(2 * np.pi * (10 * t + 15 * t**2))  # 10 -> 70 Hz
    return t, u


def integrated(model, t, u):
    return bg.simulate(model, t, {"F": bg.PiecewiseLinear(t, u)}, rtol=1e-10, atol=1e-14)["x"]


@pytest.mark.parametrize(
    "element, term, partner, change, base",
    [
        ("k", softening, None, 0.3, K),  # stiffness 30 % lower at the peak displacement
        ("c", stanton, "k", 3.0, CD),  # damping x4 at the peak displacement
        ("c", stanton, None, 3.0, CD),  # velocity-cubic: damping x4 at the peak velocity
        ("k", softening, DRIVE, 0.3, K),  # the drive's square moves the stiffness (a field law)
    ],
)
def test_stepped_lure_agrees_with_the_integrated_rewrite(element, term, partner, change, base):
    t, u = drive()
    lure = Lure(resonator(), "F", "x", [element], {element: partner}, t[1] - t[0])
    lin = lure.linear_responses({}, u, term)
    amp = lin[f"diag.x:{element}" if partner is None else f"diag.a:{element}"]
    coef = change * base / float(np.max(np.abs(amp))) ** 2
    r2 = 0.5 * float(np.mean(amp**2))
    y = lure.simulate({}, u, term, [(coef, r2)])
    rewritten = resonator()
    partner_q = rewritten.inputs["F"].symbol if partner == DRIVE else bg.Quantity("q", partner) if partner else None
    modify_law(rewritten, element, lambda x, old: old + term(coef, r2, x, partner_q))
    ref = integrated(rewritten, t, u)
    linear = integrated(resonator(), t, u)
    assert np.std(ref - linear) > 0.05 * np.std(linear)  # the term matters
    assert np.std(y - ref) < 5e-3 * np.std(ref)  # and both routes agree
    assert np.std(lin["x"] - linear) < 1e-6 * np.std(linear)  # the linear part is exact


def test_terms_named_before_are_held_while_a_new_one_is_fitted():
    """A chain step after a structural cause: softening on the spring held, velocity-cubic
    damping on the damper added; both routes agree."""
    t, u = drive()
    first = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0])
    q = first.linear_responses({}, u, softening)["diag.x:k"]
    soft = (0.3 * K / float(np.max(np.abs(q))) ** 2, 0.5 * float(np.mean(q**2)))
    lure = Lure(resonator(), "F", "x", ["c"], {"c": None}, t[1] - t[0], fixed=[("k", None, softening, *soft)])
    v = lure.linear_responses({}, u, stanton)["diag.x:c"]  # the damper's velocity, softening held
    damp = (3.0 * CD / float(np.max(np.abs(v))) ** 2, 0.5 * float(np.mean(v**2)))
    y = lure.simulate({}, u, stanton, [damp])
    rewritten = resonator()
    modify_law(rewritten, "k", lambda x, old: old + softening(*soft, x, None))
    modify_law(rewritten, "c", lambda x, old: old + stanton(*damp, x, None))
    ref = integrated(rewritten, t, u)
    assert np.std(y - ref) < 5e-3 * np.std(ref)
    only_soft = first.simulate({}, u, softening, [soft])
    assert np.std(only_soft - ref) > 0.05 * np.std(ref)  # the damping term mattered


def test_a_diverging_term_is_reported_not_returned():
    t, u = drive()
    lure = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0])
    with pytest.raises(NotConverged):
        lure.simulate({}, u, softening, [(10 * K / 1e-4**2, 0.0)])  # negative stiffness past 32 um


def friction(c, r2, x, a):
    """A smoothed Coulomb force c·r2·tanh(x/r2) (r2: the smoothing velocity)."""
    return c * r2 * sp.tanh(x / r2)


def test_terms_are_polynomials_plus_one_saturation_of_the_element_variable():
    P, hg = polynomial_term(softening, False)(2.0, 3.0)
    assert P[1, 0] == pytest.approx(6.0) and P[3, 0] == pytest.approx(-2.0)  # 2·3·x − 2·x³
    assert list(hg) == [0.0, 0.0]
    P, hg = polynomial_term(lambda c, r2, x, a: friction(c, r2, x, a) - c * x, False)(2.0, 0.5)
    assert P[1, 0] == pytest.approx(-2.0) and list(hg) == pytest.approx([1.0, 2.0])  # 1·tanh(2x) − 2x
    for other in (
        lambda c, r2, x, a: c * sp.sin(x),
        lambda c, r2, x, a: c * sp.tanh(x**2),
        lambda c, r2, x, a: c * (sp.tanh(x) + sp.tanh(2 * x / r2)),
    ):
        with pytest.raises(NotConverged):
            polynomial_term(other, False)
    with pytest.raises(NotConverged):  # of the partner: no
        polynomial_term(lambda c, r2, x, a: c * sp.tanh(a), True)


def test_friction_on_the_lure_route_agrees_with_the_integrated_rewrite():
    """A Coulomb force (smoothed over 2 % of the peak velocity) in the damper, 5× the viscous
    damping's force at the peak: the stepped route against the compiled integrator."""
    t, u = drive()
    lure = Lure(resonator(), "F", "x", ["c"], {"c": None}, t[1] - t[0])
    v = lure.linear_responses({}, u, friction)["diag.x:c"]
    s = 0.02 * float(np.max(np.abs(v)))
    coef = (5.0 * CD * float(np.max(np.abs(v))) / s, s)
    y = lure.simulate({}, u, friction, [coef])
    rewritten = resonator()
    modify_law(rewritten, "c", lambda x, old: old + friction(*coef, x, None))
    ref = integrated(rewritten, t, u)
    linear = integrated(resonator(), t, u)
    assert np.std(ref - linear) > 0.2 * np.std(linear)
    assert np.std(y - ref) < 5e-3 * np.std(ref)


def asymmetric(c, r2, x, a):
    """A term of two coefficients: a centred cubic k3·x·(x² − r2) and an even part k2·x²."""
    k3, k2 = c
    return k3 * x * (x**2 - r2) + k2 * x**2


def test_a_term_of_two_coefficients_agrees_with_the_integrated_rewrite():
    """A spring stiffer one way than the other (a hardening cubic and a quadratic that makes the
    stiffness at the peak 1.6× in extension, 0.6× in compression); the term held as a fixed
    one works the same way."""
    P, hg = polynomial_term(asymmetric, False, 2)((2.0, 0.5), 3.0)
    assert P[1, 0] == pytest.approx(-6.0) and P[2, 0] == pytest.approx(0.5) and P[3, 0] == pytest.approx(2.0)
    t, u = drive()
    lure = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0])
    q = lure.linear_responses({}, u, asymmetric)["diag.x:k"]
    peak = float(np.max(np.abs(q)))
    coef = ((0.1 * K / peak**2, 0.5 * K / peak), 0.5 * float(np.mean(q**2)))
    y = lure.simulate({}, u, asymmetric, [coef])
    rewritten = resonator()
    modify_law(rewritten, "k", lambda x, old: old + asymmetric(*coef, x, None))
    ref = integrated(rewritten, t, u)
    linear = integrated(resonator(), t, u)
    assert np.std(ref - linear) > 0.05 * np.std(linear)
    assert np.std(y - ref) < 5e-3 * np.std(ref)
    held = Lure(resonator(), "F", "x", ["c"], {"c": None}, t[1] - t[0], fixed=[("k", None, asymmetric, *coef)])
    assert np.std(held.linear_responses({}, u, stanton)["x"] - ref) < 5e-3 * np.std(ref)


def test_a_new_term_on_an_element_that_holds_one_adds_to_it():
    """A chain step on the element of an earlier one: a softening of the spring held, a new
    two-coefficient term (hardening cubic, quadratic) on the same spring; the stepped route
    against the rewrite carrying both terms."""
    t, u = drive()
    first = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0])
    q = first.linear_responses({}, u, softening)["diag.x:k"]
    peak = float(np.max(np.abs(q)))
    soft = (0.2 * K / peak**2, 0.5 * float(np.mean(q**2)))
    lure = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0], fixed=[("k", None, softening, *soft)])
    assert lure.elements == ["k"] and lure.new == ["k"]
    assert np.std(lure.linear_responses({}, u, asymmetric)["x"] - first.simulate({}, u, softening, [soft])) < 1e-9
    coef = ((0.05 * K / peak**2, 0.3 * K / peak), soft[1])
    y = lure.simulate({}, u, asymmetric, [coef])
    rewritten = resonator()
    modify_law(rewritten, "k", lambda x, old: old + softening(*soft, x, None) + asymmetric(*coef, x, None))
    ref = integrated(rewritten, t, u)
    assert np.std(y - ref) < 5e-3 * np.std(ref)
    assert np.std(first.simulate({}, u, softening, [soft]) - ref) > 0.05 * np.std(ref)  # the new term mattered


def test_the_slope_of_a_law_is_taken_at_rest():
    """A law that holds a partner's displacement (Stanton damping) and the drive (a field
    stiffness) has its small-signal slope at rest: every variable at 0, parameters at their
    values (a chain step after such a term asks for it)."""
    from bondgraph.diagnosis.rewrite import slope

    g = resonator()
    F = g.inputs["F"].symbol
    modify_law(g, "c", lambda x, old: old + stanton(2.0, 0.5, x, bg.Quantity("q", "k")))
    modify_law(g, "k", lambda x, old: old - 3.0 * x * (F**2 - 0.25) + 7.0 * x**2)
    assert slope(g, "c") == pytest.approx(CD - 1.0)  # c + 2·(0 − 0.5)
    assert slope(g, "k") == pytest.approx(K + 0.75)  # k − 3·(0 − 0.25)


def test_the_bouc_wen_restoring_force_agrees_with_the_integrated_rewrite():
    """k_h·z in the spring's law, z the Bouc–Wen state of its displacement (n = 1,
    β = γ = 1/(2·z_max)): the Lur'e route's exact-per-increment stepping against the rewritten
    bond graph with z as a state, integrated."""
    t, u = drive()
    lure = Lure(resonator(), "F", "x", ["k"], {"k": None}, t[1] - t[0])
    peak = float(np.max(np.abs(lure.linear_responses({}, u, lambda c, r2, x, a: 0 * x)["diag.x:k"])))
    kh, zmax = 0.3 * K, 0.15 * peak
    y = lure.hysteretic({}, u, "k", kh, zmax)
    rewritten = resonator()
    z = rewritten.state("z", 0, doc="Bouc–Wen state of the spring's displacement")
    qd = rewritten.flow("k")
    beta = 1 / (2 * zmax)
    rewritten.set_rate("z", qd - beta * sp.Abs(qd) * z - beta * qd * sp.Abs(z))
    modify_law(rewritten, "k", lambda x, old: old + kh * z)
    ref = integrated(rewritten, t, u)
    linear = integrated(resonator(), t, u)
    assert np.std(ref - linear) > 0.05 * np.std(linear)  # the loop matters
    assert np.std(y - ref) < 5e-3 * np.std(ref)  # and both routes agree
