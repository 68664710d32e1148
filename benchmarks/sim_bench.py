"""Workload 3: simulation throughput of our route against the naive route and the compiled limit.

Workloads (10 s of model time, output at 10 kHz = 100 001 samples, rtol = 1e-6):

* ``chain10``: the N = 10 chain driven by F = chirp(10 N, 1 → 50 Hz over 10 s), sweeping
  through all ten modes (19 to 39 Hz); outputs xN (last mass) and v1 (first mass).
* ``apa_pi``: models/apa120ml.py with hysteresis=pi (modified PI, 12 plays, 6 dead zones) and
  its default drive V = 60 + 60·sin(2π·5 t − 90°) V; outputs x, i, p, E.

Routes:

* ours: ``Simulator(model).run(t, inputs, method="dopri5", rtol=1e-6)`` (derived and compiled
  once; only ``run`` is timed; default atol floor, error weight relative to each state's peak);
* naive: the same symbolic equations, fully substituted (``Equations.state_equations()``,
  ``output_equations()``, ``operator_inputs()``) through ``sympy.lambdify`` (numpy) and scipy's
  RK45 with the same rtol and atol_i = rtol·max|x_i| (the peak of each state in our run, so the
  error weights match ours).  Without memory operators: ``solve_ivp(..., t_eval=t)``; with
  them: the step-by-step ``scipy.integrate.RK45`` object, the operator written in Python
  (``ModifiedPI.output``) inside the RHS with its memory frozen, outputs sampled from each
  step's dense output, the memory committed (``ModifiedPI.commit``) after each accepted step
  and the FSAL derivative refreshed.  Lambdify time is reported separately as setup;
* limit: handwritten.py, a hand-written numba DOPRI5 of the same equations (same tableau,
  tolerances, error norm, step control and output sampling), compiled before timing.

Every route's outputs are compared with ours: max |difference| / (range of the output) must be
below 1e-4 (rtol = 1e-6).  If a pilot run of the naive route predicts more than
``naive_limit`` seconds, it is run on a shorter horizon and its time scaled up, and the result
says so.
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

T_END = 10.0
DT = 1e-4
RTOL = 1e-6
AGREE = 1e-4


def _median(xs):
    return float(np.median(xs)) if xs else float("nan")


def _timed(fn, repeat: int, budget: float):
    """Run fn() up to ``repeat`` times (at least once, stop early past ``budget`` s)."""
    times, out, spent = [], None, 0.0
    for _ in range(max(repeat, 1)):
        t0 = time.perf_counter()
        out = fn()
        dt = time.perf_counter() - t0
        times.append(dt)
        spent += dt
        if spent > budget:
            break
    return times, out


def _agreement(ref: dict, other: dict, n: int | None = None) -> dict:
    """max |a - b| / range(a) per named series over the first n samples."""
    res = {}
    for k, a in ref.items():
        a = np.asarray(a)[:n]
        b = np.asarray(other[k])[:n]
        rng = float(np.ptp(a)) or 1.0
        res[k] = float(np.max(np.abs(a - b)) / rng)
    return res


def _sensitivity(sim, case, states: dict, outputs: dict) -> dict:
    """kappa_k = sum_j |dy_k/dx_j| * range(x_j) / range(y_k) at the initial state (operators at
    their small-signal gain): how much output k amplifies state differences of the size the
    integrator controls.  A state-valued output has kappa = 1."""
    import sympy as sp

    eqs = sim.eqs
    xs = eqs.state_symbols
    gains = {}
    th = sim.theta()
    pidx = {p: i for i, p in enumerate(eqs.params)}
    for ob in eqs.operators:
        gains[ob.symbol] = ob.operator.small_signal_gain(np.array([th[pidx[s]] for s in ob.params]))
    J = eqs.jacobian([eqs.outputs[k] for k in case["outputs"]], xs, gains)
    subs = {p: sp.Float(v) for p, v in zip(eqs.params, th)}
    subs.update({x: sp.Float(v) for x, v in zip(xs, sim.initial_state(th))})
    subs.update({u: sp.Float(0) for u in list(eqs.inputs) + list(eqs.input_rates)})
    Jn = np.array(J.xreplace(subs).tolist(), dtype=float)
    rx = np.array([np.ptp(states[str(x)]) for x in xs])
    out = {}
    for i, k in enumerate(case["outputs"]):
        ry = float(np.ptp(outputs[k])) or 1.0
        out[k] = max(1.0, float(np.sum(np.abs(Jn[i]) * rx)) / ry)
    return out


# ---- model set-up ----------------------------------------------------------------------------
def setup_chain():
    from bench_models import chain_model, chain_values

    import bondgraph as bg

    n = 10
    model = chain_model(n)
    sig = dict(amplitude=10.0, f0=1.0, f1=50.0, t1=10.0)

    def u_py(t):  # the same chirp in plain Python, value and derivative
        beta = (sig["f1"] - sig["f0"]) / sig["t1"]
        ph = 2.0 * math.pi * (sig["f0"] * t + 0.5 * beta * t * t)
        return [sig["amplitude"] * math.cos(ph)], [
            -sig["amplitude"] * math.sin(ph) * 2.0 * math.pi * (sig["f0"] + beta * t)
        ]

    from handwritten import chain_prm

    return {
        "name": "chain10",
        "model": model,
        "inputs": {"F": bg.Chirp(**sig)},
        "u_py": u_py,
        "outputs": ["xN", "v1"],
        "limit": "chain",
        "limit_prm": chain_prm(n, chain_values(n), sig["amplitude"], sig["f0"], sig["f1"], sig["t1"]),
        "desc": "N=10 chain, F = chirp(10 N, 1->50 Hz in 10 s)",
    }


def setup_apa():
    from bench_models import apa_pi

    lm = apa_pi()
    model = lm.model
    V = lm.experiment.inputs["V"]
    amp, freq, phase, offset = V.par[0], V.par[1], math.degrees(V.par[2]), V.par[3]

    def u_py(t):  # inputs (V, F) in plain Python
        w = 2.0 * math.pi * freq
        return [offset + amp * math.sin(w * t + V.par[2]), 0.0], [amp * w * math.cos(w * t + V.par[2]), 0.0]

    from handwritten import apa_prm

    op = next(iter(model.operators.values())).operator
    return {
        "name": "apa_pi",
        "model": model,
        "inputs": {"V": V},
        "u_py": u_py,
        "outputs": ["x", "i", "p", "E"],
        "limit": "apa_pi",
        "limit_prm": apa_prm(model.parameter_table(), op, amp, freq, phase, offset),
        "op": op,
        "desc": f"APA-120ML, modified PI ({op.thresholds.size} plays, {op.deadzones.size} dead zones), "
        f"V = {offset:g} + {amp:g} sin(2 pi {freq:g} t {phase:+g} deg) V",
    }


# ---- routes ------------------------------------------------------------------------------------
def run_ours(sim, case, t):
    return sim.run(t, case["inputs"], method="dopri5", rtol=RTOL)


def make_naive(sim, case):
    """Lambdified naive route for ``case``; returns run(t) -> (outputs dict, info)."""
    import sympy as sp

    eqs = sim.eqs
    xs = eqs.state_symbols
    us = list(eqs.inputs)
    dus = list(eqs.input_rates)
    ths = list(eqs.params)
    hs = [ob.symbol for ob in eqs.operators]
    tsym = sp.Symbol("t", real=True)
    full = eqs.state_equations()
    outs = eqs.output_equations()
    opins = eqs.operator_inputs()
    args = [tsym, xs, us, dus, ths, hs]
    f_rates = sp.lambdify(args, [full[x] for x in xs], modules="numpy")
    f_outs = sp.lambdify(args, [outs[k] for k in case["outputs"]], modules="numpy")
    f_opin = sp.lambdify(args, [opins[h] for h in hs], modules="numpy") if hs else None
    th = [float(v) for v in sim.theta()]
    x0 = sim.initial_state(np.array(th))
    u_py = case["u_py"]
    ops = [ob.operator for ob in eqs.operators]
    # operator parameters, in each block's parameter order
    pidx = {p: i for i, p in enumerate(ths)}
    op_prm = [np.array([th[pidx[s]] for s in ob.params]) for ob in eqs.operators]

    def run(t, atol):
        from scipy.integrate import RK45, solve_ivp

        if not ops:

            def fun(tt, x):
                u, du = u_py(tt)
                return np.array(f_rates(tt, x, u, du, th, ()))

            sol = solve_ivp(fun, (t[0], t[-1]), x0, method="RK45", t_eval=t, rtol=RTOL, atol=atol)
            if sol.status != 0:
                raise RuntimeError(sol.message)
            U = [u_py(tt)[0] for tt in t]
            Uc = np.array(U).T
            Y = f_outs(t, sol.y, list(Uc), [0.0] * len(us), th, ())
            res = {k: np.broadcast_to(np.asarray(y, float), t.shape).copy() for k, y in zip(case["outputs"], Y)}
            res.update({f"state {x}": sol.y[j] for j, x in enumerate(xs)})
            return res, {"steps": None, "rhs_calls": int(sol.nfev)}
        # memory operators: step by step, commit after each accepted step
        u0, du0 = u_py(t[0])
        v0 = f_opin(t[0], x0, u0, du0, th, [0.0] * len(ops))
        mem = [op.initial_memory(float(v), p) for op, v, p in zip(ops, v0, op_prm)]

        def hvals(tt, x, u, du):
            v = f_opin(tt, x, u, du, th, [0.0] * len(ops))
            return [op.output(vk, m, p) for op, vk, m, p in zip(ops, v, mem, op_prm)]

        def fun(tt, x):
            u, du = u_py(tt)
            return np.array(f_rates(tt, x, u, du, th, hvals(tt, x, u, du)))

        Y = np.zeros((t.size, len(case["outputs"])))
        X = np.zeros((t.size, len(xs)))
        X[0] = x0
        s = RK45(fun, t[0], x0, t[-1], rtol=RTOL, atol=atol)
        u, du = u_py(t[0])
        Y[0] = f_outs(t[0], x0, u, du, th, hvals(t[0], x0, u, du))
        k = 1
        steps = 0
        while s.status == "running":
            msg = s.step()
            if s.status == "failed":
                raise RuntimeError(f"naive RK45 failed at t={s.t}: {msg}")
            steps += 1
            if k < t.size and t[k] <= s.t:
                dense = s.dense_output()
                while k < t.size and t[k] <= s.t:
                    xk = dense(t[k])
                    X[k] = xk
                    u, du = u_py(t[k])
                    Y[k] = f_outs(t[k], xk, u, du, th, hvals(t[k], xk, u, du))
                    k += 1
            u, du = u_py(s.t)
            v = f_opin(s.t, s.y, u, du, th, [0.0] * len(ops))
            for op, vk, m, p in zip(ops, v, mem, op_prm):
                op.commit(vk, m, p)
            s.f = s.fun(s.t, s.y)  # memory changed: refresh the FSAL derivative
        res = {kname: Y[:, j] for j, kname in enumerate(case["outputs"])}
        res.update({f"state {x}": X[:, j] for j, x in enumerate(xs)})
        return res, {"steps": steps, "rhs_calls": int(s.nfev)}

    return run


def run_limit(case, sim, t, atol_vec):
    from handwritten import integrator

    fn = integrator(case["limit"])
    x0 = sim.initial_state(sim.theta())
    prm = case["limit_prm"]
    if "op" in case:
        op = case["op"]
        n_ops = 1
        mem0 = op.initial_memory(float(x0[1]), op.parameter_values())
    else:
        n_ops = 0
        mem0 = np.zeros(1)
    X = np.zeros((t.size, x0.size))
    Y = np.zeros((t.size, len(case["outputs"])))
    stats = np.zeros(4, np.int64)
    status = fn(x0, prm, mem0.copy(), n_ops, True, t, RTOL, atol_vec, X, Y, stats)
    if status != 0:
        raise RuntimeError(f"hand-written integrator failed (status {status})")
    res = {k: Y[:, j] for j, k in enumerate(case["outputs"])}
    res.update({f"state {x}": X[:, j] for j, x in enumerate(sim.state_names)})
    return res, {
        "steps": int(stats[0]),
        "rejected": int(stats[1]),
        "rhs_calls": int(stats[2]),
        "reversal_rejections": int(stats[3]),
    }


def bench_case(case, repeat: int, naive_limit: float, t_end: float = T_END, log=print) -> dict:
    from bondgraph import Simulator, config

    ATOL_FLOOR = config.get("simulate.atol_floor")

    t = np.linspace(0.0, t_end, int(round(t_end / DT)) + 1)
    res: dict = {"case": case["name"], "desc": case["desc"], "t_end": t_end, "samples": int(t.size), "rtol": RTOL}
    t0 = time.perf_counter()
    sim = Simulator(case["model"])
    res["ours_setup_s"] = time.perf_counter() - t0  # derive + compile (from the cache if warm)
    res["auto_method"] = sim.choose_method(
        t,
        sim.initial_state(sim.theta()),
        sim.theta(),
        sim.initial_memory(0.0, sim.initial_state(sim.theta()), sim.theta(), sim.signal_bank(case["inputs"])),
        sim.signal_bank(case["inputs"]),
    )
    run_ours(sim, case, t[:11])  # warm-up: loads the compiled integrator
    r = run_ours(sim, case, t)  # reference result (also sets the naive route's atol)
    ours = {k: r[k] for k in case["outputs"]}
    ours.update({f"state {x}": r.states[x] for x in sim.state_names})
    kappa = _sensitivity(sim, case, r.states, ours)
    res["output_sensitivity"] = kappa
    tol = {k: AGREE * kappa.get(k, 1.0) for k in ours}
    res["agree_tol"] = tol
    res["ours_stats"] = r.stats
    peak = np.array([np.max(np.abs(r.states[n])) for n in sim.state_names])
    atol_vec = np.maximum(RTOL * peak, ATOL_FLOOR)
    atol_floor = np.full(peak.size, ATOL_FLOOR)
    t0 = time.perf_counter()
    run_limit(case, sim, t[:11], atol_floor)  # numba compilation of the hand-written integrator
    res["limit_compile_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    naive = make_naive(sim, case)
    res["naive_setup_s"] = time.perf_counter() - t0
    n_pilot = max(int(t.size // 100), 11)
    t0 = time.perf_counter()
    naive(t[:n_pilot], atol_vec)
    pilot = time.perf_counter() - t0
    predicted = pilot * (t.size - 1) / (n_pilot - 1)
    res["naive_pilot"] = {"t_end": float(t[n_pilot - 1]), "seconds": pilot, "predicted_full_s": predicted}
    if predicted > naive_limit:
        frac = max(naive_limit / predicted, 0.01)
        n_short = max(int((t.size - 1) * frac) + 1, n_pilot)
        tn = t[:n_short]
        res["naive_scaled"] = {"t_end": float(tn[-1]), "factor": (t.size - 1) / (n_short - 1)}
        log(
            f"  {case['name']}: naive route predicted {predicted:.0f} s > {naive_limit:.0f} s: running "
            f"{tn[-1]:g} s of model time and scaling its time by {(t.size - 1) / (n_short - 1):.2f}"
        )
    else:
        tn = t
        res["naive_scaled"] = None
    scale = (t.size - 1) / (tn.size - 1)
    # timed rounds, side by side: ours, limit, naive (naive while its budget lasts)
    ours_t, lim_t, naive_t, ratios = [], [], [], []
    lim = lst = nv = nst = None
    for rnd in range(max(repeat, 3)):
        t0 = time.perf_counter()
        run_ours(sim, case, t)
        ours_t.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        lim, lst = run_limit(case, sim, t, atol_floor)
        lim_t.append(time.perf_counter() - t0)
        ratios.append(ours_t[-1] / lim_t[-1])
        if rnd < repeat and (not naive_t or sum(naive_t) < 120.0):
            t0 = time.perf_counter()
            nv, nst = naive(tn, atol_vec)
            naive_t.append(time.perf_counter() - t0)
        log(
            f"  {case['name']} round {rnd + 1}: ours {ours_t[-1]:.3f} s, limit {lim_t[-1]:.3f} s"
            + (f", naive {naive_t[-1]:.2f} s" if len(naive_t) == rnd + 1 else "")
        )
    res["ours_s"] = ours_t
    res["limit_s"] = lim_t
    res["ratio_rounds"] = ratios
    res["limit_stats"] = lst
    res["agree_limit"] = _agreement(ours, lim)
    res["naive_s_measured"] = naive_t
    res["naive_s"] = [x * scale for x in naive_t]
    res["naive_stats"] = nst
    res["agree_naive"] = _agreement(ours, nv, tn.size)
    log(
        f"  {case['name']}: ours {_median(ours_t):.3f} s ({r.stats['steps']} steps), limit {_median(lim_t):.3f} s "
        f"({lst['steps']} steps), naive {_median(naive_t):.2f} s over {tn[-1]:g} s"
        + (f" (x{scale:.2f} -> {_median(res['naive_s']):.1f} s)" if scale != 1 else "")
    )
    res["speedup_vs_naive"] = _median(res["naive_s"]) / _median(res["ours_s"])
    res["ratio_to_limit"] = _median(res["ours_s"]) / _median(res["limit_s"])
    res["agree_ok"] = all(res[f"agree_{r}"][k] < tol[k] for r in ("naive", "limit") for k in tol)
    return res


CASES = {"chain10": setup_chain, "apa_pi": setup_apa}


def run(repeat: int, naive_limit: float, quick: bool = False, log=print) -> list[dict]:
    out = []
    for name, setup in CASES.items():
        case = setup()
        out.append(bench_case(case, repeat, naive_limit, t_end=1.0 if quick else T_END, log=log))
    return out


if __name__ == "__main__":
    import json

    print(json.dumps(run(3, 600.0, quick="--quick" in sys.argv), indent=1, default=str))
