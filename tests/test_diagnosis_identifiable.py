"""Which linear parameters the calibration frees: a parameter whose effect the pivot rule
finds small beside the largest is still calibrated when, across its tolerance, it moves the
output by ``diagnosis.tolerance_z`` times the calibrated model's residual, at least the noise
floor (the rule ``calibration.visible_within_tolerance``), and held when the noise hides it.

The record is the exact response (scipy.signal.lsim) of two modes in parallel seen at their
common drive point, m_i x_i'' + c_i x_i' + k_i x_i = F, x = x_1 + x_2: the first at 32 Hz in
the drive's band (5-450 Hz), the second at 640 Hz above it, so its mass and damping touch the
output only a little, which the pivot rule holds.  The truth's second damping is 3 times the
model file's, outside the default tolerance (×/÷2).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lsim

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis.calibration import calibrate
from bondgraph.diagnosis.context import Context

NOMINAL = {"m1": 0.5, "k1": 2e4, "c1": 5.0, "m2": 0.01, "k2": 1.6e5, "c2": 1.0}
TRUTH = {**NOMINAL, "k1": 2.2e4, "c2": 3.0}
FS = 20000.0


def two_modes(p=NOMINAL) -> bg.Model:
    g = bg.Model("two modes")
    F = g.input("F", "N")
    g.add(bg.Se("force", F), bg.J0("drive"))
    g.bond("force", "drive")
    x = 0
    for i in (1, 2):
        m, k, c = (g.parameter(f"{q}{i}", p[f"{q}{i}"]) for q in "mkc")
        g.add(bg.J1(f"mode{i}"), bg.I(f"mass{i}", m), bg.C(f"spring{i}", 1 / k), bg.R(f"damper{i}", c))
        g.bond("drive", f"mode{i}")
        for e in ("mass", "spring", "damper"):
            g.bond(f"mode{i}", f"{e}{i}")
        x = x + g.displacement(f"spring{i}")
    g.output("x", x, "m")
    return g


def record(noise: float) -> Dataset:
    """1 s of a 30-tone multisine faded in over 0.1 s, with white noise of ``noise`` times the
    output's RMS."""
    t = np.arange(0.0, 1.0, 1 / FS)
    rng = np.random.default_rng(0)
    f = np.geomspace(5.0, 450.0, 30)
    u = np.sin(2 * np.pi * f[:, None] * t + rng.uniform(0, 2 * np.pi, f.size)[:, None]).sum(axis=0)
    u *= np.clip(t / 0.1, 0.0, 1.0)
    d1, d2 = ([TRUTH[f"m{i}"], TRUTH[f"c{i}"], TRUTH[f"k{i}"]] for i in (1, 2))
    _, y, _ = lsim((np.polyadd(d1, d2), np.polymul(d1, d2)), u, t)
    y = y + noise * np.std(y) * np.random.default_rng(1).normal(size=y.size)
    return Dataset(t, {"F": u, "x": y})


def test_a_parameter_the_pivot_holds_is_calibrated_when_it_stands_above_the_noise():
    ctx = Context(two_modes(), record(1e-3), "F", "x")
    _, cal, _ = calibrate(ctx)
    assert set(cal.free) == set(NOMINAL)
    said = [n for n in ctx.notes if "the calibrated model's residual" in n]
    assert said and said[0].startswith("m2 calibrated after all: within its tolerance it moves the output by"), (
        ctx.notes
    )
    # the second mode's damping ratio the data show (outside the tolerance; a scale-free ratio:
    # the output cannot tell every mass, stiffness and damping scaled together)
    ratio = cal.values["c2"] / cal.values["m2"] / (TRUTH["c2"] / TRUTH["m2"])
    assert abs(ratio - 1) < 0.05, ratio
    # ten times the noise: the same change drowns in it, and the mass is held
    ctx = Context(two_modes(), record(1e-2), "F", "x")
    _, cal, _ = calibrate(ctx)
    assert "m2" in cal.held and not any("the calibrated model's residual" in n for n in ctx.notes), ctx.notes
