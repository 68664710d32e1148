"""CPU time of ``bondgraph diagnose`` per record, this tree against another, side by side.

    python benchmarks/diagnosis_speed.py --base DIR --seeds 0-19 [--out FILE.json] [--timeout 1800]

``--base`` is a checkout of the engine to compare with (e.g. ``git worktree add --detach
/tmp/bondgraph-base COMMIT``); its ``bondgraph`` package is put first on PYTHONPATH.  For each
seed, benchmarks/blindgen draws the record (CSV in a temporary directory); both engines run
``python -m bondgraph diagnose MODEL DATA --json --workers 1`` on it, one after the other (the
order alternates from seed to seed), each with its own compiled-code cache
(BONDGRAPH_CACHE), which a first untimed diagnosis of each family's first record fills.  A
diagnosis' CPU time is its process' user + system time (``os.wait4``): on a shared machine the
wall time measures the other tenants as much as the engine.  The verdicts compared are the
first named cause and the whole chain of causes.  The JSON file is rewritten after every
record; the table and the totals are printed at the end.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)

import blindgen  # noqa: E402
from blind_accuracy import normalise, parse_seeds  # noqa: E402


def run(tree: str, cache: str, model: str, data: str, timeout: float) -> dict:
    """One diagnosis by the engine in ``tree``: CPU seconds (user + system), wall seconds and
    the verdict (first cause, chain), or the error."""
    env = dict(os.environ, PYTHONPATH=tree, BONDGRAPH_CACHE=cache)
    cmd = [sys.executable, "-m", "bondgraph", "diagnose", model, data, "--json", "--workers", "1", "--quiet"]
    t0 = time.perf_counter()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        proc = subprocess.Popen(cmd, cwd=tree, env=env, stdout=out, stderr=err, start_new_session=True)
        timed_out = False
        while True:  # os.wait4 reaps the process and gives its own resource usage
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() - t0 > timeout:
                os.killpg(proc.pid, signal.SIGKILL)
                timed_out = True
                pid, status, usage = os.wait4(proc.pid, 0)
                break
            time.sleep(0.2)
        proc.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        out.seek(0)
        err.seek(0)
        text, errs = out.read().decode(), err.read().decode()
    row = {"wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime}
    if timed_out:
        return {**row, "error": f"timeout after {timeout:g} s"}
    try:
        res = json.loads(text)
    except json.JSONDecodeError:
        return {**row, "error": f"no JSON: {(errs or text).strip()[-300:]}"}
    chain = [normalise(c.get("cause", c.get("name")) if isinstance(c, dict) else c) for c in res.get("causes") or []]
    return {**row, "named": normalise(res.get("cause")), "chain": chain, "gain": res.get("gain")}


def table(rows: list[dict]) -> str:
    lines = [
        "seed family truth               base verdict        new verdict          same  base CPU s  new CPU s  ratio"
    ]
    for r in rows:
        b, n = r["base"], r["new"]
        same = "yes" if r["same"] else "NO"
        ratio = b.get("cpu_s", float("nan")) / max(n.get("cpu_s", float("nan")), 1e-9)
        lines.append(
            f"{r['seed']:4d} {r['family']:6s} {r['cause']:18s}  {b.get('named', b.get('error', '?'))[:18]:18s}  "
            f"{n.get('named', n.get('error', '?'))[:18]:18s}  {same:4s}  {b.get('cpu_s', float('nan')):9.1f}  "
            f"{n.get('cpu_s', float('nan')):9.1f}  {ratio:5.2f}"
        )
    done = [r for r in rows if "cpu_s" in r["base"] and "cpu_s" in r["new"]]
    if done:
        tb, tn = sum(r["base"]["cpu_s"] for r in done), sum(r["new"]["cpu_s"] for r in done)
        lines += [
            "",
            f"total CPU: base {tb:.1f} s, new {tn:.1f} s over {len(done)} records: {tb / tn:.2f}x less CPU",
            f"per record: base {tb / len(done):.1f} s, new {tn / len(done):.1f} s",
            f"verdicts (first cause and chain) the same: {sum(r['same'] for r in rows)}/{len(rows)}",
        ]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="a checkout of the engine to compare with")
    ap.add_argument("--seeds", default="0-9", help="blind-generator seeds, e.g. 0-9 or 0,3,5-7")
    ap.add_argument("--out", help="JSON results (rewritten after every record)")
    ap.add_argument("--timeout", type=float, default=1800.0, help="seconds per diagnosis")
    args = ap.parse_args(argv)
    base = os.path.abspath(args.base)
    rows: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="diagnosis-speed-") as tmp:
        caches = {"base": os.path.join(tmp, "cache-base"), "new": os.path.join(tmp, "cache-new")}
        trees = {"base": base, "new": ROOT}
        warm: set[str] = set()
        for k, seed in enumerate(parse_seeds(args.seeds)):
            family, cause, mech = blindgen.plan(seed)
            try:
                rec = blindgen.draw(seed)
            except blindgen.Refused as exc:
                print(f"seed {seed}: refused ({exc})", flush=True)
                continue
            path = os.path.join(tmp, f"{rec.record_id}.csv")
            rec.write_csv(path)
            model = os.path.relpath(rec.model, ROOT)
            if family not in warm:  # fill both compiled-code caches, untimed
                for who in trees:
                    run(trees[who], caches[who], model, path, args.timeout)
                warm.add(family)
            row = {"seed": seed, "family": family, "cause": cause, "mechanism": mech}
            for who in ("base", "new") if k % 2 == 0 else ("new", "base"):
                row[who] = run(trees[who], caches[who], model, path, args.timeout)
            row["same"] = all(row[w].get("named") is not None for w in trees) and all(
                row["base"].get(key) == row["new"].get(key) for key in ("named", "chain")
            )
            rows.append(row)
            print(
                f"seed {seed}: {family} {cause}: base {row['base'].get('named')} "
                f"{row['base'].get('cpu_s', float('nan')):.1f} s, new {row['new'].get('named')} "
                f"{row['new'].get('cpu_s', float('nan')):.1f} s",
                flush=True,
            )
            os.remove(path)
            if args.out:
                with open(args.out + ".tmp", "w") as f:
                    json.dump({"base": base, "seeds": args.seeds, "records": rows}, f, indent=1)
                os.replace(args.out + ".tmp", args.out)
    print("\n" + table(rows))


if __name__ == "__main__":
    main()
