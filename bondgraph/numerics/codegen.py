"""Compile a straight-line program to numba-compiled numeric functions.

The generated functions follow the calling convention of :mod:`bondgraph.numerics.model_functions`
(``rhs``, ``output``, ``opin``, ``commit`` and, on demand, ``jac``: the local partials of the
sparse Jacobian program of :mod:`bondgraph.numerics.jacobian`).  Memory operators are
called through their compiled kernels (:meth:`MemoryOperator.kernels`), which the generated
module receives as globals before it is compiled; a fingerprint of the kernels' code is part
of the source, so changed kernels make a new module.

The source is written to a cache directory named by its hash and compiled by numba with
``cache=True``: a second run of the same model structure loads machine code from disk.
No sympy is evaluated when the functions run.  Programs longer than the setting
``codegen.tape_threshold`` run on the tape interpreter (:mod:`bondgraph.numerics.tape`) instead.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, NamedTuple

import numpy as np
import sympy as sp
from sympy.printing.pycode import PythonCodePrinter

from ..equations.system import Equations
from ..support import config
from ..support.progress import waiting
from .jacobian import JacobianProgram, slope_symbol
from .model_functions import ARGUMENTS, SIGNATURE, ModelFunctions

_NO_AUX = np.zeros(1)


def cache_dir() -> Path:
    """Directory of generated model code: $BONDGRAPH_CACHE or ~/.cache/bondgraph.

    Returns
    -------
    pathlib.Path
        The directory, created if missing (``$XDG_CACHE_HOME/bondgraph`` when that is set).
    """
    base = os.environ.get("BONDGRAPH_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "bondgraph"
    )
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

    def _print_RightSign(self, expr):
        a = self._print(expr.args[0])
        return f"(1.0 if {a} >= 0.0 else -1.0)"

    def _print_Heaviside(self, expr):
        a = self._print(expr.args[0])
        return f"(1.0 if {a} > 0.0 else (0.0 if {a} < 0.0 else 0.5))"


@dataclass
class Layout:
    """Where every symbol lives in the compiled functions' arrays.

    Parameters
    ----------
    names : dict
        Symbol → its slot in generated code (``x[i]``, ``u[i]``, ``du[i]``, ``th[i]``, ``vK``).
    mem_slices : list of tuple of int
        Per memory operator, its (start, stop) in ``mem``.
    prm_slices : list of tuple of int
        Per memory operator, its parameters' (start, stop) in θ.
    n_mem : int
        Length of the memory vector.
    """

    names: dict
    mem_slices: list[tuple[int, int]]
    prm_slices: list[tuple[int, int]]
    n_mem: int


def layout(eqs: Equations) -> Layout:
    """The array layout of ``eqs``'s compiled functions.

    Parameters
    ----------
    eqs : Equations
        The derived model.

    Returns
    -------
    Layout
        The slots of every symbol and the operators' memory and parameter slices.

    Raises
    ------
    RuntimeError
        An operator's parameters are not contiguous in θ (a derivation error).
    """
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


def generate_source(eqs: Equations, jacobian: JacobianProgram | None = None) -> str:
    """Python source of the compiled functions (see the module docstring); with ``jacobian``,
    of ``jac`` alone: the values of its local partials (:mod:`bondgraph.numerics.jacobian`).

    Parameters
    ----------
    eqs : Equations
        The derived model.
    jacobian : JacobianProgram, optional
        Generate the Jacobian's partials instead of the model's functions.

    Returns
    -------
    str
        The module's Python source (numba-compiled functions).
    """
    lay = layout(eqs)
    names = dict(lay.names)
    if jacobian is not None:
        names.update({slope_symbol(k): f"_slope{k}" for k in jacobian.slopes})
    pr = _Printer(names)
    op_index = {ob.symbol: k for k, ob in enumerate(eqs.operators)}
    op_input = {op_index[st.var]: st.expr for st in eqs.program if st.op is not None}
    lines = ["import math", "import numpy as np", "from numba import njit", "", f"SIG = {SIGNATURE!r}", ""]
    for k, ob in enumerate(eqs.operators):
        kind = type(ob.operator)
        lines.append(
            f"# op{k}_output, op{k}_commit: kernels of {kind.__module__}.{kind.__qualname__} "
            f"(code {ob.operator.kernels().fingerprint})"
        )
    signature = ", ".join(ARGUMENTS)

    def function(name: str, targets: list[sp.Expr], extra: list[str] | None = None, slopes=()) -> list[str]:
        src = ["", "@njit(SIG, cache=True)", f"def {name}({signature}):"]
        inputs = [op_input[k] for k in slopes]
        for st in eqs.needed([*targets, *inputs])[0]:
            if st.op is not None:
                j = op_index[st.var]
                (a, b), (c, d) = lay.mem_slices[j], lay.prm_slices[j]
                src.append(f"    {names[st.var]} = op{j}_output({pr.doprint(st.expr)}, mem[{a}:{b}], th[{c}:{d}])")
            else:
                src.append(f"    {names[st.var]} = {pr.doprint(st.expr)}")
        for k in slopes:  # the right difference quotient of the operator's output at frozen memory
            (a, b), (c, d) = lay.mem_slices[k], lay.prm_slices[k]
            scale = f"max(abs(_v), np.max(np.abs(mem[{a}:{b}])))" if b > a else "abs(_v)"
            src += [
                f"    _v = {pr.doprint(op_input[k])}",
                f"    _d = {2.0**-26!r} * {scale}",
                f"    _d = (_d if _d > 0.0 else 1e-12) * aux[{k}]",
                f"    _slope{k} = (op{k}_output(_v + _d, mem[{a}:{b}], th[{c}:{d}]) - "
                f"op{k}_output(_v, mem[{a}:{b}], th[{c}:{d}])) / _d",
            ]
        src += [f"    out[{i}] = {pr.doprint(e)}" for i, e in enumerate(targets)]
        src += extra or []
        src.append("    return")
        return src

    if jacobian is not None:
        return "\n".join(lines + function("jac", jacobian.partials, slopes=jacobian.slopes)) + "\n"
    rates = [eqs.rates[s] for s in eqs.state_symbols]
    opins = [st.expr for st in eqs.program if st.op is not None]
    lines += function("rhs", rates)
    lines += function("output", list(eqs.outputs.values()))
    lines += function("opin", opins)
    commits = []
    for j, _ in enumerate(eqs.operators):
        (a, b), (c, d) = lay.mem_slices[j], lay.prm_slices[j]
        commits.append(f"    op{j}_commit(out[{j}], mem[{a}:{b}], th[{c}:{d}])")
    lines += function("commit", opins, commits)
    return "\n".join(lines) + "\n"


def compile_equations(eqs: Equations) -> ModelFunctions:
    """The numeric functions of ``eqs``: generated, cached and compiled by numba, or for long
    programs (more statements than ``codegen.tape_threshold``) the tape interpreter.

    Parameters
    ----------
    eqs : Equations
        The derived model.

    Returns
    -------
    ModelFunctions
        ``rhs``, ``output``, ``opin``, ``commit``, the layout and the route taken.
    """
    if len(eqs.program) > config.get("codegen.tape_threshold"):
        with waiting("compiling the tape interpreter", status="the first run only: numba keeps it for later runs"):
            from . import tape

        try:
            program = tape.build_tape(eqs)
        except tape.TapeUnsupported:
            pass
        else:
            return ModelFunctions(tape.rhs, tape.output, tape.nothing, tape.nothing, layout(eqs), program, route="tape")
    src = generate_source(eqs)
    module = _load(eqs, src)
    return ModelFunctions(
        module.rhs, module.output, module.opin, module.commit, layout(eqs), _NO_AUX, module.__file__, "numba"
    )


class CompiledJacobian(NamedTuple):
    """``jac(t, x, u, du, th, mem, aux, out)`` writing the local partials of a
    :class:`~bondgraph.numerics.jacobian.JacobianProgram`, its ``aux`` and its route.

    On the numba route ``aux[k]`` is the direction (+1 or −1) in which memory operator ``k``'s
    slope is taken: the direction its input last moved (the integrator keeps it up to date).

    Parameters
    ----------
    jac : callable
        The compiled function.
    aux : numpy.ndarray
        Its auxiliary data.
    route : {"numba", "tape"}
        How it was compiled.
    """

    jac: Callable
    aux: np.ndarray
    route: str


def compile_jacobian(eqs: Equations, jacobian: JacobianProgram) -> CompiledJacobian:
    """The partials of ``jacobian`` compiled like :func:`compile_equations` compiles a model
    (the tape when the statements they need and the partials outnumber ``codegen.tape_threshold``).

    Parameters
    ----------
    eqs : Equations
        The derived model.
    jacobian : JacobianProgram
        The sparse Jacobian program.

    Returns
    -------
    CompiledJacobian
        The compiled partials.
    """
    if len(eqs.needed(jacobian.partials)[0]) + len(jacobian.partials) > config.get("codegen.tape_threshold"):
        from . import tape

        try:
            return CompiledJacobian(tape.rhs, tape.build_tape(eqs, (jacobian.partials, [])), "tape")
        except tape.TapeUnsupported:
            pass
    directions = np.ones(max(len(eqs.operators), 1))
    return CompiledJacobian(_load(eqs, generate_source(eqs, jacobian)).jac, directions, "numba")


def _load(eqs: Equations, src: str):
    """The generated module of ``src``, from the cache directory (written there first if new)."""
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
        for k, ob in enumerate(eqs.operators):  # the kernels the source calls, before it compiles
            kernels = ob.operator.kernels()
            setattr(module, f"op{k}_output", kernels.output)
            setattr(module, f"op{k}_commit", kernels.commit)
        sys.modules[modname] = module  # numba finds the module's globals through sys.modules
        try:
            with waiting(
                f"compiling {eqs.model.name}",
                status=f"{len(eqs.program)} statements; kept in {cache_dir()} for later runs of this structure",
            ):
                spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[modname]
            raise
    return module


def parameter_vector(eqs: Equations) -> np.ndarray:
    """θ in the order of ``eqs.params`` from the model's parameter values.

    Parameters
    ----------
    eqs : Equations
        The derived model.

    Returns
    -------
    numpy.ndarray
        θ, each parameter in its SI unit.
    """
    table = eqs.model.parameter_table()
    return np.array([float(table[p]) for p in eqs.params], float)
