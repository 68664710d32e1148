"""Checks that a model's numbers make sense before long work starts.

A parameter set to 0 where the equations divide by it (``--set m=0``), or to an absurd
magnitude (``m=1e-300``: a time constant of 1e-300 s), would otherwise surface as a division
by zero inside compiled code, an overflow warning or a solver failure minutes later.
:func:`check_start` evaluates the compiled state equations and outputs at the initial state
and their Jacobian (finite differences, as the method choice does) and raises one
:class:`~bondgraph.support.errors.ParameterError` that names the parameter at fault: among the
values that differ from their declared defaults, the ones whose reset to the default cures
the problem (else the one farthest from its default).
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from ..support.errors import ParameterError

#: fastest rate (1/s) a model may have: beyond it the parameters are absurd, not stiff
MAX_RATE = 1e50


def check_start(sim, params: Mapping | None = None, inputs: Mapping | None = None, t0: float = 0.0) -> None:
    """ParameterError unless ``sim`` (a :class:`~bondgraph.numerics.simulate.Simulator`) has finite
    state equations, outputs and Jacobian, and no rate above :data:`MAX_RATE`, at its initial
    state with parameter values ``params`` (name → value over the model's) and ``inputs``.

    Parameters
    ----------
    sim : Simulator
        The compiled model.
    params : mapping of str to float, optional
        Parameter values overriding the model's.
    inputs : mapping of str to Signal or float, optional
        The inputs (an input not given is 0).
    t0 : float, optional
        Start time, s.

    Raises
    ------
    ParameterError
        The equations are not finite or too fast at the start; the message names the
        parameter(s) whose model default cures it.
    """
    values = {p.name: v for p, v in zip(sim.eqs.params, sim.theta(params))}
    problem = _problem(sim, values, inputs, t0)
    if problem is None:
        return
    model = sim.eqs.model
    changed = _changed(model, values)
    cures = [n for n in changed if _problem(sim, {**values, n: _default(model, n)}, inputs, t0) is None]
    raise ParameterError(
        f"the model's equations {problem} with {_describe(model, values, cures or changed[:1])}; "
        f"give {'it' if len(cures or changed[:1]) <= 1 else 'them'} a physical value"
    )


def check_linear(model, matrices, values: Mapping[str, float]) -> None:
    """ParameterError unless the numeric state-space matrices are finite and the poles'
    magnitudes below :data:`MAX_RATE`; names the parameter farthest from its default.

    Parameters
    ----------
    model : Model
        The model (for its defaults).
    matrices : sequence of numpy.ndarray
        A, B, C, D.
    values : mapping of str to float
        The parameter values they were computed with.

    Raises
    ------
    ParameterError
        A matrix is not finite, or a pole is faster than :data:`MAX_RATE` (1/s).
    """
    A = matrices[0]
    problem = None
    if not all(np.all(np.isfinite(M)) for M in matrices):
        problem = "are not finite (a division by zero?)"
    elif A.size and np.max(np.abs(np.linalg.eigvals(A))) > MAX_RATE:
        problem = f"have a rate above {MAX_RATE:g} 1/s"
    if problem:
        culprits = _changed(model, values)[:1]
        raise ParameterError(
            f"the linearised model's matrices {problem} with {_describe(model, values, culprits)}; "
            f"give it a physical value"
        )


def _problem(sim, values: Mapping[str, float], inputs, t0: float) -> str | None:
    """What is wrong at the initial state with these values, or None."""
    from .integrators import eval_inputs

    th = sim.theta(values)
    try:
        x = sim.initial_state(th)
    except (TypeError, ValueError, ZeroDivisionError, OverflowError):
        return "give no finite initial state"
    if not np.all(np.isfinite(x)):
        return "give no finite initial state"
    bank = sim.signal_bank(inputs)
    nu = max(len(sim.input_names), 1)
    u, du = np.zeros(nu), np.zeros(nu)
    n = x.size
    f0, f1 = np.zeros(max(n, 1)), np.zeros(max(n, 1))
    y = np.zeros(max(len(sim.output_names), 1))
    try:
        eval_inputs(t0, *bank.args(), u, du, True)
        mem = sim.initial_memory(t0, x, th, bank)
        c = sim.compiled
        aux = c.aux.copy()
        c.rhs(t0, x, u, du, th, mem, aux, f0)
        c.output(t0, x, u, du, th, mem, aux, y)
        if not (np.all(np.isfinite(f0)) and np.all(np.isfinite(y))):
            return "are not finite at the initial state"
        radius = 0.0
        if 0 < n <= 400:
            J = np.empty((n, n))
            for j in range(n):
                xp = x.copy()
                dx = 1e-7 * max(abs(x[j]), 1e-9)
                xp[j] += dx
                c.rhs(t0, xp, u, du, th, mem, aux, f1)
                J[:, j] = (f1[:n] - f0[:n]) / dx
            if not np.all(np.isfinite(J)):
                return "have a non-finite Jacobian at the initial state"
            radius = float(np.max(np.abs(np.linalg.eigvals(J))))
    except ZeroDivisionError:
        return "divide by zero"
    except (OverflowError, FloatingPointError, np.linalg.LinAlgError):
        return "overflow"
    if radius > MAX_RATE:
        return f"have a time constant of {1 / radius:.1g} s"
    return None


def _default(model, name: str) -> float:
    return float(model.all_parameters()[name].default)


def _changed(model, values: Mapping[str, float]) -> list[str]:
    """Real parameters whose value differs from the declared default, farthest first
    (by orders of magnitude; zero and sign changes count as farthest)."""
    decl = model.all_parameters()
    out = []
    for name, v in values.items():
        d = decl.get(name)
        if d is None or d.kind != "real" or float(v) == float(d.default):
            continue
        a, b = abs(float(v)), abs(float(d.default))
        far = math.inf if a == 0 or b == 0 or (float(v) < 0) != (float(d.default) < 0) else abs(math.log10(a / b))
        out.append((far, name))
    return [name for _, name in sorted(out, key=lambda fn: -fn[0])]


def _describe(model, values: Mapping[str, float], names: list[str]) -> str:
    if not names:
        return "the model's own parameter values (check the model file)"
    decl = model.all_parameters()
    return " and ".join(f"{n}={values[n]:g} (default {decl[n].default:g})" for n in names)
