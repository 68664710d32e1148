"""Explicit state equations of a causal bond graph: the records.

:func:`~bondgraph.equations.derivation.derive` turns a model with its causality into
:class:`Equations`: a *straight-line program* ``v1 = ...; v2 = ...`` in topological order whose
intermediate names are kept (so derivation stays linear in the graph size), the state rates and
outputs as expressions of program variables, states, inputs and parameters.  Full substitution
into x' = f(x, u, θ) is done only on request (printouts, linearisation).  Operator outputs
(memory elements) appear in the program as calls ``h = H[v]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from ..model.graph import Model, OperatorBlock
from .causality import Causality
from .units import UnitReport


@dataclass
class State:
    """A state variable: symbol, kind (q, p, z for internal, x for sensor integrals), origin, x0."""

    symbol: sp.Symbol
    kind: str
    origin: str
    x0: sp.Expr


@dataclass
class Statement:
    """``var = expr``; for operator calls ``op`` is the block and ``expr`` its input."""

    var: sp.Symbol
    expr: sp.Expr
    origin: str
    op: OperatorBlock | None = None


@dataclass
class Equations:
    """Explicit state-space form of a model as a straight-line program.

    ``program`` is topologically ordered; ``rates[state]`` and ``outputs[name]`` are
    expressions of program variables, states, inputs, input derivatives and parameters.
    """

    model: Model
    causality: Causality
    states: list[State]
    inputs: list[sp.Symbol]
    input_rates: list[sp.Symbol]
    params: list[sp.Symbol]
    program: list[Statement]
    rates: dict[sp.Symbol, sp.Expr]
    outputs: dict[str, sp.Expr]
    operators: list[OperatorBlock]
    eliminated: list[str] = field(default_factory=list)
    loops: list[str] = field(default_factory=list)
    bond_vars: dict[int, tuple[sp.Symbol, sp.Symbol]] = field(default_factory=dict)
    #: the unit check's result (:class:`~bondgraph.equations.units.UnitReport`), None when not checked
    units: UnitReport | None = None

    @property
    def state_symbols(self) -> list[sp.Symbol]:
        return [s.symbol for s in self.states]

    def program_values(self, roots=None) -> dict:
        """Every program variable (or those ``roots`` depend on) as an expression of states,
        inputs and parameters (operator outputs kept as symbols)."""
        full: dict = {}
        for st in self.program if roots is None else self.needed(roots)[0]:
            if st.op is None:
                full[st.var] = st.expr.xreplace(full)
        return full

    def substituted(self, exprs: dict) -> dict:
        """``exprs`` with every program variable substituted (operator outputs kept as symbols)."""
        full = self.program_values()
        return {k: v.xreplace(full) for k, v in exprs.items()}

    def needed(self, roots) -> tuple[list[Statement], set]:
        """The program statements ``roots`` depend on, in program order, and every symbol the
        roots reach through them (the one backward dependency walk of the framework)."""
        need = set().union(set(), *(r.free_symbols for r in roots))
        keep = []
        for st in reversed(self.program):
            if st.var in need:
                need |= st.expr.free_symbols
                keep.append(st)
        return keep[::-1], need

    def _repr_latex_(self) -> str:
        """The state equations as an engineer writes them (notebook display)."""
        from .printing import latex_display

        return latex_display(self)

    def state_equations(self) -> dict[sp.Symbol, sp.Expr]:
        """x' = f(x, u, θ) fully substituted."""
        return self.substituted(self.rates)

    def output_equations(self) -> dict[str, sp.Expr]:
        return self.substituted(self.outputs)

    def operator_inputs(self) -> dict[sp.Symbol, sp.Expr]:
        return self.substituted({st.var: st.expr for st in self.program if st.op is not None})

    def jacobian(
        self, roots: list[sp.Expr], wrt: list[sp.Symbol], op_gains: dict | None = None, inline: bool = True
    ) -> sp.Matrix:
        """∂roots/∂wrt by forward differentiation through the program (sparse, linear cost).

        An operator output h = H[v] gets slope ``op_gains[h]`` (0 if not given: frozen memory).
        Entries of nonlinear laws hold program variables; ``inline`` substitutes them (for
        generated code, which computes the program anyway, pass False)."""
        wrt_set = set(wrt)
        grad: dict = {}
        for st in self.program:
            g = _grad(st.expr, grad, wrt_set)
            if st.op is not None:
                gain = (op_gains or {}).get(st.var, 0)
                g = {s: gain * d for s, d in g.items()} if gain else {}
            grad[st.var] = g
        rows = []
        for r in roots:
            g = _grad(r, grad, wrt_set)
            rows.append([g.get(w, sp.Integer(0)) for w in wrt])
        J = sp.Matrix(rows) if rows else sp.zeros(0, len(wrt))
        if inline and any(e.free_symbols & grad.keys() for e in J):
            J = J.xreplace(self.program_values(list(J)))
        return J


def _grad(expr: sp.Expr, grad: dict, wrt_set: set) -> dict:
    g: dict = {}
    for s in expr.free_symbols:
        if s in grad:
            if not grad[s]:
                continue
            d = sp.diff(expr, s)
            for w, dw in grad[s].items():
                g[w] = g.get(w, 0) + d * dw
        elif s in wrt_set:
            g[s] = g.get(s, 0) + sp.diff(expr, s)
    return g
