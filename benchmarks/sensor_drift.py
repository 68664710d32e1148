"""A linear sensor drift against the diagnosis, with and without ``diagnose --drift``.

    python benchmarks/sensor_drift.py --cache benchmarks/.data/records   # a few minutes
    python benchmarks/sensor_drift.py --share 0.02 --nulls bench:2004,ci:1011

Effect-free records of tests/truthgen get a drift of ``--share`` × their output's range over
the record (the null rows); records with creep or hysteresis and no added drift show what the
option costs (the effect rows).  Each is diagnosed through the command line as a user runs it;
the table (markdown) gives the chain named without and with ``--drift``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)

from diagnosis_accuracy import cached_draw  # noqa: E402

NULLS = "bench:2004,bench:2016,bench:2064,bench:2011,bench:2065,bench:2002,ci:1008,ci:1011,ci:1012"
EFFECTS = (
    "bench:2019,bench:2022,bench:2038,bench:2046,bench:2070,bench:2032,bench:2060,bench:2001,bench:2018,bench:2042"
)


def chain(rec, x: np.ndarray, drift: bool, workdir: str) -> tuple[str, float]:
    """(the chain named, e.g. 'hysteresis ×5.8 → creep ×1.3' or 'none'; wall seconds)."""
    path = os.path.join(workdir, f"{rec.size}_{rec.seed}.csv")
    with open(path, "w") as f:
        f.write("t,V,x\n")
        np.savetxt(f, np.column_stack([rec.t, rec.V, x]), delimiter=",", fmt="%.10g")
    cmd = [sys.executable, "-m", "bondgraph", "diagnose", os.path.join(ROOT, rec.model), path, "--json", "--quiet"]
    cmd += sum((["--set", s] for s in rec.cli_sets), []) + (["--drift"] if drift else [])
    start = time.time()
    out = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    if out.returncode:
        return f"error: {out.stderr.strip().splitlines()[-1][:60]}", time.time() - start
    j = json.loads(out.stdout)
    named = " → ".join(f"{s['cause']} ×{s['gain']:.2f}" for s in j["steps"]) or "none"
    return named, time.time() - start


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--share", type=float, default=0.01, help="drift over the record, share of the output's range")
    ap.add_argument("--nulls", default=NULLS, help="size:seed,... effect-free records to drift")
    ap.add_argument("--effects", default=EFFECTS, help="size:seed,... records with effects, no drift added")
    ap.add_argument("--cache", help="directory keeping the drawn records")
    args = ap.parse_args(argv)
    print("| record | truth | drift / noise RMS | without --drift | with --drift |")
    print("|---|---|---:|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for group, share in ((args.nulls, args.share), (args.effects, 0.0)):
            for item in filter(None, group.split(",")):
                size, seed = item.split(":")
                rec = cached_draw(int(seed), size, args.cache)
                t, x = np.asarray(rec.t), np.asarray(rec.x)
                added = share * float(np.ptp(x))
                xd = x + added * (t - t[0]) / (t[-1] - t[0])
                plain, _ = chain(rec, xd, False, work)
                with_drift, _ = chain(rec, xd, True, work)
                print(
                    f"| {size} {seed} | {rec.label} ({', '.join(rec.mechanisms) or '-'}) | "
                    f"{added / rec.noise_rms:.1f} | {plain} | {with_drift} |",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
