"""All inputs of a model packed into arrays for the compiled integrator.

A :class:`~bondgraph.model.signals.Signal` is a kind code, a row of parameters and (for
tables) a time/value table; :class:`SignalBank` concatenates them so that
:func:`~bondgraph.numerics.integrators.eval_inputs` evaluates every input and its time
derivative inside compiled code, without calling back into Python.
"""

from __future__ import annotations

import math
from typing import Mapping, NamedTuple

import numpy as np

from ..model.signals import NPAR, PWL, Signal
from .integrators import sample_inputs


class SignalArrays(NamedTuple):
    """All inputs as arrays: kind and parameter row per input, offset and length of its table
    in ``tt``/``tv`` (times and values), and ``cur``, the table interval last used per input.

    Parameters
    ----------
    kind : numpy.ndarray
        Signal kind code per input (int64).
    par : numpy.ndarray
        Parameter row per input (inputs × NPAR).
    off : numpy.ndarray
        Offset of each input's table in ``tt``/``tv``.
    len : numpy.ndarray
        Length of each input's table.
    tt : numpy.ndarray
        Table times of every input, concatenated, s.
    tv : numpy.ndarray
        Table values of every input, concatenated, in the inputs' units.
    cur : numpy.ndarray
        The table interval last used per input (a search hint, written by the integrator).
    """

    kind: np.ndarray
    par: np.ndarray
    off: np.ndarray
    len: np.ndarray
    tt: np.ndarray
    tv: np.ndarray
    cur: np.ndarray


class SignalBank:
    """All inputs of a model packed into arrays for the compiled integrator.

    Parameters
    ----------
    signals : mapping of str to Signal
        Input name → signal, in the model's input order.
    kinks : bool, optional
        Also break integration at the inputs' slope discontinuities (when laws use input
        rates or memory operators follow the inputs).
    """

    def __init__(self, signals: Mapping[str, Signal], kinks: bool = False):
        self.signals = sigs = list(signals.values())
        self.kinks = kinks
        self.names = list(signals)
        self.kind = np.array([s.kind for s in sigs], np.int64)
        self.par = np.array([s.par for s in sigs], float).reshape(len(sigs), NPAR)
        lens = [len(s.table_t) for s in sigs]
        self.len = np.array(lens, np.int64)
        self.off = np.concatenate([[0], np.cumsum(lens)[:-1]]).astype(np.int64) if sigs else np.zeros(0, np.int64)
        self.tt = np.array([x for s in sigs for x in s.table_t] or [0.0], float)
        self.tv = np.array([x for s in sigs for x in s.table_v] or [0.0], float)

    def breaks(self, t0: float, t1: float) -> np.ndarray:
        """Sorted breakpoints of all inputs in (t0, t1).

        Parameters
        ----------
        t0, t1 : float
            The open time interval, s.

        Returns
        -------
        numpy.ndarray
            The times, s, where an input jumps (or, with ``kinks``, changes slope), each once.
        """
        return np.unique(np.array([b for s in self.signals for b in s.breakpoints(t0, t1, self.kinks)], float))

    def table_spacing(self) -> float:
        """Median sample interval of the tabulated inputs (s); inf when there are none.

        Returns
        -------
        float
            The smallest of the tables' median intervals, s.
        """
        gaps = [
            np.median(np.diff(self.tt[o : o + n]))
            for k, o, n in zip(self.kind, self.off, self.len)
            if k == PWL and n > 1
        ]
        return float(min(gaps)) if gaps else math.inf

    def args(self) -> "SignalArrays":
        """The arrays the compiled integrator and :func:`eval_inputs` take, in their order.

        Returns
        -------
        SignalArrays
            The bank's arrays, with a fresh ``cur``.
        """
        return SignalArrays(
            self.kind, self.par, self.off, self.len, self.tt, self.tv, np.zeros(len(self.names), np.int64)
        )

    def sample(self, t) -> np.ndarray:
        """Values of all inputs at times ``t``: array (len(t), n_inputs).

        Parameters
        ----------
        t : float or array_like
            Times, s.

        Returns
        -------
        numpy.ndarray
            (len(t), inputs) values, in the inputs' units.
        """
        t = np.atleast_1d(np.asarray(t, float))
        out = np.zeros((t.size, len(self.names)))
        if self.names:
            sample_inputs(t, *self.args(), False, out)
        return out
