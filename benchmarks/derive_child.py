"""Child process for workload 1 (our framework); run by run.py, one fresh interpreter per call.

    python derive_child.py derive  --kind chain|stack --n N --reps R --budget S [--eig]
    python derive_child.py compile --kind chain|stack --n N

``derive``: warm-up derivation of a 2-element model (imports, lazily loaded sympy parts, as for
the peers), then per repetition: clear the sympy cache, build the graph (not timed), time
``bondgraph.derive`` (causality + state equations).  One JSON line per repetition.

``compile``: in this fresh interpreter (so neither numba's nor sympy's in-process caches help)
build and derive the model, then time ``compile_equations`` plus the first call of the
generated ``rhs`` and ``output`` (source generation, writing the cache file, numba compilation
or loading machine code from the cache).  The cache directory is $BONDGRAPH_CACHE, chosen by
the parent: a new empty directory for a cold compilation, the same one again for the cached
second run.  Also reports how long source generation alone takes (``generate_source``) and the
peak resident memory of the process.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def build(kind: str, n: int):
    from bench_models import chain_model, stack_model

    return chain_model(n) if kind == "chain" else stack_model(n)


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def cmd_derive(a):
    from sympy.core.cache import clear_cache

    import bondgraph as bg

    bg.derive(build(a.kind, 2))  # warm-up
    spent = 0.0
    eqs = None
    for rep in range(a.reps):
        clear_cache()
        model = build(a.kind, a.n)
        t0 = time.perf_counter()
        eqs = bg.derive(model)
        dt = time.perf_counter() - t0
        spent += dt
        print(
            json.dumps({"rep": rep, "seconds": dt, "states": len(eqs.states), "statements": len(eqs.program)}),
            flush=True,
        )
        if spent > a.budget:
            break
    if a.eig and eqs is not None:
        import numpy as np
        import sympy as sp

        xs = eqs.state_symbols
        J = eqs.jacobian([eqs.rates[s] for s in xs], xs)
        table = eqs.model.parameter_table()
        A = np.array(J.xreplace({k: sp.Float(v) for k, v in table.items()}).tolist(), dtype=float)
        ev = np.linalg.eigvals(A)
        print(json.dumps({"eig": sorted([[float(e.real), float(e.imag)] for e in ev])}), flush=True)
    print(json.dumps({"done": True, "peak_mb": peak_mb()}), flush=True)


def cmd_compile(a):
    import numpy as np
    from sympy.core.cache import clear_cache

    import bondgraph as bg
    from bondgraph.numerics.codegen import compile_equations, generate_source

    t0 = time.perf_counter()
    model = build(a.kind, a.n)
    t1 = time.perf_counter()
    eqs = bg.derive(model)
    t2 = time.perf_counter()
    src = generate_source(eqs)
    t3 = time.perf_counter()
    clear_cache()
    t4 = time.perf_counter()
    comp = compile_equations(eqs)
    nx = len(eqs.states)
    nu = max(len(eqs.inputs), 1)
    x = np.zeros(nx)
    u = np.zeros(nu)
    th = np.array([float(v) for v in eqs.model.parameter_table().values()])
    mem = np.zeros(max(comp.layout.n_mem, 1))
    out = np.zeros(max(nx, len(eqs.outputs), 1))
    comp.rhs(0.0, x, u, u, th, mem, comp.aux.copy(), out)
    comp.output(0.0, x, u, u, th, mem, comp.aux.copy(), out)
    t5 = time.perf_counter()
    print(
        json.dumps(
            {
                "build": t1 - t0,
                "derive": t2 - t1,
                "generate_source": t3 - t2,
                "compile": t5 - t4,
                "source_bytes": len(src),
                "states": nx,
                "statements": len(eqs.program),
                "peak_mb": peak_mb(),
                "cache": os.environ.get("BONDGRAPH_CACHE", ""),
            }
        ),
        flush=True,
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=("derive", "compile"))
    ap.add_argument("--kind", choices=("chain", "stack"), required=True)
    ap.add_argument("--n", type=int, required=True)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--budget", type=float, default=60.0)
    ap.add_argument("--eig", action="store_true")
    a = ap.parse_args()
    (cmd_derive if a.mode == "derive" else cmd_compile)(a)


if __name__ == "__main__":
    main()
