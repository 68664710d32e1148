"""A compiled interpreter for large straight-line programs (no per-model compilation).

Numba spends milliseconds per generated statement, so a model with thousands of statements
(an N-layer stack, a long chain) would take minutes to compile.  For those, the program is
translated into a *tape*: a flat list of register operations that one interpreter, compiled
once and cached, executes.  The tape is the model's ``aux`` array in the calling convention of
:mod:`bondgraph.numerics.model_functions` (a private copy per run: the registers are written).

Tape layout in ``aux`` (all float64):
``[n_rhs_ops, rhs_offset, n_out_ops, out_offset, n_states, n_outputs, reg_offset, 0]``
then the op rows ``(code, dst, a, b, c)``, then the registers.
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp
from numba import njit

from ..equations.system import Equations
from .jacobian import RightSign
from .model_functions import SIGNATURE

HEADER = 8
(
    CONST,
    LDX,
    LDU,
    LDDU,
    LDTH,
    ADD,
    MUL,
    DIV,
    NEG,
    POWC,
    POW,
    SIN,
    COS,
    EXP,
    LOG,
    SQRT,
    ABS,
    SIGN,
    TANH,
    RSIGN,
    STORE,
) = range(21)
_FUNCS = {
    sp.sin: SIN,
    sp.cos: COS,
    sp.exp: EXP,
    sp.log: LOG,
    sp.Abs: ABS,
    sp.sign: SIGN,
    sp.tanh: TANH,
    RightSign: RSIGN,
}


class TapeUnsupported(Exception):
    """The program uses something the tape cannot express (then numba compiles it)."""


class _Builder:
    def __init__(self, eqs: Equations):
        self.ops: list[tuple] = []
        self.reg: dict = {}
        self.n_regs = 0
        xs = {s: i for i, s in enumerate(eqs.state_symbols)}
        us = {s: i for i, s in enumerate(eqs.inputs)}
        dus = {s: i for i, s in enumerate(eqs.input_rates)}
        ths = {s: i for i, s in enumerate(eqs.params)}
        self.leaf = {
            **{s: (LDX, i) for s, i in xs.items()},
            **{s: (LDU, i) for s, i in us.items()},
            **{s: (LDDU, i) for s, i in dus.items()},
            **{s: (LDTH, i) for s, i in ths.items()},
        }

    def new(self) -> int:
        self.n_regs += 1
        return self.n_regs - 1

    def emit(self, code, a=0, b=0, c=0.0) -> int:
        dst = self.new()
        self.ops.append((code, dst, a, b, c))
        return dst

    def expr(self, e) -> int:
        if e in self.reg:
            return self.reg[e]
        if e.is_Number:
            r = self.emit(CONST, c=float(e))
        elif e.is_Symbol:
            if e not in self.leaf:
                raise TapeUnsupported(f"symbol {e}")
            code, i = self.leaf[e]
            r = self.emit(code, a=i)
        elif e.is_Add or e.is_Mul:
            code = ADD if e.is_Add else MUL
            args = [self.expr(a) for a in e.args]
            r = args[0]
            for a in args[1:]:
                r = self.emit(code, r, a)
        elif e.is_Pow:
            base = self.expr(e.base)
            if e.exp.is_Number:
                r = (
                    self.emit(POWC, base, c=float(e.exp))
                    if e.exp != -1
                    else self.emit(DIV, self.expr(sp.Integer(1)), base)
                )
            else:
                r = self.emit(POW, base, self.expr(e.exp))
        elif e.func in _FUNCS and len(e.args) == 1:
            r = self.emit(_FUNCS[e.func], self.expr(e.args[0]))
        else:
            raise TapeUnsupported(type(e).__name__)
        self.reg[e] = r
        return r

    def store(self, i: int, e) -> None:
        self.ops.append((STORE, i, self.expr(e), 0, 0.0))


def build_tape(eqs: Equations, roots: tuple[list, list] | None = None) -> np.ndarray:
    """The tape of ``eqs`` (see the module docstring); TapeUnsupported if it cannot be built.

    ``roots``: the expressions of the two sections instead of the rates and the outputs (the
    tape's ``rhs`` then writes the first, ``output`` the second).

    Parameters
    ----------
    eqs : Equations
        The derived model.
    roots : tuple of (list, list), optional
        The expressions of the two sections.

    Returns
    -------
    numpy.ndarray
        The tape (the ``aux`` array of the tape interpreter).

    Raises
    ------
    TapeUnsupported
        The model has memory operators, or an expression the tape cannot hold.
    """
    if eqs.operators:
        raise TapeUnsupported("memory operators")
    if roots is None:
        roots = ([eqs.rates[s] for s in eqs.state_symbols], list(eqs.outputs.values()))
    sections = []
    for section in roots:
        b = _Builder(eqs)
        for st in eqs.needed(section)[0]:
            b.reg[st.var] = b.expr(st.expr)
        for i, r in enumerate(section):
            b.store(i, r)
        sections.append((np.array(b.ops, float).reshape(-1, 5), b.n_regs))
    (rhs_ops, rhs_regs), (out_ops, out_regs) = sections
    rhs_off = HEADER
    out_off = rhs_off + rhs_ops.size
    reg_off = out_off + out_ops.size
    tape = np.zeros(reg_off + max(rhs_regs, out_regs, 1))
    tape[:HEADER] = [len(rhs_ops), rhs_off, len(out_ops), out_off, len(roots[0]), len(roots[1]), reg_off, 0]
    tape[rhs_off:out_off] = rhs_ops.ravel()
    tape[out_off:reg_off] = out_ops.ravel()
    return tape


@njit(cache=True)
def _run(n_ops, off, x, u, du, th, tape, out):
    reg = int(tape[6])
    for k in range(n_ops):
        base = off + 5 * k
        code = int(tape[base])
        dst = reg + int(tape[base + 1])
        a = int(tape[base + 2])
        b = int(tape[base + 3])
        if code == CONST:
            tape[dst] = tape[base + 4]
        elif code == LDX:
            tape[dst] = x[a]
        elif code == LDU:
            tape[dst] = u[a]
        elif code == LDDU:
            tape[dst] = du[a]
        elif code == LDTH:
            tape[dst] = th[a]
        elif code == ADD:
            tape[dst] = tape[reg + a] + tape[reg + b]
        elif code == MUL:
            tape[dst] = tape[reg + a] * tape[reg + b]
        elif code == DIV:
            tape[dst] = tape[reg + a] / tape[reg + b]
        elif code == NEG:
            tape[dst] = -tape[reg + a]
        elif code == POWC:
            c = tape[base + 4]
            v = tape[reg + a]
            if c == 2.0:
                tape[dst] = v * v
            else:
                tape[dst] = v**c
        elif code == POW:
            tape[dst] = tape[reg + a] ** tape[reg + b]
        elif code == SIN:
            tape[dst] = math.sin(tape[reg + a])
        elif code == COS:
            tape[dst] = math.cos(tape[reg + a])
        elif code == EXP:
            tape[dst] = math.exp(tape[reg + a])
        elif code == LOG:
            tape[dst] = math.log(tape[reg + a])
        elif code == SQRT:
            tape[dst] = math.sqrt(tape[reg + a])
        elif code == ABS:
            tape[dst] = abs(tape[reg + a])
        elif code == SIGN:
            v = tape[reg + a]
            tape[dst] = 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)
        elif code == TANH:
            tape[dst] = math.tanh(tape[reg + a])
        elif code == RSIGN:
            tape[dst] = 1.0 if tape[reg + a] >= 0.0 else -1.0
        else:  # STORE: out[index] = register a
            out[int(tape[base + 1])] = tape[reg + a]


@njit(SIGNATURE, cache=True)
def rhs(t, x, u, du, th, mem, aux, out):
    _run(int(aux[0]), int(aux[1]), x, u, du, th, aux, out)


@njit(SIGNATURE, cache=True)
def output(t, x, u, du, th, mem, aux, out):
    _run(int(aux[2]), int(aux[3]), x, u, du, th, aux, out)


@njit(SIGNATURE, cache=True)
def nothing(t, x, u, du, th, mem, aux, out):
    """opin/commit of a model without memory operators."""
    return
