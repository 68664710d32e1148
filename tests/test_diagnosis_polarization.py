"""A polarization that saturates inside the dynamics is named saturation, through the term on
the dipole capacitance rather than a curve on the drive.

The truth is written here: the APA-120ML model file's structure (Rodriguez-Fortun et al.,
Mechatronics 20 (2010), Fig. 11) whose dipole saturates with the field across it, E = E_s·
atanh(p/p_s) in place of E = k_x·p (same slope at zero; not the candidate's polynomial),
p_s set so that the dipole falls 11 % short of linear at the record's peak field.  Driven by
a unipolar chirp 5 → 400 Hz at two levels (0-24 V, then 0-120 V), 10 kHz × 1 s, white noise
of 0.3 % of the stroke.  The field across the dipole is the drive less the back-coupling of
the stack's force, which the large rate-dependence term (c·ẋ) makes lag and grow with the
frequency: a curve on the drive cannot place the saturation where the dipole meets it.  The
model says c 20 % lower and K 10 % higher.

Asserted: the cause is saturation, named through the term on the dipole capacitance, which
gains more than the drive-side curve; the same record with a linear dipole is effect-free.
"""

import numpy as np
import sympy as sp
from conftest import MODELS, two_level_chirp
from test_diagnosis_friction import assert_named_through

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis import diagnose, model_file_options
from bondgraph.diagnosis.rewrite import modify_law
from bondgraph.model.modelfile import load_model
from library.extensions import InputHysteresis, InputRC, InputSaturation, PolarizationSaturation

FS, T = 10_000.0, 1.0
CANDIDATES = [InputSaturation(), PolarizationSaturation(), InputRC(), InputHysteresis()]


def drive(t):
    """A unipolar chirp 5 → 400 Hz in each half, 0-24 V then 0-120 V."""
    return two_level_chirp(t, T, 5.0, 400.0, 12.0, 60.0)


def record(saturating=True, seed=5):
    t = np.arange(int(T * FS)) / FS
    u = drive(t)
    lm = load_model(MODELS / "apa120ml.py")
    truth = lm.model
    if saturating:
        table = {str(k): float(v) for k, v in truth.parameter_table().items()}
        kx, l = table["kx"], table["l"]
        ps = 1.6 * 120.0 / l / kx  # the dipole at the peak field, linear, is 1/1.6 of p_s
        modify_law(truth, "stack.C_NL", lambda q, old: kx * ps * sp.atanh(q / ps))
    res = bg.simulate(truth, t, {"V": bg.PiecewiseLinear(t, u)}, rtol=1e-9, method="dopri5")
    x = res["x"]
    rng = np.random.default_rng(seed)
    return Dataset(t, {"V": u, "x": x + 0.003 * np.ptp(x) * rng.standard_normal(t.size)})


def model_file_like():
    lm = load_model(MODELS / "apa120ml.py", {"c": 0.8 * 3000.0, "K": 1.1 * 10.77e6})
    return lm.model, model_file_options(lm.module)


def test_a_dipole_that_saturates_inside_the_dynamics_is_named_saturation():
    model, options = model_file_like()
    rep = diagnose(model, record(), candidates=CANDIDATES, workers=1, chain=False, **options)
    assert_named_through(rep, "saturation", PolarizationSaturation.label)
    gains = {c.label: c.gain for c in rep.steps[0].candidates}
    assert gains[PolarizationSaturation.label] > 1.3 * gains[InputSaturation.label], gains


def test_with_a_linear_dipole_nothing_is_named():
    model, options = model_file_like()
    rep = diagnose(model, record(saturating=False), candidates=CANDIDATES, workers=1, chain=False, **options)
    assert rep.cause == "none", rep.steps[0].why
