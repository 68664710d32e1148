"""What the unit check costs a derivation: ``bondgraph.derive`` with and without it, side by side.

    python benchmarks/units_cost.py                      # stack of 400 layers and chain of 320 masses
    python benchmarks/units_cost.py --stack 100 --repeat 5

For each model (built once, causality assigned once): a warm-up derivation, then per repetition
the sympy cache is cleared, garbage is collected, and ``derive(model, causality, units=False)``
and ``units=True`` are timed one after the other, in alternating order (process CPU time, so
other processes on a shared machine count less), then the check alone on the relations of one
derivation.  Prints the medians and the ratio.
"""

from __future__ import annotations

import argparse
import gc
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def measure(name: str, model, repeat: int) -> dict:
    from sympy.core.cache import clear_cache

    import bondgraph as bg
    from bondgraph.equations import derivation

    caus = bg.assign_causality(model)
    captured = {}
    check = derivation.check_units

    def keep(data):
        captured["data"] = data
        return check(data)

    derivation.check_units = keep
    try:
        bg.derive(model, caus)  # warm-up, and the relations for the check alone
    finally:
        derivation.check_units = check
    times: dict = {"without": [], "with": [], "check alone": []}
    order = ((False, "without"), (True, "with"))
    for rep in range(repeat):
        for units, key in order if rep % 2 == 0 else order[::-1]:  # alternate which goes first
            clear_cache()
            gc.collect()  # each starts with the same heap: the garbage of the other is not its to collect
            t = time.process_time()
            bg.derive(model, caus, units=units)
            times[key].append(time.process_time() - t)
        gc.collect()
        t = time.process_time()
        check(captured["data"])
        times["check alone"].append(time.process_time() - t)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(
        f"{name:<22} derive {med['without']:7.3f} s, with the check {med['with']:7.3f} s "
        f"(x{med['with'] / med['without']:.3f}); the check alone {med['check alone']:.3f} s "
        f"({100 * med['check alone'] / med['without']:.1f} % of a derivation)"
    )
    return med


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stack", type=int, default=400, help="layers of models/stack.py (default 400)")
    ap.add_argument("--chain", type=int, default=320, help="masses of the benchmark chain (default 320)")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    from bench_models import chain_model, stack_model

    measure(f"stack, {a.stack} layers", stack_model(a.stack), a.repeat)
    measure(f"chain, {a.chain} masses", chain_model(a.chain), a.repeat)


if __name__ == "__main__":
    main()
