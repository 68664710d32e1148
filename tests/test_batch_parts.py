"""Batch runs without a cluster: sampling designs, scalar outputs, the per-worker memo,
sensitivities on functions whose answer is known, the table writers and the CLI's checks."""

import csv
import json
import math
import sys

import numpy as np
import pytest
from conftest import MODELS
from scipy import stats

from bondgraph import config
from bondgraph.batch import analysis, jobs, sampling
from bondgraph.batch.runs import simulation_options
from bondgraph.batch.table import Table
from bondgraph.cli import main
from bondgraph.model.modelfile import load_model
from bondgraph.numerics.simulate import Simulator
from bondgraph.support.errors import UsageError

MSD = """
from bondgraph import C, Experiment, I, J1, Model, Parameter, R, Se, Step

PARAMETERS = [Parameter("m", 2.0, "kg", "mass"), Parameter("k", 800.0, "N/m", "stiffness"),
              Parameter("c", 4.0, "N*s/m", "damping"), Parameter("springs", 1, "", "springs in parallel")]
EXPERIMENT = Experiment(t_end=3.0, dt=1e-3, inputs={"F": Step(1.0)})

def build(p):
    g = Model("msd")
    F = g.input("F", "N")
    g.add(Se("force", F), J1("v"), I("mass", p.m), R("damper", p.c))
    for e in ("force", "mass", "damper"):
        g.bond("v", e) if e != "force" else g.bond("force", "v")
    for j in range(p.springs):
        g.add(C(f"spring{j}", 1 / p.k))
        g.bond("v", f"spring{j}")
    g.output("x", g.displacement("spring0"), "m")
    return g
"""


@pytest.fixture
def msd(tmp_path):
    path = tmp_path / "msd.py"
    path.write_text(MSD)
    return str(path)


# ---- sampling -------------------------------------------------------------------------------------
SPACE = {"K": "normal(10.77e6, 5%)", "c": "uniform(2000, 3000)", "M": "loguniform(0.1, 0.2)"}


def test_random_draws_are_the_inverse_cdf_of_seeded_uniforms():
    space = sampling.parse_space([f"{k}={v}" for k, v in SPACE.items()])
    runs = sampling.design_points(space, "random", 50, seed=7)
    u = np.random.default_rng(7).random((50, 3))
    assert [r["K"] for r in runs] == list(stats.norm(10.77e6, 0.05 * 10.77e6).ppf(u[:, 0]))
    assert [r["c"] for r in runs] == list(stats.uniform(2000, 1000).ppf(u[:, 1]))
    assert [r["M"] for r in runs] == list(stats.loguniform(0.1, 0.2).ppf(u[:, 2]))
    assert sampling.design_points(space, "random", 50, seed=7) == runs
    assert sampling.design_points(space, "random", 50, seed=8) != runs


def test_bounded_and_log_distributions_stay_in_their_bounds():
    n = 4000
    tn = sampling.parse_spec("normal(1, 0.5, 0.8, 2)")
    x = tn.ppf(np.random.default_rng(1).random(n))
    assert x.min() >= 0.8 and x.max() <= 2.0
    lu = sampling.loguniform(1e-3, 1e1)
    logs = np.log10(lu.ppf(np.random.default_rng(2).random(n)))
    assert stats.kstest(logs, stats.uniform(-3, 4).cdf).pvalue > 0.01  # uniform in the logarithm


def test_latin_hypercube_puts_one_draw_in_each_stratum():
    space = {"a": sampling.uniform(0, 1), "b": sampling.normal(5, 1)}
    runs = sampling.design_points(space, "lhs", 20, seed=3)
    for name in space:
        u = space[name].dist.cdf([r[name] for r in runs])
        assert sorted(np.floor(u * 20).astype(int)) == list(range(20))


def test_grid_is_the_full_factorial_and_oat_moves_one_parameter_at_a_time():
    space = sampling.parse_space(["a=linspace(1, 3, 3)", "b=values(none, bouc-wen)"])
    grid = sampling.design_points(space, "grid")
    assert grid == [{"a": a, "b": b} for a in (1.0, 2.0, 3.0) for b in ("none", "bouc-wen")]
    oat = sampling.design_points(
        {"a": sampling.uniform(1, 3), "b": sampling.normal(10, 1)}, "oat", nominal={"a": 2.0, "b": 10.0}
    )
    assert oat == [
        {"a": 2.0, "b": 10.0},
        {"a": 1.0, "b": 10.0},
        {"a": 3.0, "b": 10.0},
        {"a": 2.0, "b": 8.0},
        {"a": 2.0, "b": 12.0},
    ]


@pytest.mark.parametrize(
    "spec,words",
    [
        ("uniform(3, 1)", "lower bound"),
        ("gauss(1, 2)", "unknown spec"),
        ("normal(1, -2)", "positive"),
        ("linspace(0, 1, 1)", "at least 2"),
        ("uniform(1)", "takes 2"),
        ("loguniform(0, 1)", "positive"),
    ],
)
def test_bad_specs_are_named(spec, words):
    with pytest.raises(UsageError, match=words):
        sampling.parse_spec(spec)


def test_designs_refuse_mixed_spaces():
    with pytest.raises(UsageError, match="grid needs levels"):
        sampling.design_points({"a": sampling.uniform(0, 1), "b": sampling.values(1, 2)}, "grid")
    with pytest.raises(UsageError, match="needs a distribution"):
        sampling.design_points({"a": sampling.uniform(0, 1), "b": sampling.values(1, 2)}, "random", 5)


# ---- scalar outputs and the per-worker memo ------------------------------------------------------
def _opts(model, metrics, rtol=None):
    return simulation_options(load_model(model), {}, metrics, None, None, None, None, rtol, input="F")


def test_metrics_of_a_mass_spring_damper_match_the_analytic_values(msd):
    """Step force 1 N on m = 2 kg, k = 500 N/m, c = 4 N·s/m: x(t) = (1 − e^(−ζωt)(cos ω_d t +
    ζ/√(1−ζ²) sin ω_d t))/k, first peak (1 + e^(−ζπ/√(1−ζ²)))/k, natural frequency √(k/m)/2π,
    damping ratio c/(2√(km))."""
    metrics = ["steady(x)", "peak(x)", "rms(x)", "resonance", "damping", "final(F)", "min(x)"]
    row = jobs.run_job(jobs.Job(0, (("k", 500.0),)), _opts(msd, metrics, rtol=1e-9))
    assert row["error"] == "", row
    k, m, c = 500.0, 2.0, 4.0
    wn, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta**2)
    t = np.linspace(0, 3.0, 3001)
    x = (1 - np.exp(-zeta * wn * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))) / k
    assert row["resonance"] == pytest.approx(wn / (2 * math.pi), rel=1e-12)
    assert row["damping"] == pytest.approx(zeta, rel=1e-12)
    assert row["steady(x)"] == pytest.approx(np.mean(x[t >= 2.7]), rel=1e-5)
    assert row["rms(x)"] == pytest.approx(np.sqrt(np.mean(x**2)), rel=1e-5)
    assert row["peak(x)"] == pytest.approx((1 + math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))) / k, rel=1e-5)
    assert row["final(F)"] == 1.0 and row["min(x)"] == 0.0


def test_a_metric_a_run_cannot_give_is_left_empty_with_the_reason(msd):
    row = jobs.run_job(jobs.Job(0, (("c", 400.0),)), _opts(msd, ["resonance", "peak(x)"]))  # overdamped
    assert row["error"] == "" and row["resonance"] is None and row["peak(x)"] > 0
    assert "0 oscillatory mode" in row["warnings"]


def test_a_failing_job_keeps_its_inputs_and_names_the_problem(msd):
    row = jobs.run_job(jobs.Job(3, (("k", -5.0),), "/nonexistent.csv", "unit3.csv"), _opts(msd, ["peak(x)"]))
    assert row["job"] == 3 and row["data"] == "unit3.csv" and row["k"] == -5.0
    assert "nonexistent.csv" in row["error"] and row["seconds"] >= 0


def test_memo_builds_each_structure_once_per_process(msd):
    jobs._simulator.cache_clear()
    opts = _opts(msd, ["peak(x)"])
    rows = [jobs.run_job(jobs.Job(i, (("k", 600.0 + i), ("c", 3.0))), opts) for i in range(5)]
    assert jobs.memo_info()["misses"] == 1 and jobs.memo_info()["hits"] == 4
    jobs.run_job(jobs.Job(9, (("springs", 2),)), opts)  # a structural parameter: a second build
    assert jobs.memo_info()["misses"] == 2
    # the memoised simulator gives what a fresh build with the same values gives
    direct = Simulator(load_model(msd, {"k": 602.0, "c": 3.0}).model).run(
        np.linspace(0, 3.0, 3001), {"F": load_model(msd).experiment.inputs["F"]}
    )
    assert rows[2]["peak(x)"] == float(np.max(np.abs(direct["x"])))


def test_a_components_own_parameter_changes_only_the_parameter_vector():
    path = str(MODELS / "bimorph_t226.py")
    jobs._simulator.cache_clear()
    for f in (0.9, 1.0, 1.1):
        sim, numeric = jobs.built(path, {"omega_1": 1000.0 * f})  # declared by the beam-mode component
        assert numeric == {"omega_1": 1000.0 * f}
    assert jobs.memo_info()["misses"] == 1


# ---- sensitivities with known answers ------------------------------------------------------------
def test_regression_sensitivity_recovers_a_linear_law():
    rng = np.random.default_rng(0)
    a, b = rng.normal(10, 2, 300), rng.uniform(0, 1, 300)
    rows = [{"job": i, "a": a[i], "b": b[i], "y": 3 * a[i] - 20 * b[i] + 1} for i in range(300)]
    rows[5]["y"] = None  # a failed run is left out
    t = Table(rows, ["a", "b"])
    s = analysis.sensitivity(t, ["a", "b"], "y", "random")
    ok = np.ones(300, bool)
    ok[5] = False
    by = {r["parameter"]: r for r in s["ranking"]}
    qa = np.percentile(a[ok], [5, 95])
    assert by["a"]["swing"] == pytest.approx(3 * (qa[1] - qa[0]), rel=1e-9)
    assert by["a"]["high"] - by["a"]["low"] == pytest.approx(3 * (qa[1] - qa[0]), rel=1e-9)
    y = np.array([r["y"] for r in rows if r["y"] is not None])
    assert by["b"]["src"] == pytest.approx(-20 * np.std(b[ok]) / np.std(y), rel=1e-9)
    assert by["b"]["spearman"] == pytest.approx(stats.spearmanr(b[ok], y).statistic)
    assert s["r2"] == pytest.approx(1.0)
    summary = analysis.summary(t, ["y"])[0]
    assert summary["n"] == 299 and summary["failed"] == 1 and summary["mean"] == np.mean(y)


def test_grid_and_oat_sensitivities():
    rows = [
        {"job": i, "a": a, "b": b, "y": a * a + 10 * b}
        for i, (a, b) in enumerate((a, b) for a in (1.0, 2.0, 3.0) for b in (0.0, 1.0))
    ]
    s = analysis.sensitivity(Table(rows, ["a", "b"]), ["a", "b"], "y", "grid")
    assert [r["parameter"] for r in s["ranking"]] == ["b", "a"]
    assert s["ranking"][1] == {"parameter": "a", "low": 6.0, "high": 14.0, "swing": 8.0}
    oat = [{"job": 0, "y": 5.0}, {"job": 1, "y": 4.0}, {"job": 2, "y": 7.0}, {"job": 3, "y": 5.5}, {"job": 4, "y": 4.9}]
    s = analysis.sensitivity(Table(oat), ["a", "b"], "y", "oat")
    assert s["baseline"] == 5.0 and s["ranking"][0] == {"parameter": "a", "low": 4.0, "high": 7.0, "swing": 3.0}


# ---- the table -----------------------------------------------------------------------------------
ROWS = [
    {"job": 0, "data": "a.csv", "K": 1e7, "cause": "creep", "gain": 2.5, "seconds": 1.0, "error": ""},
    {"job": 1, "data": "b, broken.csv", "K": 1.1e7, "seconds": 0.1, "error": 'b.csv:3: bad cell "x", fix it'},
    {"job": 2, "data": "c.csv", "K": 0.1 + 0.2, "cause": "none", "gain": 1.0, "seconds": 2.0, "error": ""},
]


def test_csv_has_the_header_first_and_exact_numbers(tmp_path):
    t = Table(ROWS, ["data", "K"])
    assert t.columns == ["job", "data", "K", "cause", "gain", "seconds", "error"]
    t.write(tmp_path / "t.csv")
    with open(tmp_path / "t.csv", newline="") as fh:
        back = list(csv.reader(fh))
    assert back[0] == t.columns
    assert back[2][1] == "b, broken.csv" and back[2][3] == "" and back[2][-1] == ROWS[1]["error"]
    assert float(back[3][2]) == 0.1 + 0.2
    assert [r["job"] for r in t.failed] == [1]


def test_parquet_round_trip(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet")
    Table(ROWS, ["data", "K"]).write(tmp_path / "t.parquet")
    back = pq.read_table(tmp_path / "t.parquet").to_pydict()
    assert back["job"] == [0, 1, 2] and back["K"] == [1e7, 1.1e7, 0.1 + 0.2]
    assert back["cause"] == ["creep", None, "none"] and back["error"][1] == ROWS[1]["error"]


def test_table_to_pandas():
    pytest.importorskip("pandas")
    df = Table(ROWS, ["data", "K"]).to_pandas()
    assert list(df.columns) == Table(ROWS, ["data", "K"]).columns and df["gain"].tolist()[0] == 2.5


def test_unknown_table_format_writes_nothing(tmp_path):
    with pytest.raises(UsageError, match="use .csv or .parquet"):
        Table(ROWS).write(tmp_path / "t.xlsx")
    assert not list(tmp_path.iterdir())


# ---- command-line checks before any cluster starts -------------------------------------------------
APA = str(MODELS / "apa120ml.py")


@pytest.mark.parametrize(
    "argv,words",
    [
        (["batch", "diagnose", APA, "a.csv", "--vary", "K=uniform(1,2)"], "--vary applies to batch sweep only"),
        (["batch", "fit", APA], "give the data files"),
        (["batch", "fit", APA, "a.csv", "--params", "K", "--out", "fits.json"], "written as .csv or .parquet"),
        (["batch", "simulate", APA, "a.csv", "b.csv", "--out", "b.csv"], "would overwrite the input file b.csv"),
        (["batch", "sweep", APA, "--vary", "Kx=uniform(1,2)", "--draws", "5", "--metric", "peak(x)"], "did you mean"),
        (["batch", "sweep", APA, "--vary", "K=uniform(1e7,2e7)", "--draws", "5", "--metric", "peak(y)"], "signal 'y'"),
        (["batch", "sweep", APA, "--vary", "K=uniform(1e7,2e7)", "--metric", "peak(x)"], "number of draws"),
        (["batch", "sweep", APA, "--vary", "K=uniform(1e7,2e7)", "--draws", "5"], "at least one metric"),
        (
            [
                "batch",
                "sweep",
                APA,
                "--vary",
                "K=uniform(1e7,2e7)",
                "--draws",
                "5",
                "--metric",
                "peak(x)",
                "--workers",
                "2",
                "--scheduler",
                "tcp://127.0.0.1:1",
            ],
            "--workers sizes the local cluster",
        ),
        (
            [
                "batch",
                "sweep",
                APA,
                "--vary",
                "K=uniform(1e7,2e7)",
                "--draws",
                "5",
                "--metric",
                "peak(x)",
                "--input",
                "Vin",
            ],
            "no data files are given",
        ),
        (["batch", "fit", APA, "a.csv", "--params", "K", "--input", "V=step(1)"], "for batch simulate and sweep"),
        (
            [
                "batch",
                "sweep",
                APA,
                "--vary",
                "K=uniform(1e7,2e7)",
                "--draws",
                "5",
                "--metric",
                "peak(x)",
                "--scheduler",
                "tcp://127.0.0.1:1",
            ],
            "cannot reach the Dask scheduler at tcp://127.0.0.1:1",
        ),
    ],
)
def test_cli_refuses_bad_batches_in_one_line(argv, words, capsys):
    with config.override({"batch.connect_timeout": 1.0}):
        assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1 and "Traceback" not in err


def test_missing_dask_names_the_extra(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert main(["batch", "sweep", APA, "--vary", "K=uniform(1e7,2e7)", "--draws", "5", "--metric", "peak(x)"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install -e '.[dask]'" in err


def test_cli_help_lists_batch(capsys):
    assert main(["batch", "--help"]) == 0
    out = capsys.readouterr().out
    assert "--scheduler ADDRESS" in out and "--vary NAME=SPEC" in out


def test_sweep_report_json_and_plot(tmp_path):
    from bondgraph.batch import SweepResult

    rng = np.random.default_rng(4)
    a, b = rng.uniform(1, 2, 60), rng.normal(0, 1, 60)
    rows = [
        {"job": i, "a": a[i], "b": b[i], "y": 2 * a[i] + 0.1 * b[i], "z": None if i == 3 else b[i] ** 2}
        for i in range(60)
    ]
    res = SweepResult(
        Table(rows, ["a", "b"]), {"a": sampling.uniform(1, 2), "b": sampling.normal(0, 1)}, "random", ["y", "z"], seed=4
    )
    text = res.text()
    assert "random sweep: 60 runs, 0 failed, seed 4" in text and "sensitivity of y" in text
    doc = json.loads(json.dumps(res.as_json(), allow_nan=False))  # strict JSON
    assert doc["summary"][1]["n"] == 59 and doc["sensitivity"][0]["ranking"][0]["parameter"] == "a"
    pytest.importorskip("matplotlib")
    res.plot(str(tmp_path / "sweep.png"))
    assert (tmp_path / "sweep.png").stat().st_size > 10_000


# ---- a spread at the level of numerical noise is not ranked ----------------------------------------
def test_a_metric_that_varies_by_numerical_noise_is_not_ranked(tmp_path):
    """A stroke that varies by 1e-9 of its value over the runs (the integrator's rounding) has
    no sensitivity to rank: the ranking says so instead of ordering the parameters by noise;
    a parameter that moves a real metric by less than that is listed as without effect."""
    from bondgraph.batch import SweepResult

    rng = np.random.default_rng(2)
    a, b = rng.uniform(1, 2, 80), rng.normal(0, 1, 80)
    rows = [
        {"job": i, "a": a[i], "b": b[i], "stroke": 1.1e-4 * (1 + 1e-9 * rng.normal()), "y": 2 * a[i] + 1e-9 * b[i]}
        for i in range(80)
    ]
    t = Table(rows, ["a", "b"])
    assert analysis.relative_spread(t.column("stroke")) < 1e-8
    s = analysis.sensitivity(t, ["a", "b"], "stroke", "random")
    assert s["ranking"] == [] and 0 < s["noise"] < analysis.NOISE_SPREAD
    s = analysis.sensitivity(t, ["a", "b"], "y", "random")
    assert [r["parameter"] for r in s["ranking"]] == ["a", "b"]
    assert "negligible" not in s["ranking"][0] and s["ranking"][1]["negligible"]
    res = SweepResult(t, {"a": sampling.uniform(1, 2), "b": sampling.normal(0, 1)}, "random", ["stroke", "y"], seed=2)
    text = res.text()
    assert "sensitivity of stroke: not ranked, its runs spread by" in text and "numerical noise" in text
    assert "    b              no effect above numerical noise" in text
    assert "sensitivity of y (baseline" in text
    same = Table([{"job": i, "a": a[i], "m": 5.0} for i in range(10)], ["a"])
    assert analysis.sensitivity(same, ["a"], "m", "random")["noise"] == 0.0
    doc = json.loads(json.dumps(res.as_json(), allow_nan=False))
    assert doc["sensitivity"][0]["ranking"] == [] and doc["sensitivity"][0]["noise"] > 0
    pytest.importorskip("matplotlib")
    res.plot(str(tmp_path / "noise.png"))
    assert (tmp_path / "noise.png").stat().st_size > 10_000
