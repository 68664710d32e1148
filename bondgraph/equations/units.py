"""Dimensional analysis of a model's equations, as a Modelica tool checks a model.

The check runs inside :func:`~bondgraph.equations.derivation.derive`, on the relations the
elements write (:class:`~bondgraph.model.elements.EquationBuilder`) before algebraic loops and
derivative causality are solved, so an inconsistency is reported by the element that wrote it,
with its equation and the two units.  Any element kind is checked: the check reads what an
element writes, not its class.

What is known: the units declared for parameters, inputs, outputs and internal states (unit
strings, :mod:`bondgraph.model.units`; ``""`` is not declared), and the units a memory operator
gives its parameters (:meth:`~bondgraph.model.memory.MemoryOperator.parameter_dimensions`).
What is checked: every relation ``var = expr`` of every element (the two sides, the terms of
every sum, the arguments of exp, sin, tanh, ... and of symbolic powers, which must be pure
numbers), every state's rate (d/dt divides by s), the initial values, the inputs of memory
operators, and the outputs against their declared units.  Every bond variable, state and
undeclared unit gets its unit by propagation from what is known; a unit that follows from
nothing stays undetermined (reported, never an error).

Numbers.  An exact number multiplying something (``2*zeta*omega``, ``1/(n*K)`` with an integer
n) is a pure number; a floating-point number (``0.05*k`` or a value computed at build time from
``symbolic=False`` parameters) may hide a unit, so the check gives it whatever unit its place
needs (and ``bondgraph check`` lists those units); so does a number standing alone as a whole
modulus or source value: an element given only numbers (``C("c", 1e-3)``) is not checked.

Junction relations (common effort or flow, sums) hold by construction: they only join the
bond variables into classes of one unit.  The other relations are propagated in order of
trust: sources and declared outputs, then transformers and gyrators, then the other elements,
then internal states and memory operators.  When a relation contradicts what is known, the
element to blame is the one whose removal makes the rest consistent (ties broken by the power
convention, effort × flow in W); the message names it, its equation, the units of the two
sides and, for a declared parameter in it, the unit the equation needs.

After a consistent check the bonds whose effort × flow is not W are reported as notes (a
modal coordinate scaled to unit mass, a signal-like stage): dimensionally consistent, but not
power bonds.
"""

from __future__ import annotations

import heapq
from collections import defaultdict
from dataclasses import dataclass, field
from fractions import Fraction

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.logic.boolalg import BooleanFunction

from ..model.elements import FIXED, RELAY, Junction
from ..model.graph import Model, input_rate_symbol
from ..model.units import DENOM, ONE, div, format_dim, mul, parse_unit, power
from ..support.errors import ModelError

#: the unit a number takes from its place (a float, a number standing alone)
WILD = "any"

SECOND = (0, 0, DENOM, 0, 0, 0, 0)

#: functions whose value has the unit of their arguments (all alike)
_SAME = (sp.Abs, sp.re, sp.im, sp.floor, sp.ceiling, sp.Max, sp.Min)
#: functions whose value is a pure number whatever the unit of their arguments (alike)
_NUMBER_OF_ANY = (sp.sign, sp.Heaviside, sp.atan2)

#: trust order of relations (lower first)
ANCHOR, STRUCTURE, ELEMENT, USER, FREE, POWER = range(6)
#: most elements tried when looking for the one to blame
MAX_SUSPECTS = 24


@dataclass(slots=True)
class Relation:
    """``dim(lhs) = dim(rhs)·s^shift`` written by ``who`` (an element, output, state or operator)."""

    lhs: sp.Expr
    rhs: sp.Expr
    who: str
    priority: int
    form: str = "{lhs} = {rhs}"
    shift: int = 0
    _symbols: frozenset | None = None

    @property
    def symbols(self) -> frozenset:
        if self._symbols is None:
            self._symbols = frozenset(self.lhs.free_symbols | self.rhs.free_symbols)
        return self._symbols

    def text(self) -> str:
        return self.form.format(lhs=sp.sstr(self.lhs), rhs=sp.sstr(self.rhs))


@dataclass
class UnitEntry:
    """A named quantity of the report: its declared unit string, its unit as checked (a
    dimension, None if undetermined) and how it is known: declared, inferred, undetermined, or
    not in the equations (a number used at build time)."""

    name: str
    declared: str
    dim: tuple | None
    status: str

    @property
    def unit(self) -> str:
        if self.status in ("declared", "not in the equations"):
            return self.declared or "-"
        return "?" if self.dim is None else format_dim(self.dim)


@dataclass
class UnitReport:
    """The result of a consistent check: the units of parameters, inputs, outputs and internal
    states; numbers whose place gives them a unit (``constants``: where, value, unit); memory
    operators with their input and output units; and notes (bonds whose effort × flow is not W)."""

    parameters: list[UnitEntry] = field(default_factory=list)
    inputs: list[UnitEntry] = field(default_factory=list)
    outputs: list[UnitEntry] = field(default_factory=list)
    states: list[UnitEntry] = field(default_factory=list)
    operators: list[tuple[str, str, str]] = field(default_factory=list)
    constants: list[tuple[str, str, str]] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def inferred(self) -> list[UnitEntry]:
        """Entries whose unit was not declared but follows from the equations."""
        return [e for e in self.parameters + self.inputs + self.outputs + self.states if e.status == "inferred"]

    def lines(self) -> list[str]:
        """The report as text lines (what ``bondgraph check`` prints)."""
        out = ["units: consistent"]
        for title, entries in (
            ("parameters", self.parameters),
            ("inputs", self.inputs),
            ("outputs", self.outputs),
            ("internal states", self.states),
        ):
            if not entries:
                continue
            out.append(f"  {title}:")
            width = max(len(e.name) for e in entries)
            for e in entries:
                mark = "" if e.status == "declared" else f"   ({e.status})"
                out.append(f"    {e.name:<{width}}  {e.unit}{mark}")
        if self.operators:
            out.append("  memory operators (input -> output):")
            out += [f"    {n}: {a} -> {b}" for n, a, b in self.operators]
        if self.constants:
            out.append("  numbers that carry a unit (floating-point values take the unit their place needs):")
            out += [f"    {where}: {value} in {unit}" for where, value, unit in self.constants]
        out += [f"  note: {n}" for n in self.notes]
        return out


class _Mismatch(Exception):
    """Two things that must have one unit do not: ``a`` has ``da``, ``b`` has ``db``."""

    def __init__(self, a, da, b, db, where: str = "sides"):
        super().__init__(where)
        self.a, self.da, self.b, self.db, self.where = a, da, b, db, where
        self.relation: int | None = None


def _rational(x: sp.Number) -> Fraction | None:
    if x.is_Rational:
        return Fraction(int(x.p), int(x.q))
    f = Fraction(float(x)).limit_denominator(DENOM)
    return f if abs(float(f) - float(x)) <= 1e-12 * max(1.0, abs(float(x))) else None


class _Solver:
    """Propagation of units through the relations (see the module docstring)."""

    def __init__(self, relations: list[Relation], anchors: dict, classes: dict):
        self.relations = relations
        self.anchors = anchors
        self.classes = classes  # symbol -> root of its junction class
        self.members: dict = defaultdict(list)  # root -> the symbols of its class
        for sym, r in classes.items():
            self.members[r].append(sym)
        self.memo: dict = {}
        self.dims: dict = {}
        self.setter: dict = {}
        self.waiting: dict = defaultdict(list)
        self.queue: list = []
        self.done: set = set()
        self.current = -1
        self.who = ""  # who wrote the relation being processed
        self.floats: dict = {}  # (who, value) -> dimension, for the report

    # ---- state ---------------------------------------------------------------------------------
    def root(self, s):
        return self.classes.get(s, s)

    def reset(self, exclude=frozenset()):
        self.memo, self.setter, self.waiting, self.done = {}, {}, defaultdict(list), set()
        self.dims = {}
        for sym, d in self.anchors.items():
            for m in self.members.get(self.root(sym)) or (sym,):
                self.dims[m] = d
        self.queue = [(r.priority, i) for i, r in enumerate(self.relations) if r.who not in exclude]
        heapq.heapify(self.queue)

    def solve(self, exclude=frozenset()) -> _Mismatch | None:
        """Propagate every relation but those of ``exclude``; the first contradiction, or None."""
        self.reset(exclude)
        return self.drain()

    def drain(self) -> _Mismatch | None:
        try:
            while self.queue:
                _, i = heapq.heappop(self.queue)
                if i not in self.done:
                    self.process(i)
        except _Mismatch as exc:
            exc.relation = self.current
            return exc
        return None

    def push(self, indices):
        for i in indices:
            self.done.discard(i)
            heapq.heappush(self.queue, (self.relations[i].priority, i))

    def assign(self, sym, dim):
        old = self.dims.get(sym)
        if old is not None:
            if old != dim:
                raise _Mismatch(sym, old, sym, dim, "symbol")
            return
        r = self.classes.get(sym, sym)
        for m in self.members.get(r) or (sym,):
            self.dims[m] = dim
        self.setter[r] = self.current
        for i in self.waiting.pop(r, ()):
            heapq.heappush(self.queue, (self.relations[i].priority, i))

    # ---- relations -----------------------------------------------------------------------------
    def side(self, e):
        return WILD if e.is_Number else self.eval(e)

    def process(self, i: int):
        rel = self.relations[i]
        self.current, self.who = i, rel.who
        lhs, rhs = rel.lhs, rel.rhs
        dl = self.dims.get(lhs) if lhs.is_Symbol else self.side(lhs)
        dr = self.dims.get(rhs) if rhs.is_Symbol else self.side(rhs)
        shift = tuple(x * rel.shift for x in SECOND) if rel.shift else None
        if dl is WILD or dr is WILD:  # a number that takes any unit: note which (for the report)
            if dr is WILD and dl is not WILD and dl is not None:
                self.float_factor(rhs, div(dl, shift) if shift else dl)
            elif dl is WILD and dr is not WILD and dr is not None:
                self.float_factor(lhs, mul(dr, shift) if shift else dr)
            self.done.add(i)
            return
        if dr is not None and shift:
            dr = mul(dr, shift)
        if dl is not None and dr is not None:
            if dl != dr:
                raise _Mismatch(lhs, dl, rhs, dr)
            self.done.add(i)
            return
        if dl is not None:
            self.infer(rhs, div(dl, shift) if shift else dl)
        elif dr is not None:
            self.infer(lhs, dr)
        dl, dr = self.side(lhs), self.side(rhs)
        if dl is None or dr is None:  # wait for one of its unknown symbols
            for s in rel.symbols:
                if s not in self.dims:
                    self.waiting[self.classes.get(s, s)].append(i)
            return
        if shift:
            dr = mul(dr, shift)
        if dl != dr:
            raise _Mismatch(lhs, dl, rhs, dr)
        self.done.add(i)

    def note_float(self, e, dim):
        if dim != ONE:
            self.floats.setdefault((self.who, float(e)), dim)

    # ---- expressions ---------------------------------------------------------------------------
    def eval(self, e):
        """The unit of ``e``: a dimension, WILD, or None while unknown; constraints inside ``e``
        (terms of a sum, function arguments) are checked and used on the way."""
        if e.is_Symbol:
            return self.dims.get(e)
        if e.is_Number:
            return WILD if (e.is_Float or e.is_zero) else ONE
        got = self.memo.get(id(e))  # by identity: hashing a fresh sympy expression costs more
        if got is not None:
            return got
        d = self._eval(e)
        if d is not None:
            self.memo[id(e)] = d
        return d

    def _eval(self, e):
        if e.is_Mul:
            acc, wild, unknown, dims = ONE, False, False, self.dims
            for a in e.args:
                d = dims.get(a) if a.is_Symbol else self.eval(a)
                if d is WILD:
                    wild = True
                elif d is None:
                    unknown = True
                else:
                    acc = mul(acc, d)
            return WILD if wild else (None if unknown else acc)
        if e.is_Add:
            return self.alike(e.args, "terms of a sum")
        if e.is_Pow:
            b, x = e.args
            if x.is_Number:
                db = self.eval(b)
                if db is WILD or db is None:
                    return db
                p = _rational(x)
                if p is None:
                    return self.require_one(b, ("base of the power", e))
                return power(db, p) or WILD
            self.require_one(x, ("exponent of", e))
            return self.require_one(b, ("base of the symbolic power", e))
        if e.is_NumberSymbol or e is sp.I:
            return ONE
        if isinstance(e, _SAME):
            return self.alike(e.args, ("arguments of", e.func))
        if isinstance(e, sp.Piecewise):
            for _, cond in e.args:
                self.condition(cond)
            return self.alike([expr for expr, _ in e.args], "branches of a Piecewise")
        if isinstance(e, _NUMBER_OF_ANY):
            if len(e.args) > 1:
                self.alike(e.args, ("arguments of", e.func))
            else:
                self.eval(e.args[0])
            return ONE
        if isinstance(e, AppliedUndef):
            return WILD
        if e.is_Function:  # exp, log, sin, tanh, ...: pure numbers in and out
            for a in e.args:
                self.require_one(a, ("argument of", e.func))
            return ONE
        return WILD

    def condition(self, cond):
        if cond.is_Relational:
            self.alike(cond.args, ("sides of", cond))
        elif isinstance(cond, BooleanFunction):
            for a in cond.args:
                self.condition(a)

    def alike(self, args, what):
        """Arguments that share one unit (terms of a sum, Max, branches): checked, unknown ones inferred."""
        known, first, pending, wild = None, None, [], []
        for t in args:
            d = self.eval(t)
            if d is WILD:
                wild.append(t)
                continue
            if d is None:
                pending.append(t)
            elif known is None:
                known, first = d, t
            elif d != known:
                raise _Mismatch(first, known, t, d, what)
        if known is None:
            return None if pending else WILD
        for t in pending:
            self.infer(t, known)
        for t in wild:
            self.float_factor(t, known)
        return known

    def require_one(self, e, what):
        d = self.eval(e)
        if d is None:
            self.infer(e, ONE)
        elif d is not WILD and d != ONE:
            raise _Mismatch(e, d, sp.Integer(1), ONE, what)
        return ONE

    def infer(self, e, target):
        """Make ``e`` have unit ``target``: a contradiction raises, unknown symbols it determines
        get their unit (a product's one unknown factor, every unknown term of a sum, ...)."""
        d = self.eval(e)
        if d is WILD:
            self.float_factor(e, target)
            return
        if d is not None:
            if d != target:
                raise _Mismatch(e, d, e, target, "target")
            return
        if e.is_Symbol:
            self.assign(e, target)
        elif e.is_Add or isinstance(e, (sp.Max, sp.Min)):
            for t in e.args:
                if self.eval(t) is None:
                    self.infer(t, target)
        elif isinstance(e, sp.Piecewise):
            for expr, _ in e.args:
                if self.eval(expr) is None:
                    self.infer(expr, target)
        elif e.is_Mul:
            rest, unknown = target, []
            for a in e.args:
                da = self.eval(a)
                if da is None:
                    unknown.append(a)
                else:
                    rest = div(rest, da)
            if len(unknown) == 1:
                self.infer(unknown[0], rest)
        elif e.is_Pow and e.args[1].is_Number:
            p = _rational(e.args[1])
            t = power(target, 1 / p) if p else None
            if t is not None:
                self.infer(e.args[0], t)
        elif isinstance(e, (sp.Abs, sp.re, sp.im, sp.floor, sp.ceiling)):
            self.infer(e.args[0], target)

    def float_factor(self, e, target):
        """Note the unit a product's one floating-point factor takes (for the report)."""
        if e.is_Float:
            self.note_float(e, target)
            return
        if not e.is_Mul:
            return
        floats = [a for a in e.args if a.is_Float]
        if len(floats) != 1:
            return
        rest = target
        for a in e.args:
            if a is floats[0]:
                continue
            da = self.eval(a)
            if da is None or da is WILD:
                return
            rest = div(rest, da)
        self.note_float(floats[0], rest)


# ---- building the relations ------------------------------------------------------------------------
def _junction_classes(model: Model, bond_vars: dict) -> dict:
    """symbol -> a representative, for the bond variables a 0- or 1-junction makes equal in
    unit: every effort and every flow at one junction (the common variable and the summed one),
    joined across bonds between junctions.  Union-find on bond indices (node 2k: effort of bond
    k, 2k + 1: its flow)."""
    n = 2 * (max(bond_vars, default=0) + 1)
    parent = list(range(n))

    def find(x):
        while parent[x] != x:
            parent[x] = x = parent[parent[x]]
        return x

    at: dict = defaultdict(list)
    structural = {name for name, el in model.elements.items() if _structural(el)}
    for b in model.bonds:
        for end in (b.tail[0], b.head[0]):
            if end in structural:
                at[end].append(b.index)
    for bonds in at.values():
        for var in (0, 1):  # efforts, flows
            top = find(2 * bonds[0] + var)
            for k in bonds[1:]:
                r = find(2 * k + var)
                if r != top:
                    parent[r] = top
    out = {}
    for node in range(n):
        r = find(node)
        if r != node or parent[node] != node:
            out[bond_vars[node >> 1][node & 1]] = bond_vars[r >> 1][r & 1]
    for r in set(out.values()):
        out[r] = r
    return out


def _attribute_values(el):
    for attr in el.symbolic_attrs:
        val = getattr(el, attr)
        yield from val.values() if isinstance(val, dict) else (val,)


def _holds_symbols(expr, memo: dict, seen: set) -> bool:
    """Whether ``expr`` holds a symbol other than an element's placeholders (sympy Dummy);
    the symbols go to ``seen``."""
    if expr is None:
        return False
    got = memo.get(id(expr))
    if got is None:
        syms = [x for x in expr.free_symbols if not isinstance(x, sp.Dummy)]
        seen.update(syms)
        got = memo[id(expr)] = bool(syms)
    return got


def _structural(el) -> bool:
    """A 0- or 1-junction with the framework's own relations (equal common variables, sums)."""
    return isinstance(el, Junction) and type(el).equations is Junction.equations


@dataclass
class UnitInput:
    """What the deriver hands to :func:`check_units` (its relations before loops are solved)."""

    model: Model
    assignments: dict
    origins: dict
    operators: dict
    states: list
    rates: dict
    derivatives: list
    outputs: dict
    bond_vars: dict


def _owner(model: Model, origin: str):
    """The element that wrote a relation (origins are element names or storage port keys)."""
    el = model.elements.get(origin)
    if el is None and "." in origin:
        el = model.elements.get(origin.rpartition(".")[0])
    return el


class _Check:
    def __init__(self, data: UnitInput):
        self.data = data
        m = self.m = data.model
        self.anchors: dict = {}
        self.declared: dict = {}  # symbol -> unit text, for hints
        self.names: dict = {}  # who -> how to name it in a message (an element, or text)
        self.relations: list[Relation] = []
        self.skipped: list[Relation] = []
        self._declare()
        self.classes = _junction_classes(m, data.bond_vars)
        self.solver = _Solver(self.relations, self.anchors, self.classes)

    def anchor(self, sym, unit_text: str):
        u = parse_unit(unit_text)
        if u is not None:
            self.anchors[sym] = u.dim
            self.declared[sym] = unit_text

    def one(self) -> sp.Symbol:
        """A symbol that is a pure number (a number alone would take any unit)."""
        one = sp.Symbol("[1]", real=True)
        self.anchors[one] = ONE
        return one

    def add(self, rel: Relation, name=None):
        self.relations.append(rel)
        if name is not None and rel.who not in self.names:
            self.names[rel.who] = name

    def name(self, who: str) -> str:
        named = self.names.get(who, who)
        return named if isinstance(named, str) else f"{named.kind} '{named.name}' ({named.describe()})"

    def _declare(self):
        d, m = self.data, self.m
        self.parameters = m.all_parameters()
        self.symbols = {n: d.symbol for n, d in self.parameters.items() if d.symbolic and d.kind == "real"}
        for name, sym in self.symbols.items():
            self.anchor(sym, self.parameters[name].unit)
        for name, inp in m.inputs.items():
            self.anchor(inp.symbol, inp.unit)
            rate = input_rate_symbol(inp.symbol)
            self.add(Relation(rate, inp.symbol, f"input {name}", ANCHOR, "{lhs} = d{rhs}/dt", -1))
        for name, st in m.internal_states.items():
            self.anchor(st.symbol, st.unit)
        # element relations
        numeric: dict = {}  # element name -> it holds only numbers (its relations are skipped)
        owners: dict = {}

        holds: dict = {}  # id of an expression -> it holds a symbol (copies of a component share laws)
        seen: set = set()  # the symbol objects the laws hold

        def only_numbers(el) -> bool:
            if el.name not in numeric:
                numeric[el.name] = not isinstance(el, Junction) and not any(
                    [_holds_symbols(v, holds, seen) for v in _attribute_values(el)]
                )
            return numeric[el.name]

        for var, expr in d.assignments.items():
            if var in d.operators:
                continue
            origin = d.origins[var]
            el = owners.get(origin, False)
            if el is False:
                el = owners[origin] = _owner(m, origin)
            if el is None:
                self.add(Relation(var, expr, origin, USER), origin)
                continue
            if _structural(el):
                continue  # joined into classes (_junction_classes)
            rel = Relation(var, expr, el.name, self._priority(el))
            if only_numbers(el):
                self.skipped.append(rel)  # only numbers: their units are free
            else:
                self.add(rel, el)
        for w, stored, origin in d.derivatives:
            el = _owner(m, origin)
            who = el.name if el is not None else origin
            rel = Relation(w, stored, who, ELEMENT, "{lhs} = d({rhs})/dt", -1)
            if el is not None and only_numbers(el):
                self.skipped.append(rel)
            else:
                self.add(rel, el if el is not None else origin)
        for st in d.states:
            rate = d.rates.get(st.symbol)
            if st.kind == "z":
                who, name, prio = f"state {st.origin}", f"internal state '{st.origin}'", USER
            else:
                el = _owner(m, st.origin)
                who = el.name if el is not None else st.origin
                name = el if el is not None else st.origin
                prio = ANCHOR  # dq/dt = f and dp/dt = e hold by construction
            if rate is not None:
                self.add(Relation(st.symbol, rate, who, prio, "d{lhs}/dt = {rhs}", 1), name)
            if not st.x0.is_Number:
                self.add(Relation(st.symbol, st.x0, who, USER, "{lhs}(0) = {rhs}"), name)
        for sym, ob in d.operators.items():
            op, oname = ob.operator, str(sym)
            who, name = f"operator {oname}", f"operator '{oname}' ({op.kind})"
            vin = sp.Symbol(f"{oname}[input]", real=True)
            self.anchor(vin, op.input_unit)
            self.anchor(sym, op.output_unit)
            self.add(Relation(vin, d.assignments[sym], who, USER, "input of " + oname + ": {rhs}"), name)
            exps = op.parameter_dimensions()
            for psym, pname in zip(ob.params, op.parameter_names):
                if pname in exps:
                    a, b = (sp.Rational(x) for x in exps[pname])
                    self.add(Relation(psym, vin**a * sym**b if a or b else self.one(), who, USER), name)
        for name, expr in d.outputs.items():
            out = m.outputs[name]
            osym = sp.Symbol(f"output {name}", real=True)
            self.anchor(osym, out.unit)
            prio = ANCHOR if osym in self.anchors else FREE
            self.add(Relation(osym, expr, f"output {name}", prio, name + " = {rhs}"), f"output '{name}'")
        # key the declared units by the very symbol objects the laws hold (sympy may have made
        # equal copies since: a look-up by an equal copy compares, by the same object does not)
        canon = {x: x for x in seen}
        self.anchors = {canon.get(x, x): dim for x, dim in self.anchors.items()}
        self.declared = {canon.get(x, x): text for x, text in self.declared.items()}

    @staticmethod
    def _priority(el) -> int:
        if el.causal_class == FIXED:
            return ANCHOR
        if el.causal_class == RELAY:
            return STRUCTURE
        return ELEMENT

    # ---- running ----------------------------------------------------------------------------------
    def run(self) -> UnitReport:
        miss = self.solver.solve()
        if miss is not None:
            raise ModelError(self.explain(miss))
        return self.report()

    def power_relations(self) -> list[Relation]:
        watt = parse_unit("W").dim
        w = sp.Symbol("power [W]", real=True)
        self.anchors.setdefault(w, watt)
        self.solver.dims[w] = watt
        rels = []
        for k, (e, f) in sorted(self.data.bond_vars.items()):
            if self.solver.dims.get(e) is None or self.solver.dims.get(f) is None:
                rels.append(Relation(e * f, w, f"bond {k}", POWER, "{lhs} = power"))
        return rels

    def with_power(self) -> bool:
        """Propagate the power convention (effort × flow in W) on bonds still undetermined; keep
        what it gives if it contradicts nothing (else drop it)."""
        s = self.solver
        snapshot = dict(s.dims)
        n = len(self.relations)
        extra = self.power_relations()
        self.relations.extend(extra)
        s.push(range(n, n + len(extra)))
        ok = s.drain() is None
        del self.relations[n:]
        s.queue = [q for q in s.queue if q[1] < n]
        s.waiting = defaultdict(list, {r: [i for i in w if i < n] for r, w in s.waiting.items()})
        if not ok:
            s.dims = snapshot
            s.memo = {}
        return ok

    # ---- blame ------------------------------------------------------------------------------------
    def suspects(self, miss: _Mismatch) -> list[str]:
        """Who wrote the contradicting relation, then who set the units it used, nearest first."""
        s = self.solver
        order, seen_rel, queue = [], {miss.relation}, [miss.relation]
        while queue and len(order) < MAX_SUSPECTS:
            i = queue.pop(0)
            who = self.relations[i].who
            if who not in order:
                order.append(who)
            for sym in self.relations[i].symbols:
                j = s.setter.get(s.root(sym), -1)
                if j >= 0 and j not in seen_rel:
                    seen_rel.add(j)
                    queue.append(j)
        return order

    def culprit(self, miss: _Mismatch) -> str | None:
        s = self.solver
        found = [w for w in self.suspects(miss) if s.solve(frozenset({w})) is None]
        if len(found) > 1:  # several ways out: prefer the one that leaves power bonds (W)
            powered = [
                w for w in found if s.solve(frozenset({w})) is None and self.with_power() and not self.power_notes()
            ]
            found = powered or found
        if not found:
            return None
        first = self.relations[miss.relation].who
        return first if first in found else found[0]

    def explain(self, miss: _Mismatch) -> str:
        s = self.solver
        who = self.culprit(miss)
        again = None
        if who is not None:  # the others' units first, then its relations: where it breaks
            s.solve(frozenset({who}))
            for i, r in enumerate(self.relations):
                if r.who == who:  # in their own order of trust, before anything else
                    heapq.heappush(s.queue, (r.priority - POWER - 1, i))
            again = s.drain()
        if again is not None and self.relations[again.relation].who == who:
            miss = again
        else:
            s.solve()  # back to where the contradiction first showed
        rel = self.relations[miss.relation]
        name = self.name(rel.who)
        return (
            f"{self.m.name}: units do not match in {name}: {rel.text()}: {self.sides(miss)}{self.hint(miss.relation)}"
        )

    @staticmethod
    def sides(miss: _Mismatch) -> str:
        a, b = format_dim(miss.da), format_dim(miss.db)
        if miss.where == "sides":
            return f"the left side is {a}, the right side is {b}"
        if miss.where == "target":
            return f"{sp.sstr(miss.a)} is {a} where {b} is needed"
        if miss.where == "symbol":
            return f"{miss.a} is {a} here and {b} elsewhere"
        where = miss.where
        if isinstance(where, tuple):  # (phrase, the expression or function it is about)
            about = where[1].__name__ if isinstance(where[1], type) else sp.sstr(where[1])
            where = f"{where[0]} {about}"
        if miss.b == 1 and miss.db == ONE:
            return f"the {where} is {a} where a pure number is needed ({sp.sstr(miss.a)})"
        return f"the {where} are {a} ({sp.sstr(miss.a)}) and {b} ({sp.sstr(miss.b)})"

    def hint(self, i: int) -> str:
        """For a declared parameter in relation ``i``: the unit the relation needs it in."""
        s, rel = self.solver, self.relations[i]
        for sym in sorted(rel.symbols & set(self.declared), key=str):
            if sym.name.startswith("output ") or sym not in self.anchors:
                continue
            saved, memo = dict(s.dims), s.memo
            s.dims.pop(sym, None)
            s.memo, s.queue = {}, []
            try:
                s.process(i)
                need = s.dims.get(sym)
            except _Mismatch:
                need = None
            finally:
                s.dims, s.memo = saved, memo
            if need is not None and need != self.anchors[sym]:
                return f" ({sym} is declared {self.declared[sym]}; this equation needs {format_dim(need)})"
        return ""

    # ---- report -----------------------------------------------------------------------------------
    def report(self) -> UnitReport:
        self.with_power()
        s, m, rep = self.solver, self.m, UnitReport()

        def entry(name, sym, declared):
            if sym is None:
                return UnitEntry(name, declared, None, "not in the equations")
            dim = s.dims.get(sym)
            if parse_unit(declared) is not None:
                return UnitEntry(name, declared, dim, "declared")
            return UnitEntry(name, declared, dim, "inferred" if dim is not None else "undetermined")

        for name, decl in self.parameters.items():
            rep.parameters.append(entry(name, self.symbols.get(name), decl.unit))
        rep.inputs = [entry(n, i.symbol, i.unit) for n, i in m.inputs.items()]
        rep.outputs = [entry(n, sp.Symbol(f"output {n}", real=True), o.unit) for n, o in m.outputs.items()]
        rep.states = [entry(n, st.symbol, st.unit) for n, st in m.internal_states.items()]
        for sym, ob in self.data.operators.items():
            vin = s.dims.get(sp.Symbol(f"{sym}[input]", real=True))
            out = s.dims.get(sym)
            rep.operators.append(tuple([str(sym)] + ["?" if d is None else format_dim(d) for d in (vin, out)]))
        for rel in self.skipped:  # numbers-only elements: the unit their numbers take
            dl, dr = s.side(rel.lhs), s.side(rel.rhs)
            if dl not in (None, WILD) and dr is WILD:
                s.who = rel.who
                s.float_factor(rel.rhs, div(dl, tuple(x * rel.shift for x in SECOND)) if rel.shift else dl)
        rep.constants = [(who, f"{value:g}", format_dim(dim)) for (who, value), dim in sorted(s.floats.items())]
        rep.notes = self.power_notes()
        return rep

    def power_notes(self) -> list[str]:
        s, watt = self.solver, parse_unit("W").dim
        groups: dict = defaultdict(list)
        for k, (e, f) in sorted(self.data.bond_vars.items()):
            de, df = s.dims.get(e), s.dims.get(f)
            if de is not None and df is not None and mul(de, df) != watt:
                groups[mul(de, df)].append(k)
        notes = []
        for dim, bonds in groups.items():
            shown = ", ".join(map(str, bonds[:8])) + (f" and {len(bonds) - 8} more" if len(bonds) > 8 else "")
            notes.append(f"effort x flow is {format_dim(dim)}, not W, on bond(s) {shown}: not power bonds")
        return notes


def check_units(data: UnitInput) -> UnitReport:
    """Check the units of every relation of a model (see the module docstring).

    Parameters
    ----------
    data : UnitInput
        The model and the relations its elements wrote, from the deriver.

    Returns
    -------
    UnitReport
        The unit of every parameter, input, output and internal state (declared or inferred).

    Raises
    ------
    ModelError
        One line naming the element, its equation and the units of the two sides that do not
        match (and, for a declared parameter in it, the unit the equation needs).
    """
    return _Check(data).run()
