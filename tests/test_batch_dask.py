"""Batch runs on real Dask clusters: the embedded LocalCluster (2 worker processes) and a
scheduler with workers started here on localhost (``dask scheduler`` / ``dask worker``).

The records are simulated from the APA-120ML model file by the framework's own simulator:
one with Bouc–Wen polarization hysteresis (an effect the nominal linear model lacks), one
without, and one broken file.  Each batch row must equal the diagnosis of the same record
called directly, and a broken record must fail its own row only.  A 200-draw Monte Carlo
must give exactly the draws and statistics of a serial loop over the same draws.
"""

import contextlib
import csv
import glob
import importlib.util
import json
import math
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from scipy import stats

distributed = pytest.importorskip("distributed")

from conftest import MODELS, ROOT  # noqa: E402

from bondgraph import batch  # noqa: E402
from bondgraph.batch.jobs import memo_info  # noqa: E402
from bondgraph.batch.table import Table  # noqa: E402
from bondgraph.cli import main  # noqa: E402
from bondgraph.data import read_csv, write_csv  # noqa: E402
from bondgraph.diagnosis import diagnose, model_file_options  # noqa: E402
from bondgraph.fit.fitting import fit_parameters  # noqa: E402
from bondgraph.linear.linearize import linearize  # noqa: E402
from bondgraph.model.modelfile import load_model  # noqa: E402
from bondgraph.model.signals import Sine  # noqa: E402
from bondgraph.numerics.simulate import Simulator  # noqa: E402

APA = str(MODELS / "apa120ml.py")
RESULTS = ("cause", "causes", "gain", "baseline_rms", "extended_rms")


def record(path, hysteresis: str, changes: dict, seed: int):
    """0.3 s at 1 kHz of the APA driven by a 5 Hz sine, 1 % white sensor noise."""
    truth = load_model(APA, {"hysteresis": hysteresis})
    t = np.arange(301) / 1000.0
    nominal = truth.model.values
    res = Simulator(truth.model).run(
        t, {"V": Sine(50.0, 5.0, phase=-90.0, offset=60.0)}, params={k: f * nominal[k] for k, f in changes.items()}
    )
    x = res["x"] + 0.01 * np.std(res["x"]) * np.random.default_rng(seed).standard_normal(t.size)
    write_csv(path, t, {"V": res["V"], "x": x}, {"truth": f"APA-120ML, hysteresis={hysteresis}, {changes}"})
    return str(path)


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    d = tmp_path_factory.mktemp("records")
    hyst = record(d / "unit1.csv", "bouc-wen", {"K": 0.85, "a": 1.15}, 1)
    plain = record(d / "unit2.csv", "none", {"K": 1.1, "c": 0.8}, 2)
    broken = d / "unit3.csv"
    broken.write_text("t,V,x\n0,1,2\n0.001,1,oops\n")
    return [hyst, str(broken), plain]


@pytest.fixture(scope="module")
def direct(records):
    """The diagnosis of the effect-free record, called directly in this process."""
    lm = load_model(APA)
    data = read_csv(records[2], required=("t", "V", "x"))
    return diagnose(lm.model, data, **model_file_options(lm.module), workers=1).as_json()


def check_diagnosis_rows(table, records, direct):
    """Rows in job order; the broken record fails its own row; the effect-free record's row is
    the direct diagnosis; the hysteretic record's extension lowers the validation RMS."""
    assert [r["job"] for r in table.rows] == list(range(len(records)))
    assert [r["data"] for r in table.rows] == records
    by_unit = {os.path.basename(r["data"]): r for r in table.rows}
    broken = by_unit["unit3.csv"]
    assert "unit3.csv:3" in broken["error"] and broken.get("cause") is None
    plain = by_unit["unit2.csv"]
    assert plain["error"] == ""
    assert plain["cause"] == direct["cause"] and plain["gain"] == pytest.approx(direct["gain"], rel=1e-9)
    assert plain["baseline_rms"] == pytest.approx(direct["baseline_rms"], rel=1e-9)
    assert plain["extended_rms"] == pytest.approx(direct["extended_rms"], rel=1e-9)
    best = {}
    for c in direct["candidates"]:
        best[c["cause"]] = max(best.get(c["cause"], -math.inf), c["gain"])
    assert {k: plain[f"gain:{k}"] for k in best} == pytest.approx(best, rel=1e-9)
    if "unit1.csv" in by_unit:
        hyst = by_unit["unit1.csv"]
        assert hyst["error"] == "" and hyst["gain"] > 1.0 and hyst["baseline_rms"] > hyst["extended_rms"] > 0


# ---- Monte Carlo: the same draws and statistics as a serial loop ----------------------------------
MC_SPACE = {"K": "normal(10.77e6, 5%)", "c": "uniform(300, 1000)", "M": "loguniform(0.14, 0.2)"}
MC_METRICS = ["peak(x)", "rms(x)", "steady(x)", "resonance"]
MC_RUN = dict(inputs={"V": Sine(60.0, 200.0, offset=60.0)}, t_end=0.02, dt=1e-5)


def serial_monte_carlo(draws: int, seed: int) -> dict:
    """The same study by hand: seeded uniforms through the inverse CDFs, a plain loop of
    simulations, numpy statistics."""
    u = np.random.default_rng(seed).random((draws, 3))
    K = stats.norm(10.77e6, 0.05 * 10.77e6).ppf(u[:, 0])
    c = stats.uniform(300, 700).ppf(u[:, 1])
    M = stats.loguniform(0.14, 0.2).ppf(u[:, 2])
    lm = load_model(APA)
    sim = Simulator(lm.model)
    t = np.linspace(0, 0.02, 2001)
    out = {m: [] for m in MC_METRICS}
    for i in range(draws):
        p = {"K": K[i], "c": c[i], "M": M[i]}
        x = sim.run(t, MC_RUN["inputs"], params=p)["x"]
        out["peak(x)"].append(np.max(np.abs(x)))
        out["rms(x)"].append(np.sqrt(np.mean(x**2)))
        out["steady(x)"].append(np.mean(x[t >= 0.018]))
        poles = linearize(sim.eqs, "V", "x", params=p).poles
        out["resonance"].append(np.min(np.abs(poles[poles.imag > 0])) / (2 * np.pi))
    return {"K": K, "c": c, "M": M, **{m: np.array(v) for m, v in out.items()}}


@pytest.fixture(scope="module")
def serial_mc():
    return serial_monte_carlo(200, seed=11)


def check_monte_carlo(res, serial):
    t = res.table
    assert len(t) == 200 and not t.failed
    for name in ("K", "c", "M", *MC_METRICS):
        assert np.array_equal(t.column(name), serial[name]), name
    for s in res.summary():
        y = serial[s["metric"]]
        p5, p50, p95 = np.percentile(y, [5, 50, 95])
        assert (s["n"], s["mean"], s["std"], s["min"], s["p5"], s["median"], s["p95"], s["max"]) == (
            200,
            np.mean(y),
            np.std(y, ddof=1),
            np.min(y),
            p5,
            p50,
            p95,
            np.max(y),
        )
    # the resonance √(K_eff/M)/2π falls with the mass: M ranks first with a negative rank correlation
    sens = {s["metric"]: s for s in res.sensitivity()}["resonance"]
    assert sens["ranking"][0]["parameter"] == "M" and sens["ranking"][0]["spearman"] < -0.5


# ---- the embedded LocalCluster ----------------------------------------------------------------------
def test_local_cluster_batch_diagnosis_with_a_failing_record(records, direct, tmp_path):
    said, done = [], []
    table = batch.diagnose(APA, records, workers=2, say=said.append, progress=lambda d, n: done.append((d, n)))
    assert "local Dask cluster of 2 worker processes" in said[0]
    if importlib.util.find_spec("bokeh"):
        assert "; dashboard: http://" in said[0]
    assert done[-1] == (3, 3) and [d for d, _ in done] == sorted(d for d, _ in done)
    check_diagnosis_rows(table, records, direct)
    table.write(tmp_path / "lot.csv")
    assert (tmp_path / "lot.csv").read_text().splitlines()[0].split(",")[:2] == ["job", "data"]


def test_local_cluster_monte_carlo_matches_a_serial_loop(serial_mc):
    res = batch.sweep(APA, MC_SPACE, draws=200, seed=11, metrics=MC_METRICS, workers=2, **MC_RUN)
    check_monte_carlo(res, serial_mc)


# ---- a scheduler and workers started here ------------------------------------------------------------
@pytest.fixture(scope="module")
def scheduler(tmp_path_factory):
    d = tmp_path_factory.mktemp("dask")
    info = d / "scheduler.json"
    quiet = dict(stdout=subprocess.DEVNULL, stderr=open(d / "log.txt", "w"), cwd=d)
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-m",
                "dask",
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(info),
            ],
            **quiet,
        )
    ]
    try:
        deadline = time.time() + 60
        while not info.exists() and time.time() < deadline:
            time.sleep(0.1)
        procs.append(
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "dask",
                    "worker",
                    "--scheduler-file",
                    str(info),
                    "--nworkers",
                    "2",
                    "--nthreads",
                    "1",
                    "--no-dashboard",
                ],
                **quiet,
            )
        )
        address = json.loads(info.read_text())["address"]
        with distributed.Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        if len(procs) == 2:
            with contextlib.suppress(Exception), distributed.Client(address, timeout="10s") as client:
                client.shutdown()  # scheduler and workers close themselves
        for p in reversed(procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def readme_cluster_command() -> str:
    blocks = re.findall(r"```console\n(.*?)```", (ROOT / "docs" / "batch.md").read_text(), re.S)
    return next(ln.split("  #")[0].strip() for b in blocks for ln in b.splitlines() if ln.startswith("bondgraph batch"))


def test_readme_cluster_example_on_a_scheduler_and_workers_started_here(
    scheduler, records, direct, tmp_path, monkeypatch, capsys
):
    """The cluster command of docs/batch.md, with this scheduler's address and the lot expanded as a
    shell would: the broken and the effect-free record."""
    (tmp_path / "lot").mkdir()
    for r in records[1:]:
        shutil.copy(r, tmp_path / "lot")
    monkeypatch.chdir(tmp_path)
    argv = [
        str(ROOT / a) if a.startswith("models/") else a
        for a in shlex.split(readme_cluster_command().replace("tcp://HEAD:8786", scheduler))[1:]
    ]
    pattern = next(a for a in argv if "*" in a)
    files = sorted(glob.glob(pattern))
    i = argv.index(pattern)
    argv[i : i + 1] = files
    assert main(argv) == 0
    assert f"running on the Dask cluster at {scheduler} (2 workers" in capsys.readouterr().err
    out = next(argv[k + 1] for k, a in enumerate(argv) if a == "--out")
    with open(out, newline="") as fh:
        rows = [{k: _typed(k, v) for k, v in r.items()} for r in csv.DictReader(fh)]
    check_diagnosis_rows(Table(rows), files, direct)


def _typed(column: str, text: str):
    if column in ("data", "error", "warnings"):
        return text
    if column in ("cause", "causes"):
        return text or None
    return None if text == "" else (int(text) if column == "job" else float(text))


def test_external_cluster_monte_carlo_builds_the_model_once_per_worker(scheduler, serial_mc):
    with distributed.Client(scheduler) as client:
        before = client.run(memo_info)
        res = batch.sweep(APA, MC_SPACE, draws=200, seed=11, metrics=MC_METRICS, scheduler=client, **MC_RUN)
        after = client.run(memo_info)
    check_monte_carlo(res, serial_mc)
    built = [after[w]["misses"] - before[w]["misses"] for w in after]
    reused = sum(after[w]["hits"] - before[w]["hits"] for w in after)
    assert max(built) == 1 and reused == 200 - sum(built)


def test_cli_fit_and_simulate_with_parameter_sets_on_the_external_cluster(scheduler, records, tmp_path):
    fits = tmp_path / "fits.csv"
    assert (
        main(
            [
                "batch",
                "fit",
                APA,
                records[2],
                records[1],
                "--params",
                "a,K",
                "--scheduler",
                scheduler,
                "--out",
                str(fits),
                "--quiet",
            ]
        )
        == 0
    )
    with open(fits, newline="") as fh:
        rows = list(csv.DictReader(fh))
    direct = fit_parameters(load_model(APA), read_csv(records[2]), ["a", "K"]).result
    assert float(rows[0]["fit:a"]) == pytest.approx(direct.values["a"], rel=1e-9)
    assert float(rows[0]["rms_validation"]) == pytest.approx(direct.rms_validation, rel=1e-9)
    assert "unit3.csv:3" in rows[1]["error"] and rows[1]["fit:a"] == ""
    # the record's own parameters (K x 1.1, c x 0.8) reproduce it to its 1 % noise; a 20 % larger a does not
    sets = tmp_path / "sets.csv"
    sets.write_text("K,c,a\n11.847e6,2400,0.0474\n11.847e6,2400,0.05688\n")
    out = tmp_path / "sim.parquet"
    assert (
        main(
            [
                "batch",
                "simulate",
                APA,
                records[2],
                "--sets",
                str(sets),
                "--metric",
                "p2p(x)",
                "--scheduler",
                scheduler,
                "--out",
                str(out),
                "--quiet",
            ]
        )
        == 0
    )
    table = pytest.importorskip("pyarrow.parquet").read_table(out).to_pydict()
    x = read_csv(records[2]).columns["x"]
    assert table["a"] == ["0.0474", "0.05688"] and table["error"] == ["", ""]
    assert table["rms"][0] < 0.012 * np.std(x) < table["rms"][1]
    assert table["p2p(x)"][1] == pytest.approx(1.2 * table["p2p(x)"][0], rel=0.02)


def test_cli_grid_sweep_over_a_structural_parameter(scheduler, tmp_path, capsys):
    out = tmp_path / "grid.csv"
    with distributed.Client(scheduler) as client:
        before = client.run(memo_info)
        assert (
            main(
                [
                    "batch",
                    "sweep",
                    APA,
                    "--vary",
                    "K=linspace(9e6, 12e6, 3)",
                    "--vary",
                    "hysteresis=values(none, bouc-wen)",
                    "--metric",
                    "p2p(x)",
                    "--t-end",
                    "0.1",
                    "--scheduler",
                    scheduler,
                    "--json",
                    "--out",
                    str(out),
                    "--quiet",
                ]
            )
            == 0
        )
        after = client.run(memo_info)
    res = json.loads(capsys.readouterr().out)
    assert res["design"] == "grid" and res["runs"] == 6 and res["failed"] == 0
    assert {r["parameter"] for r in res["sensitivity"][0]["ranking"]} == {"K", "hysteresis"}
    with open(out, newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["K"], r["hysteresis"]) for r in rows] == [
        (k, h) for k in ("9000000.0", "10500000.0", "12000000.0") for h in ("none", "bouc-wen")
    ]
    # hysteresis lowers the stroke; one build per structure and worker at most
    assert float(rows[1]["p2p(x)"]) < float(rows[0]["p2p(x)"])
    assert 2 <= sum(after[w]["misses"] - before[w]["misses"] for w in after) <= 4


def test_ctrl_c_cancels_the_jobs_and_shuts_the_local_cluster_down(tmp_path):
    """SIGINT to the command's process group, as a terminal sends it: exit 130 with one line,
    no table written, no worker process left."""
    psutil = pytest.importorskip("psutil")
    out = tmp_path / "mc.csv"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bondgraph",
            "batch",
            "sweep",
            APA,
            "--vary",
            "K=uniform(9e6, 12e6)",
            "--draws",
            "20000",
            "--seed",
            "1",
            "--metric",
            "peak(x)",
            "--workers",
            "2",
            "--out",
            str(out),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    first = proc.stderr.readline()
    assert "running on a local Dask cluster of 2 worker processes" in first, first + proc.stderr.read()
    time.sleep(2.0)  # the workers are simulating
    children = psutil.Process(proc.pid).children(recursive=True)
    assert len(children) >= 2
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.strip() and not ln.startswith("batch")]
    assert lines == ["bondgraph: interrupted; no output file was changed"]
    assert not out.exists()
    _, alive = psutil.wait_procs(children, timeout=15)
    assert not alive
