"""How much a fitted creep chain creeps within a record (the measure its plausibility rule
bounds), against the step and frequency responses of first-order cells
q̇ = (c·d − q)/τ, each starting in equilibrium with the drive's first sample."""
from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from bondgraph.diagnosis import AdditiveDrive, Extension, Term
from bondgraph.diagnosis.filters import lowpass
from library.extensions import InputCreep

DT = 1e-3
T = np.arange(0.0, 5.0, DT)


def chain(d, cells):
    terms = tuple(Term(f"creep.c{k}", lowpass(d, tau, DT), 0.0, np.inf) for k, (tau, _) in enumerate(cells, 1))
    values = {f"creep.c{k}": c for k, (_, c) in enumerate(cells, 1)}
    return Extension(model=None, values=values, new=list(values),
                     additive=AdditiveDrive(d, sp.Symbol("d"), terms=terms))


def test_a_step_held_from_rest_creeps_by_the_cells_step_response():
    d = np.where(T >= 0.5, 2.0, 0.0)
    cells = [(0.3, 0.02), (1.0, 0.05), (15.0, 0.1)]
    held = T[-1] - 0.5
    expected = sum(c * -math.expm1(-held / tau) for tau, c in cells)
    assert InputCreep.creep_range(chain(d, cells)) == pytest.approx(expected, rel=2e-3)


def test_a_slow_cell_on_a_zero_mean_sine_creeps_by_its_integral_of_the_drive():
    # a cell much slower than the period is about c/(j omega tau) of the drive: its ratio alone
    # (6, a step response creeping by 6 (1 - e^(-5/15)) = 1.7 in 5 s) says little here
    omega, tau, c, a = 2 * math.pi * 4.6, 15.0, 6.0, 30.0
    d = a * np.sin(omega * T)
    wt = omega * tau
    q = c * a / (1 + wt ** 2) * (np.sin(omega * T) - wt * np.cos(omega * T) + wt * np.exp(-T / tau))
    r = InputCreep.creep_range(chain(d, [(tau, c)]))
    assert r == pytest.approx(np.ptp(q) / np.ptp(d), rel=1e-3)
    assert r < 0.02 < 1.0 < c * -math.expm1(-T[-1] / tau)
