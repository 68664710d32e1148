"""Where the simulation time goes inside the compiled integrator (workload 3), by cost model.

    python benchmarks/profile_sim.py [--t-end 10]

A sampling profiler sees one opaque native frame for numba code, so this measures instead:

1. the per-call cost of every kernel the integrator calls — the generated ``rhs``, ``output``,
   ``opin``, ``commit`` (called through the same first-class function type as in
   ``bondgraph.numerics.integrators.dopri5``), ``eval_inputs`` with the workload's signals, and
   ``_dense`` (one dense-output evaluation) — each in a compiled loop of 10^6 calls;
2. how often the integrator calls each of them in the run (from the run's step statistics and
   the algorithm: 6 stage evaluations per attempted step, 1 dense output + inputs + output per
   sample, with memory operators 6 operator-input evaluations and 4 dense evaluations per
   step that passes the error test, one commit and one FSAL refresh per accepted step);
3. the fixed Python cost of ``Simulator.run`` (a 2-sample run);

and prints count × cost per kernel as a share of the measured run time; the remainder is the
integrator's own arithmetic (stage sums, error norm, weights, bookkeeping).  The hand-written
limit's kernels (handwritten.py) are costed the same way for comparison.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from numba import njit

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

N_CALLS = 1_000_000


@njit
def _loop_fc(fn, n, t, x, u, du, th, mem, aux, out):
    acc = 0.0
    for k in range(n):
        fn(t + k * 1e-12, x, u, du, th, mem, aux, out)
        acc += out[0]
    return acc


@njit
def _loop_static(fn, n, t, x, prm, mem, out):
    acc = 0.0
    for k in range(n):
        fn(t + k * 1e-12, x, prm, mem, out)
        acc += out[0]
    return acc


def _per_call(run, n=N_CALLS, reps=3):
    run(10)  # compile
    best = []
    for _ in range(reps):
        t0 = time.perf_counter()
        run(n)
        best.append(time.perf_counter() - t0)
    return float(np.median(best)) / n


def fc_loop(fn_type):
    """A loop calling a first-class function of the integrator's type (fresh per type)."""
    from numba import types

    sig = types.float64(
        fn_type,
        types.int64,
        types.float64,
        types.float64[::1],
        types.float64[::1],
        types.float64[::1],
        types.float64[::1],
        types.float64[::1],
        types.float64[::1],
        types.float64[::1],
    )
    return njit(sig)(_loop_fc.py_func)


def profile_case(case, t_end: float):
    import bondgraph.numerics.integrators as integ
    from bondgraph import Simulator, config
    from bondgraph.numerics.model_functions import FUNCTION_TYPE

    ATOL_FLOOR = config.get("simulate.atol_floor")

    import sim_bench
    from handwritten import integrator

    sim = Simulator(case["model"])
    t = np.linspace(0.0, t_end, int(round(t_end / sim_bench.DT)) + 1)
    sim_bench.run_ours(sim, case, t[:11])
    runs = []
    for _ in range(3):
        t0 = time.perf_counter()
        r = sim_bench.run_ours(sim, case, t)
        runs.append(time.perf_counter() - t0)
    total = float(np.median(runs))
    st = r.stats
    t0 = time.perf_counter()
    for _ in range(5):
        sim_bench.run_ours(sim, case, t[:2])
    fixed = (time.perf_counter() - t0) / 5

    c = sim.compiled
    th = sim.theta()
    x = sim.initial_state(th) + 1e-9
    bank = sim.signal_bank(case["inputs"])
    mem = sim.initial_memory(0.0, x, th, bank)
    nu = max(len(sim.input_names), 1)
    u, du = np.ones(nu), np.zeros(nu)
    out = np.zeros(max(len(x), len(sim.output_names), 4))
    loop = fc_loop(FUNCTION_TYPE)
    cost = {}
    for name in ("rhs", "output", "opin", "commit"):
        fn = getattr(c, name)
        m = mem.copy()
        cost[name] = _per_call(lambda n, fn=fn, m=m: loop(fn, n, 0.0, x, u, du, th, m, c.aux.copy(), out))
    args = tuple(bank.args())

    @njit
    def loop_inputs(n, a, u, du):
        acc = 0.0
        for k in range(n):
            integ.eval_inputs(k * 1e-7, a[0], a[1], a[2], a[3], a[4], a[5], a[6], u, du, True)
            acc += u[0]
        return acc

    cost["eval_inputs"] = _per_call(lambda n: loop_inputs(n, args, u, du))
    Q = np.random.rand(4, len(x))  # the step's interpolant, computed once per step
    xd = np.zeros(len(x))

    @njit
    def loop_dense(n, x, Q, out):
        acc = 0.0
        for k in range(n):
            integ._dense(x, Q, 1e-4, (k % 100) / 100.0, out)
            acc += out[0]
        return acc

    cost["_dense"] = _per_call(lambda n: loop_dense(n, x, Q, xd))

    samples = t.size
    attempts = st["steps"] + st["rejected"]
    checked = st["steps"] + st.get("reversal_rejections", 0)  # steps that passed the error test
    ops = len(sim.eqs.operators) > 0
    counts = {
        "rhs": st["rhs_calls"],
        "eval_inputs": 6 * attempts + (6 * checked if ops else 0) + samples + st["steps"],
        "_dense": samples + (4 * checked if ops else 0),
        "output": samples,
        "opin": 6 * checked if ops else 0,
        "commit": st["steps"] if ops else 0,
    }
    rows = []
    for k, n in counts.items():
        rows.append((k, n, cost[k], n * cost[k]))
    accounted = sum(r[3] for r in rows) + fixed
    # the hand-written limit, run the same way
    from handwritten import apa_rhs, chain_rhs

    fn = integrator(case["limit"])
    lim_times = []
    for _ in range(3):
        t0 = time.perf_counter()
        lim, lst = sim_bench.run_limit(case, sim, t, np.full(len(x), ATOL_FLOOR))
        lim_times.append(time.perf_counter() - t0)
    hand = chain_rhs if case["limit"] == "chain" else apa_rhs
    prm = case["limit_prm"]
    m2 = np.zeros(16)
    lim_rhs = _per_call(lambda n: _loop_static(hand, n, 0.0, x, prm, m2, out))
    return {
        "case": case["name"],
        "total": total,
        "fixed_python": fixed,
        "rows": rows,
        "accounted": accounted,
        "stats": st,
        "samples": samples,
        "limit_total": float(np.median(lim_times)),
        "limit_rhs": lim_rhs,
        "limit_stats": lst,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--t-end", type=float, default=10.0)
    a = ap.parse_args()
    import sim_bench

    for setup in (sim_bench.setup_chain, sim_bench.setup_apa):
        p = profile_case(setup(), a.t_end)
        st = p["stats"]
        print(
            f"\n{p['case']}: run {p['total'] * 1e3:.1f} ms ({st['steps']} steps, {st['rejected']} rejected, "
            f"{st['rhs_calls']} rhs calls, {p['samples']} samples); hand-written limit {p['limit_total'] * 1e3:.1f} ms"
        )
        print(f"  {'kernel':<14}{'calls':>10}{'ns/call':>10}{'ms':>9}{'share':>8}")
        for k, n, c, tt in sorted(p["rows"], key=lambda r: -r[3]):
            print(f"  {k:<14}{n:>10}{c * 1e9:>10.1f}{tt * 1e3:>9.1f}{100 * tt / p['total']:>7.1f}%")
        print(
            f"  {'Python (run set-up, result)':<34}{p['fixed_python'] * 1e3:>9.1f}{100 * p['fixed_python'] / p['total']:>7.1f}%"
        )
        rest = p["total"] - p["accounted"]
        print(f"  {'integrator arithmetic (rest)':<34}{rest * 1e3:>9.1f}{100 * rest / p['total']:>7.1f}%")
        print(
            f"  hand-written rhs: {p['limit_rhs'] * 1e9:.1f} ns/call (generated, first-class: "
            f"{dict((r[0], r[2]) for r in p['rows'])['rhs'] * 1e9:.1f} ns)"
        )


if __name__ == "__main__":
    main()
