"""Feedforward compensation: the drive that makes a model follow a desired output trajectory.

Generic over memory operators (hysteresis of any kind: PI, modified PI, Maxwell slip, ...):

* :func:`invert_operator` gives the input sequence v with H[v] = y, through the operator's
  closed-form :meth:`~bondgraph.MemoryOperator.inverse` when it has one, else numerically,
  sample by sample (a bracketed root of ``output(v, mem) = y_k`` with the memory frozen, then
  ``commit``): exact for any operator whose output rises continuously with its input.
* :func:`feedforward` inverts a whole model. When the output depends on the drive only through
  one operator whose input is affine in the drive (hysteresis at the input followed by a
  system without memory operators, the usual identified structure), the operator is inverted
  exactly and the rest by its static gain; an iteration on the simulated model
  (iterative learning: w <- w + e/g) then removes what the rest's dynamics leave. Otherwise
  (hysteresis inside the model, e.g. in a polarization law) the same iteration runs on the drive
  itself with the secant gain of the model.

The predicted tracking error (the simulated model against the reference) is reported with
and without compensation; "without" is the linear inverse: a drive proportional to the
reference, spanning the same range as the compensated drive.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy.optimize import brentq

from ..model.memory import MemoryOperator
from ..model.signals import PiecewiseLinear
from ..numerics.simulate import Simulator
from ..numerics.steady import record_start
from ..support.errors import ModelError, UsageError, did_you_mean


def invert_operator(op: MemoryOperator, y, prm=None) -> np.ndarray:
    """The input sequence v (from rest) with op[v] = y sample by sample (units of the
    operator's input). Uses ``op.inverse()`` when available; otherwise solves each sample
    numerically, which needs an output that increases with the input (monotone hysteresis).

    Parameters
    ----------
    op : MemoryOperator
        The operator to invert.
    y : array_like
        The wanted output sequence, in the operator's output units.
    prm : array_like, optional
        The operator's parameter vector (default: its own values).

    Returns
    -------
    numpy.ndarray
        v, one input value per sample, in the operator's input units.

    Raises
    ------
    ModelError
        The operator's output does not rise with its input where it must (not monotone).
    """
    y = np.ascontiguousarray(y, dtype=np.float64).ravel()
    prm = op.parameter_values() if prm is None else np.ascontiguousarray(prm, dtype=np.float64)
    inv = op.inverse()
    if inv is not None and np.array_equal(prm, op.parameter_values()):
        return inv.run(y)
    return _numeric_inverse(op, y, prm)


def _numeric_inverse(op: MemoryOperator, y: np.ndarray, prm: np.ndarray) -> np.ndarray:
    out_fn, commit_fn = type(op).output, type(op).commit
    v = np.empty_like(y)
    v0 = _solve(lambda s: out_fn(s, op.initial_memory(s, prm), prm) - y[0], 0.0, y[0], 1.0)
    mem = op.initial_memory(v0, prm)
    prev, step = v0, max(abs(v0), 1.0)
    for k, yk in enumerate(y):
        prev = _solve(lambda s: out_fn(s, mem, prm) - yk, prev, yk, step)
        v[k] = prev
        commit_fn(prev, mem, prm)
        if k:
            step = max(abs(v[k] - v[k - 1]), 1e-12 * max(abs(prev), 1.0))
    return v


def _solve(f, start: float, target: float, step: float) -> float:
    """A root of the increasing function f near ``start``, bracketed by expanding steps."""
    f0 = f(start)
    if f0 == 0.0:
        return start
    direction = 1.0 if f0 < 0.0 else -1.0
    lo = start
    for _ in range(200):
        hi = lo + direction * step
        if (f(hi) > 0.0) == (direction > 0.0) or f(hi) == 0.0:
            a, b = sorted((lo, hi))
            return brentq(f, a, b, xtol=1e-15 * max(abs(a), abs(b), 1e-300), rtol=4 * np.finfo(float).eps)
        lo, step = hi, step * 2.0
    raise ModelError(
        f"cannot invert the operator at output {target:g}: its output does not rise "
        "with its input there (the hysteresis model is not monotone)"
    )


@dataclass
class Compensation:
    """Result of :func:`feedforward` (arrays sampled at ``t``; drive in the model input's units,
    reference and predictions in the output's).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    reference : numpy.ndarray
        The desired output trajectory, output units.
    drive : numpy.ndarray
        The compensated drive, input units.
    predicted : numpy.ndarray
        The model's response to ``drive``.
    linear_drive : numpy.ndarray
        The uncompensated (linear inverse) drive: proportional to the reference, spanning the
        same range as ``drive``.
    linear_predicted : numpy.ndarray
        The model's response to ``linear_drive``.
    method : {"operator inverse", "iteration"}
        How the drive was found.
    history : list, optional
        max |error| after each model simulation of the iteration, output units.
    notes : list, optional
        What the user must know about the result (a drive clipped to the input's range, an
        operator that is not monotone).
    """

    t: np.ndarray
    reference: np.ndarray
    drive: np.ndarray
    predicted: np.ndarray
    linear_drive: np.ndarray
    linear_predicted: np.ndarray
    method: str
    history: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    @property
    def error(self) -> float:
        """Largest tracking error with compensation (units of the output)."""
        return float(np.max(np.abs(self.predicted - self.reference)))

    @property
    def linear_error(self) -> float:
        """Largest tracking error of the uncompensated (linear inverse) drive."""
        return float(np.max(np.abs(self.linear_predicted - self.reference)))

    @property
    def improvement(self) -> float:
        """linear_error / error."""
        return self.linear_error / max(self.error, np.finfo(float).tiny)

    def summary(self) -> dict:
        """The result's numbers as a JSON object (``bondgraph compensate --json``).

        Returns
        -------
        dict
            ``method``, ``simulations``, ``max_error`` and ``max_error_uncompensated``
            (output units), the same relative to the reference's range, ``improvement`` and
            ``notes``.
        """
        span = max(float(np.ptp(self.reference)), np.finfo(float).tiny)
        return {
            "method": self.method,
            "simulations": len(self.history) + 1,
            "max_error": self.error,
            "max_error_uncompensated": self.linear_error,
            "relative_error": self.error / span,
            "relative_error_uncompensated": self.linear_error / span,
            "improvement": self.improvement,
            "notes": list(self.notes),
        }


def _input_operator(sim: Simulator, u: sp.Symbol):
    """(operator block, a, b) if the model's only memory operator takes a·u + b (a, b numbers
    after substituting the parameters); else None."""
    eqs = sim.eqs
    if len(eqs.operators) != 1:
        return None
    ob = eqs.operators[0]
    expr = eqs.substituted({"in": ob.input})["in"]
    values = dict(zip(eqs.params, sim.theta()))
    expr = sp.expand(expr.xreplace(values))
    if expr.free_symbols - {u}:
        return None
    a, b = expr.diff(u), expr.subs(u, 0)
    if a.free_symbols or not a.is_number or float(a) == 0.0:
        return None
    return ob, float(a), float(b)


def feedforward(
    model,
    t,
    reference,
    *,
    input: str = "V",
    output: str = "x",
    params=None,
    inputs=None,
    iterations: int = 10,
    tol: float = 1e-4,
    rtol: float = 1e-6,
    progress=None,
    drive_range: tuple[float, float] | None = None,
) -> Compensation:
    """The drive of model input ``input`` that makes output ``output`` follow ``reference``
    (sampled at times ``t``, measured from the output at rest with zero drive).

    ``model``: a :class:`~bondgraph.Model` or a :class:`~bondgraph.Simulator`; ``params``:
    parameter values; ``inputs``: signals for the model's other inputs (default 0).
    Iterates at most ``iterations`` simulations, stopping when the largest error is below
    ``tol`` times the reference's range. ``progress(k)`` is called after each simulation.
    ``drive_range``: (lowest, highest) drive the device accepts (default: the range the model
    declares for ``input``, if any); a drive beyond it is clipped to it, with a note, and the
    predicted output is the clipped drive's.  Every simulation starts where setting
    ``record.start`` says (:func:`~bondgraph.numerics.steady.record_start`): by default at
    the steady state at the drive's first value, so a reference that starts away from zero
    is followed without a start-up transient.

    Parameters
    ----------
    model : Model or Simulator
        The model to invert.
    t : array_like
        Sample times, s, strictly increasing.
    reference : array_like
        The desired output at ``t``, output units, measured from the output at rest.
    input : str, optional
        The model input to drive.
    output : str, optional
        The model output that must follow ``reference``.
    params : mapping of str to float, optional
        Parameter values overriding the model's.
    inputs : mapping of str to Signal, optional
        Signals of the model's other inputs (default 0).
    iterations : int, optional
        Most model simulations of the iteration.
    tol : float, optional
        Stop when the largest error is below ``tol`` times the reference's range.
    rtol : float, optional
        Relative tolerance of the integrator.
    progress : callable, optional
        ``progress(k)`` after the k-th simulation.
    drive_range : tuple of float, optional
        (lowest, highest) drive the device accepts, input units.

    Returns
    -------
    Compensation
        The compensated and the linear-inverse drive with their predicted responses.

    Raises
    ------
    UsageError
        ``t`` and ``reference`` differ in length, or an unknown input or output.
    ModelError
        The output does not respond to the input, or an operator cannot be inverted.
    """
    sim = model if isinstance(model, Simulator) else Simulator(model)
    t = np.asarray(t, float).ravel()
    ref = np.asarray(reference, float).ravel()
    if t.size != ref.size or t.size < 2:
        raise UsageError(f"reference has {ref.size} samples for {t.size} times (need equal, at least 2)")
    if input not in sim.input_names:
        raise UsageError(did_you_mean(input, sim.input_names, "model input"))
    if output not in sim.output_names:
        raise UsageError(did_you_mean(output, sim.output_names, "model output"))
    others = dict(inputs or {})
    theta = sim.theta(params)
    named = dict(zip([p.name for p in sim.eqs.params], theta))
    if drive_range is None and input in sim.eqs.model.inputs:
        drive_range = sim.eqs.model.inputs[input].range
    notes = []
    for ob in sim.eqs.operators:
        c, d = sim.eqs.params.index(ob.params[0]), sim.eqs.params.index(ob.params[-1]) + 1
        why = ob.operator.monotone_problem(np.array(theta[c:d], float)) if ob.params else ""
        if why:
            notes.append(f"operator {ob.symbol}: {why}; the drive below is the best the iteration found")

    def respond(drive):
        run_inputs = {**others, input: PiecewiseLinear(t, drive)}
        x0 = record_start(sim, theta, run_inputs, float(t[0]))
        res = sim.run(t, run_inputs, params=named, x0=x0, rtol=rtol)
        if progress:
            progress(len(history) + 1)
        return np.asarray(res[output], float)

    from ..linear.linearize import linearize  # noqa: PLC0415 - only needed here

    history: list[float] = []
    span = max(float(np.ptp(ref)), np.finfo(float).tiny)
    u_sym = sim.eqs.inputs[sim.input_names.index(input)]
    found = _input_operator(sim, u_sym)
    if found is not None:
        ob, a, b = found
        c, d = sim.eqs.params.index(ob.params[0]), sim.eqs.params.index(ob.params[-1]) + 1
        prm = np.array(theta[c:d], float)
        k0 = ob.operator.small_signal_gain(prm)
        gain = linearize(sim.eqs, input, output, named).dc_gain() / (a * k0) if k0 else 0.0
        if not np.isfinite(gain) or gain == 0.0:
            found = None
    if found is not None:
        method = "operator inverse"
        w = ref / gain

        def drive_of(w):
            return (invert_operator(ob.operator, w, prm) - b) / a
    else:
        method = "iteration"
        gain = linearize(sim.eqs, input, output, named).dc_gain()
        if not np.isfinite(gain) or gain == 0.0:  # e.g. a DE-based hysteresis state: probe the model
            probe = (ref - ref[0]) / span
            gain = float(np.ptp(respond(probe)))
            if not np.isfinite(gain) or gain == 0.0:
                raise ModelError(f"output {output} does not respond to input {input}: nothing to invert")
        w = ref / gain

        def drive_of(w):
            return w

    drive = drive_of(w)
    x = respond(drive)
    best = (np.max(np.abs(x - ref)), drive, x)
    relax = 1.0
    for _ in range(iterations - 1):
        err = ref - x
        history.append(float(np.max(np.abs(err))))
        if history[-1] <= tol * span:
            break
        if method == "iteration" and len(history) == 1:  # secant gain of the model over the stroke
            gain = float(np.ptp(x) / np.ptp(drive)) if np.ptp(drive) > 0 else gain
        w_new = w + relax * err / gain
        drive_new = drive_of(w_new)
        x_new = respond(drive_new)
        e_new = float(np.max(np.abs(x_new - ref)))
        if e_new >= best[0]:  # no progress: smaller steps from the best drive so far
            relax *= 0.5
            if relax < 1e-3:
                break
            continue
        w, drive, x = w_new, drive_new, x_new
        best = (e_new, drive, x)
    history.append(float(best[0]))
    drive, x = best[1], best[2]
    if drive_range is not None:
        lo, hi = drive_range
        outside = (drive < lo) | (drive > hi)
        if outside.any():
            notes.append(
                f"the drive would span {drive.min():.4g} to {drive.max():.4g}, beyond the input's range "
                f"{lo:g} to {hi:g} on {100 * outside.mean():.3g} % of the samples: clipped to the range (the "
                f"predicted output and errors are the clipped drive's)"
            )
            drive = np.clip(drive, lo, hi)
            x = respond(drive)
    # the linear inverse: proportional to the reference over the same drive range
    ref_span = float(np.ptp(ref))
    scale = float(np.ptp(drive)) / ref_span if ref_span > 0 else 0.0
    lin = float(np.mean(drive)) + (ref - float(np.mean(ref))) * scale
    return Compensation(t, ref, drive, x, lin, respond(lin), method, history, notes)
