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


def _nnls_weights(grid, response, t):
    """Non-negative weights of the grid's cells whose summed step response fits ``response``."""
    from scipy.optimize import nnls
    A = np.column_stack([-np.expm1(-t / tau) for tau in grid])
    return nnls(A, response)[0]


def test_one_lag_is_one_lag_on_the_grid_and_log_time_creep_is_a_spectrum():
    # two cells per decade, as the candidate's grid; step responses on a log-time axis
    grid = np.geomspace(1e-4, 10.0, 11)
    t = np.geomspace(1e-5, 30.0, 400)
    lag = -np.expm1(-t / 3.7e-3)                       # one lag between two grid points
    w = _nnls_weights(grid, lag, t)
    assert InputCreep.spread(grid, grid, w) < 0.1
    # log-time creep over three decades of the record: equal weight per third of a decade
    fine = 10 ** np.arange(-4, -1 + 1e-9, 1 / 3)
    creep = sum(-np.expm1(-t / tau) for tau in fine) / fine.size
    w = _nnls_weights(grid, creep, t)
    assert InputCreep.spread(grid, grid, w) > 0.5
    # equal weights on five neighbouring points: all but two of five
    assert InputCreep.spread(grid, grid[2:7], np.ones(5)) == pytest.approx(0.6)
