"""Run one truth record through ``bondgraph diagnose MODEL DATA --json`` as a user would (a
subprocess of the installed command line), and score the answer against the truth.

Cause names: the diagnosis' ``electrical-rc`` (or any ``electrical*``) counts as the truth's
``electrical``, and its ``friction`` as the truth's ``nonlinear-damping`` (this generator's
category for friction, which the diagnosis names apart since its vocabulary has a name for it);
names are compared lower-case.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .families import ROOT


def normalise(cause) -> str:
    name = str(cause or "none").strip().lower()
    return "electrical" if name.startswith("electrical") else FINER.get(name, name)


#: the diagnosis' names finer than this generator's categories
FINER = {"friction": "nonlinear-damping"}


def _chain(out: dict) -> tuple[list, list]:
    """(causes, gains) of a diagnosis JSON: its ``causes`` chain when present (strings, or
    objects with ``cause`` and ``gain``; a step's gain from ``steps``), else its single
    ``cause`` and ``gain``."""
    chain = out.get("causes")
    if isinstance(chain, list):
        causes = [normalise(c.get("cause") if isinstance(c, dict) else c) for c in chain]
        gains = [c.get("gain") if isinstance(c, dict) else None for c in chain]
        steps = out.get("steps")
        if isinstance(steps, list) and len(steps) == len(chain):
            gains = [s.get("gain") if isinstance(s, dict) else None for s in steps]
        causes_gains = [(c, g) for c, g in zip(causes, gains) if c != "none"]
        return [c for c, _ in causes_gains], [g for _, g in causes_gains]
    cause = normalise(out.get("cause"))
    return ([], []) if cause == "none" else ([cause], [out.get("gain")])


def _verdicts(out: dict) -> list:
    """Every chain step's candidates in brief (for the analysis of a run): cause, label, gain,
    z, effective samples, gain and z over the reference, gain over the static twin, the second
    fold's z, the optimiser effort when it was fitted again in a close race, passed, seconds."""
    keys = (
        "cause",
        "label",
        "gain",
        "z",
        "n_eff",
        "gain_reference",
        "z_reference",
        "gain_static",
        "z_second",
        "effort",
        "passed",
        "seconds",
    )
    steps = list(out.get("steps") or []) + ([out["stop"]] if out.get("stop") else [])
    return [
        [
            {k: c.get(k) for k in keys} | {"verdict": (c.get("verdict") or c.get("skipped") or "")[:120]}
            for c in st.get("candidates", [])
            if not c.get("skipped")
        ]
        for st in steps
    ]


def score(truth_causes: tuple, ordered: bool, cause: str, causes: list) -> dict:
    """Right or wrong: a null record wants ``none``; a single cause wants that cause first; a
    compound wants both causes as the first two steps of the chain (in order when ``ordered``)
    and is ``first_right`` when the first named cause is one of them."""
    truth = [normalise(c) for c in truth_causes]
    if not truth:
        right = normalise(cause) == "none"
        return {"right": right, "first_right": right}
    first_right = normalise(cause) in truth
    if len(truth) == 1:
        return {"right": normalise(cause) == truth[0], "first_right": first_right}
    head = [normalise(c) for c in causes[:2]]
    right = head == truth if ordered else sorted(head) == sorted(truth)
    return {"right": right, "first_right": first_right}


def _end_group(proc: subprocess.Popen) -> None:
    """Terminate the process group of ``proc`` (the diagnosis and its workers), then kill."""
    for sig, wait in ((signal.SIGTERM, 5.0), (signal.SIGKILL, 5.0)):
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            break
        try:
            proc.communicate(timeout=wait)
            break
        except subprocess.TimeoutExpired:
            continue


def diagnose_record(
    record,
    workdir: str | os.PathLike | None = None,
    timeout: float = 600.0,
    workers: int = 1,
    extra: list | None = None,
    engine: str | os.PathLike | None = None,
) -> dict:
    """Write ``record`` to CSV, run ``python -m bondgraph diagnose MODEL DATA --json`` on it and
    return the truth, the answer (cause, causes, gains), right/wrong, wall time and any error
    (``timeout``, a non-zero exit with the last stderr line, unreadable JSON).

    ``engine``: another source tree of the project (e.g. an exported older commit) whose
    ``bondgraph``, ``library`` and model files are used instead of the installed ones."""
    result = {
        "seed": record.seed,
        "family": record.family,
        "truth": record.label,
        "mechanisms": list(record.mechanisms),
        "samples": len(record.t),
        "visible_size": [round(v, 1) for v in record.visible_size],
        "cause": None,
        "causes": [],
        "gains": [],
        "gain": None,
        "wall": None,
        "error": None,
    }
    with tempfile.TemporaryDirectory(dir=workdir) as tmp:
        csv = Path(tmp) / f"truth_{record.seed}.csv"
        record.write_csv(csv)
        root = Path(engine) if engine else ROOT
        env = dict(os.environ)
        if engine:
            env["PYTHONPATH"] = os.pathsep.join([str(root)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
        cmd = [
            sys.executable,
            "-m",
            "bondgraph",
            "diagnose",
            str(root / record.model),
            str(csv),
            "--json",
            "--quiet",
            "--workers",
            str(workers),
        ]
        for s in record.cli_sets:
            cmd += ["--set", s]
        cmd += list(extra or [])
        start = time.perf_counter()
        # its own process group, so that a timeout ends the diagnosis *and* its worker pool
        proc = subprocess.Popen(
            cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp, env=env, start_new_session=True
        )
        try:
            stdout, stderr = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            _end_group(proc)
            result["wall"] = round(time.perf_counter() - start, 1)
            result["error"] = f"timeout after {timeout:g} s"
            result.update(right=False, first_right=False)
            return result
        result["wall"] = round(time.perf_counter() - start, 1)
    if proc.returncode != 0:
        last = (stderr.strip().splitlines() or ["(no message)"])[-1]
        result["error"] = f"exit {proc.returncode}: {last[:300]}"
        result.update(right=False, first_right=False)
        return result
    try:
        out = json.loads(stdout)
    except json.JSONDecodeError as exc:
        result["error"] = f"unreadable JSON ({exc})"
        result.update(right=False, first_right=False)
        return result
    causes, gains = _chain(out)
    result.update(
        cause=normalise(out.get("cause")),
        causes=causes,
        gains=gains,
        gain=out.get("gain"),
        steps=_verdicts(out),
        reading=(out.get("data") or {}).get("drive_reading"),
    )
    result.update(score(record.causes, record.ordered, result["cause"], causes))
    return result
