"""Elements with memory: the contract between a rate-independent operator and the integrator.

A memory operator maps a scalar input history v(t) to an output y(t) = H[v](t) whose value
depends on the input's past only through a finite memory vector (play/stop operators, Maxwell
slip branches, ...).  It is defined by two static functions, compiled by numba in nopython mode:

``output(v, mem, prm) -> float``
    The output for input ``v`` with the memory frozen at the last accepted integrator step.
    Must be continuous in ``v`` (so adaptive solvers stay well behaved) and must not modify
    ``mem``.
``commit(v, mem, prm) -> None``
    Advance the memory in place to input ``v``.  The integrator calls it exactly once per
    *accepted* step, with the input at the end of that step.  Rejected or retried steps only
    ever call ``output``, so they can never corrupt the memory.

and one Python method, ``initial_memory(v0, prm) -> ndarray``, the memory at rest at input v0.

``prm`` is a contiguous float64 array of the operator's parameters (thresholds, weights, ...);
they are model parameters, so they can be set, printed and fitted like any other.

The two functions are compiled when the operator is applied (:meth:`Component.operator`), and
the compiled kernels are what the integrator, the generated model code and :meth:`run` call.
They may call other functions: plain Python helpers are compiled with them, and functions
already compiled with ``numba.njit`` are used as they are (or recompiled from their source,
with their helpers, when numba refuses them); ``output = staticmethod(f)`` and
``output = numba.njit(f)`` work too.  A function numba cannot compile is a
:class:`~bondgraph.support.errors.ModelError` naming the operator, the function and the rule it broke.
Subclass :class:`MemoryOperator` to add an operator; see ``library/hysteresis/`` for the
play/stop (Prandtl–Ishlinskii) and Maxwell-slip banks.

An exported model (an FMU, :mod:`bondgraph.export`) runs without Python, so it carries the
operator in C: :meth:`MemoryOperator.c_source` gives the C twins of ``output``, ``commit`` and
``initial_memory`` as a :class:`CSource`.  The default gives none, and the exporter then
refuses the model, naming the operator.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .operator_kernels import OperatorKernels


@dataclass(frozen=True)
class CSource:
    """C twins of an operator's kernels, for models exported to C (:mod:`bondgraph.export`).

    Each of ``output``, ``commit`` and ``initial`` is the *body* (C99 statements) of a function
    with the arguments ``v`` (the input; ``v0`` for ``initial``), ``mem`` (the memory,
    ``n_mem`` doubles), ``prm`` (the operator's parameters, ``n_prm`` doubles):

    * ``double output(double v, const double *mem, int n_mem, const double *prm, int n_prm)``:
      returns what :meth:`MemoryOperator.output` returns; must not write ``mem``;
    * ``void commit(double v, double *mem, int n_mem, const double *prm, int n_prm)``:
      advances ``mem`` as :meth:`MemoryOperator.commit` does;
    * ``void initial(double v0, double *mem, int n_mem, const double *prm, int n_prm)``:
      writes the memory at rest at ``v0``, as :meth:`MemoryOperator.initial_memory` returns it.

    ``<math.h>`` is included.

    Parameters
    ----------
    output : str
        The body of ``output``.
    commit : str
        The body of ``commit``.
    initial : str
        The body of ``initial``.
    helpers : tuple of str, optional
        Complete C definitions (``static`` functions) the bodies call; a helper shared by
        several operators is emitted once, so one name must always carry the same text.
    """

    output: str
    commit: str
    initial: str
    helpers: tuple[str, ...] = ()


class MemoryOperator(ABC):
    """Base class of rate-independent operators with memory.

    Subclasses set ``kind`` (a short identifier used in printouts),
    implement the static functions ``output`` and ``commit`` described in the module
    docstring, ``initial_memory``, and provide ``parameter_names``/``parameter_values``
    (equal-length sequences) and ``n_memory``.
    """

    kind: str = "operator"

    #: names (without the element prefix) and default values of the operator parameters
    parameter_names: tuple[str, ...] = ()

    #: units of the input v and the output y when the operator fixes them (unit strings, see
    #: :mod:`bondgraph.model.units`); "" (the default): they follow from where the model uses it
    input_unit: str = ""
    output_unit: str = ""

    def parameter_dimensions(self) -> dict[str, tuple]:
        """How the units of the parameters follow from the input's and the output's, for
        dimensional analysis: parameter name -> (a, b) with [parameter] = [v]^a·[y]^b (a
        threshold in units of v is (1, 0), a weight in y per v (-1, 1), a pure number (0, 0)).
        Parameters left out get their units where the model uses them, or none.

        Returns
        -------
        dict of str to tuple of (int, int)
            Parameter name -> exponents (a, b); the default is empty.
        """
        return {}

    @abstractmethod
    def parameter_values(self) -> np.ndarray:
        """Default values of the parameters, in ``parameter_names`` order."""

    @property
    @abstractmethod
    def n_memory(self) -> int:
        """Length of the memory vector."""

    @abstractmethod
    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """The memory at rest with a given input.

        Parameters
        ----------
        v0 : float
            The input, in the operator's input unit.
        prm : numpy.ndarray
            The operator's parameters, in ``parameter_names`` order.

        Returns
        -------
        numpy.ndarray
            The memory vector, ``n_memory`` float64 values.
        """

    @abstractmethod
    def small_signal_gain(self, prm: np.ndarray) -> float:
        """dy/dv for a small excursion from the initial state; used by linearisation.

        Parameters
        ----------
        prm : numpy.ndarray
            The operator's parameters.

        Returns
        -------
        float
            The slope, in output unit per input unit.
        """

    @staticmethod
    @abstractmethod
    def output(v, mem, prm):
        """The output for an input with the memory frozen (pure; compiled by numba).

        Parameters
        ----------
        v : float
            The input.
        mem : numpy.ndarray
            The memory at the last accepted step; not modified.
        prm : numpy.ndarray
            The operator's parameters.

        Returns
        -------
        float
            The output y, continuous in ``v``.
        """

    @staticmethod
    @abstractmethod
    def commit(v, mem, prm):
        """Advance the memory in place to an input (called on accepted steps only; compiled by numba).

        Parameters
        ----------
        v : float
            The input at the end of the accepted step.
        mem : numpy.ndarray
            The memory, updated in place.
        prm : numpy.ndarray
            The operator's parameters.
        """

    def inverse(self) -> "MemoryOperator | None":
        """Optional: an operator G with G[H[v]] = v from rest (the exact inverse), for feedforward
        compensation (:mod:`bondgraph.fit.compensate`). The default None means "no closed form": the
        compensation then inverts ``output``/``commit`` numerically, sample by sample."""
        return None

    def c_source(self) -> CSource | None:
        """Optional: the operator's kernels in C (:class:`CSource`), for exported models. The
        default None means "not available": the exporter refuses a model that applies it."""
        return None

    def monotone_problem(self, prm: np.ndarray) -> str:
        """Optional: why the operator's output does not rise with its input for the parameters
        ``prm`` (then it has no inverse and feedforward compensation cannot use it), or "" when
        it does or the operator cannot tell.  The default says nothing.

        Parameters
        ----------
        prm : numpy.ndarray
            The operator's parameters.

        Returns
        -------
        str
            The reason, or ``""``.
        """
        return ""

    # --- used by the framework -------------------------------------------------------
    def kernels(self) -> "OperatorKernels":
        """The compiled ``output`` and ``commit`` (compiled once per class and process).

        Returns
        -------
        OperatorKernels
            The numba-compiled kernels.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If numba cannot compile a kernel (naming the operator, the function and the rule).
        """
        from .operator_kernels import compile_kernels  # numba is imported when first needed

        return compile_kernels(type(self))

    def run(self, v: np.ndarray, prm: np.ndarray | None = None) -> np.ndarray:
        """Apply the operator to a sampled input sequence, from rest at ``v[0]``, with the
        compiled kernels the integrator uses (output, then commit, at every sample).

        Parameters
        ----------
        v : numpy.ndarray
            The input samples.
        prm : numpy.ndarray, optional
            The parameters; ``parameter_values()`` by default.

        Returns
        -------
        numpy.ndarray
            The output at every sample, as long as ``v``.
        """
        prm = np.array(self.parameter_values() if prm is None else prm, dtype=np.float64)  # private,
        v = np.array(v, dtype=np.float64)  # writable copies
        mem = np.array(self.initial_memory(float(v[0]), prm), dtype=np.float64)
        k = self.kernels()
        y = np.empty_like(v)
        from .operator_kernels import run_kernels

        run_kernels(k.output, k.commit, v, mem, prm, y)
        return y


def not_monotone(model) -> list[str]:
    """For each memory operator of ``model`` whose output does not rise with its input at the
    model's parameter values (:meth:`MemoryOperator.monotone_problem`): "operator NAME: why".

    Parameters
    ----------
    model : bondgraph.Model
        The model, with its parameter values (e.g. fitted ones) set.

    Returns
    -------
    list of str
        One line per operator that cannot be inverted; empty when every operator can (or
        does not say).
    """
    table = model.parameter_table()
    out = []
    for name, ob in model.operators.items():
        prm = np.array([float(table[s]) for s in ob.params], dtype=np.float64)
        why = ob.operator.monotone_problem(prm)
        if why:
            out.append(f"operator {name}: {why}")
    return out
