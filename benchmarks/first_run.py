"""The README's first command right after install: where its time goes (run on demand).

    python benchmarks/first_run.py [--repeat 3] [--venv DIR]

Runs ``bondgraph simulate models/apa120ml.py --set hysteresis=bouc-wen --out apa.csv --plot
apa.png`` as a user's first command: a fresh interpreter with an empty model cache
(``BONDGRAPH_CACHE``) and an empty numba cache (``NUMBA_CACHE_DIR``, where numba keeps the
compiled integrator and tape interpreter), then again with both caches warm (the second run).
Each run also reports its split, measured in the same process by the command's own stages:
imports, derive (model file and state equations), compile model, compile integrator, run,
write (CSV and plot).  ``--venv DIR`` builds a fresh virtual environment in DIR first
(``pip install -e .[plot]``) and runs there, as a new user would; without it the current
interpreter is used (its own ``__pycache__`` bytecode is warm, the compiled code is not).

Every figure is the median of ``--repeat`` cold runs (each with its own empty caches) and
as many warm runs; the machine is shared, so compare the figures of one run.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COMMAND = ["simulate", "models/apa120ml.py", "--set", "hysteresis=bouc-wen", "--out", "apa.csv", "--plot", "apa.png"]

#: the child: runs the command in-process with a stage clock around its parts (the command's
#: own code, timed from outside by wrapping the functions each stage calls)
CHILD = r"""
import json, sys, time
t0 = time.process_time()
marks = {}
import bondgraph.cli as cli
import bondgraph.equations.derivation
import bondgraph.model.modelfile as modelfile
import bondgraph.data as data_mod
import bondgraph.plotting as plotting
import matplotlib.pyplot
marks["imports"] = time.process_time() - t0
s = time.process_time()
import bondgraph.numerics.integrators  # compiled (or loaded from numba's cache) as it is imported
import bondgraph.numerics.simulate as simulate_mod
marks["compile integrator"] = time.process_time() - s

def timed(stage, fn):
    def wrapper(*a, **k):
        s = time.process_time()
        try:
            return fn(*a, **k)
        finally:
            marks[stage] = marks.get(stage, 0.0) + time.process_time() - s
    return wrapper

modelfile.load_model = timed("derive", modelfile.load_model)
simulate_mod.derive = timed("derive", simulate_mod.derive)
simulate_mod.compile_equations = timed("compile model", simulate_mod.compile_equations)
simulate_mod.Simulator.run = timed("run", simulate_mod.Simulator.run)
data_mod.write_csv = timed("write", data_mod.write_csv)
plotting.plot_signals = timed("write", plotting.plot_signals)
s, w = time.process_time(), time.perf_counter()
rc = cli.main(sys.argv[1:])
marks["command"] = time.process_time() - s
marks["command wall"] = time.perf_counter() - w
marks["rc"] = rc
print("SPLIT " + json.dumps(marks), file=sys.stderr)
"""


def one_run(python: str, env: dict, cwd: Path) -> dict:
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run([python, "-c", CHILD, *COMMAND], cwd=cwd, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - t0
    line = next((ln for ln in p.stderr.splitlines() if ln.startswith("SPLIT ")), None)
    if p.returncode or line is None:
        raise SystemExit(f"the run failed:\n{p.stderr}")
    split = json.loads(line[6:])
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    split["process CPU"] = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
    split["process wall"] = wall
    split["stderr"] = [ln for ln in p.stderr.splitlines() if not ln.startswith("SPLIT ")]
    return split


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--venv", help="build a fresh virtual environment here first and run in it")
    args = ap.parse_args()
    python = sys.executable
    if args.venv:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "venv", args.venv], check=True)
        python = str(Path(args.venv) / "bin" / "python")
        subprocess.run([python, "-m", "pip", "install", "-q", "-e", f"{ROOT}[plot]"], check=True)
        print(f"fresh venv in {time.perf_counter() - t0:.0f} s: {args.venv}")
    cold, warm = [], []
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as d:
            d = Path(d)
            (d / "models").symlink_to(ROOT / "models")
            (d / "library").symlink_to(ROOT / "library")
            env = {**os.environ, "BONDGRAPH_CACHE": str(d / "bg"), "NUMBA_CACHE_DIR": str(d / "numba")}
            env.pop("BONDGRAPH_PROGRESS", None)
            cold.append(one_run(python, env, d))
            warm.append(one_run(python, env, d))
    stages = [
        "imports",
        "derive",
        "compile model",
        "compile integrator",
        "run",
        "write",
        "command",
        "process CPU",
        "command wall",
        "process wall",
    ]
    print(f"README first command, median of {args.repeat} ({'fresh venv' if args.venv else sys.executable}):")
    print("CPU seconds (user + system) unless the row says wall; the machine's load inflates the wall times")
    print(f"{'stage':40s} {'first run (s)':>14s} {'second run (s)':>15s}")
    for st in stages:
        c = statistics.median(r.get(st, 0.0) for r in cold)
        w = statistics.median(r.get(st, 0.0) for r in warm)
        print(f"{st:40s} {c:14.2f} {w:15.2f}")
    print("stderr of the last first run:")
    for ln in cold[-1]["stderr"]:
        print("   ", ln)


if __name__ == "__main__":
    main()
