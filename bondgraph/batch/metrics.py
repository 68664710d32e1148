"""Scalar outputs of one simulation, named as on the command line (``--metric SPEC``).

Signal metrics take the name of an output, input or state of the model:

* ``peak(y)``   max |y|                       * ``rms(y)``    root mean square of y
* ``max(y)``, ``min(y)``, ``mean(y)``         * ``p2p(y)``    max − min
* ``final(y)``  y at the end time             * ``steady(y)`` mean of y over the last 10 % of the run

Linear metrics come from the linearisation at the initial state (``bondgraph.linear.linearize``):

* ``resonance`` / ``resonance(k)``  natural frequency ωn/2π (Hz) of the first (k-th) oscillatory
  mode (complex pole pair), counted from the lowest
* ``damping`` / ``damping(k)``      its damping ratio ζ

Values are in the unit of the signal.  A metric a run cannot give (a model without an
oscillatory mode) is left empty in that run's row, with the reason in its ``warnings``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from ..support.errors import UsageError

#: share of the run at its end over which ``steady`` averages
STEADY_SHARE = 0.1

_SIGNAL: dict[str, Callable[[np.ndarray, np.ndarray], float]] = {
    "peak": lambda t, y: float(np.max(np.abs(y))),
    "max": lambda t, y: float(np.max(y)),
    "min": lambda t, y: float(np.min(y)),
    "mean": lambda t, y: float(np.mean(y)),
    "rms": lambda t, y: float(np.sqrt(np.mean(np.square(y)))),
    "p2p": lambda t, y: float(np.ptp(y)),
    "final": lambda t, y: float(y[-1]),
    "steady": lambda t, y: float(np.mean(y[t >= t[-1] - STEADY_SHARE * (t[-1] - t[0])])),
}
_LINEAR = ("resonance", "damping")
_SPEC = re.compile(r"^\s*([a-z0-9]+)\s*(?:\(\s*([^()]*?)\s*\))?\s*$")


@dataclass(frozen=True)
class Metric:
    """One scalar output: ``kind`` applied to signal ``arg`` (or mode number for linear kinds).

    Parameters
    ----------
    text : str
        The metric as written (the table's column name), e.g. ``"peak(x)"``.
    kind : str
        ``peak``, ``max``, ``min``, ``mean``, ``rms``, ``p2p``, ``final``, ``steady``,
        ``resonance`` or ``damping``.
    arg : str or int
        The signal's name, or the mode number (from 1) of a linear kind.
    """

    text: str
    kind: str
    arg: str | int

    @property
    def linear(self) -> bool:
        """Whether it comes from the linearisation (``resonance``, ``damping``)."""
        return self.kind in _LINEAR

    def unit(self, signal_units: dict) -> str:
        """The metric's unit: Hz for ``resonance``, none for ``damping``, else its signal's
        unit in ``signal_units`` (name → unit; empty when not declared)."""
        if self.linear:
            return "Hz" if self.kind == "resonance" else ""
        return signal_units.get(self.arg, "")

    def of(self, result, linear=None) -> float:
        """The value on a :class:`~bondgraph.numerics.simulate.SimResult` (and its ``LinearModel``).

        Parameters
        ----------
        result : SimResult
            The run.
        linear : LinearModel, optional
            The model linearised at the initial state (needed by the linear kinds).

        Returns
        -------
        float
            The value, in the signal's unit (Hz for ``resonance``, dimensionless for
            ``damping``).

        Raises
        ------
        UsageError
            The run has no such signal, or the linear model too few oscillatory modes.
        """
        if self.linear:
            return mode_property(linear, self.kind, int(self.arg))
        y = result.outputs.get(self.arg)  # outputs first: looking up an input samples every input
        try:
            y = result[self.arg] if y is None else y
        except KeyError:
            known = [*result.outputs, *result.inputs, *result.states]
            raise UsageError(
                f"metric {self.text}: the model has no signal {self.arg!r}; known: {', '.join(known)}"
            ) from None
        return _SIGNAL[self.kind](result.t, y)


def parse_metric(text: str) -> Metric:
    """A metric from its text (``--metric SPEC``; see the module docstring).

    Parameters
    ----------
    text : str
        E.g. ``"peak(x)"``, ``"steady(x)"``, ``"resonance"``, ``"damping(2)"``.

    Returns
    -------
    Metric
        The parsed metric.

    Raises
    ------
    UsageError
        An unknown kind, a signal metric without a signal, or a mode number below 1.
    """
    m = _SPEC.match(text)
    kinds = ", ".join([*_SIGNAL, *_LINEAR])
    if not m or (m.group(1) not in _SIGNAL and m.group(1) not in _LINEAR):
        raise UsageError(f"bad metric {text!r}: write e.g. peak(x), rms(x), steady(x) or resonance; kinds: {kinds}")
    kind, arg = m.group(1), m.group(2)
    if kind in _LINEAR:
        try:
            k = int(arg) if arg else 1
        except ValueError:
            k = 0
        if k < 1:
            raise UsageError(f"bad metric {text!r}: {kind}(k) takes a mode number k >= 1")
        return Metric(text.strip(), kind, k)
    if not arg:
        raise UsageError(f"bad metric {text!r}: {kind} needs a signal, e.g. {kind}(x)")
    return Metric(text.strip(), kind, arg)


def parse_metrics(texts: Sequence[str]) -> list[Metric]:
    """Several metrics (:func:`parse_metric`), each given once.

    Parameters
    ----------
    texts : sequence of str
        The metrics' texts.

    Returns
    -------
    list of Metric
        In the order given.

    Raises
    ------
    UsageError
        A bad metric, or one given twice.
    """
    out = [parse_metric(t) for t in texts]
    seen = set()
    for m in out:
        if m.text in seen:
            raise UsageError(f"metric {m.text} given twice")
        seen.add(m.text)
    return out


def mode_property(lin, kind: str, k: int) -> float:
    """Natural frequency (Hz) or damping ratio of the k-th oscillatory mode of ``lin``.

    Parameters
    ----------
    lin : LinearModel
        The linearised model.
    kind : {"resonance", "damping"}
        Which property.
    k : int
        The mode, counted from the lowest natural frequency (1 = the lowest).

    Returns
    -------
    float
        ωn/2π in Hz, or the damping ratio ζ.

    Raises
    ------
    UsageError
        The model has fewer than ``k`` oscillatory modes.
    """
    p = lin.poles
    p = p[p.imag > 1e-9 * np.maximum(np.abs(p), 1.0)]
    p = p[np.argsort(np.abs(p))]
    if p.size < k:
        raise UsageError(f"{kind}({k}): the linearised model has {p.size} oscillatory mode(s)")
    wn = float(np.abs(p[k - 1]))
    return wn / (2 * np.pi) if kind == "resonance" else float(-p[k - 1].real / wn)
