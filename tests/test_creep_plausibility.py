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
    return Extension(
        model=None, values=values, new=list(values), additive=AdditiveDrive(d, sp.Symbol("d"), terms=terms)
    )


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
    q = c * a / (1 + wt**2) * (np.sin(omega * T) - wt * np.cos(omega * T) + wt * np.exp(-T / tau))
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
    lag = -np.expm1(-t / 3.7e-3)  # one lag between two grid points
    w = _nnls_weights(grid, lag, t)
    assert InputCreep.spread(grid, grid, w) < 0.1
    # log-time creep over three decades of the record: equal weight per third of a decade
    fine = 10 ** np.arange(-4, -1 + 1e-9, 1 / 3)
    creep = sum(-np.expm1(-t / tau) for tau in fine) / fine.size
    w = _nnls_weights(grid, creep, t)
    assert InputCreep.spread(grid, grid, w) > 0.5
    # equal weights on five neighbouring points: all but two of five
    assert InputCreep.spread(grid, grid[2:7], np.ones(5)) == pytest.approx(0.6)


def test_the_held_share_counts_holds_not_the_turning_points_of_a_wave():
    from bondgraph.diagnosis.context import drive_held_share

    fs, t = 1e3, np.arange(0.0, 10.0, 1e-3)
    steps = np.repeat([0.0, 1.0, -0.5, 2.0, 0.0], t.size // 5)  # four levels of 2 s each
    assert drive_held_share(steps, fs, 0.5) == pytest.approx(1.0)
    assert drive_held_share(steps, fs, 2.5) == 0.0  # no hold lasts 2.5 s
    sine = np.sin(2 * math.pi * 0.5 * t)  # within 1 % of its range for 0.4 rad about each peak
    assert drive_held_share(sine, fs, 0.1) == pytest.approx(2 * 0.4 / (2 * math.pi), abs=0.002)
    assert drive_held_share(sine, fs, 0.15) == 0.0  # 0.127 s at most
    triangle = np.abs((t % 2.0) - 1.0)
    assert drive_held_share(triangle, fs, 0.05) == 0.0
    rest = np.where(t < 9.0, np.sin(2 * math.pi * 0.5 * t), 0.0)  # a sine, then one second at rest
    assert drive_held_share(rest, fs, 0.5) == pytest.approx(0.1, abs=0.01)


def _view(drive, fs, modes_hz, main_hz):
    from types import SimpleNamespace

    from bondgraph.diagnosis.context import drive_held_share

    t = np.arange(drive.size) / fs
    record = SimpleNamespace(
        t=t,
        dt=1 / fs,
        modes_hz=modes_hz,
        main_hz=main_hz,
        held_share=lambda length: drive_held_share(drive, fs, length),
    )
    return SimpleNamespace(record=record)


def test_on_a_drive_that_holds_only_the_models_dynamics_bound_a_creep_lag():
    fs, t = 1e4, np.arange(0.0, 5.0, 1e-4)
    model = 10 / (2 * math.pi * 350.0)  # 4.5 ms
    held = np.repeat([0.0, 1.0, 0.4, 1.5, 0.8], t.size // 5)  # levels held 1 s
    assert InputCreep.lag_limit(_view(held, fs, (350.0,), 1.5)) == pytest.approx(model)
    sine = np.sin(2 * math.pi * 1.5 * t)  # the same period, never still
    assert InputCreep.lag_limit(_view(sine, fs, (350.0,), 1.5)) == pytest.approx(0.05, rel=1e-3)  # 1 % of 5 s
    fast = np.sin(2 * math.pi * 200.0 * t)  # a quarter period below 10/omega
    assert InputCreep.lag_limit(_view(fast, fs, (350.0,), 200.0)) == pytest.approx(model)


def test_on_a_drive_that_holds_the_spectrum_starts_at_the_models_dynamics():
    fs, t = 1e4, np.arange(0.0, 5.0, 1e-4)
    held = np.repeat([0.0, 1.0, 0.4, 1.5, 0.8], t.size // 5)
    grid = InputCreep.taus(_view(held, fs, (350.0,), 1.5))
    assert grid[0] == pytest.approx(10 / (2 * math.pi * 350.0)) and grid[-1] == pytest.approx(15.0, rel=1e-3)
    grid = InputCreep.taus(_view(np.sin(2 * math.pi * 1.5 * t), fs, (350.0,), 1.5))
    assert grid[0] == pytest.approx(5e-4)  # five samples
    assert np.allclose(np.diff(np.log10(grid)), np.diff(np.log10(grid))[0])
    assert 0.4 <= np.diff(np.log10(grid))[0] <= 0.6  # two a decade
