"""Acausal bond graphs: elements joined by bonds, composite components with named ports.

A :class:`Component` is a bond graph fragment with named ports; adding one to another
copies its elements under a name space (``creep.k1``), so the flat view of any model is one
dict of elements and one list of bonds.  A :class:`Model` is the top-level component with
inputs, outputs and declared parameters.

Power convention: ``bond(a, b)`` draws the half-arrow from ``a`` to ``b`` (positive power
flows from a to b).  Endpoints are written ``"element"`` for one-port elements and
junctions, ``"element.port"`` for multiport elements, ``"component.port"`` for the
exposed ports of components.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Any

import sympy as sp

from ..support.errors import ModelError, did_you_mean
from .elements import Element, Junction, sympify
from .memory import MemoryOperator
from .parameters import Parameter
from .units import unit_problem


def _check_unit(owner: str, what: str, unit: str) -> None:
    """ModelError if ``unit`` is not a unit string (see :mod:`bondgraph.model.units`)."""
    problem = unit_problem(unit)
    if problem:
        raise ModelError(f"{owner}: {what}: {problem}")


def input_rate_symbol(u: sp.Symbol) -> sp.Symbol:
    """The symbol of du/dt for input symbol ``u`` (named ``du/dt``)."""
    return sp.Symbol(f"d{u.name}/dt", real=True)


@dataclass(frozen=True)
class Bond:
    """A bond from ``tail`` to ``head``: (element name, port name) pairs; ``index`` is 1-based."""

    index: int
    tail: tuple[str, str]
    head: tuple[str, str]


@dataclass
class InternalState:
    """A state of an element with internal dynamics (e.g. Bouc–Wen z): d(symbol)/dt = rate."""

    symbol: sp.Symbol
    rate: sp.Expr
    x0: sp.Expr
    unit: str = ""
    doc: str = ""


@dataclass
class OperatorBlock:
    """A memory operator applied to a scalar expression: symbol = op[input]."""

    symbol: sp.Symbol
    operator: MemoryOperator
    input: sp.Expr
    params: list[sp.Symbol] = field(default_factory=list)


@dataclass
class Output:
    name: str
    expr: sp.Expr
    unit: str = ""
    doc: str = ""


@dataclass
class Input:
    name: str
    symbol: sp.Symbol
    unit: str = ""
    doc: str = ""
    range: tuple[float, float] | None = None


class Quantity(sp.Symbol):
    """Placeholder for a port variable (effort, flow, state, displacement) of an element.

    Created by :meth:`Component.effort` and friends; resolved to the bond variables when
    equations are derived.  A sympy symbol, usable in output and law expressions.

    Parameters
    ----------
    what : {"e", "f", "q", "p", "x"}
        Effort, flow into the element (power-in), displacement, momentum, or a state.
    endpoint : str
        The element (and port) it refers to: ``"elem"`` or ``"elem.port"``.
    """

    def __new__(cls, what: str, endpoint: str):
        obj = super().__new__(cls, f"{what}[{endpoint}]", real=True)
        obj.what, obj.endpoint = what, endpoint
        return obj

    def __getnewargs_ex__(self):
        return (self.what, self.endpoint), {}

    def _hashable_content(self):
        return (self.name, "quantity")


class Component:
    """A bond-graph fragment: elements, bonds, exposed ports, own parameters and blocks.

    Adding a component to another copies its elements under its name (``creep.k1``).

    Parameters
    ----------
    name : str
        The component's name, the prefix of its elements once added to another.
    doc : str, optional
        One line on what it models, shown in printouts.
    """

    def __init__(self, name: str, doc: str = ""):
        self.name = name
        self.doc = doc
        self.elements: dict[str, Element] = {}
        self.bonds: list[Bond] = []
        self.ports: dict[str, str] = {}
        self.parameters: dict[str, tuple[Parameter, Any]] = {}
        self.internal_states: dict[str, InternalState] = {}
        self.operators: dict[str, OperatorBlock] = {}
        self.components: dict[str, str] = {}  # flattened sub-component name -> its doc

    # ---- building -------------------------------------------------------------------
    def add(self, *items):
        """Add elements or components.

        Parameters
        ----------
        *items : Element or Component
            What to add; a component's elements are copied under ``<component>.<name>``.

        Returns
        -------
        Element or Component or None
            The last item added (None if none was given), so ``k = m.add(C("k", 1e-6))``.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If an item is neither an element nor a component, or its name is taken.
        """
        for item in items:
            if isinstance(item, Component):
                self._add_component(item)
            elif isinstance(item, Element):
                self._check_new_name(item.name)
                self.elements[item.name] = item
            else:
                raise ModelError(f"{self.name}: can only add elements or components, not {item!r}")
        return items[-1] if items else None

    def _check_new_name(self, name: str):
        if name in self.elements or name in self.components or name in self.ports:
            raise ModelError(f"{self.name}: the name '{name}' is used twice")

    def bond(self, a: str, b: str) -> Bond:
        """Connect endpoint ``a`` to ``b``, the half-arrow from a to b.

        Positive power flows from ``a`` to ``b``: e·f > 0 means energy moves from a to b.

        Parameters
        ----------
        a, b : str
            Endpoints: ``"element"`` for one-ports and junctions, ``"element.port"`` for
            multiports, ``"component.port"`` for a component's exposed ports.

        Returns
        -------
        Bond
            The new bond, numbered from 1.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If an endpoint is unknown, both are the same element, or a port is bonded already.
        """
        tail, head = self.resolve(a), self.resolve(b)
        if tail[0] == head[0]:
            raise ModelError(f"{self.name}: bond {a} → {b} connects element '{tail[0]}' to itself")
        index = max((b.index for b in self.bonds), default=0) + 1
        tail = (tail[0], tail[1] if tail[1] is not None else f"#{index}")
        head = (head[0], head[1] if head[1] is not None else f"#{index}")
        for end in (tail, head):
            elem = self.elements[end[0]]
            if not isinstance(elem, Junction) and any(end in (bd.tail, bd.head) for bd in self.bonds):
                if len(elem.ports) == 1:
                    raise ModelError(
                        f"{self.name}: one-port {elem.kind} '{elem.name}' already has a bond; "
                        f"put a junction between it and its neighbours"
                    )
                raise ModelError(f"{self.name}: port '{end[1]}' of '{elem.name}' already has a bond")
        bd = Bond(index, tail, head)
        self.bonds.append(bd)
        return bd

    def unbond(self, a: str, b: str) -> None:
        """Remove the bond a → b (to splice elements into an existing graph).

        Parameters
        ----------
        a, b : str
            The bond's tail and head endpoints, as given to :meth:`bond`.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If there is no such bond.
        """
        ta, hb = self.resolve(a), self.resolve(b)
        for bd in self.bonds:
            if (
                bd.tail[0] == ta[0]
                and bd.head[0] == hb[0]
                and (ta[1] is None or bd.tail[1] == ta[1])
                and (hb[1] is None or bd.head[1] == hb[1])
            ):
                self.bonds.remove(bd)
                return
        raise ModelError(f"{self.name}: there is no bond {a} → {b}")

    def chain(self, *endpoints: str) -> list[Bond]:
        """Bond a → b → c ... in sequence.

        Parameters
        ----------
        *endpoints : str
            The endpoints in order; each consecutive pair is bonded as by :meth:`bond`.

        Returns
        -------
        list of Bond
            The new bonds, one fewer than the endpoints.

        Raises
        ------
        bondgraph.support.errors.ModelError
            As :meth:`bond`.
        """
        return [self.bond(a, b) for a, b in zip(endpoints, endpoints[1:])]

    def expose(self, port: str, endpoint: str):
        """Make ``endpoint`` reachable from outside as ``<component>.<port>``.

        Parameters
        ----------
        port : str
            The name the outside uses.
        endpoint : str
            The endpoint inside the component.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the port is exposed twice, would hide an element of that name, or the endpoint
            is unknown.
        """
        if port in self.ports:
            raise ModelError(f"{self.name}: port '{port}' exposed twice")
        if port in self.elements and endpoint != port:
            raise ModelError(f"{self.name}: port '{port}' would hide the element of that name")
        self.resolve(endpoint)
        self.ports[port] = endpoint

    def resolve(self, endpoint: str) -> tuple[str, str | None]:
        """The element and port an endpoint string names.

        Parameters
        ----------
        endpoint : str
            ``"element"``, ``"element.port"`` or an exposed port's name.

        Returns
        -------
        tuple of (str, str or None)
            ``(element, port)``; the port is None for a junction (a new junction port).

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the endpoint is not a string, names a multiport without its port, or is
            unknown (the message suggests close names).
        """
        if not isinstance(endpoint, str):
            raise ModelError(f"{self.name}: endpoint must be a string like 'm' or 'tf.p1', got {endpoint!r}")
        if endpoint in self.ports and self.ports[endpoint] != endpoint:
            return self.resolve(self.ports[endpoint])
        if endpoint in self.elements:
            elem = self.elements[endpoint]
            if isinstance(elem, Junction):
                return endpoint, None
            if len(elem.ports) == 1:
                return endpoint, elem.ports[0]
            raise ModelError(
                f"{self.name}: '{endpoint}' is a {elem.kind} with ports "
                f"{', '.join(elem.ports)}; bond to '{endpoint}.{elem.ports[0]}' etc."
            )
        head, _, port = endpoint.rpartition(".")
        if head in self.elements and port in self.elements[head].ports:
            return head, port
        raise ModelError(f"{self.name}: " + did_you_mean(endpoint, self.endpoint_names(), "element or port"))

    def endpoint_names(self) -> list[str]:
        """Every endpoint string that :meth:`resolve` accepts.

        Returns
        -------
        list of str
            Exposed ports, one-ports and junctions by name, multiports as ``elem.port``.
        """
        names = list(self.ports)
        for n, e in self.elements.items():
            if isinstance(e, Junction) or len(e.ports) == 1:
                names.append(n)
            else:
                names += [f"{n}.{p}" for p in e.ports]
        return names

    # ---- parameters, blocks, port quantities ----------------------------------------------
    def parameter(
        self, name: str, value: float, unit: str = "", doc: str = "", bounds: tuple[float, float] | None = None
    ) -> sp.Symbol:
        """Declare a real parameter owned by this component.

        Parameters
        ----------
        name : str
            The parameter's name (``<component>.<name>`` once the component is added).
        value : float
            Its value, in ``unit``.
        unit : str, optional
            Its SI unit, e.g. ``"N/m"`` (see :mod:`bondgraph.model.units`).
        doc : str, optional
            One line on what it is.
        bounds : tuple of (float, float), optional
            (lowest, highest) allowed value, for fitting.

        Returns
        -------
        sympy.Symbol
            The parameter's symbol, for laws and expressions.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the parameter is declared twice.
        bondgraph.support.errors.ParameterError
            If the name is not an identifier or the unit cannot be read.
        """
        decl = Parameter(name, float(value), unit, doc, bounds=bounds)
        if name in self.parameters:
            raise ModelError(f"{self.name}: parameter '{name}' declared twice")
        self.parameters[name] = (decl, float(value))
        return decl.symbol

    def state(self, name: str, rate, x0=0, unit: str = "", doc: str = "") -> sp.Symbol:
        """Declare an internal state z with dz/dt = rate (DE-based memory such as Bouc–Wen).

        Parameters
        ----------
        name : str
            The state's name and symbol.
        rate : sympy.Expr or float or str
            dz/dt, in the state's unit per s; may use port quantities, inputs, input rates,
            parameters (use :meth:`set_rate` when it needs the state's own symbol).
        x0 : sympy.Expr or float or str, optional
            The initial value, 0 by default.
        unit : str, optional
            The state's SI unit.
        doc : str, optional
            One line on what it is.

        Returns
        -------
        sympy.Symbol
            The state's symbol.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the state is declared twice, the unit is not a unit, or rate or x0 are not
            scalar expressions.
        """
        if name in self.internal_states:
            raise ModelError(f"{self.name}: internal state '{name}' declared twice")
        _check_unit(self.name, f"internal state '{name}'", unit)
        sym = sp.Symbol(name, real=True)
        self.internal_states[name] = InternalState(
            sym, sympify(rate, f"state '{name}' rate"), sympify(x0, f"state '{name}' x0"), unit, doc
        )
        return sym

    def set_rate(self, name: str, rate):
        """Set the rate of an internal state declared earlier (for rates that use its symbol).

        Parameters
        ----------
        name : str
            The state, as declared by :meth:`state`.
        rate : sympy.Expr or float or str
            dz/dt, in the state's unit per s.

        Raises
        ------
        KeyError
            If no such state was declared.
        bondgraph.support.errors.ModelError
            If ``rate`` is not a scalar expression.
        """
        self.internal_states[name].rate = sympify(rate, f"state '{name}' rate")

    def operator(self, name: str, op: MemoryOperator, input) -> sp.Symbol:
        """Apply a memory operator (hysteresis, friction) to an expression.

        The operator's parameters become model parameters ``<name>.<pname>``.

        Parameters
        ----------
        name : str
            The output's name and symbol.
        op : MemoryOperator
            The operator; its kernels are compiled and checked now.
        input : sympy.Expr or float or str
            What drives it: an expression of port quantities, inputs, states, parameters.

        Returns
        -------
        sympy.Symbol
            The symbol of the operator's output, h = op[input].

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the name is taken, ``op`` is not a MemoryOperator, or a kernel is broken.
        """
        if name in self.operators:
            raise ModelError(f"{self.name}: operator '{name}' declared twice")
        if not isinstance(op, MemoryOperator):
            raise ModelError(f"{self.name}: operator '{name}' must be a MemoryOperator, got {op!r}")
        op.kernels()  # compiled and checked now: a broken kernel is an error at the line that applies it
        values = op.parameter_values()
        syms = [
            self.parameter(f"{name}.{pn}", v, doc=f"{op.kind} parameter") for pn, v in zip(op.parameter_names, values)
        ]
        sym = sp.Symbol(name, real=True)
        self.operators[name] = OperatorBlock(sym, op, sympify(input, f"operator '{name}' input"), syms)
        return sym

    def effort(self, endpoint: str) -> Quantity:
        """The effort at an endpoint (V, N, ...; never sign-flipped).

        Parameters
        ----------
        endpoint : str
            ``"element"`` or ``"element.port"``.

        Returns
        -------
        Quantity
            A placeholder, resolved to the bond effort when equations are derived.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the endpoint is unknown.
        """
        return self._quantity("e", endpoint)

    def flow(self, endpoint: str) -> Quantity:
        """The flow *into* the element at an endpoint (power-in convention; A, m/s, ...).

        Parameters
        ----------
        endpoint : str
            ``"element"`` or ``"element.port"``.

        Returns
        -------
        Quantity
            A placeholder, resolved when equations are derived.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the endpoint is unknown.
        """
        return self._quantity("f", endpoint)

    def displacement(self, endpoint: str) -> Quantity:
        """The time integral of the flow into an endpoint (q of a C: C or m).

        Parameters
        ----------
        endpoint : str
            ``"element"`` or ``"element.port"``.

        Returns
        -------
        Quantity
            A placeholder, resolved when equations are derived.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the endpoint is unknown.
        """
        return self._quantity("q", endpoint)

    def momentum(self, endpoint: str) -> Quantity:
        """The time integral of the effort at an endpoint (p of an I: N·s or V·s).

        Parameters
        ----------
        endpoint : str
            ``"element"`` or ``"element.port"``.

        Returns
        -------
        Quantity
            A placeholder, resolved when equations are derived.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the endpoint is unknown.
        """
        return self._quantity("p", endpoint)

    def _quantity(self, what: str, endpoint: str) -> Quantity:
        elem, port = self.resolve(endpoint)
        if port is None:
            return Quantity(what, elem)
        return Quantity(what, elem if len(self.elements[elem].ports) == 1 else f"{elem}.{port}")

    # ---- composition -------------------------------------------------------------------------
    def _add_component(self, comp: "Component"):
        self._check_new_name(comp.name)
        prefix = comp.name + "."
        mapping = comp._rename_map(prefix)
        for name, elem in comp.elements.items():
            self._check_new_name(prefix + name)
            self.elements[prefix + name] = elem.renamed(prefix + name).xreplace(mapping)
        offset = max((b.index for b in self.bonds), default=0)
        for bd in comp.bonds:
            k = bd.index + offset
            tail, head = ((prefix + e[0], f"#{k}" if e[1].startswith("#") else e[1]) for e in (bd.tail, bd.head))
            self.bonds.append(Bond(k, tail, head))
        for port, ep in comp.ports.items():
            self.ports[prefix + port] = prefix + ep
        for name, (decl, val) in comp.parameters.items():
            new = Parameter(prefix + name, val, decl.unit, decl.doc, bounds=decl.bounds)
            self.parameters[prefix + name] = (new, val)
        for name, st in comp.internal_states.items():
            self.internal_states[prefix + name] = InternalState(
                mapping[st.symbol], st.rate.xreplace(mapping), st.x0.xreplace(mapping), st.unit, st.doc
            )
        for name, ob in comp.operators.items():
            self.operators[prefix + name] = OperatorBlock(
                mapping[ob.symbol], ob.operator, ob.input.xreplace(mapping), [mapping[s] for s in ob.params]
            )
        self.components[comp.name] = comp.doc
        for sub, doc in comp.components.items():
            self.components[prefix + sub] = doc

    def _rename_map(self, prefix: str) -> dict:
        mapping: dict = {}
        for name, (decl, _) in self.parameters.items():
            mapping[decl.symbol] = sp.Symbol(prefix + name, real=True)
        for name, st in self.internal_states.items():
            mapping[st.symbol] = sp.Symbol(prefix + name, real=True)
        for name, ob in self.operators.items():
            mapping[ob.symbol] = sp.Symbol(prefix + name, real=True)
        for sym in self._all_symbols():
            if isinstance(sym, Quantity):
                mapping[sym] = Quantity(sym.what, prefix + sym.endpoint)
        return mapping

    def _all_symbols(self) -> set:
        syms = set()
        for e in self.elements.values():
            syms |= e.free_symbols()
        for st in self.internal_states.values():
            syms |= st.rate.free_symbols | st.x0.free_symbols
        for ob in self.operators.values():
            syms |= ob.input.free_symbols
        return syms

    # ---- roles and rewriting ----------------------------------------------------------------------
    def tag(self, element: str, role: str) -> None:
        """Give an element a role that model extensions (diagnosis) use to find where an
        effect belongs.

        Parameters
        ----------
        element : str
            The element's name.
        role : str
            What it stands for in the physics: ``"stiffness"``, ``"damping"``,
            ``"polarization"``, ...

        Raises
        ------
        bondgraph.support.errors.ModelError
            If there is no such element.
        """
        if element not in self.elements:
            raise ModelError(f"{self.name}: " + did_you_mean(element, self.elements, "element"))
        self.elements[element].role = role

    def with_role(self, role: str) -> list[str]:
        """The elements tagged with a role.

        Parameters
        ----------
        role : str
            The role, as given to :meth:`tag`.

        Returns
        -------
        list of str
            Their names, in insertion order.
        """
        return [n for n, e in self.elements.items() if getattr(e, "role", None) == role]

    def replace(self, element: Element) -> None:
        """Swap an element for another of the same name and ports (e.g. a new law).

        Parameters
        ----------
        element : Element
            The new element; it keeps the old one's role.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If there is no element of that name or the ports differ.
        """
        old = self.elements.get(element.name)
        if old is None:
            raise ModelError(f"{self.name}: " + did_you_mean(element.name, self.elements, "element"))
        if old.ports != element.ports:
            raise ModelError(f"{self.name}: replacement for '{element.name}' must have ports {old.ports}")
        element.role = getattr(old, "role", None)
        self.elements[element.name] = element

    def substitute(self, mapping: dict) -> None:
        """Replace symbols everywhere (element laws, internal states, operator inputs, outputs).

        Parameters
        ----------
        mapping : dict of sympy.Symbol to sympy.Expr
            As for :meth:`sympy.Basic.xreplace`.
        """
        self.elements = {n: e.xreplace(mapping) for n, e in self.elements.items()}
        for st in self.internal_states.values():
            st.rate, st.x0 = st.rate.xreplace(mapping), st.x0.xreplace(mapping)
        for ob in self.operators.values():
            ob.input = ob.input.xreplace(mapping)
        for o in getattr(self, "outputs", {}).values():
            o.expr = o.expr.xreplace(mapping)

    def copy(self):
        """An independent copy (rewrites of the copy leave this model untouched).

        Returns
        -------
        Component
            A deep copy, of the same class.
        """
        return copy.deepcopy(self)

    # ---- views ---------------------------------------------------------------------------------
    def bonds_of(self, name: str) -> list[Bond]:
        """The bonds at an element.

        Parameters
        ----------
        name : str
            The element's name.

        Returns
        -------
        list of Bond
            The bonds with the element at either end, in bond order.
        """
        return [b for b in self.bonds if b.tail[0] == name or b.head[0] == name]

    def check(self) -> None:
        """Check the graph's structure: it has bonds, every port is bonded, every junction
        has at least two bonds.

        Raises
        ------
        bondgraph.support.errors.ModelError
            Naming the offending element and the fix.
        """
        if not self.bonds:
            raise ModelError(f"{self.name}: the graph has no bonds")
        count: dict[str, int] = {n: 0 for n in self.elements}
        ports_used: set = set()
        for b in self.bonds:
            for end in (b.tail, b.head):
                count[end[0]] += 1
                ports_used.add(end)
        for name, elem in self.elements.items():
            if isinstance(elem, Junction):
                if count[name] < 2:
                    raise ModelError(
                        f"{self.name}: junction '{name}' has {count[name]} bond(s); "
                        f"a junction needs at least two (remove it or bond more elements to it)"
                    )
            else:
                missing = [p for p in elem.ports if (name, p) not in ports_used]
                if missing:
                    which = f"port(s) {', '.join(missing)} of " if len(elem.ports) > 1 else ""
                    raise ModelError(
                        f"{self.name}: {which}{elem.kind} '{name}' is not connected; bond it to a junction or remove it"
                    )


class Model(Component):
    """A complete bond-graph model: a component with inputs and named outputs.

    Parameters
    ----------
    name : str
        The model's name, used in printouts and error messages.
    doc : str, optional
        One line on what it models.
    """

    def __init__(self, name: str, doc: str = ""):
        super().__init__(name, doc)
        self.inputs: dict[str, Input] = {}
        self.outputs: dict[str, Output] = {}
        self.declared: list[Parameter] = []
        self.values: dict[str, Any] = {}

    def input(self, name: str, unit: str = "", doc: str = "", range: tuple[float, float] | None = None) -> sp.Symbol:
        """Declare an input signal (e.g. the drive voltage ``V``).

        Declaring an input twice returns the first declaration's symbol.

        Parameters
        ----------
        name : str
            The input's name and symbol.
        unit : str, optional
            Its SI unit, e.g. ``"V"``.
        doc : str, optional
            One line on what it is.
        range : tuple of (float, float), optional
            (lowest, highest) value the device accepts (e.g. a unipolar amplifier's
            (0, 120) V); ``bondgraph compensate`` keeps the drives it computes within it.

        Returns
        -------
        sympy.Symbol
            The input's symbol.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the unit is not a unit or the range is not (lowest, highest).
        """
        if name in self.inputs:
            return self.inputs[name].symbol
        _check_unit(self.name, f"input '{name}'", unit)
        if range is not None:
            lo, hi = (float(v) for v in range)
            if not lo < hi:
                raise ModelError(
                    f"{self.name}: input '{name}' range {range!r} must be (lowest, highest), lowest < highest"
                )
            range = (lo, hi)
        sym = sp.Symbol(name, real=True)
        self.inputs[name] = Input(name, sym, unit, doc, range)
        return sym

    def input_rate(self, name: str) -> sp.Symbol:
        """The symbol of an input's time derivative (for rate-dependent laws and states).

        Parameters
        ----------
        name : str
            A declared input.

        Returns
        -------
        sympy.Symbol
            ``d<name>/dt``, in the input's unit per s.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If there is no such input.
        """
        if name not in self.inputs:
            raise ModelError(f"{self.name}: " + did_you_mean(name, self.inputs, "input"))
        return input_rate_symbol(self.inputs[name].symbol)

    def output(self, name: str, expr, unit: str = "", doc: str = "") -> None:
        """Declare a named output.

        Parameters
        ----------
        name : str
            The output's name.
        expr : sympy.Expr or str
            An expression of port quantities, states, inputs and parameters; or a string
            ``"elem.e"``, ``"elem.f"`` (flow into elem), ``"elem.q"``, ``"elem.p"`` naming a
            port quantity.
        unit : str, optional
            Its SI unit, e.g. ``"m"``.
        doc : str, optional
            One line on what it is.

        Raises
        ------
        bondgraph.support.errors.ModelError
            If the output is declared twice, the unit is not a unit, or the expression is
            not valid.
        """
        if name in self.outputs:
            raise ModelError(f"{self.name}: output '{name}' declared twice")
        _check_unit(self.name, f"output '{name}'", unit)
        if isinstance(expr, str):
            endpoint, _, what = expr.rpartition(".")
            if what not in ("e", "f", "q", "p") or not endpoint:
                raise ModelError(f"{self.name}: output '{name}': write 'element.e', '.f', '.q' or '.p', got {expr!r}")
            expr = self._quantity(what, endpoint)
        self.outputs[name] = Output(name, sympify(expr, f"output '{name}'"), unit, doc)

    def parameter_table(self) -> dict[sp.Symbol, float]:
        """The numeric value of every symbolic parameter (declared by the file or by components).

        Returns
        -------
        dict of sympy.Symbol to float
            Parameter symbol -> its current value, in its SI unit.
        """
        table = {d.symbol: float(self.values[d.name]) for d in self.declared if d.symbolic}
        for name, (decl, val) in self.parameters.items():
            table[decl.symbol] = float(self.values.get(name, val))
        return table

    def all_parameters(self) -> dict[str, Parameter]:
        """Every parameter declaration: the model file's and the components'.

        Returns
        -------
        dict of str to Parameter
            Name -> declaration.
        """
        out = {d.name: d for d in self.declared}
        out.update({n: d for n, (d, _) in self.parameters.items()})
        return out

    def storage_elements(self):
        """The storage elements (C, I, C-fields).

        Returns
        -------
        list of Element
            In insertion order.
        """
        return [e for e in self.elements.values() if e.is_storage]

    def _repr_svg_(self) -> str:
        """The bond graph with its power half-arrows (notebook display); the causal strokes
        are drawn by the display of ``bg.assign_causality(model)``."""
        from .drawing import svg

        return svg(self)
