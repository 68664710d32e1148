"""``python -m benchmarks.generalgen SEED [SEED...] --out DIR``: write the seeds' records.

Each seed writes ``DIR/gen3_<seed>.csv`` (time, drive, measured output), a copy of its model
file ``DIR/<system>.py`` and the truth ``DIR/gen3_<seed>.truth.json``.  A seed may be a range
``A-B`` (both included).  ``--count`` only draws the seeds (no simulation) and prints how many
records of each cause and system they hold - the one thing the protocol allows to be read off
the held-out seeds.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import Counter


def parse_seeds(specs: list[str]) -> list[int]:
    """Seeds from ``["3", "10-12"]`` → ``[3, 10, 11, 12]`` (order kept, duplicates dropped)."""
    out: list[int] = []
    for spec in specs:
        for part in spec.split(","):
            part = part.strip()
            if not part:
                continue
            lo, _, hi = part.partition("-")
            if not lo.isdigit() or (hi and not hi.isdigit()):
                raise ValueError(f"a seed is a non-negative integer or a range A-B, not {part!r}")
            lo_i, hi_i = int(lo), int(hi or lo)
            if hi_i < lo_i:
                raise ValueError(f"empty seed range {part!r}")
            out += [s for s in range(lo_i, hi_i + 1) if s not in out]
    return out


def counts(seeds: list[int]) -> str:
    """A table of causes (with missing-mode counts) and systems over ``seeds``, from draws only."""
    from .effects import VOCABULARY
    from .record import draw

    by_cause: Counter = Counter()
    by_system: Counter = Counter()
    modes: Counter = Counter()
    for s in seeds:
        d = draw(s)
        by_cause[d.effect.cause] += 1
        by_system[d.system.name] += 1
        if d.effect.cause == "higher-mode":
            modes[d.effect.count] += 1
    lines = [f"{len(seeds)} seeds ({seeds[0]}..{seeds[-1]})", "cause              records"]
    lines += [f"  {c:<17}{by_cause.get(c, 0):>7}" for c in VOCABULARY]
    lines.append("  higher-mode by count: " + ", ".join(f"{k}: {v}" for k, v in sorted(modes.items())))
    lines.append("system             records")
    lines += [f"  {k:<17}{v:>7}" for k, v in sorted(by_system.items())]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.generalgen", description=__doc__.splitlines()[0])
    ap.add_argument("seeds", nargs="+", metavar="SEED", help="seed or range A-B (0-99 development, 1000-1199 held out)")
    ap.add_argument("--out", help="output directory (created if missing)")
    ap.add_argument("--count", action="store_true", help="only count causes and systems from the draws")
    args = ap.parse_args(argv)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.count:
        print(counts(seeds))
        return 0
    if not args.out:
        print("error: --out DIR is required (or --count)", file=sys.stderr)
        return 2
    from .record import generate

    for s in seeds:
        t0 = time.perf_counter()
        csv, truth, model = generate(s, args.out)
        print(f"{csv}  {model.name}  {truth.name}  ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
