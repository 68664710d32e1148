"""A stiffness that softens with the drive's field is named softening, inside the dynamics.

The truth is written here: a mass on a spring and a damper (40 Hz, damping ratio 0.02; the
model says 38 Hz and 0.03) whose spring softens linearly with the drive's magnitude,
k(F) = k0·(1 − 0.2·|F|/F_max) (the bender's k_a(E) law, Wood, Steltz & Fearing, ICRA 2005,
Sec. III-B; not the candidate's even quadratic form), driven by the same 10 → 40 Hz chirp up to
the resonance twice, at a low and at a five times higher unipolar level (as a piezo
is driven), 2 kHz × 4 s, white noise of 0.5 % of the stroke.  At the higher level the
resonance sits 4 % lower, which a curve on the drive cannot produce and amplitude-dependent
(cubic) softening of the spring explains only in part.

Asserted: the cause is softening, named through the field-dependent stiffness; the same
record with a constant spring is effect-free.
"""

import numpy as np
import sympy as sp
from conftest import two_level_chirp
from test_diagnosis_friction import assert_named_through, model_file_like, resonator

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis import diagnose
from bondgraph.diagnosis.rewrite import modify_law
from library.extensions import (
    FieldStiffness,
    FrictionDamping,
    InputExpansion,
    InputSaturation,
    NonlinearDamping,
    StiffnessSoftening,
)

FS, T = 2000.0, 4.0
CANDIDATES = [
    InputSaturation(),
    InputExpansion(),
    StiffnessSoftening(),
    FieldStiffness(),
    NonlinearDamping(velocity=True),
]


def drive(t):
    """The chirp 10 → 40 Hz in each half, 0-0.4 N then 0-2 N."""
    return two_level_chirp(t, T, 10.0, 40.0, 0.2, 1.0)


def record(field=True, seed=4):
    t = np.arange(int(T * FS)) / FS
    u = drive(t)
    truth = resonator()
    if field:
        F = truth.inputs["F"].symbol
        fmax = float(np.max(np.abs(u)))
        modify_law(truth, "k", lambda q, old: old * (1 - 0.2 * sp.Abs(F) / fmax))
    x = bg.simulate(truth, t, {"F": bg.PiecewiseLinear(t, u)}, rtol=1e-9, method="dopri5")["x"]
    rng = np.random.default_rng(seed)
    return Dataset(t, {"F": u, "x": x + 0.005 * np.ptp(x) * rng.standard_normal(t.size)})


def test_a_stiffness_that_softens_with_the_field_is_named_softening():
    rep = diagnose(model_file_like(), record(), candidates=CANDIDATES, workers=1, chain=False)
    assert_named_through(rep, "softening", FieldStiffness.label)


def test_without_the_field_dependence_nothing_is_named():
    rep = diagnose(model_file_like(), record(field=False), candidates=CANDIDATES, workers=1, chain=False)
    assert rep.cause == "none", rep.steps[0].why


def test_after_a_structural_cause_the_field_is_the_models_input():
    """Once friction is named (a structural cause: no drive transform of a linear core is left),
    the field law is written on the model's input; it was None there and ended the diagnosis
    with an internal error.  The chain is the friction alone."""
    from test_diagnosis_friction import record as friction_record

    rep = diagnose(model_file_like(), friction_record(), candidates=[FrictionDamping(), FieldStiffness()], workers=1)
    assert rep.causes == ["friction"], [s.why for s in rep.steps]
    tried = [c for c in rep.steps[1].candidates if c.label == FieldStiffness.label]
    assert tried and not tried[0].skipped and not tried[0].error
