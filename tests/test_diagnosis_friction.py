"""Friction in a structure is named friction, on the exact Lur'e route.

The truth is written here: a mass on a spring and a damper (40 Hz, damping ratio 0.02; the
model says 38 Hz and 0.03) with a Coulomb force F·(2/π)·arctan(v/v_s) in the damper (an
arctan, not the candidate's tanh; v_s 1 % of the peak velocity; F such that at the peak
velocity the friction's equivalent viscous damping equals the viscous one), driven through
its resonance by a 10 → 70 Hz chirp, 2 kHz × 2 s, white noise of 0.5 % of the stroke.  The
truth is integrated by the compiled explicit method at rtol 1e-9 (within 1.7e-6 of the stroke
of scipy's Radau at the same tolerance, 3000× below the noise, in a hundredth of the time).

Asserted: the cause is friction (named ``nonlinear-damping`` before the cause vocabulary had
a name for it), through the friction candidate (damping that falls with amplitude, where the
cubic forms' rises); the same record without friction is effect-free.

A shear-thinning damper, c·v·((1 − ρ) + ρ/(1 + |v|/v₀)) with ρ = 0.8 and v₀ a fifth of the
peak velocity (a rational law, not the candidate's tanh), is viscous at low speed and levels
off gradually: the friction candidate fits it with a wide knee, and rule ``knee-width`` names it
``nonlinear-damping``.
"""

import math

import numpy as np
import sympy as sp

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis import diagnose
from bondgraph.diagnosis.rewrite import modify_law
from library.extensions import FrictionDamping, NonlinearDamping, StiffnessSoftening

FS, T = 2000.0, 2.0


def resonator(f=40.0, zeta=0.02):
    """m = 1 kg, k = (2πf)², c = 2ζ√(km); x the spring's displacement; roles tagged."""
    k = (2 * math.pi * f) ** 2
    g = bg.Model("resonator", "mass, spring, damper")
    F = g.input("F", "N")
    g.add(
        bg.Se("src", F),
        bg.J1("v"),
        bg.I("m", 1.0),
        bg.C("k", g.parameter("kk", 1 / k, "m/N")),
        bg.R("c", g.parameter("cc", 2 * zeta * math.sqrt(k), "N*s/m")),
    )
    g.chain("src", "v", "m")
    g.bond("v", "k")
    g.bond("v", "c")
    g.output("x", "k.q", "m")
    for el, role in (("m", "inertia"), ("k", "stiffness"), ("c", "damping")):
        g.tag(el, role)
    return g


def record(friction=True, seed=2, thinning=False):
    t = np.arange(int(T * FS)) / FS
    u = np.sin(2 * np.pi * (10 * t + 15 * t**2))
    lin = bg.simulate(resonator(), t, {"F": bg.PiecewiseLinear(t, u)}, rtol=1e-9)
    truth = resonator()
    vpk = float(np.max(np.abs(np.gradient(lin["x"], t))))
    c = 2 * 0.02 * 2 * math.pi * 40.0
    if thinning:
        rho, v0 = 0.8, 0.2 * vpk
        modify_law(truth, "c", lambda f, old: old - c * rho * f + c * rho * f / (1 + sp.Abs(f) / v0))
    elif friction:
        force = c * vpk * math.pi / 4  # 4F/(π v_pk) = c at the peak velocity
        vs = 0.01 * vpk
        modify_law(truth, "c", lambda f, old: old + force * 2 / math.pi * sp.atan(f / vs))
    x = bg.simulate(truth, t, {"F": bg.PiecewiseLinear(t, u)}, rtol=1e-9, method="dopri5")["x"]
    rng = np.random.default_rng(seed)
    return Dataset(t, {"F": u, "x": x + 0.005 * np.ptp(x) * rng.standard_normal(t.size)})


CANDIDATES = [StiffnessSoftening(), NonlinearDamping(velocity=True), NonlinearDamping(), FrictionDamping()]


def model_file_like():
    """The model with the file-like deviation of the device (38 Hz, damping ratio 0.03)."""
    return resonator(38.0, 0.03)


def assert_named_through(rep, cause: str, label: str, min_gain: float = 1.5) -> None:
    """The report names ``cause`` first, through the passing candidate ``label`` with the
    highest gain, and that gain exceeds ``min_gain``."""
    assert rep.cause == cause, rep.steps[0].why
    named = max((c for c in rep.steps[0].candidates if c.passed), key=lambda c: c.gain)
    assert named.label == label
    assert named.gain > min_gain


def test_friction_is_named_friction():
    rep = diagnose(model_file_like(), record(), candidates=CANDIDATES, workers=1, chain=False)
    assert_named_through(rep, "friction", FrictionDamping.label)


def test_without_friction_nothing_is_named():
    rep = diagnose(model_file_like(), record(friction=False), candidates=CANDIDATES, workers=1, chain=False)
    assert rep.cause == "none", rep.steps[0].why


def test_a_thinning_damper_is_nonlinear_damping():
    rep = diagnose(model_file_like(), record(thinning=True), candidates=CANDIDATES, workers=1, chain=False)
    assert rep.cause == "nonlinear-damping", rep.steps[0].why
    named = max((c for c in rep.steps[0].candidates if c.passed), key=lambda c: c.gain)
    assert named.label.startswith(FrictionDamping.label) and named.label.endswith("(rule 'knee-width')")
    assert named.gain > 1.5
