"""Peer derivation of the N-mass chain; runs inside the peers' virtual environment.

    python peer_chain.py --peer pypi-bondgraph|bondgraphtools --n N --reps R --budget S [--eig]

Builds the same chain as ``bench_models.chain_model`` with the peer's own API (parameters as
sympy symbols), and times the peer's own route from the built graph to symbolic state
equations:

* PyPI ``bondgraph`` 0.2.0: ``BondGraph.get_state_equations()`` (its SCAP, then repeated
  substitution);
* BondGraphTools 0.4.6: ``BondGraph.constitutive_relations`` (row-reduction of the implicit
  system; returns the relations dx_i - f_i(x, u)).

The sympy cache is cleared before every repetition, and a warm-up on a 2-mass chain runs first
(module imports, lazily loaded sympy parts) so the first repetition is not charged for them.
Prints one JSON line per repetition, flushed, so the parent can enforce a timeout per run.
``--eig`` also prints the eigenvalues of the numeric state matrix (cross-check against ours).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import sympy as sp
from sympy.core.cache import clear_cache


def values(n):
    # same numbers as bench_models.chain_values (this file runs without our package)
    vals = {}
    for i in range(1, n + 1):
        vals[f"m{i}"] = 0.5 + 0.05 * i
        vals[f"k{i}"] = 1.0e4 * (1 + 0.02 * i)
        vals[f"c{i}"] = 2.0 + 0.1 * i
    return vals


# ---- PyPI bondgraph 0.2.0 -------------------------------------------------------------------
def build_pypi(n):
    from bondgraph.common import Bond
    from bondgraph.core import BondGraph
    from bondgraph.elements import Element_C, Element_I, Element_R, Source_effort
    from bondgraph.junctions import JunctionEqualEffort, JunctionEqualFlow

    g = BondGraph()
    src = Source_effort("src", sp.Symbol("F"))
    v = [JunctionEqualFlow(f"v{i}") for i in range(1, n + 1)]
    g.add(Bond(src, v[0]))
    for i in range(1, n + 1):
        g.add(Bond(v[i - 1], Element_I(f"M{i}", sp.Symbol(f"m{i}"), sp.Symbol(f"p{i}"))))
    for i in range(1, n):
        f0 = JunctionEqualEffort(f"F{i}")
        s1 = JunctionEqualFlow(f"s{i}")
        g.add(Bond(v[i - 1], f0))
        g.add(Bond(f0, v[i]))
        g.add(Bond(f0, s1))
        g.add(Bond(s1, Element_C(f"K{i}", 1 / sp.Symbol(f"k{i}"), sp.Symbol(f"q{i}"))))
        g.add(Bond(s1, Element_R(f"D{i}", sp.Symbol(f"c{i}"))))
    g.add(Bond(v[n - 1], Element_C(f"K{n}", 1 / sp.Symbol(f"k{n}"), sp.Symbol(f"q{n}"))))
    g.add(Bond(v[n - 1], Element_R(f"D{n}", sp.Symbol(f"c{n}"))))
    return g


def derive_pypi(g):
    return g.get_state_equations()


def pypi_matrix(eqs, n):
    subs = {sp.Symbol(k): v for k, v in values(n).items()}
    states = list(eqs)
    A = sp.Matrix([[sp.diff(eqs[s], x) for x in states] for s in states]).xreplace(subs)
    return [[float(a) for a in row] for row in A.tolist()]


# ---- BondGraphTools 0.4.6 -------------------------------------------------------------------
def build_bgt(n):
    import BondGraphTools as bgt

    model = bgt.new(name=f"chain{n}")
    src = bgt.new("Se", name="src")  # no value: a control variable u_0
    v = [bgt.new("1", name=f"v{i}") for i in range(1, n + 1)]
    masses = [bgt.new("I", name=f"M{i}", value=sp.Symbol(f"m{i}")) for i in range(1, n + 1)]
    bgt.add(model, src, *v, *masses)
    bgt.connect(src, v[0])
    for i in range(n):
        bgt.connect(v[i], masses[i])
    for i in range(1, n + 1):
        # BondGraphTools takes a compliance symbol (C_i = 1/k_i: an expression would turn
        # the parameter into a control variable)
        k = bgt.new("C", name=f"K{i}", value=sp.Symbol(f"C{i}"))
        d = bgt.new("R", name=f"D{i}", value=sp.Symbol(f"c{i}"))
        if i < n:
            f0 = bgt.new("0", name=f"F{i}")
            s1 = bgt.new("1", name=f"s{i}")
            bgt.add(model, f0, s1, k, d)
            bgt.connect(v[i - 1], f0)
            bgt.connect(f0, v[i])
            bgt.connect(f0, s1)
            bgt.connect(s1, k)
            bgt.connect(s1, d)
        else:
            bgt.add(model, k, d)
            bgt.connect(v[n - 1], k)
            bgt.connect(v[n - 1], d)
    return model


def derive_bgt(model):
    return model.constitutive_relations


def bgt_matrix(rels, n):
    subs = {sp.Symbol(k): v for k, v in values(n).items()}
    subs.update({sp.Symbol(f"C{i}"): 1 / subs[sp.Symbol(f"k{i}")] for i in range(1, n + 1)})
    m = 2 * n
    xs = [sp.Symbol(f"x_{i}") for i in range(m)]
    dxs = [sp.Symbol(f"dx_{i}") for i in range(m)]
    sol = sp.solve(rels, dxs, dict=True)[0]
    A = sp.Matrix([[sp.diff(sol[d], x) for x in xs] for d in dxs]).xreplace(subs)
    return [[float(a) for a in row] for row in A.tolist()]


PEERS = {
    "pypi-bondgraph": (build_pypi, derive_pypi, pypi_matrix),
    "bondgraphtools": (build_bgt, derive_bgt, bgt_matrix),
}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--peer", choices=sorted(PEERS), required=True)
    ap.add_argument("--n", type=int, required=True)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--budget", type=float, default=60.0, help="stop repeating once this many s are spent")
    ap.add_argument("--eig", action="store_true")
    a = ap.parse_args()
    build, derive, matrix = PEERS[a.peer]
    derive(build(2))  # warm-up: imports and lazily loaded sympy parts
    spent = 0.0
    for rep in range(a.reps):
        clear_cache()
        g = build(a.n)
        t0 = time.perf_counter()
        eqs = derive(g)
        dt = time.perf_counter() - t0
        spent += dt
        print(json.dumps({"rep": rep, "seconds": dt}), flush=True)
        if spent > a.budget:
            break
    if a.eig:
        import numpy as np

        A = np.array(matrix(eqs, a.n))
        ev = np.linalg.eigvals(A)
        print(json.dumps({"eig": sorted([[float(e.real), float(e.imag)] for e in ev])}), flush=True)
    versions = {}
    for mod in ("sympy", "bondgraph", "BondGraphTools"):
        try:
            from importlib.metadata import version

            versions[mod] = version(mod if mod != "BondGraphTools" else "bondgraphtools")
        except Exception:  # noqa: BLE001
            pass
    print(json.dumps({"done": True, "versions": versions}), flush=True)


if __name__ == "__main__":
    sys.exit(main())
