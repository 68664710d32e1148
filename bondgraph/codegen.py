"""Compile a straight-line program to numba-compiled numeric functions.

Generated functions share one signature ``f(t, x, u, du, th, mem, out)`` (float64 scalar
and contiguous float64 arrays) so one compiled integrator serves every model:

* ``rhs``    out = dx/dt
* ``output`` out = named outputs
* ``opin``   out = inputs of the memory operators (for step-reversal checks)
* ``commit`` advance the operators' memory to the current input (accepted steps only)
* ``jac``    out = ∂(dx/dt)/∂x, row-major (generated on demand for implicit solvers)

The source is written to a cache directory named by its hash and compiled by numba with
``cache=True``: a second run of the same model structure loads machine code from disk.
No sympy is evaluated when the functions run.
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from .equations import Equations

SIGNATURE = "void(float64, float64[::1], float64[::1], float64[::1], float64[::1], float64[::1], float64[::1])"
FUNCTIONS = ("rhs", "output", "opin", "commit")


def cache_dir() -> Path:
    """Directory of generated model code: $BONDGRAPH_CACHE or ~/.cache/bondgraph."""
    base = os.environ.get("BONDGRAPH_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "bondgraph")
    path = Path(base)
    path.mkdir(parents=True, exist_ok=True)
    return path


class _Printer(PythonCodePrinter):
    """Python/numba code for scalar sympy expressions, with symbols mapped to array slots."""

    def __init__(self, names: dict):
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})
        self.names = names

    def _print_Symbol(self, expr):
        try:
            return self.names[expr]
        except KeyError:
            raise KeyError(f"symbol {expr} has no value in the generated code") from None

    _print_Dummy = _print_Symbol

    def _print_sign(self, expr):
        a = self._print(expr.args[0])
        return f"(math.copysign(1.0, {a}) if {a} != 0.0 else 0.0)"

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Rational(self, expr):
        return repr(float(expr))

    def _print_Heaviside(self, expr):
        a = self._print(expr.args[0])
        return f"(1.0 if {a} > 0.0 else (0.0 if {a} < 0.0 else 0.5))"


@dataclass
class Layout:
    """Where every symbol lives in the compiled functions' arrays."""

    names: dict
    mem_slices: list[tuple[int, int]]
    prm_slices: list[tuple[int, int]]
    n_mem: int


def layout(eqs: Equations) -> Layout:
    names: dict = {}
    for i, s in enumerate(eqs.state_symbols):
        names[s] = f"x[{i}]"
    for i, (u, du) in enumerate(zip(eqs.inputs, eqs.input_rates)):
        names[u] = f"u[{i}]"
        names[du] = f"du[{i}]"
    pindex = {p: i for i, p in enumerate(eqs.params)}
    for p, i in pindex.items():
        names[p] = f"th[{i}]"
    for k, st in enumerate(eqs.program):
        names[st.var] = f"v{k}"
    mem_slices, prm_slices, pos = [], [], 0
    for ob in eqs.operators:
        prm = [pindex[s] for s in ob.params]
        if prm and prm != list(range(prm[0], prm[0] + len(prm))):
            raise RuntimeError(f"parameters of operator {ob.symbol} are not contiguous")
        prm_slices.append((prm[0], prm[0] + len(prm)) if prm else (0, 0))
        n = ob.operator.n_memory
        mem_slices.append((pos, pos + n))
        pos += n
    return Layout(names, mem_slices, prm_slices, pos)


def generate_source(eqs: Equations, with_jacobian: bool = False) -> str:
    """Python source of the compiled functions (see the module docstring)."""
    lay = layout(eqs)
    pr = _Printer(lay.names)
    op_index = {ob.symbol: k for k, ob in enumerate(eqs.operators)}
    lines = ["import math", "import numpy as np", "from numba import njit", "",
             f"SIG = {SIGNATURE!r}", ""]
    for k, ob in enumerate(eqs.operators):
        lines += [ob.operator.kernel_source(f"op{k}"), "",
                  f"op{k}_output = njit(cache=True)(op{k}_output)",
                  f"op{k}_commit = njit(cache=True)(op{k}_commit)", ""]

    def body(roots: list[sp.Expr]) -> list[str]:
        need = set()
        for r in roots:
            need |= r.free_symbols
        stmts = []
        for k in range(len(eqs.program) - 1, -1, -1):
            st = eqs.program[k]
            if st.var in need:
                need |= st.expr.free_symbols
                stmts.append(k)
        out = []
        for k in reversed(stmts):
            st = eqs.program[k]
            if st.op is not None:
                j = op_index[st.var]
                (a, b), (c, d) = lay.mem_slices[j], lay.prm_slices[j]
                out.append(f"    v{k} = op{j}_output({pr.doprint(st.expr)}, mem[{a}:{b}], th[{c}:{d}])")
            else:
                out.append(f"    v{k} = {pr.doprint(st.expr)}")
        return out

    def function(name: str, targets: list[sp.Expr], extra: list[str] | None = None) -> list[str]:
        src = ["@njit(SIG, cache=True)", f"def {name}(t, x, u, du, th, mem, out):"]
        src += body(targets)
        src += [f"    out[{i}] = {pr.doprint(e)}" for i, e in enumerate(targets)]
        src += extra or []
        src.append("    return")
        return src + [""]

    rates = [eqs.rates[s] for s in eqs.state_symbols]
    outputs = list(eqs.outputs.values())
    opins = [st.expr for st in eqs.program if st.op is not None]
    lines += function("rhs", rates)
    lines += function("output", outputs)
    lines += function("opin", opins)
    commits = []
    for j, _ in enumerate(eqs.operators):
        (a, b), (c, d) = lay.mem_slices[j], lay.prm_slices[j]
        commits.append(f"    op{j}_commit(out[{j}], mem[{a}:{b}], th[{c}:{d}])")
    lines += function("commit", opins, commits)
    if with_jacobian:
        xs = eqs.state_symbols
        lines += function("jac", list(eqs.jacobian([eqs.rates[s] for s in xs], xs)))
    return "\n".join(lines) + "\n"


@dataclass
class Compiled:
    """Compiled numeric functions of a model plus the layout of their arrays."""

    module: object
    layout: Layout
    source_path: Path

    def __getattr__(self, name):
        if name in FUNCTIONS or name == "jac":
            return getattr(self.module, name)
        raise AttributeError(name)


@dataclass
class Taped:
    """A large model run by the tape interpreter (see :mod:`bondgraph.tape`): the same function
    interface as :class:`Compiled`, with the tape as the initial ``mem``."""

    layout: Layout
    tape: np.ndarray

    def __getattr__(self, name):
        from . import tape
        if name in ("rhs", "output"):
            return getattr(tape, name)
        if name in ("opin", "commit"):
            return tape.nothing
        raise AttributeError(name)


#: programs longer than this run on the tape interpreter instead of being compiled by numba
TAPE_THRESHOLD = 300


def compile_equations(eqs: Equations, with_jacobian: bool = False) -> Compiled | Taped:
    """Generate, cache and load the compiled functions of ``eqs`` (large models: a tape)."""
    if len(eqs.program) > TAPE_THRESHOLD and not with_jacobian:
        from .tape import TapeUnsupported, build_tape
        try:
            tape = build_tape(eqs)
        except TapeUnsupported:
            pass
        else:
            lay = layout(eqs)
            lay.n_mem = tape.size
            return Taped(lay, tape)
    src = generate_source(eqs, with_jacobian)
    key = hashlib.sha256(src.encode()).hexdigest()[:20]
    path = cache_dir() / f"bg_{key}.py"
    if not path.exists() or path.read_text() != src:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(src)
        os.replace(tmp, path)
    modname = f"bondgraph_generated_{key}"
    module = sys.modules.get(modname)
    if module is None:
        spec = importlib.util.spec_from_file_location(modname, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[modname] = module
        spec.loader.exec_module(module)
    return Compiled(module, layout(eqs), path)


def parameter_vector(eqs: Equations) -> np.ndarray:
    """θ in the order of ``eqs.params`` from the model's parameter values."""
    table = eqs.model.parameter_table()
    return np.array([float(table[p]) for p in eqs.params], float)
