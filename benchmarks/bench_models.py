"""Benchmark models shared by the workloads: the N-mass chain and the APA-120ML / stack files.

The chain (workloads 1-3): an effort source F drives mass 1; masses i and i+1 are joined by a
spring k_i and a damper c_i in parallel; the last mass is tied to a wall by spring k_N and
damper c_N.  N masses, N springs, N dampers, 2N states (momenta p_i, spring displacements q_i).
Every coefficient is its own symbolic parameter, as in the peers' runs.

Bond graph: Se(F) -> 1(v1); I(m_i) on 1(v_i); between masses a 0-junction (the spring-damper
force) with a 1-junction for the relative velocity v_i - v_{i+1} carrying C(1/k_i) and R(c_i).
"""

from __future__ import annotations

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def chain_values(n: int) -> dict[str, float]:
    """Numeric values: slightly non-uniform so the modes are distinct (SI units)."""
    vals = {}
    for i in range(1, n + 1):
        vals[f"m{i}"] = 0.5 + 0.05 * i  # kg
        vals[f"k{i}"] = 1.0e4 * (1 + 0.02 * i)  # N/m
        vals[f"c{i}"] = 2.0 + 0.1 * i  # N s/m
    return vals


def chain_model(n: int):
    """Our framework's N-mass chain (parameters as symbols)."""
    import bondgraph as bg

    vals = chain_values(n)
    g = bg.Model(f"chain{n}")
    F = g.input("F", "N", "drive force on mass 1")
    p = {k: g.parameter(k, v) for k, v in vals.items()}
    g.add(bg.Se("src", F))
    for i in range(1, n + 1):
        g.add(bg.J1(f"v{i}"), bg.I(f"M{i}", p[f"m{i}"]))
        g.bond(f"v{i}", f"M{i}")
    g.bond("src", "v1")
    for i in range(1, n):
        g.add(bg.J0(f"F{i}"), bg.J1(f"s{i}"), bg.C(f"K{i}", 1 / p[f"k{i}"]), bg.R(f"D{i}", p[f"c{i}"]))
        g.bond(f"v{i}", f"F{i}")
        g.bond(f"F{i}", f"v{i + 1}")
        g.bond(f"F{i}", f"s{i}")
        g.bond(f"s{i}", f"K{i}")
        g.bond(f"s{i}", f"D{i}")
    g.add(bg.C(f"K{n}", 1 / p[f"k{n}"]), bg.R(f"D{n}", p[f"c{n}"]))
    g.bond(f"v{n}", f"K{n}")
    g.bond(f"v{n}", f"D{n}")
    g.output("xN", g.displacement(f"K{n}"), "m", "displacement of the last mass")
    g.output("v1", g.flow("M1"), "m/s", "velocity of mass 1")
    return g


def load_file_model(name: str, **overrides):
    """A model file from models/ (stack.py, apa120ml.py) built with ``overrides``."""
    if ROOT not in sys.path:
        sys.path.insert(0, ROOT)
    from bondgraph.model.modelfile import load_model

    return load_model(os.path.join(ROOT, "models", f"{name}.py"), overrides)


def stack_model(layers: int):
    return load_file_model("stack", layers=layers).model


def apa_pi():
    """APA-120ML with the modified-PI polarization (12 plays, dead zones on the absolute PI sum,
    Table 3 read with signed weights) and its default experiment.  The reading is pinned: the
    model file's default became the relative dead zones, an operator without return-point
    memory whose branches restart at every reversal of its input, so two integrators that
    commit at different steps legitimately part by more than their tolerance."""
    return load_file_model("apa120ml", hysteresis="pi", table3="absolute-signed")
