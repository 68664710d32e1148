"""Stiff models at scale: the compiled implicit route (``radau5``) against the explicit route
(``dopri5``) and scipy's Radau fed the same sparse analytic Jacobian (run on demand; not part
of the test suite).

    python benchmarks/stiff_bench.py [--layers 10,50,200,400] [--cap 150] [--readme]

Cases: ``models/stack.py --set layers=N`` over 0.1 s of the model file's experiment (a 100 V
step at 1 ms, output every 10 µs: 10 001 samples, rtol 1e-6); ``models/apa120ml.py`` with its
hysteresis (``bouc-wen``: Table 2, a state; ``pi``: the modified Prandtl–Ishlinskii operator
of Table 3, memory) over its experiment (0.4 s, 60 + 60 sin(2π·5 t − 90°) V).

Every measurement runs in a fresh process, one at a time, so its time and peak memory are its
own; a process that passes ``--cap`` seconds is killed and reported as ``> cap``.

* default: the command a user types, ``bondgraph simulate MODEL --set ... --t-end 0.1 --out
  F``, end to end (interpreter start, model build, derivation, compilation, auto's stiffness
  test, integration, CSV), first with an empty cache directory (cold: numba compiles), then
  again on it (warm); wall time, CPU time (user + system) and peak RSS.
* routes: in one process per route, ``Simulator(model)`` (setup), then ``run`` with the
  route: ``radau5``, ``dopri5``, ``scipy-radau`` (scipy's Radau with the sparse analytic Jacobian);
  the integration alone is timed (warm cache), with its step counts and the process's peak RSS.
  ``scipy-radau`` is :func:`scipy_radau` (same Jacobian, same error weights), not
  ``--method radau``, whose loose first pass (it sets atol from the states' peaks) stalls on
  the stack's decaying ringing.
* agreement: the output x(t) of every route against a reference, as max |difference| / max
  |reference|: for the stack at N ≤ 50 the exact step response (the model is linear and the
  step lies on the sample grid, so x_{k+1} = Φ·x_k + Γ·V_k with Φ, Γ from one matrix
  exponential is exact), for the APA dopri5 at rtol 1e-10.
* growth exponent: least-squares slope of log(time) against log(N) over the layer counts, for
  the default command (warm) and for radau5's integration.

The machine is shared: read the ratios (taken between figures of the same run), and the CPU
times, rather than the absolute wall times.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
STACK_T_END = 0.1
ROUTES = ("radau5", "dopri5", "scipy-radau")


# ---- children ------------------------------------------------------------------------------
def _case(spec: dict):
    from bondgraph.model.modelfile import load_model

    if spec["case"] == "stack":
        lm = load_model(ROOT / "models" / "stack.py", {"layers": spec["layers"]})
        return lm, lm.experiment.times(STACK_T_END, None)
    lm = load_model(ROOT / "models" / "apa120ml.py", {"hysteresis": spec["hysteresis"]})
    return lm, lm.experiment.times(None, None)


def child_route(spec: dict) -> dict:
    """One route in this process: setup, then the timed integration; x(t) saved to spec['save']."""
    from bondgraph.numerics.simulate import Simulator

    lm, t = _case(spec)
    c0, t0 = time.process_time(), time.perf_counter()
    sim = Simulator(lm.model)
    setup = time.perf_counter() - t0
    if spec["route"] != "dopri5":
        sim.sparse_jacobian()  # built and compiled outside the timed run (as dopri5's rhs is)
    jac_setup = time.perf_counter() - t0 - setup
    rtol = spec.get("rtol", 1e-6)
    if spec["route"] == "scipy-radau":
        c1, t1, stats, x = scipy_radau(sim, t, lm.experiment.inputs, rtol)
        run = time.perf_counter() - t1
        np.save(spec["save"], x)
        return {
            "setup_s": setup,
            "jacobian_setup_s": jac_setup,
            "run_s": run,
            "run_cpu_s": time.process_time() - c1,
            "stats": stats,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "route": sim.compiled.route,
        }
    sim.run(t[:3], lm.experiment.inputs, method=spec["route"])  # loads the integrator's machine code
    c1, t1 = time.process_time(), time.perf_counter()
    res = sim.run(t, lm.experiment.inputs, method=spec["route"], rtol=rtol)
    run = time.perf_counter() - t1
    np.save(spec["save"], res["x"])
    return {
        "setup_s": setup,
        "jacobian_setup_s": jac_setup,
        "run_s": run,
        "run_cpu_s": time.process_time() - c1,
        "setup_cpu_s": c1 - c0,
        "stats": res.stats,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "route": sim.compiled.route,
    }


def scipy_radau(sim, t, inputs, rtol):
    """scipy's Radau (``solve_ivp``) on the compiled right-hand side with the same sparse
    analytic Jacobian as radau5 (dense below 400 states, as scipy's own choice would be) and the
    same error weights: atol_i = rtol·max|x_i| from a radau5 run (not timed), so that neither
    side chases rounding noise where a state crosses zero.  Memory operators: committed after
    each accepted step (solve_ivp gives no hook inside a step: for the APA with PI this is the
    coarser contract).  Returns (CPU and wall start, counts, x(t))."""
    import scipy.integrate as si

    from bondgraph.numerics.integrators import eval_inputs

    ref = sim.run(t, inputs, method="radau5", rtol=rtol)
    peak = np.max(np.abs(np.column_stack(list(ref.states.values()))), axis=0)
    atol = np.maximum(rtol * peak, 1e-20)
    th = sim.theta()
    x = sim.initial_state(th)
    bank = sim.signal_bank(inputs)
    mem = sim.initial_memory(t[0], x, th, bank)
    args = bank.args()
    nu = max(len(sim.input_names), 1)
    u, du = np.zeros(nu), np.zeros(nu)
    aux = sim.compiled.aux.copy()
    dx = np.zeros(x.size)
    nv = len(sim.eqs.operators)
    v = np.zeros(max(nv, 1))
    y = np.zeros(max(len(sim.output_names), 1))

    def f(tt, xx):
        eval_inputs(tt, *args, u, du, True)
        sim.compiled.rhs(tt, np.ascontiguousarray(xx), u, du, th, mem, aux, dx)
        return dx.copy()

    def jac(tt, xx):
        return sim.jacobian_at(tt, np.ascontiguousarray(xx), th, mem, bank, sparse=x.size > 400)

    c1, t1 = time.process_time(), time.perf_counter()
    edges = [t[0], *bank.breaks(t[0], t[-1]), t[-1]]
    out = np.zeros(t.size)
    counts = {"steps": 0, "rhs_calls": 0, "jacobians": 0, "factorizations": 0}
    k = 0
    for a, b in zip(edges[:-1], edges[1:]):
        s = si.Radau(f, a, x, b, rtol=rtol, atol=atol, jac=jac)
        while s.status == "running":
            s.step()
            if s.status == "failed":
                raise RuntimeError("scipy's Radau failed")
            dense = s.dense_output()
            while k < t.size and t[k] <= s.t:
                xx = np.ascontiguousarray(dense(t[k]))
                eval_inputs(t[k], *args, u, du, True)
                sim.compiled.output(t[k], xx, u, du, th, mem, aux, y)
                out[k] = y[sim.output_names.index("x")]
                k += 1
            if nv:
                eval_inputs(s.t, *args, u, du, True)
                sim.compiled.commit(s.t, np.ascontiguousarray(s.y), u, du, th, mem, aux, v)
            counts["steps"] += 1
        x = s.y
        counts["rhs_calls"] += s.nfev
        counts["jacobians"] += s.njev
        counts["factorizations"] += s.nlu
    return c1, t1, counts, out


def child_cli(spec: dict) -> dict:
    """The command line in this process (started by the parent, which times it)."""
    import contextlib
    import io

    from bondgraph.cli import main

    argv = ["simulate", str(ROOT / "models" / spec["model"]), "--out", spec["out"]]
    for k, v in spec["set"].items():
        argv += ["--set", f"{k}={v}"]
    if spec.get("t_end"):
        argv += ["--t-end", str(spec["t_end"])]
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        rc = main(argv)
    lines = [ln for ln in err.getvalue().replace("\r", "\n").splitlines() if ln.startswith("simulated")]
    return {
        "rc": rc,
        "summary": lines[-1] if lines else "",
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


# ---- parent --------------------------------------------------------------------------------
def spawn(mode: str, spec: dict, cap: float, cache: str) -> dict:
    """Run a child; its wall and CPU time, or {'timeout': cap}."""
    env = dict(os.environ, BONDGRAPH_CACHE=cache)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        p = subprocess.run(
            [sys.executable, __file__, f"--{mode}", json.dumps(spec)],
            cwd=ROOT,
            env=env,
            capture_output=True,
            text=True,
            timeout=cap,
        )
    except subprocess.TimeoutExpired:
        return {"timeout": cap}
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        return {"error": (p.stderr.strip().splitlines() or ["?"])[-1]}
    out = json.loads(p.stdout.strip().splitlines()[-1])
    out["wall_s"] = wall
    out["cpu_s"] = r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime
    return out


def exact_stack(layers: int):
    """The exact sampled response x(t) of the linear stack to its step (see the docstring)."""
    from bondgraph.numerics.simulate import Simulator

    sys.path.insert(0, str(ROOT / "tests"))
    from truth import exact_step_response

    lm, t = _case({"case": "stack", "layers": layers})
    return exact_step_response(Simulator(lm.model), t, lm.experiment.inputs)


def slope(ns, ts) -> float | None:
    pts = [(n, v) for n, v in zip(ns, ts) if v is not None]
    if len(pts) < 2:
        return None
    return float(np.polyfit(np.log([p[0] for p in pts]), np.log([p[1] for p in pts]), 1)[0])


def fmt(r: dict, key: str = "run_s") -> str:
    if "timeout" in r:
        return f"> {r['timeout']:.0f}"
    if "error" in r:
        return "failed"
    return f"{r[key]:.2f}"


def bench(layers: list[int], cap: float, log=print) -> dict:
    work = Path(tempfile.mkdtemp(prefix="stiff-bench-"))
    warm_cache = str(work / "cache-warm")
    results: dict = {"stack": {}, "apa": {}, "machine": platform.platform(), "cap_s": cap, "layers": layers}
    cases = [("stack", {"case": "stack", "layers": n}, {"layers": n}, "stack.py", STACK_T_END) for n in layers]
    cases += [
        ("apa", {"case": "apa", "hysteresis": h}, {"hysteresis": h}, "apa120ml.py", None) for h in ("bouc-wen", "pi")
    ]
    for group, spec, settings, model, t_end in cases:
        key = str(spec.get("layers", spec.get("hysteresis")))
        row: dict = {}
        cli = {"model": model, "set": settings, "t_end": t_end, "out": str(work / "out.csv")}
        cold = str(work / f"cache-cold-{group}-{key}")
        row["default_cold"] = spawn("cli", cli, cap, cold)
        row["default_warm"] = spawn("cli", cli, cap, cold)
        row["summary"] = row["default_warm"].get("summary", "")
        log(
            f"{group} {key}: default cold {fmt(row['default_cold'], 'wall_s')} s, warm {fmt(row['default_warm'], 'wall_s')} s"
        )
        log(f"    {row['summary']}")
        saved = {}
        for route in ROUTES:
            save = str(work / f"{group}-{key}-{route}.npy")
            r = spawn("route", {**spec, "route": route, "save": save}, cap, warm_cache)
            row[route] = r
            if "run_s" in r:
                saved[route] = save
            st = r.get("stats", {})
            log(f"    {route}: {fmt(r)} s, {st.get('steps', '-')} steps, peak {r.get('peak_rss_mb', 0):.0f} MB")
        if group == "stack" and spec["layers"] <= 50:
            ref = exact_stack(spec["layers"])
        elif group == "apa":
            save = str(work / f"{group}-{key}-ref.npy")
            r = spawn("route", {**spec, "route": "dopri5", "rtol": 1e-10, "save": save}, 10 * cap, warm_cache)
            ref = np.load(save) if "run_s" in r else None
        else:
            ref = None
        if ref is not None:
            row["agreement"] = {
                route: float(np.max(np.abs(np.load(p) - ref)) / np.max(np.abs(ref))) for route, p in saved.items()
            }
            log(f"    agreement: {row['agreement']}")
        results[group][key] = row
    ns = layers
    results["exponent_default_warm"] = slope(ns, [results["stack"][str(n)]["default_warm"].get("wall_s") for n in ns])
    results["exponent_default_warm_cpu"] = slope(
        ns, [results["stack"][str(n)]["default_warm"].get("cpu_s") for n in ns]
    )
    results["exponent_radau5_run"] = slope(ns, [results["stack"][str(n)]["radau5"].get("run_s") for n in ns])
    return results


def table(results: dict) -> str:
    lines = [
        "| stack layers (states) | default, cold | default, warm | peak RSS | radau5 run | steps | dopri5 run | steps "
        "| scipy Radau run | steps | dopri5 / radau5 | Radau / radau5 | error vs exact: radau5, dopri5, Radau |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def steps(r):
        return str(r.get("stats", {}).get("steps", "-"))

    def ratio(a, b):
        if "run_s" in b and "run_s" in a:
            return f"{a['run_s'] / b['run_s']:.0f}"
        if "timeout" in a and "run_s" in b:
            return f"> {a['timeout'] / b['run_s']:.0f}"
        return "-"

    def default(r):
        if "wall_s" not in r:
            return fmt(r, "wall_s") + " s"
        return f"{r['wall_s']:.1f} s (CPU {r['cpu_s']:.1f} s)"

    for n, row in results["stack"].items():
        agree = row.get("agreement", {})
        err = ", ".join(f"{agree[r]:.1e}" if r in agree else "-" for r in ROUTES) if agree else "-"
        lines.append(
            f"| {n} ({3 * int(n)}) | {default(row['default_cold'])} | {default(row['default_warm'])} "
            f"| {row['default_warm'].get('peak_rss_mb', 0):.0f} MB "
            f"| {fmt(row['radau5'])} s | {steps(row['radau5'])} | {fmt(row['dopri5'])} s | {steps(row['dopri5'])} "
            f"| {fmt(row['scipy-radau'])} s | {steps(row['scipy-radau'])} | {ratio(row['dopri5'], row['radau5'])} "
            f"| {ratio(row['scipy-radau'], row['radau5'])} | {err} |"
        )
    lines += [
        "",
        "| APA-120ML hysteresis | default, warm (route) | dopri5 run | steps | radau5 run | steps "
        "| scipy Radau run | steps | error vs dopri5 at rtol 1e-10: dopri5, radau5, Radau |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for h, row in results["apa"].items():
        agree = row.get("agreement", {})
        err = ", ".join(f"{agree[r]:.1e}" if r in agree else "-" for r in ("dopri5", "radau5", "scipy-radau"))
        route = row["summary"].split("(")[-1].split(",")[0] if "(" in row["summary"] else "?"
        lines.append(
            f"| {h} | {default(row['default_warm'])} ({route}) | {fmt(row['dopri5'])} s | {steps(row['dopri5'])} "
            f"| {fmt(row['radau5'])} s | {steps(row['radau5'])} | {fmt(row['scipy-radau'])} s | {steps(row['scipy-radau'])} "
            f"| {err} |"
        )
    ex = results
    lines += [
        "",
        f"Growth in layers (least-squares slope of log time against log N over N = "
        f"{', '.join(map(str, ex['layers']))}): the default command (warm) {ex['exponent_default_warm']:.2f} "
        f"(CPU time {ex['exponent_default_warm_cpu']:.2f}), radau5's integration {ex['exponent_radau5_run']:.2f}.",
    ]
    return "\n".join(lines)


MARK_BEGIN, MARK_END = "<!-- stiff_bench: begin -->", "<!-- stiff_bench: end -->"


def write_readme(text: str) -> None:
    path = ROOT / "benchmarks" / "README.md"
    doc = path.read_text()
    a, b = doc.index(MARK_BEGIN) + len(MARK_BEGIN), doc.index(MARK_END)
    path.write_text(doc[:a] + "\n" + text + "\n" + doc[b:])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--layers", default="10,50,200,400")
    ap.add_argument("--cap", type=float, default=150.0, help="seconds a measurement may take (default 150)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / ".data" / "stiff_results.json"))
    ap.add_argument("--readme", action="store_true", help="write the table into benchmarks/README.md")
    ap.add_argument("--route", help=argparse.SUPPRESS)
    ap.add_argument("--cli", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.route:
        print(json.dumps(child_route(json.loads(args.route))))
        return
    if args.cli:
        print(json.dumps(child_cli(json.loads(args.cli))))
        return
    results = bench([int(n) for n in args.layers.split(",")], args.cap)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(results, indent=1, default=str))
    text = table(results)
    print(text)
    if args.readme:
        write_readme(text)


if __name__ == "__main__":
    main()
