"""The diagnosis on the ci seed set of the independent truth generator, through the command line
as a user runs it (``python -m bondgraph diagnose MODEL DATA --json``; one worker: the suite's
two processes already take the machine's two cores, and on records this small a second worker
adds a third of the CPU time for a few per cent of the wall time).

The truths are tests/truthgen's (its package docstring is the protocol: hand-written physics of
four device families, mechanisms structurally unlike the diagnosis' candidates, drawn linear
parameters, drives, coloured noise, jittered time, a visibility rule).  The set was fixed before
the engine was tuned and is never tuned on.  The protocol's target is >= 90 % right and at most
1 false alarm in 15 null draws; what the engine gives today (benchmarks/README.md, "Diagnosis
accuracy") is 12 of these 14 right (the first cause right on 12: the compound 1004 on steps,
each level reached once, shows no memory a static curve does not), no false alarm on the three
null records, every record answered in under a minute (median 15 s, the longest 55 s: 1002,
one worker, quiet machine; on the 72-record bench set: 63 right, no false alarm in 17 null
records).  This test guards that level: one record
more may turn wrong (optimiser paths differ slightly between machines) but not two, at most
one false alarm, and every record is answered (within the runner's 5-minute timeout; the
time goal itself is measured by the benchmarks, not asserted here, since a shared machine's
load decides a wall time).
"""

from __future__ import annotations

import pytest
from truthgen import SEEDS, draw
from truthgen.runner import diagnose_record


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    work = tmp_path_factory.mktemp("ci_set")
    return [diagnose_record(draw(seed, "ci"), workdir=work, timeout=300, workers=1) for seed in SEEDS["ci"]]


def _table(results) -> str:
    return "\n".join(
        f"{r['seed']} {r['family']} {r['truth']}: {r['cause']} {r['causes']} "
        f"{'right' if r['right'] else 'WRONG'} {r['wall']} s {r['error'] or ''}"
        for r in results
    )


def test_every_record_is_answered(results):
    assert all(r["error"] is None for r in results), _table(results)


def test_accuracy_holds_its_measured_level(results):
    right = sum(r["right"] for r in results)
    first = sum(r["first_right"] for r in results)
    assert right >= 11 and first >= 11, _table(results)


def test_null_records_raise_at_most_one_alarm(results):
    nulls = [r for r in results if r["truth"] == "none"]
    assert len(nulls) >= 3
    assert sum(not r["right"] for r in nulls) <= 1, _table(results)
