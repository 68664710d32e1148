"""The compliant moving mass (``OutputMode``): the inertia element split into m1 = μ·M and
m2 = (1 − μ)·M joined by a spring tuned to the two-mass mode ω.  Checked against the
eigenvalue problem of the same two masses written by hand: a mass M = 1 kg on a spring
(40 Hz), split at μ = 0.3 with the shell mode asked at 600 Hz.  The extended bond graph's
two natural frequencies are those of the hand-written 2-DOF system, the lower one still the
40 Hz of the whole mass (the total mass is unchanged, none added), and below it the response
is the unsplit model's."""
import math

import numpy as np
from scipy import linalg

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis import View
from bondgraph.diagnosis.calibration import calibrate
from bondgraph.diagnosis.context import Context
from bondgraph.linearize import linearize
from library.extensions import OutputMode
from test_diagnosis_friction import resonator

F0, MU, F_SHELL = 40.0, 0.3, 600.0


def view_of_resonator():
    t = np.arange(4000) / 2000.0
    u = np.sin(2 * np.pi * (5 * t + 20 * t ** 2))
    y = bg.simulate(resonator(), t, {"F": bg.PiecewiseLinear(t, u)}, rtol=1e-9)["x"]
    ctx = Context(resonator(), Dataset(t, {"F": u, "x": y}))
    state, cal, _ = calibrate(ctx)
    return View(ctx, state, cal.free)


def test_the_split_mass_has_the_two_mass_modes_of_the_same_masses_by_hand():
    view = view_of_resonator()
    ext = OutputMode().build(view, view.rewrite(), 2 * math.pi * F_SHELL, 0.001, MU)
    lin = linearize(bg.derive(ext), "F", "x")
    # by hand: ground -k- m1 -k2- m2, k2 = ω²·m1·m2/M
    M, k = 1.0, (2 * math.pi * F0) ** 2
    m1, m2 = MU * M, (1 - MU) * M
    k2 = (2 * math.pi * F_SHELL) ** 2 * m1 * m2 / M
    w2 = linalg.eigvals(np.array([[k + k2, -k2], [-k2, k2]]), np.diag([m1, m2])).real
    expected = np.sort(np.sqrt(w2))
    np.testing.assert_allclose(lin.natural_frequencies, expected, rtol=2e-3)
    assert abs(expected[0] / (2 * math.pi * F0) - 1) < 0.05      # still the whole mass's mode
    # below the whole mass's mode the split leaves the response as it was
    base = linearize(bg.derive(view.rewrite()), "F", "x")
    w = 2 * math.pi * np.array([5.0, 20.0])
    ratio = np.abs(bg.lti.frequency_response(lin.A, lin.B, lin.C, lin.D, w)
                   / bg.lti.frequency_response(base.A, base.B, base.C, base.D, w))
    np.testing.assert_allclose(ratio, 1.0, atol=0.02)
