"""The diagnosis on the real-size stack records, as a user runs it:

    python benchmarks/stack_standin.py              # both records, ~5-10 min on a loaded 2-core machine

1. **The real P-885 record** (tests/data/p885_bursts.csv: a PI P-885.91 stack, 1 Hz bursts,
   200 Hz x 70 s) against ``models/stack.py`` (20 layers, modes near 500 kHz).
2. **A stand-in for a record we cannot share**: a piezo stack driven ±150 V by a 1 Hz sine,
   sampled at 5 kHz for 10 s, with rate-independent hysteresis and creep.  The truth is the
   *lumped* stack of Rodriguez-Fortun et al. (2010) with a Bouc–Wen polarization law
   (their eq. 9: a differential hysteresis in the polarization domain, not the diagnosis'
   Prandtl–Ishlinskii operator on the drive) and two Kelvin–Voigt creep cells in series with
   the polarization capacitor (time constants 0.3 s and 3 s), linear parameters changed by
   10-30 % from the model file, 0.2 % white sensor noise.  Generated once into
   benchmarks/.data/.

Each runs ``bondgraph diagnose models/stack.py FILE --json`` (wall time measured around the
command: two worker processes, on a shared machine) and prints the chain, the step gains and
the time.  The target: each answered in < 2 min with rate-independent hysteresis first.
"""

from __future__ import annotations

import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from diagnose_bench import _cli, timed  # noqa: E402

DATA_DIR = os.path.join(HERE, ".data")
CHANGES = {"a": 1.15, "K": 0.8, "c": 1.3, "kx": 1.2, "Re": 1.25}


def standin_truth():
    """The lumped stack with Bouc–Wen polarization and Kelvin–Voigt creep cells (see the module doc)."""
    import bondgraph as bg
    from bondgraph import J0, J1, C, I, R, Se
    from bondgraph.model.modelfile import load_model
    from library.piezo import bouc_wen_polarization, layer_extension, piezo_layer

    p = load_model(os.path.join(ROOT, "models", "stack.py")).params
    val = {k: p.value(k) * CHANGES.get(k, 1.0) for k in ("Re", "l", "a", "K", "kx", "c", "M_layer")}
    n = int(p.value("layers"))
    kx = val["kx"]
    g = bg.Model("stack truth: Bouc-Wen polarization + creep")
    V = g.input("V", "V")
    # Bouc-Wen in the polarization domain: kw sets the loop (about 12 % of the stroke at 150 V)
    layer = piezo_layer(
        "stack",
        l=val["l"],
        a=val["a"],
        K=val["K"],
        R_NL=val["c"],
        polarization=lambda c, name: bouc_wen_polarization(c, name, kx, 0.9e5, 4.0e7, 0.5, 1.0),
    )
    layer.unbond("pol", "C_NL")
    layer.add(J0("cr"))
    layer.bond("pol", "cr")
    layer.bond("cr", "C_NL")
    for k, (ratio, tau) in enumerate([(0.05, 0.3), (0.06, 3.0)]):
        Ck = ratio / kx
        layer.add(J1(f"cell{k}"), C(f"Cc{k}", Ck), R(f"Rc{k}", tau / Ck))
        layer.bond("cr", f"cell{k}")
        layer.bond(f"cell{k}", f"Cc{k}")
        layer.bond(f"cell{k}", f"Rc{k}")
    g.add(layer)
    g.add(Se("amp", V), J1("i"), R("Re", val["Re"]), I("M", (n + 1) / 2 * val["M_layer"]))
    g.chain("amp", "i", "stack.elec")
    g.bond("i", "Re")
    g.bond("stack.mech", "M")
    x = layer_extension("stack", val["a"], val["l"]) + sum(
        val["a"] / val["l"] * bg.Quantity("q", f"stack.Cc{k}") for k in range(2)
    )
    g.output("x", x, "m")
    return g


def standin_file() -> str:
    import bondgraph as bg
    from bondgraph.data import write_csv

    path = os.path.join(DATA_DIR, "stack_standin_5kHz_10s.csv")
    if os.path.exists(path):
        return path
    os.makedirs(DATA_DIR, exist_ok=True)
    t = np.arange(50_001) / 5000.0
    V = 150.0 * np.sin(2 * math.pi * 1.0 * t)
    res = bg.simulate(standin_truth(), t, {"V": bg.PiecewiseLinear(t, V)}, method="radau", rtol=1e-7)
    x = res["x"] + np.random.default_rng(7).normal(0, 0.002 * np.ptp(res["x"]), t.size)
    write_csv(
        path,
        t,
        {"V": V, "x": x},
        {"truth": "lumped stack, Bouc-Wen polarization, two creep cells", "drive": "150 V, 1 Hz sine"},
    )
    return path


def main():
    files = [
        ("P-885 real record (200 Hz x 70 s)", os.path.join(ROOT, "tests", "data", "p885_bursts.csv")),
        ("stand-in: ±150 V 1 Hz, 5 kHz x 10 s, hysteresis + creep", standin_file()),
    ]
    rows = []
    for name, path in files:
        rec = timed(_cli() + ["diagnose", os.path.join(ROOT, "models", "stack.py"), path, "--json"])
        out = json.loads(rec["stdout"]) if rec["rc"] == 0 else {}
        steps = " → ".join(f"{s['cause']} ×{s['gain']:.3g}" for s in out.get("steps", [])) or "none"
        rows.append((name, steps, out.get("gain", float("nan")), rec["seconds"], rec["rc"]))
        print(
            f"{name}: {steps}; total gain {out.get('gain', float('nan')):.3g}; {rec['seconds']:.0f} s "
            f"(exit {rec['rc']})",
            flush=True,
        )
        if rec["rc"] != 0:
            print(rec.get("stderr", "")[-800:])
    print("\n| record | chain (step gains) | total gain | wall |\n|---|---|---:|---:|")
    for name, steps, gain, sec, rc in rows:
        print(f"| {name} | {steps} | {gain:.3g} | {sec:.0f} s |")


if __name__ == "__main__":
    main()
