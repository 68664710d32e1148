"""Derivation of the state equations from a causal bond graph (see :func:`bondgraph.derive`).

After SCAP every bond variable is computed by exactly one element; each element writes its
constitutive relations through the :class:`~bondgraph.model.elements.EquationBuilder` protocol, which
:class:`Deriver` implements.  Those assignments form a directed graph over the bond variables,
states and inputs:

* strongly connected components are algebraic loops; linear ones are solved symbolically
  (small systems, only the loop's own variables), nonlinear ones are reported by element;
* storage ports in derivative causality are eliminated: their stored quantity is an
  algebraic function of the independent states, its time derivative is taken by the chain
  rule and the resulting linear system in the unknown port variables is solved (e.g. two
  masses rigidly coupled through a TF become one inertia m1 + n²·m2);
* a topological order of what remains is the straight-line program of :class:`Equations`.
"""

from __future__ import annotations

from collections import defaultdict

import networkx as nx
import sympy as sp

from ..model.elements import Port, sympify
from ..model.graph import Model, OperatorBlock, Quantity, input_rate_symbol
from ..support import config
from ..support.errors import CausalityError, ModelError
from .causality import Causality, assign_causality
from .system import Equations, State, Statement
from .units import UnitInput, UnitReport, check_units


def _is_cheap(expr: sp.Expr) -> bool:
    if expr.is_Atom:
        return True
    if expr.is_Mul and len(expr.args) == 2 and expr.args[0].is_Number and expr.args[1].is_Atom:
        return True
    return False


class Deriver:
    def __init__(self, model: Model, causality: Causality, units: bool | None = None):
        self.m = model
        self.c = causality
        self.check = config.get("units.check") if units is None else units
        self.assign_map: dict[sp.Symbol, sp.Expr] = {}
        self.origin: dict[sp.Symbol, str] = {}
        self.ops: dict[sp.Symbol, OperatorBlock] = {}
        self.states: list[State] = []
        self.rates: dict[sp.Symbol, sp.Expr] = {}
        self.dependent: list[tuple[sp.Symbol, sp.Expr, str]] = []  # (unknown w, stored quantity, element)
        self.quantity_map: dict = {}
        self.eliminated: list[str] = []
        self.loops: list[str] = []
        self._names: set[str] = set()

    # ---- naming ----------------------------------------------------------------------------
    def _unique(self, base: str) -> str:
        name, k = base, 2
        while name in self._names:
            name, k = f"{base}_{k}", k + 1
        self._names.add(name)
        return name

    def _bond_label(self, b) -> str:
        ends = [b.head, b.tail]
        for elem, port in ends:
            e = self.m.elements[elem]
            if e.ports:  # not a junction
                return elem if len(e.ports) == 1 else f"{elem}.{port}"
        return f"{b.tail[0]}_{b.head[0]}"

    # ---- main ------------------------------------------------------------------------------
    def run(self) -> Equations:
        m = self.m
        # generated names never collide with the user's (parameters, inputs, states, operators)
        self._names |= {str(s) for s in m.parameter_table()} | set(m.inputs) | set(m.internal_states) | set(m.operators)
        self.e, self.f = {}, {}
        for b in m.bonds:
            label = self._bond_label(b)
            self.e[b.index] = sp.Symbol(self._unique(f"e_{label}"), real=True)
            self.f[b.index] = sp.Symbol(self._unique(f"f_{label}"), real=True)
        self.ports = defaultdict(list)  # element -> [(port, bond, sign)]
        for b in m.bonds:
            self.ports[b.tail[0]].append((b.tail[1], b, -1))
            self.ports[b.head[0]].append((b.head[1], b, +1))
        for name, elem in m.elements.items():
            self._element(name, elem)
        for name, st in m.internal_states.items():
            self.states.append(State(st.symbol, "z", name, st.x0))
        self._resolve_quantities()
        for name, st in m.internal_states.items():
            self.rates[st.symbol] = self._q(st.rate)
        for name, ob in m.operators.items():
            ob_in = self._q(ob.input)
            self.assign(ob.symbol, ob_in, f"operator {name}")
            self.ops[ob.symbol] = ob
        outputs = {n: self._q(o.expr) for n, o in m.outputs.items()}
        units = self._check_units(outputs) if self.check else None
        self._solve_loops()
        if self.dependent:
            self._eliminate_dependent()
        program = self._order(list(self.rates.values()) + list(outputs.values()))
        program, rates, outputs = _collapse(program, self.rates, outputs)
        inputs = [i.symbol for i in m.inputs.values()]
        params = list(m.parameter_table())
        return Equations(
            m,
            self.c,
            self.states,
            inputs,
            [input_rate_symbol(u) for u in inputs],
            params,
            program,
            rates,
            outputs,
            list(self.ops.values()),
            self.eliminated,
            self.loops,
            {b.index: (self.e[b.index], self.f[b.index]) for b in m.bonds},
            units,
        )

    def _check_units(self, outputs: dict) -> UnitReport:
        """Dimensional analysis of the element relations as written (before loops and derivative
        causality are solved, so that a contradiction names the element that wrote it)."""
        return check_units(
            UnitInput(
                self.m,
                self.assign_map,
                self.origin,
                self.ops,
                self.states,
                self.rates,
                self.dependent,
                outputs,
                {b.index: (self.e[b.index], self.f[b.index]) for b in self.m.bonds},
            )
        )

    # ---- constitutive relations (the element protocol) ---------------------------------------
    def _element(self, name: str, elem):
        ports = {}
        for port, b, s in self.ports[name]:
            key = name if len(elem.ports) <= 1 else f"{name}.{port}"
            ports[port] = Port(
                port,
                key,
                self.e[b.index],
                self.f[b.index],
                s,
                self.c.sets_effort(b, (name, port)),
                key if elem.is_storage else name,
                self,
            )
        elem.equations(ports, self)
        for port in ports.values():
            self.quantity_map.setdefault(("e", port.key), port.e)
            self.quantity_map.setdefault(("f", port.key), port.f_in)

    # EquationBuilder (see bondgraph.model.elements.base): what elements may do in equations()
    @property
    def model_name(self) -> str:
        return self.m.name

    def assign(self, var: sp.Symbol, expr, origin: str) -> None:
        if var in self.assign_map:
            raise CausalityError(f"{self.m.name}: variable {var} is computed twice ({self.origin[var]}, {origin})")
        self.assign_map[var] = _expr(expr, origin, var)
        self.origin[var] = origin

    def symbol(self, base: str) -> sp.Symbol:
        return sp.Symbol(self._unique(base), real=True)

    def state(self, base: str, kind: str, x0, origin: str) -> sp.Symbol:
        sym = self.symbol(base)
        self.states.append(State(sym, kind, origin, _expr(x0, origin, "initial value")))
        return sym

    def rate(self, state: sp.Symbol, expr) -> None:
        self.rates[state] = _expr(expr, "rate", state)

    def derivative(self, base: str, stored, origin: str) -> sp.Symbol:
        w = self.symbol(base)
        self.dependent.append((w, _expr(stored, origin, "stored quantity"), origin))
        return w

    def quantity(self, what: str, key: str, expr) -> None:
        self.quantity_map[(what, key)] = expr

    # ---- port quantities in user expressions --------------------------------------------------
    def _resolve_quantities(self):
        syms = set()
        for st in self.m.internal_states.values():
            syms |= st.rate.free_symbols
        for ob in self.m.operators.values():
            syms |= ob.input.free_symbols
        for o in self.m.outputs.values():
            syms |= o.expr.free_symbols
        for el in self.m.elements.values():
            syms |= el.free_symbols()
        for q in sorted((s for s in syms if isinstance(s, Quantity)), key=str):
            self._quantity(q)
        # element laws may use port quantities too (e.g. modulated sources, feedback)
        for var, expr in list(self.assign_map.items()):
            if any(isinstance(s, Quantity) for s in expr.free_symbols):
                self.assign_map[var] = self._q(expr)
        for k, v in list(self.rates.items()):
            self.rates[k] = self._q(v)

    def _quantity(self, q: Quantity):
        key = (q.what, q.endpoint)
        if key in self.quantity_map:
            return self.quantity_map[key]
        elem_name = q.endpoint.split(".")[0] if q.endpoint not in self.m.elements else q.endpoint
        if q.what in ("e", "f"):
            raise ModelError(
                f"{self.m.name}: '{q.endpoint}' has no single {'effort' if q.what == 'e' else 'flow'}"
                f" (a {self.m.elements[elem_name].kind}); ask for one of its bonded elements instead"
            )
        # displacement / momentum of something that is not a storage port: integrate a sensor state
        rate_key = ("f" if q.what == "q" else "e", q.endpoint)
        if rate_key not in self.quantity_map:
            raise ModelError(
                f"{self.m.name}: cannot integrate the {'flow' if q.what == 'q' else 'effort'}"
                f" of '{q.endpoint}' (it has no single one)"
            )
        sym = sp.Symbol(self._unique(f"{'x' if q.what == 'q' else 'p'}_{q.endpoint}"), real=True)
        self.states.append(State(sym, "x", q.endpoint, sp.Integer(0)))
        self.rates[sym] = self.quantity_map[rate_key]
        self.quantity_map[key] = sym
        return sym

    def _q(self, expr: sp.Expr) -> sp.Expr:
        qs = {s: self._quantity(s) for s in expr.free_symbols if isinstance(s, Quantity)}
        return expr.xreplace(qs) if qs else expr

    # ---- algebraic loops ---------------------------------------------------------------------
    def _graph(self) -> nx.DiGraph:
        g = nx.DiGraph()
        g.add_nodes_from(self.assign_map)
        for var, expr in self.assign_map.items():
            for s in expr.free_symbols:
                if s in self.assign_map:
                    g.add_edge(s, var)
        return g

    def _solve_loops(self):
        """Solve each algebraic loop by tearing: pick a few tear variables that break every
        cycle, express the loop's other variables through them in causal order, and solve
        the small linear system of the tear residuals.  Only the tear variables get new
        assignments; the rest keep theirs, so the program stays compact (a star of N
        parallel resistors needs one tear variable and an O(N) expression)."""
        g = self._graph()
        for comp in nx.strongly_connected_components(g):
            if len(comp) == 1:
                v = next(iter(comp))
                if not g.has_edge(v, v):
                    continue
            names = sorted({self.origin[v] for v in comp})
            if any(v in self.ops for v in comp):
                raise CausalityError(
                    f"{self.m.name}: algebraic loop through a memory operator "
                    f"({', '.join(names)}); add a storage element in the loop"
                )
            tears = _tear_set(g.subgraph(comp))
            rest = nx.DiGraph(g.subgraph(comp - set(tears)))
            sub: dict = {}
            for v in nx.topological_sort(rest):
                sub[v] = self.assign_map[v].xreplace(sub)
            eqs = [t - self.assign_map[t].xreplace(sub) for t in tears]
            try:
                A, b = sp.linear_eq_to_matrix(eqs, tears)
            except (ValueError, sp.PolynomialError):
                raise CausalityError(
                    f"{self.m.name}: nonlinear algebraic loop through {', '.join(names)}; "
                    f"add a storage element (small C or I) to break it"
                ) from None
            try:
                sol = _solve_linear(A, b)
            except ZeroDivisionError:
                raise CausalityError(f"{self.m.name}: singular algebraic loop through {', '.join(names)}") from None
            for t, val in zip(tears, sol):
                self.assign_map[t] = val
            self.loops.append(
                f"algebraic loop through {', '.join(names)} ({len(comp)} variables, "
                f"torn at {', '.join(map(str, tears))}) solved symbolically"
            )

    # ---- derivative causality ----------------------------------------------------------------
    def _eliminate_dependent(self):
        """Solve for the unknown port variables of storage ports in derivative causality."""
        order = list(nx.topological_sort(self._graph()))
        full: dict = {}
        for v in order:
            if v not in self.ops:
                full[v] = self.assign_map[v].xreplace(full)
        unknowns = [w for w, _, _ in self.dependent]
        wset = set(unknowns)
        names = [n for _, _, n in self.dependent]
        state_syms = [s.symbol for s in self.states]
        inputs = [i.symbol for i in self.m.inputs.values()]
        rates_full = {x: r.xreplace(full) for x, r in self.rates.items()}
        eqs = []
        for w, stored, name in self.dependent:
            stored_full = stored.xreplace(full)
            bad = stored_full.free_symbols & (wset | set(self.ops))
            if bad:
                raise CausalityError(
                    f"{self.m.name}: derivative causality of {', '.join(names)} cannot be "
                    f"resolved (its stored quantity depends on {', '.join(map(str, bad))}); "
                    f"add a compliance or inertia between the coupled storage elements"
                )
            dt = sum((sp.diff(stored_full, x) * rates_full[x] for x in state_syms if stored_full.has(x)), sp.Integer(0))
            dt += sum(
                (sp.diff(stored_full, u) * input_rate_symbol(u) for u in inputs if stored_full.has(u)), sp.Integer(0)
            )
            eqs.append(w - dt)
        try:
            A, b = sp.linear_eq_to_matrix(eqs, unknowns)
            sol = _solve_linear(A, b)
        except (ValueError, sp.PolynomialError, ZeroDivisionError):
            raise CausalityError(
                f"{self.m.name}: derivative causality of {', '.join(names)} cannot be resolved "
                f"(nonlinear or singular coupling); add a compliance or inertia between the "
                f"rigidly coupled storage elements, or make them linear"
            ) from None
        for (w, stored, name), s in zip(self.dependent, sol):
            self.assign(w, s, name)
            self.eliminated.append(
                f"{name} is in derivative causality: its stored quantity "
                f"{sp.sstr(stored.xreplace(full))} depends on the other states; "
                f"state eliminated, its port variable {w} = {sp.sstr(s)}"
            )

    # ---- ordering ----------------------------------------------------------------------------
    def _order(self, roots: list[sp.Expr]) -> list[Statement]:
        g = self._graph()
        need = set()
        stack = [s for r in roots for s in r.free_symbols if s in self.assign_map]
        while stack:
            v = stack.pop()
            if v in need:
                continue
            need.add(v)
            stack.extend(p for p in g.predecessors(v) if p not in need)
        sub = g.subgraph(need)
        try:
            order = (
                list(nx.lexicographical_topological_sort(sub, key=str))
                if len(need) < 400
                else list(nx.topological_sort(sub))
            )
        except nx.NetworkXUnfeasible:
            raise CausalityError(f"{self.m.name}: unresolved algebraic loop") from None
        return [Statement(v, self.assign_map[v], self.origin[v], self.ops.get(v)) for v in order]


def _tear_set(g: nx.DiGraph) -> list[sp.Symbol]:
    """A small set of variables whose removal leaves ``g`` acyclic (greedy feedback vertex set)."""
    g = nx.DiGraph(g)
    tears: list = []
    while True:
        cyclic = [
            c for c in nx.strongly_connected_components(g) if len(c) > 1 or g.has_edge(next(iter(c)), next(iter(c)))
        ]
        if not cyclic:
            return sorted(tears, key=str)
        comp = max(cyclic, key=len)
        v = max(sorted(comp, key=str), key=lambda n: g.in_degree(n) * g.out_degree(n) + 2 * g.has_edge(n, n))
        tears.append(v)
        g.remove_node(v)


def _solve_linear(A: sp.Matrix, b: sp.Matrix) -> list[sp.Expr]:
    """Solve A·v = b symbolically; small results are put over a common denominator."""
    if A.shape[0] == 1:
        if A[0, 0] == 0:
            raise ZeroDivisionError
        sol = [b[0] / A[0, 0]]
    else:
        if A.det() == 0:
            raise ZeroDivisionError
        sol = list(A.LUsolve(b))
    return [sp.cancel(x) if sp.count_ops(x) < 60 else x for x in sol]


def _collapse(program: list[Statement], rates: dict, outputs: dict):
    """Substitute trivial assignments (aliases, sign flips, scaled aliases) forward."""
    sub: dict = {}
    kept: list[Statement] = []
    for st in program:
        expr = st.expr.xreplace(sub) if sub else st.expr
        if st.op is None and _is_cheap(expr):
            sub[st.var] = expr
        else:
            kept.append(Statement(st.var, expr, st.origin, st.op))
    return (kept, {k: v.xreplace(sub) for k, v in rates.items()}, {k: v.xreplace(sub) for k, v in outputs.items()})


def _expr(value, origin: str, what) -> sp.Expr:
    """``value`` as a sympy expression (elements may hand over numbers); the message of a bad
    value names where it came from (built only then: printing symbols is slow)."""
    return value if isinstance(value, sp.Expr) else sympify(value, f"{origin}: {what}")


def derive(model: Model, causality: Causality | None = None, units: bool | None = None) -> Equations:
    """Derive the state equations of ``model``, assigning causality first if needed, and check
    their units (:mod:`bondgraph.equations.units`).

    Parameters
    ----------
    model : Model
        The acausal bond graph.
    causality : Causality, optional
        A causality already assigned to ``model`` (default: :func:`assign_causality`).
    units : bool, optional
        Check the units of every equation (default: the setting ``units.check``); the result
        is ``Equations.units``.

    Returns
    -------
    Equations
        The explicit state equations as a straight-line program.

    Raises
    ------
    CausalityError, ModelError
        When no causal assignment exists, an algebraic loop cannot be solved, or the units of
        an equation do not match (the message names the element, the equation and both units).
    """
    return Deriver(model, causality or assign_causality(model), units).run()
