"""Benchmark suite of issue 5 (run on demand; not part of the test suite).

    python benchmarks/run.py [--quick] [--peers] [--workloads derive,peers,simulate,diagnose]
                             [--repeat N] [--out benchmarks/results.json] [--readme]

Workloads
  derive    1. equation derivation (built graph -> symbolic state equations) and compilation
               (symbolic equations -> ready-to-run compiled functions, first call included) of
               the N-mass chain (N = 10 ... 320) and the N-layer stack of models/stack.py
               (N = 10 ... 400); compilation in a fresh interpreter with an empty
               $BONDGRAPH_CACHE, then the cached second run separately; growth exponents fitted
               on log-log (chain N = 20 ... 320).
  peers     2. the same chain derived by BondGraphTools and the PyPI `bondgraph` 0.2.0, each in
               its own virtual environment (benchmarks/.peers-venv, created with --peers), with
               our derivation timed the same way; a peer that cannot be installed is skipped
               with the reason.
  simulate  3. 10 s of model time at 10 kHz output: the N = 10 chain and the APA-120ML with a
               modified-PI capacitor; ours vs the naive route (lambdify + solve_ivp) and vs a
               hand-written numba DOPRI5 (the compiled limit); results checked for agreement.
  diagnose  4. `bondgraph diagnose` on a 250 000-sample file (skipped until the command exists).

Every time is a median over repetitions (--repeat, default 3; a point whose repetitions would
take more than a minute gets fewer, and the table says how many).  Ratios are taken from
figures measured in this run.  The JSON holds every raw time.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import select
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PEER_VENV = os.path.join(HERE, ".peers-venv")
PEER_PACKAGES = {"bondgraphtools": "bondgraphtools", "pypi-bondgraph": "bondgraph==0.2.0"}
PEER_LABEL = {"bondgraphtools": "BondGraphTools", "pypi-bondgraph": "PyPI bondgraph"}

CHAIN_N = [10, 20, 40, 80, 160, 320]
STACK_N = [10, 25, 50, 100, 200, 400]
PEER_N = [10, 20, 40, 80]
QUICK_CHAIN_N = [10, 20, 40, 80]
QUICK_STACK_N = [10, 50]
QUICK_PEER_N = [10, 20]

GOALS = {
    "derive_vs_peer": 5.0,  # N = 10 chain: at least 5x faster than the fastest peer
    "derive_exponent": 1.3,  # chain N = 20..320
    "stack400_total_s": 20.0,  # 400-layer stack derived + compiled
    "compile_chain320_s": 5.0,  # N = 320 chain compiled
    "sim_vs_naive": 20.0,  # at least 20x faster than lambdify + solve_ivp
    "sim_vs_limit": 3.0,  # within 3x of the hand-written compiled limit
    "diagnose_s": 120.0,
    "diagnose_mb": 2048.0,
}


def log(msg=""):
    print(msg, flush=True)


def median(xs):
    xs = [x for x in xs if x is not None and not (isinstance(x, float) and math.isnan(x))]
    return float(np.median(xs)) if xs else float("nan")


def fmt_s(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, str):
        return x
    if x >= 100:
        return f"{x:.0f} s"
    if x >= 1:
        return f"{x:.2f} s"
    if x >= 1e-3:
        return f"{x * 1e3:.1f} ms"
    return f"{x * 1e6:.0f} us"


def fit_exponent(ns, ts):
    """Least-squares slope of log t against log N."""
    pts = [(n, t) for n, t in zip(ns, ts) if t is not None and t > 0 and not math.isnan(t)]
    if len(pts) < 2:
        return float("nan")
    x = np.log([p[0] for p in pts])
    y = np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


# ---- child processes -----------------------------------------------------------------------------
def run_lines(cmd, timeout_per_line: float, env=None):
    """Run ``cmd``, collecting its JSON stdout lines; kill it if no line arrives within
    ``timeout_per_line`` s.  Returns (lines, timed_out, returncode, stderr tail)."""
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=HERE)
    lines, buf, timed_out = [], "", False
    deadline = time.monotonic() + timeout_per_line
    fd = proc.stdout.fileno()
    os.set_blocking(fd, False)
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            timed_out = True
            proc.kill()
            break
        r, _, _ = select.select([fd], [], [], min(left, 1.0))
        if r:
            chunk = os.read(fd, 65536).decode()
            if not chunk:
                break
            buf += chunk
            while "\n" in buf:
                line, buf = buf.split("\n", 1)
                line = line.strip()
                if line.startswith("{"):
                    try:
                        lines.append(json.loads(line))
                    except json.JSONDecodeError:
                        pass
                    deadline = time.monotonic() + timeout_per_line
        elif proc.poll() is not None:
            rest = proc.stdout.read() or ""
            buf += rest
            for line in buf.splitlines():
                if line.strip().startswith("{"):
                    lines.append(json.loads(line))
            break
    proc.wait()
    err = proc.stderr.read() if proc.stderr else ""
    return lines, timed_out, proc.returncode, err[-2000:]


def our_python():
    return sys.executable


# ---- workload 1: derivation and compilation ---------------------------------------------------------
def derive_points(kind, n, repeat, timeout, eig=False):
    cmd = [
        our_python(),
        os.path.join(HERE, "derive_child.py"),
        "derive",
        "--kind",
        kind,
        "--n",
        str(n),
        "--reps",
        str(repeat),
        "--budget",
        "60",
    ] + (["--eig"] if eig else [])
    lines, to, rc, err = run_lines(cmd, timeout)
    times = [ln["seconds"] for ln in lines if "seconds" in ln]
    eigs = next((ln["eig"] for ln in lines if "eig" in ln), None)
    if to:
        return {"times": times, "timeout": True, "error": None, "eig": eigs}
    if rc != 0 or not times:
        return {"times": times, "timeout": False, "error": err.strip().splitlines()[-1:] or [f"exit {rc}"], "eig": eigs}
    return {
        "times": times,
        "timeout": False,
        "error": None,
        "eig": eigs,
        "states": next((ln.get("states") for ln in lines if "states" in ln), None),
        "statements": next((ln.get("statements") for ln in lines if "statements" in ln), None),
    }


def compile_point(kind, n, repeat, timeout):
    """Cold compilations (fresh interpreter, empty cache) and the cached second runs."""
    cold, cached, rec = [], [], {}
    spent = 0.0
    for rep in range(max(repeat, 1)):
        cache = tempfile.mkdtemp(prefix="bg-bench-cache-")
        env = dict(os.environ, BONDGRAPH_CACHE=cache)
        try:
            cmd = [our_python(), os.path.join(HERE, "derive_child.py"), "compile", "--kind", kind, "--n", str(n)]
            lines, to, rc, err = run_lines(cmd, timeout, env)
            if to or rc != 0 or not lines:
                rec["error"] = "> timeout" if to else (err.strip().splitlines()[-1:] or [f"exit {rc}"])[0]
                break
            first = lines[0]
            cold.append(first)
            lines2, to2, rc2, err2 = run_lines(cmd, timeout, env)  # same cache: the second run
            if lines2:
                cached.append(lines2[0])
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        spent += first["compile"] + first["derive"]
        if spent > 60.0:
            break
    rec.update(
        {
            "reps": len(cold),
            "compile_s": [c["compile"] for c in cold],
            "generate_source_s": [c["generate_source"] for c in cold],
            "derive_cold_s": [c["derive"] for c in cold],
            "build_s": [c["build"] for c in cold],
            "cached_compile_s": [c["compile"] for c in cached],
            "peak_mb": [c["peak_mb"] for c in cold],
            "source_bytes": cold[0]["source_bytes"] if cold else None,
            "states": cold[0]["states"] if cold else None,
            "statements": cold[0]["statements"] if cold else None,
        }
    )
    return rec


def workload_derive(args):
    chain_ns = QUICK_CHAIN_N if args.quick else CHAIN_N
    stack_ns = QUICK_STACK_N if args.quick else STACK_N
    out = {"chain": {}, "stack": {}}
    for kind, ns in (("chain", chain_ns), ("stack", stack_ns)):
        for n in ns:
            d = derive_points(kind, n, args.repeat, args.timeout)
            c = compile_point(kind, n, args.repeat, args.timeout * 5)
            out[kind][n] = {"derive": d, "compile": c}
            log(
                f"  {kind:5s} N={n:4d}: derive {fmt_s(median(d['times']))} (n={len(d['times'])}), "
                f"compile {fmt_s(median(c.get('compile_s', [])))} (n={c.get('reps')}; source generation "
                f"{fmt_s(median(c.get('generate_source_s', [])))}), cached {fmt_s(median(c.get('cached_compile_s', [])))}"
                + (f"  [{c['error']}]" if c.get("error") else "")
            )
    lo, hi = 20, 320
    ns = [n for n in chain_ns if lo <= n <= hi]
    out["chain_exponent_derive"] = fit_exponent(ns, [median(out["chain"][n]["derive"]["times"]) for n in ns])
    out["chain_exponent_compile"] = fit_exponent(ns, [median(out["chain"][n]["compile"]["compile_s"]) for n in ns])
    out["stack_exponent_derive"] = fit_exponent(
        stack_ns, [median(out["stack"][n]["derive"]["times"]) for n in stack_ns]
    )
    out["stack_exponent_compile"] = fit_exponent(
        stack_ns, [median(out["stack"][n]["compile"]["compile_s"]) for n in stack_ns]
    )
    out["exponent_range"] = [min(ns), max(ns)] if ns else None
    return out


# ---- workload 2: peers ---------------------------------------------------------------------------------
def ensure_peer_venv():
    """Create benchmarks/.peers-venv and install the peers; returns {peer: reason or None}."""
    py = os.path.join(PEER_VENV, "bin", "python")
    status = {}
    if not os.path.exists(py):
        log(f"  creating {PEER_VENV}")
        r = subprocess.run([sys.executable, "-m", "venv", PEER_VENV], capture_output=True, text=True)
        if r.returncode != 0:
            return {p: f"cannot create the virtual environment: {r.stderr.strip()[-300:]}" for p in PEER_PACKAGES}
        subprocess.run([py, "-m", "pip", "install", "-q", "--upgrade", "pip"], capture_output=True, text=True)
    for peer, spec in PEER_PACKAGES.items():
        probe = (
            "import BondGraphTools"
            if peer == "bondgraphtools"
            else "import importlib.metadata as m; assert m.version('bondgraph') == '0.2.0'; import bondgraph.core"
        )
        # -I: isolated mode, so our own `bondgraph` (the current directory) is never imported
        ok = subprocess.run([py, "-I", "-c", probe], capture_output=True, text=True, cwd=HERE).returncode == 0
        if not ok:
            log(f"  pip install {spec} into {PEER_VENV}")
            r = subprocess.run([py, "-m", "pip", "install", "-q", spec], capture_output=True, text=True)
            pr = subprocess.run([py, "-I", "-c", probe], capture_output=True, text=True, cwd=HERE)
            if r.returncode != 0 or pr.returncode != 0:
                why = (r.stderr or r.stdout) if r.returncode != 0 else ("installed, but " + pr.stderr)
                status[peer] = "cannot be installed: " + (why.strip().splitlines() or ["?"])[-1][:300]
                continue
        status[peer] = None
    return status


def peer_versions():
    py = os.path.join(PEER_VENV, "bin", "python")
    if not os.path.exists(py):
        return {}
    r = subprocess.run(
        [
            py,
            "-I",
            "-c",
            "import json, importlib.metadata as m; print(json.dumps({k: m.version(k) for k in "
            "('bondgraph', 'bondgraphtools', 'sympy')}))",
        ],
        capture_output=True,
        text=True,
    )
    try:
        return json.loads(r.stdout)
    except json.JSONDecodeError:
        return {}


def workload_peers(args, derive_results=None):
    ns = QUICK_PEER_N if args.quick else PEER_N
    out = {"ns": ns, "peers": {}, "ours": {}, "skipped": {}}
    if not args.peers:
        log(
            "  peers: skipped (run with --peers to install BondGraphTools and PyPI bondgraph 0.2.0 "
            "into benchmarks/.peers-venv)"
        )
        out["skipped"] = {p: "not requested (--peers)" for p in PEER_PACKAGES}
        return out
    status = ensure_peer_venv()
    py = os.path.join(PEER_VENV, "bin", "python")
    out["versions"] = peer_versions()
    # ours, measured the same way (warm-up, sympy cache cleared, one process per N)
    for n in ns:
        d = derive_points("chain", n, args.repeat, args.timeout, eig=(n == 10))
        out["ours"][n] = d
    ref_eig = out["ours"].get(10, {}).get("eig")
    for peer, reason in status.items():
        if reason:
            log(f"  {PEER_LABEL[peer]}: skipped, {reason}")
            out["skipped"][peer] = reason
            continue
        res = {}
        dead = None
        for n in ns:
            if dead is not None:
                res[n] = {"times": [], "timeout": True, "note": f"not run: N={dead} already exceeded the timeout"}
                log(f"  {PEER_LABEL[peer]:15s} N={n:3d}: > {args.timeout:.0f} s (not run: N={dead} timed out)")
                continue
            cmd = [
                py,
                "-I",
                os.path.join(HERE, "peer_chain.py"),
                "--peer",
                peer,
                "--n",
                str(n),
                "--reps",
                str(args.repeat),
                "--budget",
                "60",
            ] + (["--eig"] if n == 10 else [])
            lines, to, rc, err = run_lines(cmd, args.timeout)
            times = [ln["seconds"] for ln in lines if "seconds" in ln]
            rec = {"times": times, "timeout": to}
            if n == 10:
                eig = next((ln["eig"] for ln in lines if "eig" in ln), None)
                if eig is not None and ref_eig is not None:
                    a, b = np.array(eig), np.array(ref_eig)
                    rec["eig_max_rel_diff"] = (
                        float(np.max(np.abs(a - b)) / np.max(np.abs(b))) if a.shape == b.shape else None
                    )
            if to and not times:
                dead = n
                log(f"  {PEER_LABEL[peer]:15s} N={n:3d}: > {args.timeout:.0f} s (timeout)")
            elif rc not in (0, None) and not times:
                rec["error"] = (err.strip().splitlines() or [f"exit {rc}"])[-1][:300]
                log(f"  {PEER_LABEL[peer]:15s} N={n:3d}: failed: {rec['error']}")
                dead = n
            else:
                log(
                    f"  {PEER_LABEL[peer]:15s} N={n:3d}: {fmt_s(median(times))} (n={len(times)})"
                    + (
                        f", state-matrix eigenvalues match ours to {rec['eig_max_rel_diff']:.1e}"
                        if rec.get("eig_max_rel_diff") is not None
                        else ""
                    )
                )
            res[n] = rec
        out["peers"][peer] = res
        ok = [n for n in ns if res[n]["times"]]
        out.setdefault("exponents", {})[peer] = fit_exponent(ok, [median(res[n]["times"]) for n in ok])
    for n in ns:
        log(f"  ours            N={n:3d}: {fmt_s(median(out['ours'][n]['times']))} (n={len(out['ours'][n]['times'])})")
    return out


# ---- workload 3: simulation ------------------------------------------------------------------------------
def workload_simulate(args):
    import sim_bench

    return sim_bench.run(args.repeat, args.naive_limit, quick=args.quick, log=log)


# ---- workload 4: diagnosis ---------------------------------------------------------------------------------
def workload_diagnose(args):
    import diagnose_bench

    return diagnose_bench.run(quick=args.quick, log=log)


# ---- machine, report -------------------------------------------------------------------------------------
def machine():
    cpu = "?"
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    mem = "?"
    try:
        with open("/proc/meminfo") as fh:
            kb = int(fh.readline().split()[1])
            mem = f"{kb / 1024**2:.0f} GiB"
    except (OSError, ValueError, IndexError):
        pass
    from importlib.metadata import PackageNotFoundError, version

    vers = {}
    for pkg in ("bondgraph", "sympy", "numba", "llvmlite", "numpy", "scipy", "networkx"):
        try:
            vers[pkg] = version(pkg)
        except PackageNotFoundError:
            pass
    import hashlib

    h = hashlib.sha256()
    for sub in ("bondgraph", "library", "models"):
        folder = os.path.join(ROOT, sub)
        for name in sorted(os.listdir(folder)):
            if name.endswith(".py"):
                with open(os.path.join(folder, name), "rb") as fh:
                    h.update(name.encode() + fh.read())
    return {
        "source_sha256": h.hexdigest()[:16],
        "cpu": cpu,
        "cores": os.cpu_count(),
        "memory": mem,
        "python": platform.python_version(),
        "platform": platform.platform(),
        "packages": vers,
        "openblas_coretype": os.environ.get("OPENBLAS_CORETYPE", ""),
    }


def goal_rows(res):
    """[(goal, figure, met)] for every goal that this run measured."""
    rows = []
    d = res.get("derive")
    p = res.get("peers")
    if p and p.get("peers"):
        ours10 = median(p["ours"].get(10, {}).get("times", []))
        peer10 = {k: median(v.get(10, {}).get("times", [])) for k, v in p["peers"].items()}
        peer10 = {k: v for k, v in peer10.items() if not math.isnan(v)}
        if peer10:
            fastest = min(peer10, key=peer10.get)
            ratio = peer10[fastest] / ours10
            rows.append(
                (
                    f"derivation, N=10 chain, >= {GOALS['derive_vs_peer']:.0f}x faster than the fastest peer",
                    f"{ratio:.0f}x ({PEER_LABEL[fastest]} {fmt_s(peer10[fastest])} vs ours {fmt_s(ours10)})",
                    ratio >= GOALS["derive_vs_peer"],
                )
            )
    if d:
        e = d["chain_exponent_derive"]
        lo, hi = d.get("exponent_range") or (20, 320)
        rows.append(
            (
                f"derivation growth exponent <= {GOALS['derive_exponent']} (chain N={lo}..{hi})",
                f"{e:.2f}",
                e <= GOALS["derive_exponent"],
            )
        )
        s400 = d["stack"].get(400) or d["stack"].get(max(d["stack"]))
        nmax = 400 if 400 in d["stack"] else max(d["stack"])
        tot = median(s400["derive"]["times"]) + median(s400["compile"].get("compile_s", []))
        rows.append(
            (
                f"{nmax}-layer stack derived + compiled < {GOALS['stack400_total_s']:.0f} s",
                f"{fmt_s(tot)} (derive {fmt_s(median(s400['derive']['times']))} + compile "
                f"{fmt_s(median(s400['compile'].get('compile_s', [])))})",
                tot < GOALS["stack400_total_s"],
            )
        )
        c = d["chain"].get(320) or d["chain"][max(d["chain"])]
        nmax = 320 if 320 in d["chain"] else max(d["chain"])
        ct = median(c["compile"].get("compile_s", []))
        rows.append(
            (
                f"compilation of the N={nmax} chain < {GOALS['compile_chain320_s']:.0f} s",
                fmt_s(ct),
                ct < GOALS["compile_chain320_s"],
            )
        )
        # the cache matters for models numba compiles (larger ones run on the tape interpreter,
        # which has nothing to compile): judge it on the largest chain compiled by numba
        compiled = [n for n in sorted(d["chain"]) if median(d["chain"][n]["compile"].get("compile_s", [0])) > 0.5]
        nc = compiled[-1] if compiled else nmax
        cold = median(d["chain"][nc]["compile"].get("compile_s", []))
        cc = median(d["chain"][nc]["compile"].get("cached_compile_s", []))
        rows.append(
            (
                f"second run of the same model skips compilation (cached; N={nc}, numba-compiled)",
                f"{fmt_s(cc)} vs {fmt_s(cold)} cold",
                cc < 0.2 * cold,
            )
        )
    for s in res.get("simulate") or []:
        rows.append(
            (
                f"simulation {s['case']}: >= {GOALS['sim_vs_naive']:.0f}x faster than the naive route",
                f"{s['speedup_vs_naive']:.1f}x",
                s["speedup_vs_naive"] >= GOALS["sim_vs_naive"],
            )
        )
        rows.append(
            (
                f"simulation {s['case']}: within {GOALS['sim_vs_limit']:.0f}x of the compiled limit",
                f"{s['ratio_to_limit']:.2f}x",
                s["ratio_to_limit"] <= GOALS["sim_vs_limit"],
            )
        )
        rows.append(
            (
                f"simulation {s['case']}: results equal to the naive route within tolerance",
                "yes" if s["agree_ok"] else "NO",
                s["agree_ok"],
            )
        )
    dg = res.get("diagnose")
    if dg and dg.get("status") == "ok":
        rows.append(
            (
                f"diagnosis of 250k samples < {GOALS['diagnose_s']:.0f} s and < {GOALS['diagnose_mb']:.0f} MB",
                f"{fmt_s(dg['seconds'])}, {dg['peak_mb']:.0f} MB",
                dg["seconds"] < GOALS["diagnose_s"] and dg["peak_mb"] < GOALS["diagnose_mb"],
            )
        )
    return rows


def tables(res) -> str:
    """Markdown tables of every figure of this run."""
    out = []
    d = res.get("derive")
    if d:
        out.append("### 1. Derivation and compilation (medians; n = repetitions)\n")
        out.append(
            "| model | N | states | derivation | compilation, cold (fresh process, empty cache) | of which source generation | compilation, cached second run | peak RSS (compile) |"
        )
        out.append("|---|---:|---:|---:|---:|---:|---:|---:|")
        for kind in ("chain", "stack"):
            for n, r in d[kind].items():
                c = r["compile"]
                dd = r["derive"]
                dtxt = (
                    "> timeout"
                    if dd.get("timeout") and not dd["times"]
                    else f"{fmt_s(median(dd['times']))} (n={len(dd['times'])})"
                )
                ctxt = (
                    c.get("error")
                    if c.get("error") and not c.get("compile_s")
                    else f"{fmt_s(median(c.get('compile_s', [])))} (n={c.get('reps')})"
                )
                out.append(
                    f"| {kind} | {n} | {c.get('states') or dd.get('states') or '-'} | {dtxt} | {ctxt} | "
                    f"{fmt_s(median(c.get('generate_source_s', [])))} | {fmt_s(median(c.get('cached_compile_s', [])))} | "
                    f"{median(c.get('peak_mb', [])):.0f} MB |"
                )
        rng = d.get("exponent_range")
        out.append("")
        out.append(
            f"Growth exponents (least squares on log-log): chain N = {rng[0]}..{rng[1]}: derivation "
            f"**{d['chain_exponent_derive']:.2f}**, compilation **{d['chain_exponent_compile']:.2f}**; "
            f"stack N = {min(d['stack'])}..{max(d['stack'])}: derivation {d['stack_exponent_derive']:.2f}, "
            f"compilation {d['stack_exponent_compile']:.2f}.\n"
        )
    p = res.get("peers")
    if p:
        out.append(
            "### 2. Derivation of the N-mass chain against peers (medians; sympy cache cleared per repetition)\n"
        )
        if not p.get("peers"):
            out.append(
                "Peers not run: " + "; ".join(f"{PEER_LABEL[k]}: {v}" for k, v in p.get("skipped", {}).items()) + "\n"
            )
        else:
            names = list(p["peers"])
            out.append("| N | ours | " + " | ".join(f"{PEER_LABEL[k]} | ratio" for k in names) + " |")
            out.append("|---:|---:|" + "---:|---:|" * len(names))
            for n in p["ns"]:
                ours = median(p["ours"][n]["times"])
                cells = [f"{n}", f"{fmt_s(ours)} (n={len(p['ours'][n]['times'])})"]
                for k in names:
                    r = p["peers"][k].get(n, {})
                    if r.get("times"):
                        t = median(r["times"])
                        cells += [f"{fmt_s(t)} (n={len(r['times'])})", f"{t / ours:.0f}x"]
                    elif r.get("timeout"):
                        cells += [f"> {res['args']['timeout']:.0f} s", f"> {res['args']['timeout'] / ours:.0f}x"]
                    else:
                        cells += [r.get("error", "-"), "-"]
                out.append("| " + " | ".join(cells) + " |")
            out.append("")
            ex = p.get("exponents", {})
            out.append(
                "Peer growth exponents over the N they finished: "
                + ", ".join(f"{PEER_LABEL[k]} {v:.2f}" for k, v in ex.items())
                + ". "
                + "State-matrix eigenvalues of the N = 10 chain: "
                + ", ".join(
                    f"{PEER_LABEL[k]} equal to ours within {p['peers'][k].get(10, {}).get('eig_max_rel_diff', float('nan')):.0e}"
                    for k in names
                )
                + ". Versions: "
                + ", ".join(f"{k} {v}" for k, v in p.get("versions", {}).items())
                + ".\n"
            )
            for k, v in p.get("skipped", {}).items():
                out.append(f"{PEER_LABEL[k]} skipped: {v}\n")
    sims = res.get("simulate")
    if sims:
        out.append(
            f"### 3. Simulation: {sims[0]['t_end']:g} s of model time, 10 kHz output ({sims[0]['samples']} samples), "
            f"rtol = {sims[0]['rtol']:g} (medians)\n"
        )
        out.append(
            "| workload | ours | naive (lambdify + solve_ivp) | speed-up | compiled limit (hand-written numba) | ours / limit | steps ours / limit / naive | max difference / range (naive, limit) |"
        )
        out.append("|---|---:|---:|---:|---:|---:|---:|---|")
        for s in sims:
            worst_n = max(s["agree_naive"].items(), key=lambda kv: kv[1] / s["agree_tol"][kv[0]])
            worst_l = max(s["agree_limit"].items(), key=lambda kv: kv[1] / s["agree_tol"][kv[0]])
            naive_txt = fmt_s(median(s["naive_s"]))
            if s.get("naive_scaled"):
                naive_txt += f" (scaled from {s['naive_scaled']['t_end']:g} s)"
            out.append(
                f"| {s['case']} | {fmt_s(median(s['ours_s']))} | {naive_txt} | {s['speedup_vs_naive']:.1f}x | "
                f"{fmt_s(median(s['limit_s']))} | {s['ratio_to_limit']:.2f}x | "
                f"{s['ours_stats']['steps']} / {s['limit_stats']['steps']} / {s['naive_stats'].get('steps') or '-'} | "
                f"{worst_n[0]}: {worst_n[1]:.1e}, {worst_l[0]}: {worst_l[1]:.1e} "
                f"({'within' if s['agree_ok'] else 'NOT within'} tolerance) |"
            )
        out.append("")
        for s in sims:
            out.append(
                f"- {s['case']}: {s['desc']}; ours {s['ours_stats']['rhs_calls']} RHS calls, "
                f"{s['ours_stats']['rejected']} rejected steps ({s['ours_stats'].get('reversal_rejections', 0)} at "
                f"operator reversals); naive set-up (lambdify) {fmt_s(s['naive_setup_s'])}; ratios per round "
                f"(ours/limit) {', '.join(f'{x:.2f}' for x in s.get('ratio_rounds', []))}."
            )
        out.append("")
    dg = res.get("diagnose")
    if dg:
        out.append("### 4. Diagnosis\n")
        if dg.get("status") == "ok":
            out.append(
                f"`bondgraph diagnose` on {dg['samples']} samples: {fmt_s(dg['seconds'])} wall, peak {dg['peak_mb']:.0f} MB.\n"
            )
        else:
            out.append(f"{dg.get('status')}\n")
    return "\n".join(out)


def goals_table(res) -> str:
    rows = goal_rows(res)
    if not rows:
        return ""
    lines = []
    if res.get("args", {}).get("quick"):
        lines += ["**--quick run: smaller models and 1 s of model time; these rows do not test the goals.**", ""]
    lines += ["| goal | this run | met |", "|---|---|---|"]
    lines += [f"| {g} | {f} | {'yes' if ok else '**no**'} |" for g, f, ok in rows]
    return "\n".join(lines)


def write_readme(res, path):
    """Replace the generated section of benchmarks/README.md with this run's figures."""
    start, end = "<!-- results:start -->", "<!-- results:end -->"
    m = res["machine"]
    body = [
        start,
        "",
        f"Latest run: {res['date']}, command `{res['command']}` ({res['wall_s'] / 60:.1f} min)."
        + "".join(
            f" Figures of workloads {', '.join(e['workloads'])} from the run of {e['date']}, `{e['command']}`."
            for e in res.get("earlier_runs", [])
        ),
        f"Machine: {m['cpu']}, {m['cores']} cores, {m['memory']}, {m['platform']}; Python {m['python']}; "
        + ", ".join(f"{k} {v}" for k, v in m["packages"].items())
        + f"; framework sources (bondgraph/, library/, models/) sha256 {m['source_sha256']}.",
        "Shared machine: every figure is a median of the repetitions shown; each ratio is taken between figures of one invocation.",
        "",
        "#### Goals",
        "",
        goals_table(res),
        "",
        tables(res),
        end,
    ]
    text = open(path, encoding="utf-8").read() if os.path.exists(path) else ""
    if start in text and end in text:
        text = text[: text.index(start)] + "\n".join(body) + text[text.index(end) + len(end) :]
    else:
        text = text.rstrip() + "\n\n" + "\n".join(body) + "\n"
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text)


def _int_keys(obj):
    """JSON turns the N keys into strings; turn them back."""
    if isinstance(obj, dict):
        return {(int(k) if isinstance(k, str) and k.isdigit() else k): _int_keys(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_int_keys(v) for v in obj]
    return obj


def main(argv=None):
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--quick", action="store_true", help="small sizes, 1 s of model time: a smoke test of the suite")
    ap.add_argument("--peers", action="store_true", help="install and time the peers (BondGraphTools, PyPI bondgraph)")
    ap.add_argument("--workloads", default="derive,peers,simulate,diagnose")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--timeout", type=float, default=120.0, help="per peer/derivation run (s); compilation gets 5x")
    ap.add_argument(
        "--naive-limit",
        type=float,
        default=600.0,
        help="run the naive simulation on a shorter horizon if it would take longer (s)",
    )
    ap.add_argument("--out", default=os.path.join(HERE, "results.json"))
    ap.add_argument("--readme", action="store_true", help="write the figures into benchmarks/README.md")
    ap.add_argument(
        "--merge",
        action="store_true",
        help="keep the other workloads' figures from an existing --out file (each ratio still "
        "comes from one invocation)",
    )
    args = ap.parse_args(argv)
    sys.path.insert(0, HERE)
    wl = [w.strip() for w in args.workloads.split(",") if w.strip()]
    unknown = set(wl) - {"derive", "peers", "simulate", "diagnose"}
    if unknown:
        ap.error(f"unknown workload(s) {sorted(unknown)}")
    t0 = time.time()
    res = {
        "date": _dt.datetime.now().astimezone().isoformat(timespec="seconds"),
        "command": "python benchmarks/run.py " + " ".join(argv if argv is not None else sys.argv[1:]),
        "machine": machine(),
        "args": vars(args),
        "goals": GOALS,
    }
    if args.merge and os.path.exists(args.out):
        with open(args.out, encoding="utf-8") as fh:
            old = json.load(fh)
        for key in ("derive", "peers", "simulate", "diagnose"):
            if key not in wl and key in old:
                res[key] = _int_keys(old[key])
        kept = [k for k in ("derive", "peers", "simulate", "diagnose") if k in old and k not in wl]
        earlier = [dict(e, workloads=[k for k in e["workloads"] if k not in wl]) for e in old.get("earlier_runs", [])]
        earlier.append(
            {
                "date": old.get("date"),
                "command": old.get("command"),
                "workloads": [k for k in kept if not any(k in e["workloads"] for e in earlier)],
            }
        )
        res["earlier_runs"] = [e for e in earlier if e["workloads"]]
    m = res["machine"]
    log(
        f"machine: {m['cpu']}, {m['cores']} cores, {m['memory']}; Python {m['python']}; "
        + ", ".join(f"{k} {v}" for k, v in m["packages"].items())
    )
    workloads = [
        ("derive", "derivation and compilation", workload_derive),
        ("peers", "peers", workload_peers),
        ("simulate", "simulation", workload_simulate),
        ("diagnose", "diagnosis", workload_diagnose),
    ]
    for k, (key, title, work) in enumerate(workloads, 1):
        if key in wl:
            log(f"\n[{k}] {title}")
            res[key] = work(args)
    res["wall_s"] = time.time() - t0
    with open(args.out, "w", encoding="utf-8") as fh:
        json.dump(res, fh, indent=1, default=str)
    log("\n" + tables(res))
    log("Goals:\n" + goals_table(res))
    log(f"\nwrote {args.out} ({res['wall_s'] / 60:.1f} min)")
    if args.readme:
        write_readme(res, os.path.join(HERE, "README.md"))
        log(f"updated {os.path.join(HERE, 'README.md')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
