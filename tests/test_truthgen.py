"""Self-tests of the independent truth generator (tests/truthgen; its package docstring is the
protocol: families, causes, mechanisms, ranges, the visibility rule and the fixed seed sets).

They check that the generator is what the protocol says — deterministic per seed, effect-free
where it claims none, every effect visible by the rule, every cause and mechanism reachable —
and that its hand-written physics agrees with the model files it is drawn around (an
independent route to the same linear response).  They do not run the diagnosis.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from truthgen import SEEDS, VISIBLE, bimorph, design, draw, drives, fresh_seeds, stack
from truthgen.draws import factor
from truthgen.families import FAMILIES, ROOT, Shape
from truthgen.generator import plan
from truthgen.mechanisms import MECHANISMS, creep_cells
from truthgen.operators import HYSTERESIS, MaxwellSlip, loop_stats
from truthgen.runner import _chain, diagnose_record, score
from truthgen.system import simulate

from bondgraph import Sine
from bondgraph.data import read_csv
from bondgraph.model.modelfile import load_model
from bondgraph.numerics.simulate import simulate as bondgraph_simulate


@pytest.fixture(scope="module")
def ci_records():
    return {s: draw(s, "ci") for s in SEEDS["ci"]}


# ----------------------------------------------------------------------------- the protocol


def test_seed_sets_are_disjoint_and_meet_the_protocol():
    sets = {k: set(v) for k, v in SEEDS.items()}
    assert not sets["dev"] & sets["ci"] and not sets["dev"] & sets["bench"] and not sets["ci"] & sets["bench"]
    for name, least, nulls in (("ci", 12, 3), ("bench", 60, 15)):
        designs = [design(s) for s in SEEDS[name]]
        assert len(designs) >= least
        assert sum(not causes for _, causes in designs) >= nulls
        assert any(len(causes) == 2 for _, causes in designs)
        assert {"apa", "t215"} <= {fam for fam, _ in designs}


def test_design_walks_every_family_cause_cycle():
    """Any 6 x lcm(cycle lengths) consecutive seeds hit every (family, cause) equally often."""
    lengths = [len(f.causes) for f in FAMILIES.values()]
    span = 6 * math.lcm(*lengths)
    seen = {}
    for s in range(span):
        fam, causes = design(s)
        seen[(fam, causes)] = seen.get((fam, causes), 0) + 1
    for fam in FAMILIES.values():
        cycle = ["+".join(c for c in entry.split("+") if c != "none") for entry in fam.causes]
        for entry in set(cycle):
            causes = tuple(c for c in entry.split("+") if c)
            assert seen[(fam.name, causes)] > 0


def test_every_cause_of_every_family_has_mechanisms_and_revealing_drives():
    for fam in FAMILIES.values():
        for entry in fam.causes:
            causes = tuple(c for c in entry.split("+") if c != "none")
            for cause in causes:
                assert len(MECHANISMS[fam.physics][cause]) >= 3, (fam.name, cause)
                assert set(fam.reveal[cause]) <= set(drives.KINDS)
            assert fam.drive_kinds(causes, fam.shape("bench", causes, np.random.default_rng(0), {})), entry


def test_dev_seeds_reach_every_mechanism_of_every_cause():
    """Every mechanism a family's causes can use is drawn by some dev seed, at either size."""
    wanted = {
        (f.physics, c, name)
        for f in FAMILIES.values()
        for entry in f.causes
        for c in entry.split("+")
        if c != "none"
        for name in MECHANISMS[f.physics][c]
    }
    for size in ("ci", "bench"):
        seen = {
            (pl.family.physics, m.cause, m.name) for pl in (plan(s, size) for s in SEEDS["dev"]) for m in pl.mechanisms
        }
        assert seen == wanted, sorted(wanted - seen)


def test_factor_never_returns_the_nominal_value():
    rng = np.random.default_rng(1)
    f = np.array([factor(rng, 0.8, 1.25) for _ in range(2000)])
    assert f.min() >= 0.8 - 1e-12 and f.max() <= 1.25 + 1e-12
    assert np.all(np.abs(np.log(f)) >= math.log1p(0.02) - 1e-12)
    assert (f > 1).any() and (f < 1).any()


# ----------------------------------------------------------------------------- the records


def test_draw_is_deterministic_per_seed():
    a, b = draw(1011, "ci"), draw(1011, "ci")
    assert np.array_equal(a.t, b.t) and np.array_equal(a.V, b.V) and np.array_equal(a.x, b.x)
    assert a.truth() == {**b.truth(), "seconds": a.truth()["seconds"]}
    c = draw(1017, "ci")
    assert not np.array_equal(a.x[:100], c.x[:100])


@pytest.mark.parametrize("kind", drives.KINDS)
def test_no_drive_is_silent(kind):
    """Every drawn drive moves within its record, short records with long burst periods included
    (a silent burst drive once left the generator dividing by a zero stroke)."""
    r = drives.DriveRange(-150.0, 150.0, True, (1.0, 50.0), f_res=800.0)
    t = np.linspace(0.0, 1.8, 3601)
    for seed in range(100):
        spec = drives.draw(kind, r, 1.8, 2000.0, np.random.default_rng(seed))
        assert np.ptp(drives.signal(spec, t)) > 0, (kind, seed, spec)


def test_ci_records_follow_the_visibility_rule(ci_records):
    for seed, rec in ci_records.items():
        assert set(rec.causes) == set(design(seed)[1]), seed
        if not rec.causes:
            # effect-free: the noise-free truth is the linear device itself
            assert rec.effect_size == () and rec.mechanisms == ()
            assert np.array_equal(rec.clean, rec.clean0)
            continue
        assert min(rec.effect_size) >= VISIBLE and min(rec.visible_size) >= VISIBLE, seed
        assert len(rec.mechanisms) == len(rec.causes) == len(rec.strengths)
        if len(rec.causes) == 1:
            # the stored effect size is the record's own: RMS(with - without) / noise RMS
            size = rec.noise["gain"] * np.sqrt(np.mean((rec.clean - rec.clean0) ** 2)) / rec.noise_rms
            assert size == pytest.approx(rec.effect_size[0], rel=0.1), seed


def test_records_are_realistic_measurements(ci_records):
    for seed, rec in ci_records.items():
        ds = rec.dataset()
        assert ds.is_uniform and abs(ds.sample_rate - rec.fs) / rec.fs < 1e-3
        assert rec.noise["level"] >= 0.001 - 1e-12 and rec.noise["level"] <= 0.02
        stroke = rec.stroke * rec.noise["gain"]
        assert rec.noise_rms / stroke == pytest.approx(rec.noise["level"], rel=0.1)
        # the measurement is gain * truth + offset + noise
        resid = rec.x - rec.noise["gain"] * rec.clean - rec.noise["offset"] * rec.stroke
        assert np.sqrt(np.mean(resid**2)) == pytest.approx(rec.noise_rms, rel=1e-6)
        assert rec.params != rec.nominal
        assert abs(rec.V[0]) < 1e-6 * max(1.0, np.ptp(rec.V)) + 0.01 * np.ptp(rec.V)


def test_csv_writes_and_reads_back_without_the_truth(tmp_path, ci_records):
    rec = ci_records[SEEDS["ci"][0]]
    path = tmp_path / "rec.csv"
    rec.write_csv(path)
    ds = read_csv(path)
    assert np.array_equal(ds.t, rec.t) and np.array_equal(ds.column("V"), rec.V)
    assert np.array_equal(ds.column("x"), rec.x)
    text = path.read_text()
    for secret in (rec.cause, *rec.mechanisms):
        assert secret not in text
    assert ds.metadata["model"] == rec.model


# ----------------------------------------------------------------------------- the physics


@pytest.mark.parametrize(
    "family,overrides,signal,h,T",
    [
        ("apa", {}, Sine(amplitude=60.0, frequency=50.0, phase=-90.0, offset=60.0), 1e-5, 0.05),
        ("stack", {"lumped": True}, Sine(amplitude=100.0, frequency=500.0), 1e-6, 0.004),
        ("t215", {}, Sine(amplitude=1.0, frequency=300.0), 1e-5, 0.05),
        ("t226", {}, Sine(amplitude=1.0, frequency=400.0), 1e-5, 0.05),
    ],
)
def test_hand_written_linear_truth_matches_the_model_file(family, overrides, signal, h, T):
    """Two routes to one answer: the truth's hand-written equations at the file's values and
    the bond-graph model file simulated by the framework."""
    fam = FAMILIES[family]
    lm = load_model(ROOT / fam.model, overrides)
    t = np.arange(int(round(T / h)) + 1) * h
    res = bondgraph_simulate(lm.model, t, {"V": signal}, rtol=1e-9)
    y = simulate(fam.module.system(fam.nominal(overrides)), res["V"], h)[0]
    assert np.max(np.abs(res["x"] - y)) < 1e-4 * np.ptp(res["x"])


def test_static_gains_are_the_analytic_ones():
    p = FAMILIES["apa"].nominal({})
    sys_ = stack.system(p)
    V = np.full(50, 100.0)
    assert simulate(sys_, V, 1e-4)[0][-1] == pytest.approx(100.0 * stack.static_gain(p), rel=1e-9)
    q = FAMILIES["t215"].nominal({})
    assert simulate(bimorph.system(q), V, 1e-5)[0][-1] == pytest.approx(100.0 * bimorph.static_gain(q), rel=1e-9)


def test_cantilever_ratios_match_the_t215_beam_modes():
    q = FAMILIES["t215"].nominal({"modes": 3})
    for k in (2, 3):
        w, slope, at = bimorph.cantilever_ratios(k, 0.95)
        assert q["omega"][k - 1] / q["omega"][0] == pytest.approx(w, rel=1e-3)
        assert q["mp"][k - 1] * q["phi"][k - 1] / (q["mp"][0] * q["phi"][0]) == pytest.approx(slope * at, rel=1e-3)


@pytest.mark.parametrize("name", sorted(HYSTERESIS))
def test_field_hysteresis_operators_lag_and_are_rate_independent(name):
    op = HYSTERESIS[name](np.random.default_rng(3))
    gap, span = loop_stats(op)
    assert gap > 0.05 * span  # the descending branch lies above the rising one: dissipative
    u = np.sin(np.linspace(0, 4 * np.pi, 801))
    fine = op.apply(np.interp(np.linspace(0, 800, 3201), np.arange(801), u))[::4]
    assert np.allclose(op.apply(u), fine, atol=0.02 * span)


def test_maxwell_slip_force_is_bounded_by_its_sliders():
    op = MaxwellSlip(np.random.default_rng(5))
    y = op.apply(np.sin(np.linspace(0, 20, 2000)))
    assert np.max(np.abs(y)) <= float(op.k @ op.d) + 1e-12


def test_log_time_creep_grows_by_its_strength_per_decade():
    cells = creep_cells("log-time", 0.02, {"taus": 10 ** np.arange(-4, 4, 1 / 3)}, 10.0)
    tau, w = map(np.array, zip(*cells))
    creep = lambda t: float(np.sum(w * -np.expm1(-t / tau)))  # noqa: E731
    assert creep(1.0) - creep(0.1) == pytest.approx(0.02, rel=0.05)


def test_every_mechanism_changes_the_response():
    """Every mechanism of every family, applied at its lowest strength to a short revealing
    record, changes the noise-free response and keeps it finite."""
    for fam in FAMILIES.values():
        p = fam.nominal({})
        h, T, fs = (1e-4, 1.0, 10000.0) if fam.physics == "stack" else (2e-5, 0.3, 50000.0)
        t = np.arange(int(T / h) + 1) * h
        r = fam.drive_range(p, Shape(fs, T, h, "fast"), np.random.default_rng(0))
        for cause, mechs in MECHANISMS[fam.physics].items():
            kinds = [
                k
                for k in fam.reveal.get(cause, ())
                if k in ("steps", "chirp", "stepped-sine", "resonant-bursts", "triangle")
            ]
            if not kinds:
                continue
            V = drives.signal(drives.draw(kinds[0], r, T, fs, np.random.default_rng(1)), t)
            sys0, probes = fam.module.system(p, probes=True)
            out = simulate(sys0, V, h, probes)
            ctx = {"p": p, "fs": fs, "T": T, "h": h, "ref": fam.refs(out[0], out[1:], V), **fam.context(p)}
            for mech in mechs.values():
                if not mech.applies(ctx):
                    continue
                fx = fam.module.Effects()
                mech.apply(fx, mech.lo, mech.shape(np.random.default_rng(2), ctx), ctx)
                y = simulate(fam.module.system(p, fx), V, h)[0]
                assert np.all(np.isfinite(y)), (fam.name, mech.name)
                assert np.max(np.abs(y - out[0])) > 1e-4 * np.ptp(out[0]), (fam.name, cause, mech.name)


# ----------------------------------------------------------------------------- scoring


def test_scoring_of_null_single_and_compound_truths():
    assert score((), True, "none", [])["right"]
    assert not score((), True, "creep", ["creep"])["right"]
    assert score(("electrical",), True, "electrical-rc", ["electrical"])["right"]
    both = ("hysteresis", "creep")
    assert score(both, False, "creep", ["creep", "hysteresis"])["right"]
    assert not score(both, True, "creep", ["creep", "hysteresis"])["right"]
    half = score(both, False, "hysteresis", ["hysteresis"])
    assert not half["right"] and half["first_right"]


def test_fresh_seeds_lie_outside_every_set_and_hold_one_effect_or_none():
    fresh = fresh_seeds(1990, 30, {"apa", "t215"})
    assert len(fresh) == 30 and fresh == sorted(set(fresh)) and fresh[0] >= 1990
    assert not set(fresh) & set().union(*map(set, SEEDS.values()))
    assert all(design(s)[0] in ("apa", "t215") and len(design(s)[1]) <= 1 for s in fresh)
    with pytest.raises(ValueError, match="unknown families"):
        fresh_seeds(3000, 5, {"apa", "t251"})
    # the runs of 20 measured so far (benchmarks/README.md, "Fresh records" and later)
    assert [
        fresh_seeds(s, 20, {"apa", "t215"})[-1]
        for s in (
            3000,
            3032,
            3066,
            3100,
            3135,
            3170,
            3202,
            3236,
            3272,
            3304,
            3339,
            3373,
            3409,
            3441,
            3475,
            3511,
            3543,
            3578,
            3610,
            3646,
            3680,
            3712,
            3747,
            3782,
            3817,
            3849,
            3883,
            3919,
            3951,
            3986,
            4018,
            4054,
            4088,
            4120,
            4155,
            4190,
            4225,
        )
    ] == [
        3031,
        3063,
        3098,
        3134,
        3169,
        3201,
        3235,
        3271,
        3303,
        3338,
        3372,
        3408,
        3440,
        3474,
        3510,
        3542,
        3577,
        3609,
        3645,
        3679,
        3711,
        3746,
        3781,
        3816,
        3848,
        3882,
        3918,
        3950,
        3985,
        4017,
        4053,
        4087,
        4119,
        4154,
        4189,
        4224,
        4256,
    ]


def test_diagnosis_json_chains_are_read_in_every_shape():
    """As ``diagnose --json`` writes them (``causes`` and per-step gains in ``steps``), and the
    simpler shapes of other tools."""
    assert _chain({"cause": "none", "gain": 1.0}) == ([], [])
    assert _chain({"cause": "creep", "gain": 2.5}) == (["creep"], [2.5])
    assert _chain(
        {
            "cause": "creep",
            "causes": ["creep", "hysteresis"],
            "steps": [{"cause": "creep", "gain": 3.0}, {"cause": "hysteresis", "gain": 1.5}],
        }
    ) == (["creep", "hysteresis"], [3.0, 1.5])
    assert _chain(
        {
            "cause": "hysteresis",
            "causes": [{"cause": "hysteresis", "gain": 4.0}, {"cause": "electrical-rc", "gain": 1.3}],
        }
    ) == (["hysteresis", "electrical"], [4.0, 1.3])


def test_diagnose_helper_reports_cli_failures(tmp_path, ci_records):
    """The helper that runs one record through ``bondgraph diagnose --json`` (used by
    benchmarks/diagnosis_accuracy.py): a refused option comes back as an error, not a crash."""
    rec = ci_records[SEEDS["ci"][0]]
    out = diagnose_record(rec, workdir=tmp_path, timeout=120, extra=["--no-such-option"])
    assert out["error"].startswith("exit 2") and out["right"] is False
    assert out["truth"] == rec.label and out["wall"] > 0
