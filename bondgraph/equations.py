"""From a causal bond graph to explicit state equations.

After SCAP every bond variable is computed by exactly one element or junction.  Those
assignments form a directed graph over the bond variables, states and inputs:

* strongly connected components are algebraic loops; linear ones are solved symbolically
  (small systems, only the loop's own variables), nonlinear ones are reported by element;
* storage ports in derivative causality are eliminated: their stored quantity is an
  algebraic function of the independent states, its time derivative is taken by the chain
  rule and the resulting linear system in the unknown port variables is solved (e.g. two
  masses rigidly coupled through a TF become one inertia m1 + n²·m2);
* a topological order of what remains is a *straight-line program* ``v1 = ...; v2 = ...``
  whose intermediate names are kept, so derivation stays linear in the graph size.  Full
  substitution into x' = f(x, u, θ) is done only on request (printouts, linearisation).

Operator outputs (memory elements) appear in the program as calls ``h = H[v]``.
"""
from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field

import networkx as nx
import sympy as sp

from .causality import Causality, assign_causality, _ep
from .elements import C, CField, E, F, GY, I, J0, J1, P, Q, R, Se, Sf, TF
from .errors import CausalityError, ModelError
from .graph import Model, OperatorBlock, Quantity


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

    @property
    def state_symbols(self) -> list[sp.Symbol]:
        return [s.symbol for s in self.states]

    def substituted(self, exprs: dict) -> dict:
        """``exprs`` with every program variable substituted (operator outputs kept as symbols)."""
        full: dict = {}
        for st in self.program:
            if st.op is None:
                full[st.var] = st.expr.xreplace(full)
        return {k: v.xreplace(full) for k, v in exprs.items()}

    def state_equations(self) -> dict[sp.Symbol, sp.Expr]:
        """x' = f(x, u, θ) fully substituted."""
        return self.substituted(self.rates)

    def output_equations(self) -> dict[str, sp.Expr]:
        return self.substituted(self.outputs)

    def operator_inputs(self) -> dict[sp.Symbol, sp.Expr]:
        return self.substituted({st.var: st.expr for st in self.program if st.op is not None})

    def jacobian(self, roots: list[sp.Expr], wrt: list[sp.Symbol], op_gains: dict | None = None) -> sp.Matrix:
        """∂roots/∂wrt by forward differentiation through the program (sparse, linear cost).

        An operator output h = H[v] gets slope ``op_gains[h]`` (0 if not given: frozen memory)."""
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
        return sp.Matrix(rows) if rows else sp.zeros(0, len(wrt))


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


def derive(model: Model, causality: Causality | None = None) -> Equations:
    """Derive the state equations of ``model`` (assigning causality first if needed)."""
    return _Deriver(model, causality or assign_causality(model)).run()


def _is_cheap(expr: sp.Expr) -> bool:
    if expr.is_Atom:
        return True
    if expr.is_Mul and len(expr.args) == 2 and expr.args[0].is_Number and expr.args[1].is_Atom:
        return True
    return False


class _Deriver:
    def __init__(self, model: Model, causality: Causality):
        self.m = model
        self.c = causality
        self.assign: dict[sp.Symbol, sp.Expr] = {}
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
            if not isinstance(e, (J0, J1)):
                return elem if len(e.ports) == 1 else f"{elem}.{port}"
        return f"{b.tail[0]}_{b.head[0]}"

    def _set(self, var: sp.Symbol, expr: sp.Expr, origin: str):
        if var in self.assign:
            raise CausalityError(f"{self.m.name}: variable {var} is computed twice ({self.origin[var]}, {origin})")
        self.assign[var] = expr
        self.origin[var] = origin

    # ---- main ------------------------------------------------------------------------------
    def run(self) -> Equations:
        m = self.m
        # generated names never collide with the user's (parameters, inputs, states, operators)
        self._names |= {str(s) for s in m.parameter_table()} | set(m.inputs) | set(m.internal_states) \
            | set(m.operators)
        self.e, self.f, self.sign = {}, {}, {}
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
            self._set(ob.symbol, ob_in, f"operator {name}")
            self.ops[ob.symbol] = ob
        outputs = {n: self._q(o.expr) for n, o in m.outputs.items()}
        self._solve_loops()
        if self.dependent:
            self._eliminate_dependent()
        program = self._order(list(self.rates.values()) + list(outputs.values()))
        program, rates, outputs = _collapse(program, self.rates, outputs)
        inputs = [i.symbol for i in m.inputs.values()]
        params = list(m.parameter_table())
        return Equations(m, self.c, self.states, inputs, [_rate_symbol(u) for u in inputs], params,
                         program, rates, outputs, list(self.ops.values()), self.eliminated, self.loops,
                         {b.index: (self.e[b.index], self.f[b.index]) for b in m.bonds})

    # ---- constitutive relations ------------------------------------------------------------
    def _element(self, name: str, elem):
        ports = self.ports[name]
        sets = {port: self.c.sets_effort(b, (name, port)) for port, b, s in ports}
        if isinstance(elem, Se):
            (_, b, s), = ports
            self._set(self.e[b.index], elem.effort, name)
        elif isinstance(elem, Sf):
            (_, b, s), = ports
            self._set(self.f[b.index], -s * elem.flow, name)
        elif isinstance(elem, C):
            (port, b, s), = ports
            e, f = self.e[b.index], self.f[b.index]
            if sets[port]:
                q = sp.Symbol(self._unique(f"q_{name}"), real=True)
                self.states.append(State(q, "q", name, elem.q0))
                self._set(e, elem.law.xreplace({Q: q}), name)
                self.rates[q] = s * f
                self.quantity_map[("q", name)] = q
            else:
                w = sp.Symbol(self._unique(f"f_in_{name}"), real=True)
                self._set(f, s * w, name)
                q = _invert_law(elem.law, Q, e, name, "C")
                self.dependent.append((w, q, name))
                self.quantity_map[("q", name)] = q
        elif isinstance(elem, I):
            (port, b, s), = ports
            e, f = self.e[b.index], self.f[b.index]
            if not sets[port]:
                p = sp.Symbol(self._unique(f"p_{name}"), real=True)
                self.states.append(State(p, "p", name, elem.p0))
                self._set(f, s * elem.law.xreplace({P: p}), name)
                self.rates[p] = e
                self.quantity_map[("p", name)] = p
            else:
                w = sp.Symbol(self._unique(f"e_in_{name}"), real=True)
                self._set(e, w, name)
                p = _invert_law(elem.law, P, s * f, name, "I")
                self.dependent.append((w, p, name))
                self.quantity_map[("p", name)] = p
        elif isinstance(elem, R):
            (port, b, s), = ports
            e, f = self.e[b.index], self.f[b.index]
            if sets[port]:
                law = elem.effort_of_flow()
                if law is None:
                    raise CausalityError(f"{self.m.name}: R '{name}' must take effort and give flow, but its law "
                                         f"f(e) cannot be inverted; give it as law=lambda f: ... or change the graph")
                self._set(e, law.xreplace({F: s * f}), name)
            else:
                law = elem.flow_of_effort()
                if law is None:
                    raise CausalityError(f"{self.m.name}: R '{name}' must take effort and give flow, but its law "
                                         f"e(f) cannot be inverted; give it as conductance_law=lambda e: ...")
                self._set(f, s * law.xreplace({E: e}), name)
        elif isinstance(elem, (TF, GY)):
            (p1, b1, s1), (p2, b2, s2) = sorted(ports, key=lambda t: t[0])
            n = elem.ratio
            e1, f1, e2, f2 = self.e[b1.index], self.f[b1.index], self.e[b2.index], self.f[b2.index]
            if isinstance(elem, TF):
                if sets[p1]:
                    self._set(e1, n * e2, name)
                    self._set(f2, -s1 * s2 * n * f1, name)
                else:
                    self._set(e2, e1 / n, name)
                    self._set(f1, -s1 * s2 * f2 / n, name)
            else:
                if sets[p1]:
                    self._set(e1, -s2 * n * f2, name)
                    self._set(e2, s1 * n * f1, name)
                else:
                    self._set(f2, -s2 * e1 / n, name)
                    self._set(f1, s1 * e2 / n, name)
        elif isinstance(elem, (J0, J1)):
            common_is_effort = isinstance(elem, J0)
            # the strong bond brings the common variable in
            strong = [(port, b, s) for port, b, s in ports if sets[port] != common_is_effort]
            (sp_port, sb, ss), = strong
            common = self.e if common_is_effort else self.f
            summed = self.f if common_is_effort else self.e
            terms = []
            for port, b, s in ports:
                if b is sb:
                    continue
                self._set(common[b.index], common[sb.index], name)
                terms.append(s * summed[b.index])
            self._set(summed[sb.index], -ss * sp.Add(*terms), name)
            self.quantity_map[("e" if common_is_effort else "f", name)] = common[sb.index]
        elif isinstance(elem, CField):
            self._cfield(name, elem, ports, sets)
        else:
            raise ModelError(f"{self.m.name}: element '{name}' of unsupported kind {elem.kind}")
        for port, b, s in ports:
            key = name if len(elem.ports) <= 1 else f"{name}.{port}"
            self.quantity_map.setdefault(("e", key), self.e[b.index])
            self.quantity_map.setdefault(("f", key), s * self.f[b.index])

    def _cfield(self, name, elem: CField, ports, sets):
        efforts = elem.efforts()
        qsym = {pn: sp.Symbol(self._unique(f"q_{name}.{pn}"), real=True) for pn in elem.ports}
        byport = {port: (b, s) for port, b, s in ports}
        deriv = [pn for pn in elem.ports if not sets[pn]]
        for pn in elem.ports:
            if pn not in deriv:
                self.states.append(State(qsym[pn], "q", f"{name}.{pn}", elem.q0[pn]))
        sub = {elem.placeholders[pn]: qsym[pn] for pn in elem.ports}
        if deriv:
            # dependent displacements from e_i = dU/dq_i on the derivative ports
            eqs = [efforts[pn].xreplace(sub) - self.e[byport[pn][0].index] for pn in deriv]
            unknowns = [qsym[pn] for pn in deriv]
            try:
                A, rhs = sp.linear_eq_to_matrix(eqs, unknowns)
                sol = A.LUsolve(rhs)
            except (sp.matrices.common.NonSquareMatrixError, ValueError, ZeroDivisionError):
                raise CausalityError(
                    f"{self.m.name}: ports {', '.join(deriv)} of C-field '{name}' are in derivative causality "
                    f"and its law cannot be inverted for them; make the field linear or add compliance") from None
            dep = {qsym[pn]: sp.simplify(sol[i]) for i, pn in enumerate(deriv)}
            sub_dep = {**sub}
            for pn in elem.ports:
                sub_dep[elem.placeholders[pn]] = dep.get(qsym[pn], qsym[pn])
        else:
            dep, sub_dep = {}, sub
        for pn in elem.ports:
            b, s = byport[pn]
            if pn in deriv:
                w = sp.Symbol(self._unique(f"f_in_{name}.{pn}"), real=True)
                self._set(self.f[b.index], s * w, f"{name}.{pn}")
                self.dependent.append((w, dep[qsym[pn]], f"{name}.{pn}"))
                self.quantity_map[("q", f"{name}.{pn}")] = dep[qsym[pn]]
            else:
                self._set(self.e[b.index], efforts[pn].xreplace(sub_dep), f"{name}.{pn}")
                self.rates[qsym[pn]] = s * self.f[b.index]
                self.quantity_map[("q", f"{name}.{pn}")] = qsym[pn]

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
        for var, expr in list(self.assign.items()):
            if any(isinstance(s, Quantity) for s in expr.free_symbols):
                self.assign[var] = self._q(expr)
        for k, v in list(self.rates.items()):
            self.rates[k] = self._q(v)

    def _quantity(self, q: Quantity):
        key = (q.what, q.endpoint)
        if key in self.quantity_map:
            return self.quantity_map[key]
        elem_name = q.endpoint.split(".")[0] if q.endpoint not in self.m.elements else q.endpoint
        if q.what in ("e", "f"):
            raise ModelError(f"{self.m.name}: '{q.endpoint}' has no single {'effort' if q.what == 'e' else 'flow'}"
                             f" (a {self.m.elements[elem_name].kind}); ask for one of its bonded elements instead")
        # displacement / momentum of something that is not a storage port: integrate a sensor state
        rate_key = ("f" if q.what == "q" else "e", q.endpoint)
        if rate_key not in self.quantity_map:
            raise ModelError(f"{self.m.name}: cannot integrate the {'flow' if q.what == 'q' else 'effort'}"
                             f" of '{q.endpoint}' (it has no single one)")
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
        g.add_nodes_from(self.assign)
        for var, expr in self.assign.items():
            for s in expr.free_symbols:
                if s in self.assign:
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
                raise CausalityError(f"{self.m.name}: algebraic loop through a memory operator "
                                     f"({', '.join(names)}); add a storage element in the loop")
            tears = _tear_set(g.subgraph(comp))
            rest = nx.DiGraph(g.subgraph(comp - set(tears)))
            sub: dict = {}
            for v in nx.topological_sort(rest):
                sub[v] = self.assign[v].xreplace(sub)
            eqs = [t - self.assign[t].xreplace(sub) for t in tears]
            try:
                A, b = sp.linear_eq_to_matrix(eqs, tears)
            except (ValueError, sp.PolynomialError):
                raise CausalityError(f"{self.m.name}: nonlinear algebraic loop through {', '.join(names)}; "
                                     f"add a storage element (small C or I) to break it") from None
            try:
                sol = _solve_linear(A, b)
            except ZeroDivisionError:
                raise CausalityError(f"{self.m.name}: singular algebraic loop through {', '.join(names)}") from None
            for t, val in zip(tears, sol):
                self.assign[t] = val
            self.loops.append(f"algebraic loop through {', '.join(names)} ({len(comp)} variables, "
                              f"torn at {', '.join(map(str, tears))}) solved symbolically")

    # ---- derivative causality ----------------------------------------------------------------
    def _eliminate_dependent(self):
        """Solve for the unknown port variables of storage ports in derivative causality."""
        order = list(nx.topological_sort(self._graph()))
        full: dict = {}
        for v in order:
            if v not in self.ops:
                full[v] = self.assign[v].xreplace(full)
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
                raise CausalityError(f"{self.m.name}: derivative causality of {', '.join(names)} cannot be "
                                     f"resolved (its stored quantity depends on {', '.join(map(str, bad))}); "
                                     f"add a compliance or inertia between the coupled storage elements")
            dt = sum((sp.diff(stored_full, x) * rates_full[x] for x in state_syms if stored_full.has(x)),
                     sp.Integer(0))
            dt += sum((sp.diff(stored_full, u) * _rate_symbol(u) for u in inputs if stored_full.has(u)),
                      sp.Integer(0))
            eqs.append(w - dt)
        try:
            A, b = sp.linear_eq_to_matrix(eqs, unknowns)
            sol = _solve_linear(A, b)
        except (ValueError, sp.PolynomialError, ZeroDivisionError):
            raise CausalityError(f"{self.m.name}: derivative causality of {', '.join(names)} cannot be resolved "
                                 f"(nonlinear or singular coupling); add a compliance or inertia between the "
                                 f"rigidly coupled storage elements, or make them linear") from None
        for (w, stored, name), s in zip(self.dependent, sol):
            self._set(w, s, name)
            self.eliminated.append(f"{name} is in derivative causality: its stored quantity "
                                   f"{sp.sstr(stored.xreplace(full))} depends on the other states; "
                                   f"state eliminated, its port variable {w} = {sp.sstr(s)}")

    # ---- ordering ----------------------------------------------------------------------------
    def _order(self, roots: list[sp.Expr]) -> list[Statement]:
        g = self._graph()
        need = set()
        stack = [s for r in roots for s in r.free_symbols if s in self.assign]
        while stack:
            v = stack.pop()
            if v in need:
                continue
            need.add(v)
            stack.extend(p for p in g.predecessors(v) if p not in need)
        sub = g.subgraph(need)
        try:
            order = list(nx.lexicographical_topological_sort(sub, key=str)) if len(need) < 400 \
                else list(nx.topological_sort(sub))
        except nx.NetworkXUnfeasible:
            raise CausalityError(f"{self.m.name}: unresolved algebraic loop") from None
        return [Statement(v, self.assign[v], self.origin[v], self.ops.get(v)) for v in order]


def _tear_set(g: nx.DiGraph) -> list[sp.Symbol]:
    """A small set of variables whose removal leaves ``g`` acyclic (greedy feedback vertex set)."""
    g = nx.DiGraph(g)
    tears: list = []
    while True:
        cyclic = [c for c in nx.strongly_connected_components(g)
                  if len(c) > 1 or g.has_edge(next(iter(c)), next(iter(c)))]
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


def _invert_law(law: sp.Expr, var: sp.Symbol, value: sp.Expr, name: str, kind: str) -> sp.Expr:
    """Stored quantity of a storage element in derivative causality: var with law(var) = value."""
    if law.is_polynomial(var) and sp.degree(law, var) == 1:
        a = sp.diff(law, var)
        return sp.cancel((value - law.subs(var, 0)) / a)
    sols = sp.solve(sp.Eq(law, value), var)
    if len(sols) != 1:
        raise CausalityError(f"{name}: {kind} '{name}' is in derivative causality but its law cannot be inverted; "
                             f"make it linear or add a compliance/inertia next to it")
    return sols[0]


def _rate_symbol(u: sp.Symbol) -> sp.Symbol:
    return sp.Symbol(f"d{u.name}/dt", real=True)


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
    return (kept, {k: v.xreplace(sub) for k, v in rates.items()},
            {k: v.xreplace(sub) for k, v in outputs.items()})
