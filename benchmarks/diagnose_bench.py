"""Workload 4: ``bondgraph diagnose`` on a 250 000-sample APA-120ML file (wall time, peak memory).

Generates the file once (the APA-120ML with the modified-PI capacitor driven by a 5 Hz sine,
25 s at 10 kHz = 250 000 samples, written with ``bondgraph.data.write_csv``; cached under
benchmarks/.data/) and times ``bondgraph diagnose models/apa120ml.py FILE --json`` end to end
in a wrapper process that reports the peak resident memory of the command alone.
"""

from __future__ import annotations

import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DATA_DIR = os.path.join(HERE, ".data")
SAMPLES = 250_000
DT = 1e-4

TIMEOUT = 600.0

_WRAPPER = (
    "import json, resource, subprocess, sys, time\n"
    "t0 = time.perf_counter()\n"
    "try:\n"
    "    r = subprocess.run(sys.argv[2:], capture_output=True, text=True, timeout=float(sys.argv[1]))\n"
    "    rc, out, err = r.returncode, r.stdout, r.stderr\n"
    "except subprocess.TimeoutExpired:\n"
    "    rc, out, err = 'timeout', '', ''\n"
    "dt = time.perf_counter() - t0\n"
    "print(json.dumps({'rc': rc, 'seconds': dt, 'stdout': out, "
    "'peak_mb': resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, 'stderr': err[-1500:]}))\n"
)


def _cli():
    exe = os.path.join(os.path.dirname(sys.executable), "bondgraph")
    return [exe] if os.path.exists(exe) else [sys.executable, "-m", "bondgraph"]


def timed(cmd: list[str], timeout: float = TIMEOUT) -> dict:
    """Run ``cmd`` in the wrapper: {'rc', 'seconds', 'peak_mb', 'stdout', 'stderr'} ('rc' = 'timeout'
    when killed)."""
    import json

    r = subprocess.run([sys.executable, "-c", _WRAPPER, str(timeout)] + cmd, capture_output=True, text=True, cwd=ROOT)
    try:
        return json.loads(r.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return {
            "rc": f"wrapper failed: {r.stdout[-300:]!r} {r.stderr[-300:]!r}",
            "seconds": 0.0,
            "peak_mb": 0.0,
            "stdout": "",
            "stderr": "",
        }


def make_data(path: str, samples: int = SAMPLES) -> None:
    """APA-120ML (modified PI) response to a 5 Hz, 0-120 V sine: t, V, x, i columns."""
    import numpy as np

    sys.path.insert(0, HERE)
    from bench_models import apa_pi

    from bondgraph import Simulator
    from bondgraph.data import write_csv

    lm = apa_pi()
    t = np.arange(samples) * DT
    res = Simulator(lm.model).run(t, dict(lm.experiment.inputs), method="dopri5")
    cols = {"V": res["V"], "x": res["x"], "i": res["i"]}
    write_csv(
        path,
        t,
        cols,
        {
            "model": "models/apa120ml.py",
            "param hysteresis": "pi",
            "input V": str(lm.experiment.inputs["V"]),
            "note": "synthetic benchmark data",
        },
    )


def run(quick: bool = False, log=print) -> dict:
    samples = 25_000 if quick else SAMPLES
    os.makedirs(DATA_DIR, exist_ok=True)
    path = os.path.join(DATA_DIR, f"apa120ml_pi_{samples}.csv")
    if not os.path.exists(path):
        log(f"  generating {path} ({samples} samples)")
        make_data(path, samples)
    cmd = _cli() + ["diagnose", os.path.join(ROOT, "models", "apa120ml.py"), path, "--json"]
    log("  " + " ".join(cmd))
    rec = timed(cmd)
    if rec["rc"] == "timeout":
        log(f"  diagnose: > {TIMEOUT:.0f} s (killed)")
        return {
            "status": f"> {TIMEOUT:.0f} s (killed at the benchmark's time limit)",
            "command": cmd,
            "peak_mb": rec["peak_mb"],
        }
    if rec["rc"] != 0:
        log(f"  diagnose failed (exit {rec['rc']}): {rec['stderr'].strip().splitlines()[-1:]}")
        return {"status": f"failed: exit {rec['rc']}: {rec['stderr'].strip()[-300:]}", "command": cmd}
    log(f"  diagnose: {rec['seconds']:.1f} s, peak {rec['peak_mb']:.0f} MB")
    return {"status": "ok", "samples": samples, "seconds": rec["seconds"], "peak_mb": rec["peak_mb"], "command": cmd}
