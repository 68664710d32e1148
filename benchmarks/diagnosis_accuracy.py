"""Diagnosis accuracy on independent truths: a seed set of tests/truthgen through the CLI.

    python benchmarks/diagnosis_accuracy.py                       # the ci set (14 small records)
    python benchmarks/diagnosis_accuracy.py --set bench           # the 72 realistic records
    python benchmarks/diagnosis_accuracy.py --set bench --limit 20 --timeout 900
    python benchmarks/diagnosis_accuracy.py --seeds 2004,2010 --size bench
    python benchmarks/diagnosis_accuracy.py --fresh 3100 --families apa,t215  # 20 records nobody has seen
    python benchmarks/diagnosis_accuracy.py --set bench --resume  # continue an interrupted run
    python benchmarks/diagnosis_accuracy.py --set bench --cache benchmarks/.data/records  # keep the records
    git archive REV | tar -x -C /tmp/old && python benchmarks/diagnosis_accuracy.py --engine /tmp/old

Each record is drawn by ``truthgen.draw(seed, size)`` (the protocol is the package docstring of
tests/truthgen: hand-written truth physics, randomized devices, mechanisms, drives and sensors,
a visibility rule), written to CSV, and diagnosed by ``python -m bondgraph diagnose MODEL DATA
--json`` in a subprocess with a per-record timeout, as a user would run it.  Recorded per
record: the truth (cause, mechanism, visible size), the named cause and chain with gains, the
wall time of the diagnosis and of the generation, errors and timeouts.  Printed (and written
with ``--markdown``): the per-record table, the confusion matrix (rows: truth, columns: first
named cause), the score, the null false-alarm count and the wall times.  Results go to
``--out`` (JSON, one entry per record, rewritten after every record so that ``--resume``
continues where a run stopped).

Scoring (truthgen.runner.score): a null record is right when ``none`` is named; a single cause
when it is named first; a compound when both causes are the first two steps of the chain (in
order when the truth's order is clear).  ``electrical-rc`` counts as ``electrical``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "tests"))

from truthgen import SEEDS, design, draw, fresh_seeds  # noqa: E402
from truthgen.families import FAMILIES  # noqa: E402
from truthgen.runner import diagnose_record  # noqa: E402

DEFAULT_OUT = os.path.join(HERE, ".data", "diagnosis_accuracy_{set}.json")


def confusion(results: list) -> str:
    """Markdown confusion matrix: truth label (rows) x first named cause (columns)."""
    rows = sorted({r["truth"] for r in results}, key=lambda s: (s != "none", "+" in s, s))
    cols = sorted(
        {(r["cause"] or ("timeout" if "timeout" in (r["error"] or "") else "error")) for r in results},
        key=lambda s: (s != "none", s in ("error", "timeout"), s),
    )
    lines = ["| truth \\ named | " + " | ".join(cols) + " | right |", "|---|" + "---|" * (len(cols) + 1)]
    for row in rows:
        mine = [r for r in results if r["truth"] == row]
        counts = []
        for col in cols:
            n = sum(
                1 for r in mine if (r["cause"] or ("timeout" if "timeout" in (r["error"] or "") else "error")) == col
            )
            counts.append(str(n) if n else "·")
        lines.append(f"| {row} | " + " | ".join(counts) + f" | {sum(r['right'] for r in mine)}/{len(mine)} |")
    return "\n".join(lines)


def table(results: list) -> str:
    lines = [
        "| seed | family | truth (mechanism) | visible | samples | named (chain, gains) | right | diagnose s | error |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        chain = (
            " > ".join(
                f"{c} ({g:.2f})" if isinstance(g, (int, float)) else c
                for c, g in zip(r["causes"], r["gains"] + [None] * len(r["causes"]))
            )
            or "none"
        )
        lines.append(
            f"| {r['seed']} | {r['family']} | {r['truth']} ({', '.join(r['mechanisms']) or '-'}) | "
            f"{', '.join(str(v) for v in r['visible_size']) or '-'} | {r['samples']} | "
            f"{(r['cause'] + ': ' + chain) if r['cause'] else '-'} | {'yes' if r['right'] else 'no'} | "
            f"{r['wall']} | {r['error'] or ''} |"
        )
    return "\n".join(lines)


def summary(results: list) -> str:
    n = len(results)
    right = sum(r["right"] for r in results)
    nulls = [r for r in results if r["truth"] == "none"]
    alarms = sum(1 for r in nulls if not r["right"])
    compounds = [r for r in results if "+" in r["truth"]]
    walls = [r["wall"] for r in results if r["wall"] is not None]
    errors = sum(1 for r in results if r["error"])
    timeouts = sum(1 for r in results if r["error"] and "timeout" in r["error"])
    out = [
        f"- records: {n}; right: **{right}/{n}** ({100 * right / max(n, 1):.0f} %)",
        f"- null records: {len(nulls)}; false alarms: **{alarms}/{len(nulls)}**",
    ]
    if compounds:
        out.append(
            f"- compound records: {len(compounds)}; named as a two-step chain: "
            f"{sum(r['right'] for r in compounds)}, first cause one of the two: "
            f"{sum(r['first_right'] for r in compounds)}"
        )
    by_family = {}
    for r in results:
        by_family.setdefault(r["family"], []).append(r["right"])
    out.append("- by family: " + ", ".join(f"{f} {sum(v)}/{len(v)}" for f, v in sorted(by_family.items())))
    if walls:
        out.append(
            f"- diagnosis wall time: median {statistics.median(walls):.1f} s, max {max(walls):.1f} s, "
            f"total {sum(walls) / 60:.1f} min; errors {errors} (timeouts {timeouts})"
        )
    return "\n".join(out)


def cached_draw(seed: int, size: str, cache: str | None):
    """``draw(seed, size)``, kept in (and read back from) ``cache`` when given."""
    if not cache:
        return draw(seed, size)
    import pickle

    os.makedirs(cache, exist_ok=True)
    path = os.path.join(cache, f"{size}_{seed}.pkl")
    if os.path.exists(path):
        with open(path, "rb") as f:
            return pickle.load(f)
    rec = draw(seed, size)
    with open(path + ".tmp", "wb") as f:
        pickle.dump(rec, f)
    os.replace(path + ".tmp", path)
    return rec


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", default="ci", choices=sorted(SEEDS), help="seed set (default ci)")
    ap.add_argument("--seeds", help="comma-separated seeds instead of a set")
    ap.add_argument(
        "--fresh",
        type=int,
        metavar="START",
        help="instead of a set: the seeds from START on that no set holds, single-effect or "
        "effect-free, in --families, --limit of them (default 20; bench size).  Records "
        "nobody has looked at: run an engine on them once, then move START past them",
    )
    ap.add_argument(
        "--size", choices=("ci", "bench"), help="record size (default: ci for the ci and dev sets, bench for bench)"
    )
    ap.add_argument("--limit", type=int, help="only the first N seeds of the set")
    ap.add_argument("--families", help="comma-separated families to keep (apa, t215, stack, t226)")
    ap.add_argument("--timeout", type=float, help="seconds per diagnosis (default 180 for ci, 900 for bench)")
    ap.add_argument("--workers", type=int, default=2, help="diagnose --workers (default 2, the CLI's default)")
    ap.add_argument("--out", help="results JSON (default benchmarks/.data/diagnosis_accuracy_<set>.json)")
    ap.add_argument("--resume", action="store_true", help="keep the results already in --out and skip those seeds")
    ap.add_argument("--markdown", help="also write the report as markdown to this file")
    ap.add_argument(
        "--cache",
        help="keep generated records in this folder (pickles) and reuse them: the "
        "generator is deterministic, so a rerun on another engine skips it",
    )
    ap.add_argument(
        "--engine",
        help="diagnose with another source tree of the project (e.g. 'git archive REV' "
        "unpacked): its bondgraph, library and models come first on PYTHONPATH",
    )
    args = ap.parse_args(argv)

    keep = set(args.families.split(",")) if args.families else None
    if keep and keep - set(FAMILIES):
        ap.error(f"unknown families {', '.join(sorted(keep - set(FAMILIES)))}: use {', '.join(FAMILIES)}")
    if args.fresh is not None:
        seeds = fresh_seeds(args.fresh, args.limit or 20, keep)
        name = f"fresh seeds from {args.fresh}"
    else:
        seeds = [int(s) for s in args.seeds.split(",")] if args.seeds else list(SEEDS[args.set])
        if keep:
            seeds = [s for s in seeds if design(s)[0] in keep]
        if args.limit:
            seeds = seeds[: args.limit]
        name = args.set if not args.seeds else "seeds " + args.seeds
    size = args.size or ("bench" if (args.set == "bench" and not args.seeds) or args.fresh is not None else "ci")
    timeout = args.timeout or (900.0 if size == "bench" else 180.0)
    out_path = args.out or DEFAULT_OUT.format(
        set="fresh" if args.fresh is not None else args.set if not args.seeds else "seeds"
    )
    os.makedirs(os.path.dirname(out_path), exist_ok=True)
    results = []
    if args.resume and os.path.exists(out_path):
        with open(out_path) as f:
            results = [r for r in json.load(f)["results"] if r["seed"] in seeds]
    done = {r["seed"] for r in results}
    started = time.strftime("%Y-%m-%d %H:%M")
    for k, seed in enumerate(seeds, 1):
        if seed in done:
            continue
        t0 = time.perf_counter()
        try:
            rec = cached_draw(seed, size, args.cache)
        except RuntimeError as exc:  # the visibility rule refused the seed
            print(f"[{k}/{len(seeds)}] seed {seed}: not generated ({exc})", file=sys.stderr, flush=True)
            continue
        gen = time.perf_counter() - t0
        print(
            f"[{k}/{len(seeds)}] seed {seed} {rec.family} {rec.label} ({', '.join(rec.mechanisms) or '-'}), "
            f"{len(rec.t)} samples, generated in {gen:.1f} s ... ",
            end="",
            file=sys.stderr,
            flush=True,
        )
        r = diagnose_record(rec, timeout=timeout, workers=args.workers, engine=args.engine)
        r["generate_s"] = round(gen, 1)
        r["size"] = size
        results.append(r)
        print(
            f"named {r['cause']} {r['causes']} in {r['wall']} s: {'right' if r['right'] else 'WRONG'}"
            + (f" [{r['error']}]" if r["error"] else ""),
            file=sys.stderr,
            flush=True,
        )
        with open(out_path + ".tmp", "w") as f:
            json.dump(
                {
                    "set": args.set,
                    "size": size,
                    "timeout": timeout,
                    "workers": args.workers,
                    "engine": args.engine,
                    "started": started,
                    "results": results,
                },
                f,
                indent=1,
            )
        os.replace(out_path + ".tmp", out_path)
    results.sort(key=lambda r: seeds.index(r["seed"]))
    report = (
        f"Diagnosis accuracy, {name} ({size} records), "
        f"{started}; timeout {timeout:g} s, diagnose --workers {args.workers}"
        + (f", engine {args.engine}" if args.engine else "")
        + "\n\n"
        + summary(results)
        + "\n\n"
        + confusion(results)
        + "\n\n"
        + table(results)
        + "\n"
    )
    print(report)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(report)
    return 0


if __name__ == "__main__":
    sys.exit(main())
