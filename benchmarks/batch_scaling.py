"""Scaling of a batch sweep on Dask (issue 13; run on demand, not part of the test suite).

    python benchmarks/batch_scaling.py [--draws 1000] [--workers 1,2] [--out benchmarks/batch_results.json]

Workload: a Monte Carlo sweep of the APA-120ML model file (models/apa120ml.py, its default
experiment: 0.4 s of a 5 Hz sine at 10 kHz output, 4001 samples) over K, c and M, with the
scalar outputs peak(x) and rms(x): ``draws`` simulations.

Measured in one run, side by side:

1. **serial**: the same draws in a plain loop in this process (one Simulator, ``run`` per draw,
   the same metrics), no Dask: the single-run time and the reference total.
2. **compile**: deriving and compiling the model from an empty code cache in a fresh
   interpreter (what every simulation would cost without reuse).
3. **Dask, N workers** for each N: a LocalCluster of N worker processes (start-up timed
   apart), then ``batch.sweep`` twice on it: *cold* (fresh workers: imports, model build,
   loading the compiled code) and *warm* (the workers' memo holds the built simulator);
   the memo's builds per worker are read back from the workers; and the warm sweep once
   more with one Dask task per simulation (``per_task=1``) to show Dask's own per-task cost.

Reported: wall times; speed-up warm(1)/warm(N); and the per-job overhead in CPU time, which a
loaded machine does not distort: (CPU of the workers + CPU of this process, which hosts the
scheduler and the client) over the draws, minus the serial loop's CPU per simulation; for
batched tasks (the default) and for one task per job.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MODEL = os.path.join(ROOT, "models", "apa120ml.py")
SPACE = {"K": "normal(10.77e6, 5%)", "c": "uniform(2500, 3500)", "M": "loguniform(0.14, 0.2)"}
METRICS = ["peak(x)", "rms(x)"]
SEED = 1
IDLE_S = 5.0

COMPILE = """
import time
t0 = time.perf_counter()
from bondgraph.model.modelfile import load_model
from bondgraph.numerics.simulate import Simulator
t1 = time.perf_counter()
lm = load_model({model!r})
sim = Simulator(lm.model)
sim.run(lm.experiment.times(), lm.experiment.inputs)
print(time.perf_counter() - t1)
"""


def serial(draws: int) -> dict:
    """A plain loop over the sweep's draws: build, wall and CPU time, the peak values."""
    from bondgraph.batch.sampling import design_points, parse_spec
    from bondgraph.model.modelfile import load_model
    from bondgraph.numerics.simulate import Simulator

    points = design_points({k: parse_spec(v) for k, v in SPACE.items()}, "random", draws, SEED)
    t0 = time.perf_counter()
    lm = load_model(MODEL)
    sim = Simulator(lm.model)
    t = lm.experiment.times()
    sim.run(t, lm.experiment.inputs)
    t1, c1 = time.perf_counter(), time.process_time()
    peaks = []
    for p in points:
        x = sim.run(t, lm.experiment.inputs, params=p)["x"]
        peaks.append(float(np.max(np.abs(x))))
        float(np.sqrt(np.mean(np.square(x))))
    return {
        "build_s": t1 - t0,
        "loop_s": time.perf_counter() - t1,
        "loop_cpu_s": time.process_time() - c1,
        "peaks": np.array(peaks),
    }


def cold_compile() -> float:
    with tempfile.TemporaryDirectory() as cache:
        out = subprocess.run(
            [sys.executable, "-c", COMPILE.format(model=MODEL)],
            capture_output=True,
            text=True,
            env={**os.environ, "BONDGRAPH_CACHE": cache},
            check=True,
        )
    return float(out.stdout.strip().splitlines()[-1])


def on_cluster(n: int, draws: int) -> dict:
    import distributed

    from bondgraph import batch
    from bondgraph.batch.jobs import memo_info

    t0 = time.perf_counter()
    with (
        distributed.LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.CRITICAL
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        out = {"workers": n, "startup_s": time.perf_counter() - t0}
        for label, kw in (("cold", {}), ("warm", {}), ("per_task_1", {"per_task": 1})):
            before, cpu_before, here = client.run(memo_info), client.run(time.process_time), time.process_time()
            t1 = time.perf_counter()
            res = batch.sweep(MODEL, SPACE, draws=draws, seed=SEED, metrics=METRICS, scheduler=client, **kw)
            out[f"{label}_s"] = time.perf_counter() - t1
            cpu_after, after = client.run(time.process_time), client.run(memo_info)
            out[f"{label}_cpu_s"] = sum(cpu_after[w] - cpu_before[w] for w in cpu_after) + time.process_time() - here
            out[f"{label}_builds_per_worker"] = sorted(after[w]["misses"] - before[w]["misses"] for w in after)
            out[f"{label}_failed"] = len(res.table.failed)
            out["peaks"] = res.table.column("peak(x)")
        cpu_before, here, t1 = client.run(time.process_time), time.process_time(), time.perf_counter()
        time.sleep(IDLE_S)  # what the idle cluster (event loops, heartbeats) costs per second
        cpu_after = client.run(time.process_time)
        out["idle_cpu_per_s"] = (sum(cpu_after[w] - cpu_before[w] for w in cpu_after) + time.process_time() - here) / (
            time.perf_counter() - t1
        )
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--workers", default="1,2", help="comma-separated worker counts (default 1,2)")
    ap.add_argument("--out", default=os.path.join(HERE, "batch_results.json"))
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    ref = serial(args.draws)
    compile_s = cold_compile()
    runs = [on_cluster(int(n), args.draws) for n in args.workers.split(",")]
    load1 = os.getloadavg()
    peaks = ref.pop("peaks")
    for r in runs:
        assert np.array_equal(r.pop("peaks"), peaks), "Dask and serial results differ"
    single, single_cpu = ref["loop_s"] / args.draws, ref["loop_cpu_s"] / args.draws
    first = runs[0]
    result = {
        "draws": args.draws,
        "single_run_s": single,
        "single_run_cpu_s": single_cpu,
        **ref,
        "cold_compile_s": compile_s,
        "runs": runs,
        "load_before": load0,
        "load_after": load1,
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "machine": platform.machine(),
    }
    with open(args.out, "w") as fh:
        json.dump(result, fh, indent=1)
    print(
        f"APA-120ML sweep, {args.draws} simulations; load average {load0[0]:.1f} before, {load1[0]:.1f} after "
        f"({os.cpu_count()} CPUs)\n"
    )
    print(
        f"single run {1e3 * single:.1f} ms wall, {1e3 * single_cpu:.1f} ms CPU; serial loop {ref['loop_s']:.2f} s "
        f"(+ {ref['build_s']:.2f} s model build); cold derive + compile {compile_s:.1f} s "
        f"(x {args.draws} = {compile_s * args.draws / 60:.0f} min without reuse)\n"
    )
    print(
        "| workers | cluster start (s) | cold sweep (s) | warm sweep (s) | speed-up | builds per worker | "
        "overhead per job, CPU (ms) | of which idle loops (ms) | one task per job (s) | "
        "overhead per job, one task each, CPU (ms) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in runs:
        over = (r["warm_cpu_s"] / args.draws - single_cpu) * 1e3
        idle = r["idle_cpu_per_s"] * r["warm_s"] / args.draws * 1e3
        over1 = (r["per_task_1_cpu_s"] / args.draws - single_cpu) * 1e3
        print(
            f"| {r['workers']} | {r['startup_s']:.1f} | {r['cold_s']:.2f} | {r['warm_s']:.2f} | "
            f"{first['warm_s'] / r['warm_s']:.2f} | {r['cold_builds_per_worker']} | {over:.2f} | {idle:.2f} | "
            f"{r['per_task_1_s']:.2f} | {over1:.2f} |"
        )
    print(
        f"\nspeed-up: warm sweep with {first['workers']} worker(s) / with N; overhead per job: CPU time of the "
        f"workers and of the client/scheduler process per job, minus the serial loop's CPU per simulation; "
        f"idle loops: the idle cluster's CPU per second times the sweep's wall time, per job"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
