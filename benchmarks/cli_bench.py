"""Command-line timings (run on demand; not part of the test suite).

    python benchmarks/cli_bench.py [--repeat N] [--compare] [--layers 200,400]

1. Start-up: ``bondgraph --help`` and ``bondgraph simulate --help`` in fresh processes, side by
   side with a bare ``python -c pass`` and with ``python -c "import bondgraph.numerics.simulate"`` (what
   every command imported before the package's names became lazy).
2. Printouts: ``bondgraph equations models/stack.py --set layers=N`` in a fresh process (output
   to /dev/null), and in-process the parts: model build, derivation, rendering.  With
   ``--compare`` the same equations are also printed with sympy's plain printer (the route
   before the printers remembered sub-expressions; about 40 s for 200 layers).

Every time is the median of ``--repeat`` runs (default 5 for start-up, half as many for
printouts), as wall time and as CPU time (user + system: less sensitive to other load; the
in-process parts give CPU time only).  The machine is shared: read the ratios, not the
absolute times.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def wall(argv, repeat: int) -> tuple[float, float]:
    """Median wall time and median CPU time (user + system) of a fresh process."""
    walls, cpus = [], []
    for _ in range(repeat):
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(argv, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        walls.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def startup(repeat: int) -> list[tuple[str, float]]:
    py = sys.executable
    rows = [
        ("python -c pass", wall([py, "-c", "pass"], repeat)),
        ("bondgraph --help", wall([py, "-m", "bondgraph", "--help"], repeat)),
        ("bondgraph simulate --help", wall([py, "-m", "bondgraph", "simulate", "--help"], repeat)),
        (
            "python -c 'import bondgraph.numerics.simulate' (the former eager import)",
            wall([py, "-c", "import bondgraph.numerics.simulate"], repeat),
        ),
    ]
    return rows


def printouts(layers: list[int], repeat: int, compare: bool) -> list[tuple[str, float]]:
    rows = []
    py = sys.executable
    for n in layers:
        rows.append(
            (
                f"bondgraph equations models/stack.py --set layers={n} (fresh process)",
                wall([py, "-m", "bondgraph", "equations", "models/stack.py", "--set", f"layers={n}"], repeat),
            )
        )
    sys.path.insert(0, str(ROOT))
    import sympy as sp

    from bondgraph.equations.derivation import derive
    from bondgraph.equations.printing import render
    from bondgraph.model.modelfile import load_model

    for n in layers:
        clock = time.process_time
        t0 = clock()
        lm = load_model(ROOT / "models" / "stack.py", {"layers": n})
        t1 = clock()
        eqs = derive(lm.model)
        t2 = clock()
        text = render(eqs)
        t3 = clock()
        rows += [
            (f"  layers={n}: build the model", (None, t1 - t0)),
            (f"  layers={n}: derive", (None, t2 - t1)),
            (f"  layers={n}: render ({len(text) / 1e6:.1f} MB of text)", (None, t3 - t2)),
        ]
        if compare:
            t4 = clock()
            plain = [sp.sstr(rhs) for rhs in eqs.state_equations().values()]
            t5 = clock()
            assert all(f"= {p}" in text for p in plain[:5])
            rows.append((f"  layers={n}: state equations with sympy's plain printer", (None, t5 - t4)))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--layers", default="200,400")
    ap.add_argument("--compare", action="store_true", help="also time sympy's plain printer (slow)")
    args = ap.parse_args()
    env_note = (
        f"python {sys.version.split()[0]}, {os.cpu_count()} CPUs, load average "
        f"{', '.join(f'{x:.1f}' for x in os.getloadavg())}"
    )
    print(f"# {time.strftime('%Y-%m-%d %H:%M')}; {env_note}")
    print("| what | wall (s) | CPU (s) |\n|---|---|---|")
    for name, (w, c) in startup(args.repeat) + printouts(
        [int(x) for x in args.layers.split(",")], max(1, args.repeat // 2), args.compare
    ):
        print(f"| {name} | {'' if w is None else f'{w:.2f}'} | {c:.2f} |")


if __name__ == "__main__":
    main()
