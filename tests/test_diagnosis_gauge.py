"""Exact scale symmetries of a calibration (bondgraph.diagnosis.gauge): found from the model's
output alone, and the point kept is the one nearest the model file's values, with the output
unchanged.

The records are the exact responses of the linear systems (scipy.signal.lsim), not the
framework's: a mass-spring-damper read by its displacement (every m, c, k scaled by s moves x
by 1/s, which the sensor gain takes back) and a series RLC circuit read by the capacitor's
voltage (R, L and 1/C scaled together change nothing at all).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lsim

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.diagnosis.context import Context
from bondgraph.diagnosis.gauge import fix_scales, scale_start, scale_symmetries

FS = 2000.0


def msd(m=0.5, k=2e4, c=5.0) -> bg.Model:
    g = bg.Model("msd")
    F = g.input("F", "N")
    pm, pk, pc = g.parameter("m1", m), g.parameter("k1", k), g.parameter("c1", c)
    g.add(bg.Se("force", F), bg.J1("v"), bg.I("mass1", pm), bg.C("spring1", 1 / pk), bg.R("damper1", pc))
    g.bond("force", "v")
    for e in ("mass1", "spring1", "damper1"):
        g.bond("v", e)
    g.output("x", g.displacement("spring1"), "m")
    return g


def rlc(R=10.0, L=0.05, C=2e-5) -> bg.Model:
    g = bg.Model("rlc")
    V = g.input("V", "V")
    pR, pL, pC = g.parameter("R", R), g.parameter("L", L), g.parameter("C", C)
    g.add(bg.Se("source", V), bg.J1("i"), bg.R("resistor", pR), bg.I("inductor", pL), bg.C("capacitor", pC))
    g.bond("source", "i")
    for e in ("resistor", "inductor", "capacitor"):
        g.bond("i", e)
    g.output("vC", g.effort("capacitor"), "V")
    return g


def record(num, den, name_in, name_out, seed=0) -> Dataset:
    t = np.arange(0.0, 2.0, 1 / FS)
    rng = np.random.default_rng(seed)
    f = np.geomspace(2.0, 300.0, 30)
    u = np.sin(2 * np.pi * f[:, None] * t + rng.uniform(0, 2 * np.pi, f.size)[:, None]).sum(axis=0)
    _, y, _ = lsim((num, den), u, t)
    return Dataset(t, {name_in: u, name_out: y})


CASES = {
    # m x'' + c x' + k x = F with m, c, k off the model file's 0.5, 5, 2e4
    "msd": (msd, ["m1", "k1", "c1"], ([1.0], [0.6, 3.0, 2.6e4]), "F", "x", {"m1": 1, "k1": 1, "c1": 1}),
    # vC / V = 1 / (L C s² + R C s + 1)
    "rlc": (rlc, ["R", "L", "C"], ([1.0], [0.06 * 1.5e-5, 12.0 * 1.5e-5, 1.0]), "V", "vC", {"R": 1, "L": 1, "C": -1}),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_the_scale_symmetry_is_found_and_the_nominal_point_kept(case):
    build, names, (num, den), u, y, exponents = CASES[case]
    model = build()
    ctx = Context(model, record(num, den, u, y), u, y, None, None, 0.3, lambda s: None, "linear")
    nominal = {n: ctx.ident.current(n) for n in names}
    far = {n: nominal[n] * 7.0 ** exponents[n] for n in names}  # on the orbit of the nominal point
    raw = ctx.ident.predict(far)
    found = scale_symmetries(ctx, names, far, raw)
    assert len(found) == 1
    e = found[0] * np.sign(found[0][0])
    assert list(e) == [exponents[n] * exponents[names[0]] for n in names]
    bounds = {n: (nominal[n] / 100, nominal[n] * 100) for n in names}
    factors = {n: 1.5 for n in names}
    moved, moved_raw, _ = fix_scales(ctx, names, far, raw, nominal, factors, bounds)
    for n in names:
        assert moved[n] == pytest.approx(nominal[n], rel=1e-9)
    idx = ctx.ident.fit_idx
    g, *_ = np.linalg.lstsq(moved_raw[idx, None], raw[idx], rcond=None)
    assert np.max(np.abs(g[0] * moved_raw - raw)) <= 1e-9 * np.max(np.abs(raw))


def test_no_symmetry_when_a_mass_is_held():
    """With the mass not calibrated, scaling k and c alone moves the resonance: no symmetry."""
    model = msd()
    ctx = Context(
        model, record([1.0], [0.6, 3.0, 2.6e4], "F", "x"), "F", "x", None, None, 0.3, lambda s: None, "linear"
    )
    values = {"k1": 2.6e4, "c1": 3.0}
    assert scale_symmetries(ctx, ["k1", "c1"], values, ctx.ident.predict(values)) == []


def test_the_scale_start_carries_every_value_back_with_a_parameter_held():
    """The damping held at the model file's value, the mass and stiffness calibrated ×0.31
    (a calibration that slid along the whole set's symmetry until the device scaled by 0.31
    has the held damping: the true damping is 1/0.31 times the model file's): the start moves
    every parameter, the held damping included, by one factor to the point nearest the model
    file's values, so the output is unchanged and the device is found at its own scale; within
    narrower bounds the start is clipped onto them."""
    model = msd()
    ctx = Context(
        model, record([1.0], [0.6, 3.0, 2.6e4], "F", "x"), "F", "x", None, None, 0.3, lambda s: None, "linear"
    )
    names = ["m1", "k1", "c1"]
    nominal = {n: ctx.ident.current(n) for n in names}
    truth = {"m1": 1.1 * nominal["m1"], "k1": 0.9 * nominal["k1"], "c1": 3.2 * nominal["c1"]}
    values = {n: truth[n] * nominal["c1"] / truth["c1"] for n in names}  # slid: c1 at the model's
    raw = ctx.ident.predict(values)
    factors = {"m1": 1.2, "k1": 1.5, "c1": 4.0}
    wide = {n: (nominal[n] / 100, nominal[n] * 100) for n in names}
    start = scale_start(ctx, names, values, raw, nominal, factors, wide)
    assert set(start) == set(names)
    moved = ctx.ident.predict(start)
    g = float(moved @ raw / (moved @ moved))
    assert np.linalg.norm(g * moved - raw) <= 1e-6 * np.linalg.norm(raw)  # the output unchanged
    s = start["m1"] / truth["m1"]  # the device at one scale (which the data cannot tell) ...
    for n in names:
        assert start[n] / truth[n] == pytest.approx(s, rel=1e-9)
        assert nominal[n] / factors[n] < start[n] < nominal[n] * factors[n]  # ... a plausible one
    assert s == pytest.approx(0.926, abs=0.01)  # nearest: the narrow mass and stiffness weigh most
    narrow = {n: (nominal[n] / 1.2, nominal[n] * 1.2) for n in names}
    start = scale_start(ctx, names, values, raw, nominal, factors, narrow)
    assert start["c1"] == pytest.approx(1.2 * nominal["c1"], rel=1e-12)


def test_no_scale_start_without_a_symmetry_of_the_whole_set():
    """The RLC circuit's symmetry needs R, L and 1/C together; with only R given, none moves."""
    model = rlc()
    ctx = Context(
        model,
        record([1.0], [0.06 * 1.5e-5, 12.0 * 1.5e-5, 1.0], "V", "vC"),
        "V",
        "vC",
        None,
        None,
        0.3,
        lambda s: None,
        "linear",
    )
    values = {"R": 12.0}
    raw = ctx.ident.predict(values)
    assert scale_start(ctx, ["R"], values, raw, {"R": 10.0}, {"R": 1.5}, {"R": (1.0, 100.0)}) is None
