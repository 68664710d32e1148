"""Blind accuracy of ``bondgraph diagnose`` on records made by benchmarks/blindgen, a generator
written from the physics alone (its protocol is blindgen's docstring).

    python benchmarks/blind_accuracy.py --seeds 0-19 --out FILE.json [--timeout 600] [--resume]
                                        [--markdown FILE.md]

For each seed: draw the record, write its CSV to a temporary directory (named by an opaque
record id), run ``python -m bondgraph diagnose MODEL DATA --json`` in its own process group
(killed on timeout) and keep the truth, the first named cause, the chain of causes, the gains,
the wall times and any error.  The JSON file is rewritten after every record; --resume keeps
the seeds already in it.  At the end: a per-record table, the confusion matrix (rows truth,
columns first named cause), the score (right = ``none`` on a null, else the true cause named
first; ``electrical-*`` counts as ``electrical``), false alarms on nulls and wall times.
A seed whose effect stays invisible (blindgen.Refused) is listed and left out of the score.
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


def parse_seeds(text: str) -> list[int]:
    """'0-19' or '0,3,5-7' -> sorted seeds."""
    seeds = set()
    for part in text.split(","):
        lo, _, hi = part.strip().partition("-")
        seeds.update(range(int(lo), int(hi or lo) + 1))
    return sorted(seeds)


def normalise(cause) -> str:
    """Lower-case cause name, ``electrical-*`` as ``electrical``, ``friction`` as this
    generator's ``nonlinear-damping`` (its category for friction); a missing one as ``missing``."""
    if cause is None:
        return "missing"
    name = str(cause).strip().lower()
    return "electrical" if name.startswith("electrical") else FINER.get(name, name)


#: the diagnosis' names finer than this generator's categories
FINER = {"friction": "nonlinear-damping"}


def _names(causes) -> tuple[list, list]:
    """(names, gains) of a causes chain of strings or of objects with a name and a gain."""
    names, gains = [], []
    for c in causes or []:
        if isinstance(c, dict):
            names.append(c.get("cause", c.get("name")))
            gains.append(c.get("gain"))
        else:
            names.append(c)
    return names, gains


def diagnose(model: str, data: str, timeout: float) -> dict:
    """Run the diagnosis in its own process group; the parsed JSON or an error."""
    cmd = [sys.executable, "-m", "bondgraph", "diagnose", model, data, "--json"]
    t0 = time.time()
    proc = subprocess.Popen(
        cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return {"error": f"timeout after {timeout:g} s", "diagnose_s": time.time() - t0}
    result = {"diagnose_s": time.time() - t0, "returncode": proc.returncode}
    try:
        result["json"] = json.loads(out)
    except json.JSONDecodeError:
        result["error"] = f"exit {proc.returncode}, no JSON: {(err or out).strip()[-400:]}"
    return result


def run_seed(seed: int, timeout: float, tmp: str) -> dict:
    family, cause, mech = blindgen.plan(seed)
    row = {"seed": seed, "family": family, "cause": cause, "mechanism": mech}
    t0 = time.time()
    try:
        rec = blindgen.draw(seed)
    except blindgen.Refused as exc:
        return {**row, "refused": str(exc), "generate_s": time.time() - t0}
    row["generate_s"] = time.time() - t0
    row["truth"] = rec.truth
    path = os.path.join(tmp, f"{rec.record_id}.csv")
    rec.write_csv(path)
    res = diagnose(rec.model, path, timeout)
    os.remove(path)
    row["diagnose_s"] = res["diagnose_s"]
    if "error" in res:
        row["error"] = res["error"]
        return row
    out = res["json"]
    names, gains = _names(out.get("causes"))
    if not any(g is not None for g in gains):  # a chain of names: each step's gain from its step
        gains = [s.get("gain") for s in out.get("steps") or []][: len(names)]
    row.update(
        named=normalise(out.get("cause")),
        causes=[normalise(n) for n in names],
        gains=gains,
        gain=out.get("gain"),
        diagnosis=out,
    )
    return row


def outcome(row) -> str:
    """The column of the confusion matrix: the first named cause, or error / timeout."""
    if "error" in row:
        return "timeout" if row["error"].startswith("timeout") else "error"
    return row["named"]


def summary(rows: list[dict]) -> str:
    done = [r for r in rows if "refused" not in r]
    lines = [
        "seed family  truth              mechanism           vis/noise  named              "
        "chain                                  gain      gen s   diag s  ok"
    ]
    for r in rows:
        if "refused" in r:
            lines.append(f"{r['seed']:4d} {r['family']:7s} {r['cause']:18s} {str(r['mechanism']):19s} REFUSED")
            continue
        vis = f"{r['truth']['visible_ratio']:9.3g}" if r["cause"] != "none" else f"{'-':>9s}"
        chain = " > ".join(
            f"{c} x{g:.3g}" if isinstance(g, (int, float)) else c
            for c, g in zip(r.get("causes", []), r.get("gains", []) + [None] * 9)
        )[:38]
        gain = r.get("gain")
        gain = f"{gain:.3g}" if isinstance(gain, (int, float)) else str(gain)
        ok = "yes" if outcome(r) == r["cause"] else "no"
        lines.append(
            f"{r['seed']:4d} {r['family']:7s} {r['cause']:18s} {str(r['mechanism']):19s} "
            f"{vis}  {outcome(r):18s} {chain:38s} {gain:9s} {r['generate_s']:6.1f} "
            f"{r.get('diagnose_s', float('nan')):8.1f}  {ok}"
        )
    truths = sorted({r["cause"] for r in done}, key=lambda c: (c != "none", c))
    cols = sorted({outcome(r) for r in done} | set(truths), key=lambda c: (c != "none", c))
    lines += [
        "",
        "confusion (rows truth, columns first named cause)",
        "                   " + " ".join(f"{c[:10]:>10s}" for c in cols),
    ]
    for t in truths:
        counts = [sum(1 for r in done if r["cause"] == t and outcome(r) == c) for c in cols]
        lines.append(f"{t:18s} " + " ".join(f"{n:10d}" for n in counts))
    right = sum(outcome(r) == r["cause"] for r in done)
    nulls = [r for r in done if r["cause"] == "none"]
    alarms = sum(outcome(r) != "none" for r in nulls)
    lines += ["", f"score: {right}/{len(done)} right" + (f" ({100 * right / len(done):.0f} %)" if done else "")]
    for fam in sorted({r["family"] for r in done}):
        sub = [r for r in done if r["family"] == fam]
        lines.append(f"  {fam}: {sum(outcome(r) == r['cause'] for r in sub)}/{len(sub)}")
    lines.append(f"false alarms on nulls: {alarms}/{len(nulls)}")
    refused = [r["seed"] for r in rows if "refused" in r]
    if refused:
        lines.append(f"refused seeds (effect invisible): {refused}")
    diag = [r["diagnose_s"] for r in done if "diagnose_s" in r]
    gen = [r["generate_s"] for r in rows]
    if diag:
        lines.append(
            f"diagnose wall time: total {sum(diag):.0f} s, mean {sum(diag) / len(diag):.1f} s, max {max(diag):.1f} s"
        )
    if gen:
        lines.append(f"generation wall time: mean {sum(gen) / len(gen):.1f} s, max {max(gen):.1f} s")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", required=True, help="e.g. 0-19 or 0,3,5-7")
    ap.add_argument("--out", required=True, help="JSON results (rewritten after every record)")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per diagnosis")
    ap.add_argument("--resume", action="store_true", help="keep the seeds already in --out")
    ap.add_argument("--markdown", help="also write the tables to this Markdown file")
    args = ap.parse_args(argv)
    rows = []
    if args.resume and os.path.exists(args.out):
        with open(args.out) as f:
            rows = json.load(f)["records"]
    done = {r["seed"] for r in rows}
    with tempfile.TemporaryDirectory(prefix="blindgen-") as tmp:
        for seed in parse_seeds(args.seeds):
            if seed in done:
                continue
            row = run_seed(seed, args.timeout, tmp)
            rows.append(row)
            rows.sort(key=lambda r: r["seed"])
            with open(args.out + ".tmp", "w") as f:
                json.dump({"generator": "benchmarks/blindgen", "records": rows}, f, indent=1, default=str)
            os.replace(args.out + ".tmp", args.out)
            print(
                f"seed {seed}: {row['family']} {row['cause']} -> {'REFUSED' if 'refused' in row else outcome(row)}",
                flush=True,
            )
    text = summary(rows)
    print("\n" + text)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write("# Blind diagnosis accuracy (benchmarks/blindgen)\n\n```\n" + text + "\n```\n")


if __name__ == "__main__":
    main()
