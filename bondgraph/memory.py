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
:class:`~bondgraph.errors.ModelError` naming the operator, the function and the rule it broke.
Subclass :class:`MemoryOperator` to add an operator; see ``library/hysteresis/`` for the
play/stop (Prandtl–Ishlinskii) and Maxwell-slip banks.
"""
from __future__ import annotations

import hashlib
import inspect
import re
import types
from abc import ABC, abstractmethod
from typing import Callable, NamedTuple

import numpy as np
from numba import njit
from numba import types as nbt
from numba.core.dispatcher import Dispatcher
from numba.core.errors import NumbaError

from .errors import ModelError

OUTPUT_TYPE = nbt.float64(nbt.float64, nbt.float64[::1], nbt.float64[::1])
COMMIT_TYPE = nbt.void(nbt.float64, nbt.float64[::1], nbt.float64[::1])


class OperatorKernels(NamedTuple):
    """The compiled ``output`` and ``commit`` of an operator class, and a fingerprint of their
    code (it changes when the code or a helper or constant they use changes)."""

    output: Callable
    commit: Callable
    fingerprint: str


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
    def kernels(self) -> OperatorKernels:
        """The compiled ``output`` and ``commit`` (compiled once per class and process)."""
        return compile_kernels(type(self))

    def run(self, v: np.ndarray, prm: np.ndarray | None = None) -> np.ndarray:
        """Apply the operator to a sampled input sequence, from rest at ``v[0]``, with the
        compiled kernels the integrator uses (output, then commit, at every sample)."""
        prm = np.array(self.parameter_values() if prm is None else prm, dtype=np.float64)  # private,
        v = np.array(v, dtype=np.float64)                                                 # writable copies
        mem = np.array(self.initial_memory(float(v[0]), prm), dtype=np.float64)
        k = self.kernels()
        y = np.empty_like(v)
        _run_kernels(k.output, k.commit, v, mem, prm, y)
        return y


@njit(nbt.void(nbt.FunctionType(OUTPUT_TYPE), nbt.FunctionType(COMMIT_TYPE), nbt.float64[::1],
               nbt.float64[::1], nbt.float64[::1], nbt.float64[::1]), cache=True)
def _run_kernels(output, commit, v, mem, prm, y):
    for k in range(v.shape[0]):
        y[k] = output(v[k], mem, prm)
        commit(v[k], mem, prm)


_COMPILED: dict[type, OperatorKernels] = {}


def compile_kernels(cls: type) -> OperatorKernels:
    """Compile (once per process) and check the kernels of operator class ``cls``."""
    if cls not in _COMPILED:
        fns = {which: _static_function(cls, which) for which in ("output", "commit")}
        compiled = {which: _compile(cls, which, fn, sig)
                    for (which, fn), sig in zip(fns.items(), (OUTPUT_TYPE, COMMIT_TYPE))}
        digest = hashlib.sha256()
        for fn in fns.values():
            digest.update(_fingerprint(fn, set()).encode())
        _COMPILED[cls] = OperatorKernels(compiled["output"], compiled["commit"], digest.hexdigest()[:20])
    return _COMPILED[cls]


def _name(cls: type) -> str:
    return f"memory operator {cls.__qualname__} (kind '{getattr(cls, 'kind', '?')}')"


def _static_function(cls: type, which: str):
    """The plain (or numba-compiled) function behind ``cls.<which>``."""
    raw = inspect.getattr_static(cls, which, None)
    fn = raw.__func__ if isinstance(raw, staticmethod) else raw
    if isinstance(fn, Dispatcher):
        params = inspect.signature(fn.py_func).parameters
    elif isinstance(fn, types.FunctionType) and isinstance(raw, staticmethod):
        params = inspect.signature(fn).parameters
    else:
        raise ModelError(f"{_name(cls)}: {which} must be a static function {which}(v, mem, prm) "
                         f"(decorate it with @staticmethod, or assign staticmethod(f) or numba.njit(f)), "
                         f"got {raw!r}")
    positional = [p for p in params.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    if len(positional) != 3 or len(params) != 3:
        raise ModelError(f"{_name(cls)}: {which} must take exactly three arguments (v, mem, prm), "
                         f"it takes ({', '.join(params)})")
    return fn


def _compile(cls: type, which: str, fn, sig):
    """``fn`` compiled for ``sig`` (helpers it calls compiled too); ModelError if numba refuses."""
    try:
        if isinstance(fn, Dispatcher):
            try:
                fn.compile(sig)
                return fn
            except NumbaError:  # e.g. it calls plain Python helpers: compile them with its source
                fn = fn.py_func
        cache = len({f.__code__.co_filename for f in _plain_functions(fn, {})}) == 1
        return _jit(fn, sig, {}, cache)
    except NumbaError as exc:
        raise ModelError(f"{_name(cls)}: {which}(v, mem, prm) cannot be compiled by numba in nopython mode "
                         f"({_numba_reason(exc)}); use numbers, numpy arrays, math and numpy functions, and "
                         f"functions that obey the same rules") from None


def _helpers(fn) -> dict:
    """The plain Python functions ``fn`` reads as globals, by name."""
    return {name: fn.__globals__[name] for name in _global_names(fn.__code__)
            if isinstance(fn.__globals__.get(name), types.FunctionType)}


def _plain_functions(fn, seen: dict) -> dict:
    """``fn`` and every plain Python function it reaches through its helpers."""
    if fn not in seen:
        seen[fn] = True
        for h in _helpers(fn).values():
            _plain_functions(h, seen)
    return seen


def _jit(fn, sig, done: dict, cache: bool):
    """njit ``fn`` after compiling the plain Python functions it calls (recursively).

    numba's disk cache is invalidated by changes to the file of the function it compiled, not
    to the files of functions it calls, so it is used only when all of them share one file."""
    if fn in done:
        return done[fn]
    helpers = _helpers(fn)
    target = fn
    if helpers:
        done[fn] = None  # recursion guard: a self-recursive helper keeps its own name
        namespace = dict(fn.__globals__)
        namespace.update({name: _jit(h, None, done, cache) or h for name, h in helpers.items()})
        target = types.FunctionType(fn.__code__, namespace, fn.__name__, fn.__defaults__, fn.__closure__)
        target.__qualname__, target.__module__ = fn.__qualname__, fn.__module__
    options = {"cache": True} if cache else {}
    try:
        compiled = njit(sig, **options)(target) if sig is not None else njit(**options)(target)
    except RuntimeError:  # no place to cache (a function defined in exec'd text)
        compiled = njit(sig)(target) if sig is not None else njit(target)
    done[fn] = compiled
    return compiled


def _global_names(code) -> set[str]:
    names = set(code.co_names)
    for c in code.co_consts:
        if isinstance(c, types.CodeType):
            names |= _global_names(c)
    return names


def _fingerprint(fn, seen: set) -> str:
    """Text that changes when the code of ``fn``, of a function it calls, or a global value it
    reads changes (so compiled model code that inlines the kernels is rebuilt)."""
    fn = fn.py_func if isinstance(fn, Dispatcher) else fn
    if id(fn) in seen:
        return fn.__qualname__
    seen.add(id(fn))
    parts = [fn.__module__ or "", fn.__qualname__, _code_text(fn.__code__)]
    for name in sorted(_global_names(fn.__code__)):
        val = fn.__globals__.get(name)
        if isinstance(val, (types.FunctionType, Dispatcher)):
            parts.append(f"{name}=" + _fingerprint(val, seen))
        elif isinstance(val, types.ModuleType):
            parts.append(f"{name}=module {val.__name__}")
        elif isinstance(val, np.ndarray):
            parts.append(f"{name}=array {hashlib.sha256(val.tobytes()).hexdigest()}")
        elif isinstance(val, (int, float, complex, bool, str, tuple, type(None))):
            parts.append(f"{name}={val!r}")
        else:
            parts.append(f"{name}:{type(val).__qualname__}")
    return "\n".join(parts)


def _code_text(code) -> str:
    consts = [_code_text(c) if isinstance(c, types.CodeType) else repr(c) for c in code.co_consts]
    return f"{code.co_code.hex()}|{consts}|{code.co_names}|{code.co_varnames}"


def _numba_reason(exc: Exception) -> str:
    """One line from numba's message: the problem and, when given, where it is."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    reason = next((ln for ln in lines if not ln.startswith(("Failed in", "During:", "File", "^"))), lines[0])
    where = next((m for m in (re.search(r'File "([^"]+)", line (\d+)', ln) for ln in lines) if m), None)
    reason = re.sub(r"\x1b\[[0-9;]*m", "", reason)
    return f"{reason} at {where.group(1)}:{where.group(2)}" if where else reason
