"""Accuracy of ``bondgraph diagnose`` on the general-systems generator's records.

For each seed: write the record (``python -m benchmarks.generalgen SEED --out DIR``, in a
subprocess), run the installed CLI ``bondgraph diagnose MODEL CSV --json`` on it (a
subprocess, with a time limit), score the answer against the truth (the rule of
``benchmarks/generalgen/scoring.py``), and print a per-record table and a confusion matrix.
The results go to ``benchmarks/.data/general_accuracy-<time>.json`` (ignored by git).  A
diagnosis that fails or times out is an error row (wrong).

    python benchmarks/general_accuracy.py --seeds 0-19 --workers 2

The held-out seeds (1000-1199) are refused unless ``--held-out`` says this is the final
evaluation (``benchmarks/generalgen/PROTOCOL.md``).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from benchmarks.generalgen.__main__ import parse_seeds  # noqa: E402
from benchmarks.generalgen.effects import VOCABULARY  # noqa: E402
from benchmarks.generalgen.record import HELD_OUT  # noqa: E402
from benchmarks.generalgen.scoring import score, summarise  # noqa: E402

DATA = ROOT / "benchmarks" / ".data"


def _bondgraph() -> list[str]:
    """The installed CLI: the ``bondgraph`` script next to this Python, else on the PATH."""
    here = Path(sys.executable).with_name("bondgraph")
    found = str(here) if here.exists() else shutil.which("bondgraph")
    if not found:
        raise SystemExit("error: the bondgraph command is not installed (pip install -e .)")
    return [found]


def _installed_package(cli: list[str]) -> Path | None:
    """The directory of the ``bondgraph`` package the installed CLI imports (asked from a
    neutral working directory, so that no checkout on the path shadows the installation)."""
    python = Path(cli[0]).with_name("python")
    if not python.exists():
        return None
    out = subprocess.run(
        [str(python), "-c", "import bondgraph, os; print(os.path.dirname(bondgraph.__file__))"],
        capture_output=True,
        text=True,
        cwd=os.path.expanduser("~") if os.path.isdir(os.path.expanduser("~")) else "/",
    )
    return Path(out.stdout.strip()).resolve() if out.returncode == 0 and out.stdout.strip() else None


def _last_line(text: str) -> str:
    lines = [ln for ln in (text or "").strip().splitlines() if ln.strip()]
    return lines[-1][:300] if lines else ""


def run_one(seed: int, records: Path, timeout: float, diagnose_workers: int, extra: list[str]) -> dict:
    """Generate, diagnose and score one seed; never raises (failures are error rows)."""
    row: dict = {"seed": seed}
    t0 = time.perf_counter()
    gen = subprocess.run(
        [sys.executable, "-m", "benchmarks.generalgen", str(seed), "--out", str(records)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    row["generate_s"] = round(time.perf_counter() - t0, 2)
    truth_path = records / f"gen3_{seed}.truth.json"
    if gen.returncode != 0 or not truth_path.exists():
        row.update(
            error=f"generator failed: {_last_line(gen.stderr)}",
            truth="?",
            visible=True,
            first="error",
            right=False,
            site_right=None,
        )
        return row
    truth = json.loads(truth_path.read_text())
    row.update(
        system=truth["system"],
        drive=truth["drive_label"],
        fs=truth["fs"],
        samples=truth["samples"],
        truth=truth["cause"],
        site=truth["site"],
        count=truth.get("count"),
        visible=truth["visible"],
    )
    cmd = _bondgraph() + ["diagnose", str(records / truth["model"]), str(records / f"gen3_{seed}.csv"), "--json"]
    cmd += ["--quiet", "--workers", str(diagnose_workers)] + extra
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        diagnosis = None
        if proc.returncode == 0:
            try:
                diagnosis = json.loads(proc.stdout)
            except json.JSONDecodeError:
                diagnosis = {"error": "the diagnosis printed no JSON"}
        else:
            diagnosis = {"error": f"exit {proc.returncode}: {_last_line(proc.stderr)}"}
    except subprocess.TimeoutExpired:
        diagnosis = {"error": f"timed out after {timeout:.0f} s"}
    row["seconds"] = round(time.perf_counter() - t0, 1)
    row.update(score(truth, diagnosis))
    if diagnosis and "error" not in diagnosis:
        row["diagnosis_seconds"] = diagnosis.get("seconds")
        row["sites_named"] = [s.get("site") for s in diagnosis.get("steps") or []]
    return row


def _truth_label(r: dict) -> str:
    if r.get("truth") in (None, "?"):
        return "?"
    if r["truth"] == "none":
        return "none"
    label = f"{r['truth']}@{r['site']}"
    return label + (f" x{r['count']}" if r.get("count") else "") + ("" if r.get("visible", True) else " (invisible)")


def table(rows: list[dict]) -> str:
    """The per-record table."""
    head = f"{'seed':>5}  {'system':<7} {'drive':<32} {'fs':>6}  {'truth':<34} {'named chain':<40} {'right':<6} {'site':<8} {'s':>6}"
    lines = [head, "-" * len(head)]
    for r in rows:
        chain = "error: " + r["error"] if r.get("error") else (", ".join(r.get("named") or []) or "none")
        lines.append(
            f"{r['seed']:>5}  {r.get('system', '?'):<7} {str(r.get('drive', '?'))[:32]:<32} {r.get('fs', 0) / 1000:>5.0f}k  "
            f"{_truth_label(r)[:34]:<34} {chain[:40]:<40} {'yes' if r.get('right') else 'no':<6} "
            f"{str(r.get('site_right', '')) if r.get('site_right') is not None else '-':<8} {r.get('seconds', 0):>6.1f}"
        )
    return "\n".join(lines)


def confusion(summary: dict) -> str:
    """The confusion matrix: truth (rows) against the first named cause (columns)."""
    cols = [c for c in VOCABULARY if any(c in v for v in summary["confusion"].values())]
    cols += sorted({c for v in summary["confusion"].values() for c in v} - set(cols))
    short = {c: c[:9] for c in cols}
    lines = ["truth \\ named first  " + " ".join(f"{short[c]:>9}" for c in cols)]
    for truth in VOCABULARY:
        if truth in summary["confusion"]:
            counts = summary["confusion"][truth]
            lines.append(f"{truth:<20} " + " ".join(f"{counts.get(c, 0):>9}" for c in cols))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", required=True, nargs="+", help="seeds or ranges, e.g. 0-19")
    ap.add_argument("--workers", type=int, default=1, help="records diagnosed at once (default 1)")
    ap.add_argument("--diagnose-workers", type=int, help="--workers of each diagnosis (default 2 // workers, >= 1)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds a diagnosis may take (default 900)")
    ap.add_argument("--records", type=Path, default=DATA / "generalgen", help="where the records are written")
    ap.add_argument("--held-out", action="store_true", help="allow the held-out seeds 1000-1199: the final evaluation")
    ap.add_argument("--diagnose-arg", action="append", default=[], help="an extra argument for bondgraph diagnose")
    ap.add_argument(
        "--any-install", action="store_true", help="measure the installed bondgraph even if not from this checkout"
    )
    args = ap.parse_args(argv)
    try:
        seeds = parse_seeds(args.seeds)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    held = [s for s in seeds if s in HELD_OUT]
    if held and not args.held_out:
        print(
            f"error: seeds {held[0]}..{held[-1]} are held out until the final evaluation (PROTOCOL.md); "
            "pass --held-out only for it",
            file=sys.stderr,
        )
        return 2
    installed = _installed_package(_bondgraph())
    if installed is not None and installed != (ROOT / "bondgraph").resolve() and not args.any_install:
        print(
            f"error: the installed bondgraph command runs {installed}, not this checkout's "
            f"({ROOT / 'bondgraph'}): pip install -e . here, or pass --any-install",
            file=sys.stderr,
        )
        return 2
    args.records.mkdir(parents=True, exist_ok=True)
    dw = args.diagnose_workers or max(1, 2 // max(1, args.workers))
    started = time.strftime("%Y%m%d-%H%M%S")
    t0 = time.perf_counter()
    with ThreadPoolExecutor(max_workers=max(1, args.workers)) as pool:
        rows = list(pool.map(lambda s: run_one(s, args.records, args.timeout, dw, args.diagnose_arg), seeds))
    wall = time.perf_counter() - t0
    summary = summarise(rows)
    print(table(rows))
    print()
    print(confusion(summary))
    print()
    print(
        f"right {summary['right']}/{summary['scored']} (effects {summary['effects_right']}/{summary['effects']}, "
        f"false alarms {summary['false_alarms']}/{summary['effect_free']}, errors {summary['errors']}); "
        f"site right {summary['site_right']}, wrong {summary['site_wrong']}, unknown {summary['site_unknown']}; "
        f"{summary['invisible']} invisible left out; {wall / 60:.1f} min"
    )
    DATA.mkdir(parents=True, exist_ok=True)
    out = DATA / f"general_accuracy-{started}.json"
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
    ).stdout.strip()
    payload = {
        "seeds": seeds,
        "commit": commit,
        "wall_s": wall,
        "summary": summary,
        "rows": rows,
        "host_cpus": os.cpu_count(),
    }
    tmp = out.with_suffix(".tmp")
    tmp.write_text(json.dumps(payload, indent=1, default=str))
    os.replace(tmp, out)
    print(f"results: {out.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
