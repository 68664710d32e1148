"""Elements with memory: the contract between a rate-independent operator and the integrator.

A memory operator maps a scalar input history v(t) to an output y(t) = H[v](t) whose value
depends on the input's past only through a finite memory vector (play/stop operators, Maxwell
slip branches, ...).  It is defined by two *pure, module-level, numba-compilable* functions:

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

The code generator copies the *source* of ``output`` and ``commit`` into the compiled model, so
both functions may use only ``math``, ``numpy as np`` and their arguments (no globals, no
closures).  Subclass :class:`MemoryOperator` to add an operator; see
``library/hysteresis.py`` for the play/stop (Prandtl–Ishlinskii) and Maxwell-slip banks.
"""
from __future__ import annotations

import inspect
import textwrap
from abc import ABC, abstractmethod

import numpy as np


class MemoryOperator(ABC):
    """Base class of rate-independent operators with memory.

    Subclasses set ``kind`` (a short identifier used in generated code and printouts),
    implement the static functions ``output`` and ``commit`` described in the module
    docstring, ``initial_memory``, and provide ``parameter_names``/``parameter_values``
    (equal-length sequences) and ``n_memory``.
    """

    kind: str = "operator"

    #: names (without the element prefix) and default values of the operator parameters
    parameter_names: tuple[str, ...] = ()

    @abstractmethod
    def parameter_values(self) -> np.ndarray:
        """Default values of the parameters, in ``parameter_names`` order."""

    @property
    @abstractmethod
    def n_memory(self) -> int:
        """Length of the memory vector."""

    @abstractmethod
    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """Memory at rest with input ``v0``."""

    @abstractmethod
    def small_signal_gain(self, prm: np.ndarray) -> float:
        """dy/dv for a small excursion from the initial state; used by linearisation."""

    @staticmethod
    @abstractmethod
    def output(v, mem, prm):
        """Output for input ``v`` with frozen memory (pure)."""

    @staticmethod
    @abstractmethod
    def commit(v, mem, prm):
        """Advance ``mem`` in place to input ``v`` (accepted steps only)."""

    def inverse(self) -> "MemoryOperator | None":
        """Optional: an operator G with G[H[v]] = v from rest (the exact inverse), for feedforward
        compensation (:mod:`bondgraph.compensate`). The default None means "no closed form": the
        compensation then inverts ``output``/``commit`` numerically, sample by sample."""
        return None

    # --- used by the framework -------------------------------------------------------
    def kernel_source(self, prefix: str) -> str:
        """Source of ``output`` and ``commit`` renamed to ``{prefix}_output``/``_commit``."""
        parts = []
        for fname in ("output", "commit"):
            fn = getattr(type(self), fname)
            lines = textwrap.dedent(inspect.getsource(fn)).splitlines()
            # drop the decorators (possibly spanning several lines), keep the body verbatim
            start = next(k for k, ln in enumerate(lines) if ln.startswith(f"def {fname}("))
            src = "\n".join(lines[start:])
            src = src.replace(f"def {fname}(", f"def {prefix}_{fname}(", 1)
            parts.append(src)
        return "\n\n".join(parts)

    def run(self, v: np.ndarray, prm: np.ndarray | None = None) -> np.ndarray:
        """Apply the operator to a sampled input sequence (reference, pure Python)."""
        prm = self.parameter_values() if prm is None else prm
        prm = np.ascontiguousarray(prm, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        mem = self.initial_memory(float(v[0]), prm)
        out_fn = type(self).output
        commit_fn = type(self).commit
        y = np.empty_like(v)
        for k, vk in enumerate(v):
            y[k] = out_fn(vk, mem, prm)
            commit_fn(vk, mem, prm)
        return y
