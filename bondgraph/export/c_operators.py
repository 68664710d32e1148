"""Run memory operators through their C twins (:meth:`MemoryOperator.c_source`), to check them
against the compiled numba kernels before a model that applies them is exported.

:func:`c_runs` compiles the C source of several operators into one shared library and returns,
per operator, a function ``run(v, prm=None) -> y`` that does what :meth:`MemoryOperator.run`
does (memory at rest at ``v[0]`` by the C ``initial``, then ``output`` and ``commit`` at every
sample), so ``run(v)`` and ``op.run(v)`` can be compared sample by sample.
"""

from __future__ import annotations

import ctypes
import tempfile
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..model.memory import MemoryOperator
from ..support.errors import ModelError
from .c_model import helpers, operator_functions
from .compiler import build_shared, find_compiler


def c_runs(operators: Sequence[MemoryOperator], cc: str | None = None) -> list[Callable]:
    """Per operator, ``run(v, prm=None) -> ndarray``: its output along the sampled input ``v``
    from rest, computed by its C twin (``prm`` defaults to the operator's parameter values).

    Parameters
    ----------
    operators : sequence of MemoryOperator
        The operators to compile.
    cc : str, optional
        The C compiler (default ``$CC``, else ``cc``).

    Returns
    -------
    list of callable
        One ``run`` per operator, in order.

    Raises
    ------
    ModelError
        An operator has no C source, or the compiler refuses it (naming the operator).
    UsageError
        No C compiler.
    """
    sources = []
    for op in operators:
        src = op.c_source()
        if src is None:
            raise ModelError(f"memory operator {type(op).__qualname__} (kind '{op.kind}') has no C source")
        sources.append(src)
    names = [type(op).__qualname__ for op in operators]
    lines = ["#include <math.h>", '#define BG_EXPORT __attribute__((visibility("default")))', ""]
    lines += helpers(sources, names)
    for k, (name, src) in enumerate(zip(names, sources)):
        lines += operator_functions(k, name, src)
        lines += [
            f"BG_EXPORT void run{k}(const double *v, long n, double *mem, int n_mem, const double *prm, int n_prm,"
            " double *y)",
            "{",
            f"    op{k}_initial(v[0], mem, n_mem, prm, n_prm);",
            "    for (long i = 0; i < n; i++) {",
            f"        y[i] = op{k}_output(v[i], mem, n_mem, prm, n_prm);",
            f"        op{k}_commit(v[i], mem, n_mem, prm, n_prm);",
            "    }",
            "}",
        ]
    cc = find_compiler(cc)
    with tempfile.TemporaryDirectory(prefix="bondgraph-ops-") as tmp:
        (Path(tmp) / "ops.c").write_text("\n".join(lines) + "\n")
        lib_path = Path(tmp) / "ops.so"
        error = build_shared(cc, Path(tmp), ["ops.c"], lib_path)
        if error is not None:
            raise ModelError(f"the C compiler refused the C source of the operators {', '.join(names)}: {error}")
        lib = ctypes.CDLL(str(lib_path))  # loaded before the directory goes: the mapping stays
    return [_runner(getattr(lib, f"run{k}"), op) for k, op in enumerate(operators)]


def _runner(fn, op: MemoryOperator) -> Callable:
    dp = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [dp, ctypes.c_long, dp, ctypes.c_int, dp, ctypes.c_int, dp]
    fn.restype = None

    def run(v, prm=None) -> np.ndarray:
        v = np.ascontiguousarray(v, dtype=np.float64)
        prm = np.ascontiguousarray(op.parameter_values() if prm is None else prm, dtype=np.float64)
        mem = np.zeros(max(op.n_memory, 1))
        y = np.empty_like(v)
        args = [a.ctypes.data_as(dp) for a in (v, mem, prm, y)]
        fn(args[0], v.size, args[1], op.n_memory, args[2], prm.size, args[3])
        return y

    run._keep = fn  # the library stays loaded while a runner lives
    return run
