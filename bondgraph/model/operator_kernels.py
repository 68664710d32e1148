"""Compilation of memory-operator kernels with numba (nopython), their checks and fingerprints:
the part of the operator contract (:mod:`bondgraph.model.memory`) that needs numba, imported only when
an operator is applied or run, so that loading a model without operators stays fast."""

from __future__ import annotations

import hashlib
import inspect
import re
import types
from typing import Callable, NamedTuple

import numpy as np
from numba import njit
from numba import types as nbt
from numba.core.dispatcher import Dispatcher
from numba.core.errors import NumbaError

from ..support.errors import ModelError

OUTPUT_TYPE = nbt.float64(nbt.float64, nbt.float64[::1], nbt.float64[::1])
COMMIT_TYPE = nbt.void(nbt.float64, nbt.float64[::1], nbt.float64[::1])


class OperatorKernels(NamedTuple):
    """The compiled ``output`` and ``commit`` of an operator class, and a fingerprint of their
    code (it changes when the code or a helper or constant they use changes)."""

    output: Callable
    commit: Callable
    fingerprint: str


@njit(
    nbt.void(
        nbt.FunctionType(OUTPUT_TYPE),
        nbt.FunctionType(COMMIT_TYPE),
        nbt.float64[::1],
        nbt.float64[::1],
        nbt.float64[::1],
        nbt.float64[::1],
    ),
    cache=True,
)
def run_kernels(output, commit, v, mem, prm, y):
    """y[k] = output(v[k]), then commit(v[k]), for every sample (what the integrator does per accepted step)."""
    for k in range(v.shape[0]):
        y[k] = output(v[k], mem, prm)
        commit(v[k], mem, prm)


_COMPILED: dict[type, OperatorKernels] = {}


def compile_kernels(cls: type) -> OperatorKernels:
    """Compile (once per process) and check the kernels of operator class ``cls``."""
    if cls not in _COMPILED:
        fns = {which: _static_function(cls, which) for which in ("output", "commit")}
        compiled = {
            which: _compile(cls, which, fn, sig) for (which, fn), sig in zip(fns.items(), (OUTPUT_TYPE, COMMIT_TYPE))
        }
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
        raise ModelError(
            f"{_name(cls)}: {which} must be a static function {which}(v, mem, prm) "
            f"(decorate it with @staticmethod, or assign staticmethod(f) or numba.njit(f)), "
            f"got {raw!r}"
        )
    positional = [p for p in params.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    if len(positional) != 3 or len(params) != 3:
        raise ModelError(
            f"{_name(cls)}: {which} must take exactly three arguments (v, mem, prm), it takes ({', '.join(params)})"
        )
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
        raise ModelError(
            f"{_name(cls)}: {which}(v, mem, prm) cannot be compiled by numba in nopython mode "
            f"({_numba_reason(exc)}); use numbers, numpy arrays, math and numpy functions, and "
            f"functions that obey the same rules"
        ) from None


def _helpers(fn) -> dict:
    """The plain Python functions ``fn`` reads as globals, by name."""
    return {
        name: fn.__globals__[name]
        for name in _global_names(fn.__code__)
        if isinstance(fn.__globals__.get(name), types.FunctionType)
    }


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
