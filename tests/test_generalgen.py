"""The general-systems generator (``benchmarks/generalgen``): deterministic seeds, records
that read back and hide their truth, the intended share of effect-free draws, model files
that load and simulate, and two independent routes that agree: the generator's own truth
physics with every effect off against ``bondgraph.simulate`` of the model file at the same
parameters."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from conftest import ROOT

sys.path.insert(0, str(ROOT))

import bondgraph as bg  # noqa: E402
from benchmarks.generalgen import SYSTEMS, VOCABULARY, draw, score  # noqa: E402
from benchmarks.generalgen.__main__ import counts, parse_seeds  # noqa: E402
from benchmarks.generalgen.effects import FORMS  # noqa: E402
from benchmarks.generalgen.network import Link, Network, drive_spectrum, integrate, linear_response  # noqa: E402
from benchmarks.generalgen.record import generate, realize  # noqa: E402
from benchmarks.generalgen.scoring import summarise  # noqa: E402
from bondgraph.data import read_csv  # noqa: E402
from bondgraph.model.modelfile import load_model  # noqa: E402

#: a development seed with a short record (an RLC circuit under steps, 11 584 samples)
SHORT = 3


def test_draws_are_deterministic_and_independent_of_order():
    a = [draw(s) for s in (5, 17, 42)]
    b = [draw(s) for s in (42, 17, 5)][::-1]
    for x, y in zip(a, b):
        assert (x.system.name, x.fs, x.n, x.effect, x.noise) == (y.system.name, y.fs, y.n, y.effect, y.noise)
        assert x.params == y.params
        np.testing.assert_array_equal(x.drive.evaluate(1 / x.fs, 50, 2), y.drive.evaluate(1 / y.fs, 50, 2))


def test_a_seed_is_one_deterministic_record():
    d = draw(SHORT)
    assert d.n < 20000  # keeps this test fast
    r1, r2 = realize(d), realize(draw(SHORT))
    np.testing.assert_array_equal(r1.y, r2.y)
    np.testing.assert_array_equal(r1.u, r2.u)
    assert json.dumps(r1.truth, default=str) == json.dumps(r2.truth, default=str)


def test_the_csv_reads_back_and_holds_no_truth(tmp_path):
    csv, truth_path, model = generate(SHORT, tmp_path)
    truth = json.loads(truth_path.read_text())
    ds = read_csv(str(csv))
    sysm = SYSTEMS[truth["system"]]
    assert ds.names == ("t", sysm.input, sysm.output)
    assert len(ds) == truth["samples"]
    assert ds.sample_rate == pytest.approx(truth["fs"])
    assert ds.is_uniform
    # nothing of the truth: no cause, site, form or parameter in the file's text
    text = csv.read_text()
    header = "".join(line for line in text.splitlines(True) if not line[:1].isdigit() and not line.startswith("-"))
    words = set(VOCABULARY) | {f for forms in FORMS.values() for f in forms} | {"truth", "cause", "site", "effect"}
    assert not any(w in header.lower() for w in words - {"none"})
    assert set(ds.metadata) == {"record", "source"}
    assert model.read_text() == sysm.model_file.read_text()
    assert truth["model"] == model.name and truth["cause"] in VOCABULARY


def test_about_one_in_five_development_draws_is_effect_free():
    causes = [draw(s).effect.cause for s in range(100)]
    share = causes.count("none") / 100
    assert 0.12 <= share <= 0.28  # 0.2 intended; binomial sd 0.04
    assert set(causes) == set(VOCABULARY)  # every cause drawn at least once
    assert all(draw(s).effect.count in (1, 2) for s in range(100) if draw(s).effect.cause == "higher-mode")


def test_draws_stay_inside_the_declared_ranges():
    for s in range(100):
        d = draw(s)
        assert 10_000 <= d.n <= 150_000 and 1000 <= d.fs <= 50_000
        for k, v in d.params.items():
            factor = v / d.model_params[k]
            assert 1 / d.system.tolerance(k) < factor < d.system.tolerance(k)


def test_counting_reads_only_the_draws():
    assert parse_seeds(["0-2", "5", "2"]) == [0, 1, 2, 5]
    with pytest.raises(ValueError):
        parse_seeds(["3-1"])
    text = counts(list(range(20)))
    assert "none" in text and "higher-mode by count" in text


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_model_file_loads_simulates_and_has_the_truths_modes(name):
    sysm = SYSTEMS[name]
    lm = load_model(sysm.model_file)
    res = bg.simulate(lm.model, np.linspace(0, lm.experiment.t_end, 201), lm.experiment.inputs)
    assert np.all(np.isfinite(res[sysm.output]))
    lin = bg.linearize(bg.derive(lm.model), input=sysm.input, output=sysm.output)
    w = np.sort(np.asarray(lin.summary()["natural_frequencies_rad_s"]))
    np.testing.assert_allclose(w, sysm.network(sysm.defaults()).modes()[0], rtol=1e-9)


@pytest.mark.parametrize("name", sorted(SYSTEMS))
def test_truth_without_effects_equals_the_model_file_simulated_by_bondgraph(name):
    """Two independent routes: the generator's RK4 (fixed step h = dt/16) on its own network
    and bondgraph's compiled integrator on the model file (rtol 1e-10), both at the same
    detuned parameters, on a sine at 0.7 times the first mode from rest.  They agree to
    1e-7 of the output's peak (measured: 2e-12 to 8e-10)."""
    sysm = SYSTEMS[name]
    p = {k: v * (1.12 if i % 2 else 0.91) for i, (k, v) in enumerate(sysm.defaults().items())}
    net = sysm.network(p)
    f1, f_top = net.modes()[0][[0, -1]] / (2 * np.pi)
    dt, n, os = 1 / (40 * f_top), 3000, 16
    amp, fd = sysm.drive_level, 0.7 * f1
    ours = integrate(net, amp * np.sin(2 * np.pi * fd * np.arange(2 * n * os + 1) * dt / (2 * os)), dt / os, os).y
    lm = load_model(sysm.model_file, p)
    theirs = bg.simulate(lm.model, np.arange(n + 1) * dt, {sysm.input: bg.Sine(amp, fd)}, rtol=1e-10, atol=1e-16)
    theirs = theirs[sysm.output]
    assert np.max(np.abs(ours - theirs)) < 1e-7 * np.max(np.abs(theirs))


def test_frequency_route_agrees_with_the_integrator():
    """The visibility rule's linear route (modal residues times the drive's spectrum) against
    the RK4 truth, on a faded-in chirp through the three-mass chain: 1e-6 of the RMS."""
    sysm = SYSTEMS["chain3"]
    net = sysm.network(sysm.defaults())
    fs, n, os = 2000.0, 8000, 16
    dt = 1 / fs

    def drive(q):
        t = np.arange(n * q + 1) * dt / q
        return 10 * np.sin(2 * np.pi * (5 * t + 60 * t * t / (2 * n * dt))) * np.clip(t / 0.3, 0, 1) ** 2

    ours = integrate(net, drive(2 * os), dt / os, os).y[:n]
    om, ze = net.modes()
    fft = linear_response(net, drive_spectrum(drive(4), 4, n, dt, 25 / np.min(om * ze)))
    assert np.sqrt(np.mean((ours - fft) ** 2)) < 1e-6 * np.std(ours)


@pytest.mark.parametrize("law", ["bouc-wen", "prandtl-ishlinskii", "preisach"])
def test_a_hysteretic_spring_takes_energy_from_the_mass(law):
    """Passivity: under a slow sine, each hysteretic spring law's force-elongation loop
    encloses energy the spring absorbs (the integral of force over elongation, around a
    settled period, is positive: a spring that gave it back would drive the mass)."""
    base = Network(np.array([1.0]), [Link(0, -1, 1e4, 0.5)], np.array([1.0]), np.array([1.0]))
    fs, os, n = 2000.0, 16, 4000
    h = 1 / (fs * os)
    t = np.arange(2 * n * os + 1) * h / 2
    slow = 50 * np.sin(2 * np.pi * 2.0 * t) * np.clip(t / 0.5, 0, 1)
    net = base.copy()
    link = net.links[0]
    if law == "bouc-wen":
        link.spring_law, link.spring_par = law, (0.4, 0.7 / 1e-3, 0.3 / 1e-3, 1.0)
    elif law == "prandtl-ishlinskii":
        link.spring_law, link.spring_par, link.plays = law, (0.5,), ((1e-3, 0.3), (2e-3, 0.2))
    else:
        grid = np.linspace(-5e-3, 5e-3, 6)
        link.spring_law, link.spring_par = law, (0.7, 1e-3)
        link.relays = tuple((a, b, 1 / 15) for i, a in enumerate(grid) for b in grid[:i])
    net.out_link = 0
    tr = integrate(net, slow, h, os)
    e, f = tr.elongation[0], tr.y
    half = slice(n // 2, n)  # one settled period and more
    absorbed = np.trapezoid(f[half], e[half])
    assert absorbed > 0.03 * np.ptp(f[half]) * np.ptp(e[half])  # a loop, run the passive way


def test_hardening_raises_the_resonance():
    """A cubic hardening spring raises the free-oscillation frequency."""
    base = Network(np.array([1.0]), [Link(0, -1, 1e4, 0.5)], np.array([1.0]), np.array([1.0]))
    fs, os, n = 2000.0, 16, 4000
    h = 1 / (fs * os)
    t = np.arange(2 * n * os + 1) * h / 2
    lin = integrate(base, 300 * np.exp(-(((t - 0.01) / 0.002) ** 2)), h, os).y
    hard = base.copy()
    hard.links[0].spring_law, hard.links[0].spring_par = "poly", (1e-3, 0.0, 2.0, 0.0)
    stiff = integrate(hard, 300 * np.exp(-(((t - 0.01) / 0.002) ** 2)), h, os).y

    def crossings(y):
        s = np.signbit(y[200:])
        return np.count_nonzero(s[1:] != s[:-1])

    assert crossings(stiff) > crossings(lin)


def test_scoring_rule():
    none = {"cause": "none", "site": None}
    assert score(none, {"causes": []})["right"]
    assert not score(none, {"causes": ["drift"]})["right"]
    hard = {"cause": "hardening", "site": "spring1", "site_aliases": ["spring1"]}
    r = score(hard, {"causes": ["hardening", "drift"], "steps": [{"cause": "hardening", "site": "spring1"}]})
    assert r["right"] and r["site_right"] is True
    r = score(hard, {"causes": ["hardening"], "steps": [{"cause": "hardening"}]})
    assert r["right"] and r["site_right"] == "unknown"
    r = score(hard, {"causes": ["hardening"], "steps": [{"cause": "hardening", "site": "spring12"}]})
    assert r["site_right"] is False
    assert not score(hard, {"causes": ["softening", "hardening"], "steps": []})["right"]
    modes = {"cause": "higher-mode", "site": "mass1", "site_aliases": ["mass1"], "count": 2}
    assert not score(modes, {"causes": ["higher-mode"], "steps": [{"cause": "higher-mode", "site": "mass1"}]})["right"]
    two = {
        "causes": ["higher-mode", "higher-mode"],
        "steps": [{"cause": "higher-mode"}, {"cause": "higher-mode", "site": "mass1"}],
    }
    r = score(modes, two)
    assert r["right"] and r["site_right"] is True
    assert not score(modes, {"causes": ["drift", "higher-mode", "higher-mode"]})["right"]
    err = score(hard, {"error": "exit 1: boom"})
    assert not err["right"] and err["first"] == "error"
    rows = [
        {"truth": "none", "visible": True, **score(none, {"causes": []})},
        {"truth": "hardening", "visible": True, **r},
        {"truth": "hardening", "visible": False, **err},
    ]
    s = summarise(rows)
    assert (s["scored"], s["invisible"], s["right"], s["false_alarms"]) == (2, 1, 2, 0)


def test_the_readme_counts_are_the_draws():
    """benchmarks/README.md shows the causes drawn for both seed sets: they are the draws'."""
    text = (ROOT / "benchmarks" / "README.md").read_text()
    section = text.split("### Causes drawn", 1)[1].split("###", 1)[0]
    shown = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 3 and cells[0].split(" ")[0] in VOCABULARY:
            shown[cells[0].split(" ")[0]] = (int(cells[1].split()[0]), int(cells[2].split()[0]))
    assert set(shown) == set(VOCABULARY)
    for column, seeds in ((0, range(100)), (1, range(1000, 1200))):
        causes = [draw(s).effect.cause for s in seeds]
        assert {c: causes.count(c) for c in VOCABULARY} == {c: v[column] for c, v in shown.items()}
