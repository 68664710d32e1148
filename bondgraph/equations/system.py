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

    Built by :func:`~bondgraph.equations.derivation.derive`; the fields are also the
    attributes of the same names.  Efforts and flows follow the power-in convention: the
    power ``e * f`` of a bond is positive when it flows from the half-arrow's tail to its head.

    Parameters
    ----------
    model : Model
        The model the equations were derived from.
    causality : Causality
        Its causal assignment.
    states : list of State
        The state variables: displacements q, momenta p, internal states z, sensor
        integrals x, each with its origin and initial value.
    inputs : list of sympy.Symbol
        The model's inputs (source efforts or flows, e.g. a voltage in V).
    input_rates : list of sympy.Symbol
        The symbols ``du/dt`` of the input derivatives the equations use (in the input's
        unit per s).
    params : list of sympy.Symbol
        The parameters, in SI units.
    program : list of Statement
        The straight-line program ``var = expr`` in topological order; operator outputs
        appear as calls ``h = H[v]``.
    rates : dict of sympy.Symbol to sympy.Expr
        ``rates[state]`` is the state's time derivative, an expression of program
        variables, states, inputs, input rates and parameters.
    outputs : dict of str to sympy.Expr
        The named outputs, expressions of the same symbols.
    operators : list of OperatorBlock
        The memory operators (hysteresis, friction) the program calls.
    eliminated : list of str, optional
        One line per storage element in derivative causality whose state was eliminated,
        for printing.
    loops : list of str, optional
        One line per algebraic loop solved symbolically during derivation, for printing.
    bond_vars : dict of int to tuple of (sympy.Symbol, sympy.Symbol), optional
        Bond number -> its (effort, flow) program variables.
    units : UnitReport, optional
        The unit check's result, ``None`` when not checked.
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
        """The states' symbols, in state order (the order of the state vector x)."""
        return [s.symbol for s in self.states]

    def program_values(self, roots=None) -> dict:
        """Every program variable as an expression of states, inputs and parameters.

        Parameters
        ----------
        roots : iterable of sympy.Expr, optional
            Only the variables these expressions depend on; all by default.

        Returns
        -------
        dict of sympy.Symbol to sympy.Expr
            Program variable -> its expression, operator outputs kept as symbols.
        """
        full: dict = {}
        for st in self.program if roots is None else self.needed(roots)[0]:
            if st.op is None:
                full[st.var] = st.expr.xreplace(full)
        return full

    def substituted(self, exprs: dict) -> dict:
        """``exprs`` with every program variable substituted.

        Parameters
        ----------
        exprs : dict
            Values are sympy expressions of program variables, states, inputs and parameters.

        Returns
        -------
        dict
            The same keys, each expression with the program substituted (operator outputs
            kept as symbols).
        """
        full = self.program_values()
        return {k: v.xreplace(full) for k, v in exprs.items()}

    def needed(self, roots) -> tuple[list[Statement], set]:
        """The program statements ``roots`` depend on (the framework's one backward
        dependency walk).

        Parameters
        ----------
        roots : iterable of sympy.Expr
            The expressions whose dependencies are wanted.

        Returns
        -------
        statements : list of Statement
            The statements the roots depend on, in program order.
        symbols : set of sympy.Symbol
            Every symbol the roots reach through them.
        """
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
        """The state equations x' = f(x, u, θ), fully substituted.

        Returns
        -------
        dict of sympy.Symbol to sympy.Expr
            State -> its time derivative (units of the state per s), operator outputs kept
            as symbols.
        """
        return self.substituted(self.rates)

    def output_equations(self) -> dict[str, sp.Expr]:
        """The outputs y = g(x, u, θ), fully substituted.

        Returns
        -------
        dict of str to sympy.Expr
            Output name -> its expression, operator outputs kept as symbols.
        """
        return self.substituted(self.outputs)

    def operator_inputs(self) -> dict[sp.Symbol, sp.Expr]:
        """What each memory operator is driven by, fully substituted.

        Returns
        -------
        dict of sympy.Symbol to sympy.Expr
            Operator output h (of ``h = H[v]``) -> its input v as an expression of states,
            inputs and parameters.
        """
        return self.substituted({st.var: st.expr for st in self.program if st.op is not None})

    def jacobian(
        self, roots: list[sp.Expr], wrt: list[sp.Symbol], op_gains: dict | None = None, inline: bool = True
    ) -> sp.Matrix:
        """∂roots/∂wrt by forward differentiation through the program (sparse, linear cost).

        An operator output h = H[v] gets slope ``op_gains[h]`` (0 if not given: frozen memory).
        Entries of nonlinear laws hold program variables; ``inline`` substitutes them (for
        generated code, which computes the program anyway, pass False).

        Parameters
        ----------
        roots : list of sympy.Expr
            The expressions to differentiate (rows).
        wrt : list of sympy.Symbol
            The symbols to differentiate with respect to (columns).
        op_gains : dict of sympy.Symbol to sympy.Expr, optional
            Operator output -> its small-signal slope dh/dv; outputs not listed get 0.
        inline : bool, optional
            Substitute program variables in the entries (True by default).

        Returns
        -------
        sympy.Matrix
            ``len(roots)`` x ``len(wrt)``, entry (i, j) = ∂roots[i]/∂wrt[j].
        """
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
