"""The blind truth generator of benchmarks/blindgen (its package docstring is the protocol):
what its records promise the benchmark that runs them.  A seed gives the same record every
time, its CSV file is the project's format and reads back to the recorded numbers, the file
says nothing of the truth, and the seed rule is balanced (a null every fourth record of a
family, every cause of a family in each run of consecutive seeds).  The accuracy it measures
is in benchmarks/README.md ("Blind generator")."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from conftest import ROOT

from bondgraph.data import read_csv

sys.path.insert(0, str(ROOT / "benchmarks"))
import blindgen  # noqa: E402


@pytest.mark.parametrize("seed", [0, 3])
def test_a_seed_is_one_record_and_its_csv_reads_back(seed, tmp_path):
    a, b = blindgen.draw(seed), blindgen.draw(seed)
    for k in ("t", "V", "x"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k))
    path = tmp_path / "rec.csv"
    a.write_csv(path)
    data = read_csv(path)
    np.testing.assert_allclose(data.t, a.t, rtol=1e-9, atol=0)
    np.testing.assert_allclose(data.columns["V"], a.V, rtol=1e-6, atol=1e-6 * np.ptp(a.V))
    np.testing.assert_allclose(data.columns["x"], a.x, rtol=1e-8, atol=1e-8 * np.ptp(a.x))
    text = path.read_text(encoding="utf-8").lower()
    head = "\n".join(line for line in text.splitlines() if line.startswith("#"))
    truth = a.truth
    assert truth["cause"] == blindgen.plan(seed)[1]
    for word in ("truth", truth["cause"], truth.get("mechanism")):
        assert word in (None, "none") or word.lower() not in head, word


def test_the_seed_rule_is_balanced():
    plans = [blindgen.plan(s) for s in range(64)]
    for family, mod in blindgen.FAMILIES.items():
        mine = [cause for fam, cause, _ in plans if fam == family]
        assert mine[::4] == ["none"] * len(mine[::4]) and "none" not in [c for i, c in enumerate(mine) if i % 4]
        assert set(mine) == {"none", *mod.CAUSES}
