"""Where a model run against a measured record starts: its steady state at the record's first
drive value, or its declared initial state (setting ``record.start``).

A real record often starts with the drive already away from zero (a stack held at a bias
voltage); a model started from rest then shows a start-up transient the record does not have.
With ``record.start = "steady"`` (the default) the run starts at the equilibrium of the state
equations with every input held at its value at the first sample (input rates zero):

- the energy states (kind ``q`` and ``p``) declared at rest (x0 = 0) solve their rows of
  f(x, u(t0)) = 0: one Newton step from the declared state on a finite-difference Jacobian
  (exact for a linear model, A·x + B·u0 = 0), then, when the rates are not yet zero,
  :func:`scipy.optimize.root` from that linear estimate;
- a state declared with a non-zero initial value keeps it (a start the model means: a fitted
  history, like the level a creep chain's cells start from);
- the internal states (kind ``z``: a Bouc–Wen variable, say) and the sensor integrals (kind
  ``x``) keep their declared values, and the memory operators (hysteresis, creep) are at rest
  at their input values (:meth:`~bondgraph.numerics.simulate.Simulator.initial_memory`): at an
  equilibrium their rates vanish whatever their value, and "at rest" is the state a device has
  before any excursion.

When the declared state is already an equilibrium (the usual model with a drive that starts at
zero) it is returned as it is, so such records give exactly the results of ``"rest"``.  A model
without an equilibrium at that drive (a free mass under a constant force, a singular Jacobian)
starts from its declared state.  The exact linear routes (:mod:`bondgraph.linear.lti`) start at
the same point: by superposition (the response from rest to u − u(t0) plus the DC gain times
u(t0)) when every state is declared at rest, else from :func:`linear_start`.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
from scipy.optimize import root

from ..support import config
from ..support.errors import UsageError
from .integrators import eval_inputs

#: the values of setting ``record.start``
STARTS = ("steady", "rest")


def starts_steady() -> bool:
    """Whether runs against a record start at the steady state (setting ``record.start``).

    Returns
    -------
    bool
        True for ``"steady"``, False for ``"rest"`` (the model's declared x0).

    Raises
    ------
    UsageError
        The setting holds another value.
    """
    start = config.get("record.start")
    if start not in STARTS:
        raise UsageError(f"config: record.start must be one of {', '.join(STARTS)}, got {start!r}")
    return start == "steady"


def steady_state(sim, th: np.ndarray, inputs: Mapping | None = None, t0: float = 0.0) -> np.ndarray:
    """The equilibrium of ``sim``'s state equations with the inputs held at their values at
    ``t0`` (module docstring), or the declared initial state when there is none.

    Parameters
    ----------
    sim : Simulator
        The compiled model.
    th : numpy.ndarray
        θ, the parameter vector (:meth:`~bondgraph.numerics.simulate.Simulator.theta`).
    inputs : mapping of str to Signal or float, optional
        The inputs (an input not given is 0), read at ``t0`` only.
    t0 : float, optional
        The time of the first sample, s.

    Returns
    -------
    numpy.ndarray
        The state, in the order of ``sim.state_names`` (states' units).
    """
    x_d = sim.initial_state(th)
    solve = free_states(sim, x_d)
    if not solve.any():
        return x_d
    bank = sim.signal_bank(inputs)
    nu = max(len(sim.input_names), 1)
    u, du = np.zeros(nu), np.zeros(nu)
    eval_inputs(t0, *bank.args(), u, du, True)
    du[:] = 0.0  # the inputs held at their first values
    c = sim.compiled
    aux = c.aux.copy()
    idx = np.nonzero(solve)[0]

    def rates(y: np.ndarray, mem: np.ndarray | None = None) -> np.ndarray:
        x = x_d.copy()
        x[idx] = y
        mem = sim.initial_memory(t0, x, th, bank) if mem is None else mem
        f = np.zeros(max(x.size, 1))
        c.rhs(t0, x, u, du, th, mem, aux, f)
        return f[idx]

    y0 = x_d[idx]
    mem0 = sim.initial_memory(t0, x_d, th, bank)
    f0 = rates(y0, mem0)
    if not np.any(f0):
        return x_d
    J = np.empty((idx.size, idx.size))
    for j in range(idx.size):
        y = y0.copy()
        h = 1e-7 * max(abs(y[j]), 1e-9)
        y[j] += h
        J[:, j] = (rates(y, mem0) - f0) / h
    try:
        y_lin = y0 - np.linalg.solve(J, f0)
    except np.linalg.LinAlgError:
        return x_d
    if not np.all(np.isfinite(y_lin)) or np.linalg.cond(J) > 1e14:
        return x_d
    f_lin = rates(y_lin)
    if np.all(np.abs(f_lin) <= 1e-10 * np.abs(f0).max()):
        y_best = y_lin  # linear (or linear enough): the Newton step is the equilibrium
    else:
        sol = root(rates, y_lin, method="hybr")
        y_best = sol.x if sol.success and np.all(np.isfinite(sol.x)) else y_lin
    x = x_d.copy()
    x[idx] = y_best
    return x


def free_states(sim, x_declared: np.ndarray) -> np.ndarray:
    """Which states the steady start solves: energy states (kind ``q``, ``p``) declared at rest.

    Parameters
    ----------
    sim : Simulator
        The compiled model.
    x_declared : numpy.ndarray
        The declared initial state (:meth:`~bondgraph.numerics.simulate.Simulator.initial_state`).

    Returns
    -------
    numpy.ndarray
        One bool per state, in the order of ``sim.state_names``.
    """
    kinds = np.array([s.kind in ("q", "p") for s in sim.eqs.states], bool)
    return kinds & (np.asarray(x_declared) == 0)


def linear_start(A: np.ndarray, B: np.ndarray, u0: float, x_declared: np.ndarray, free: np.ndarray) -> np.ndarray:
    """The steady start of a linear model x' = A·x + B·u: the ``free`` states solve their rows
    of A·x + B·u0 = 0 with the others at their declared values (:func:`steady_state`'s rule).

    Parameters
    ----------
    A : numpy.ndarray
        n × n state matrix, in the order of ``x_declared``.
    B : numpy.ndarray
        n × 1 input matrix.
    u0 : float
        The input at the first sample.
    x_declared : numpy.ndarray
        The declared initial state.
    free : numpy.ndarray
        The states to solve (:func:`free_states`).

    Returns
    -------
    numpy.ndarray
        The initial state; the declared one when the free block of A is singular.
    """
    x = np.array(x_declared, float)
    f = np.nonzero(free)[0]
    if f.size == 0:
        return x
    rhs = -(A[f] @ np.where(free, 0.0, x) + B[f, 0] * u0)
    try:
        x[f] = np.linalg.solve(A[np.ix_(f, f)], rhs)
    except np.linalg.LinAlgError:
        return np.array(x_declared, float)
    return x if np.all(np.isfinite(x)) else np.array(x_declared, float)


def record_start(sim, th: np.ndarray, inputs: Mapping | None = None, t0: float = 0.0) -> np.ndarray:
    """The initial state of a run against a record, as setting ``record.start`` says: the
    steady state at the inputs' values at ``t0`` (:func:`steady_state`) or the declared x0.

    Parameters
    ----------
    sim : Simulator
        The compiled model.
    th : numpy.ndarray
        θ, the parameter vector.
    inputs : mapping of str to Signal or float, optional
        The run's inputs (an input not given is 0).
    t0 : float, optional
        The time of the first sample, s.

    Returns
    -------
    numpy.ndarray
        The initial state, in the order of ``sim.state_names``.

    Raises
    ------
    UsageError
        Setting ``record.start`` is neither ``"steady"`` nor ``"rest"``.
    """
    return steady_state(sim, th, inputs, t0) if starts_steady() else sim.initial_state(th)
