"""The element protocol: what causality assignment and equation derivation ask of every element.

Neither :mod:`bondgraph.equations.causality` nor :mod:`bondgraph.equations` asks an element for its class;
each element answers a few questions about itself (the pattern of ``to_loads()`` in
sympy.physics.mechanics).  A new kind of element is a subclass of :class:`Element` that answers
them; it works with the whole pipeline (SCAP, equations, printouts, simulation, linearisation)
without a framework edit.

Causality (SCAP, see :mod:`bondgraph.equations.causality`), per port, in power-in terms: does the element
*set the effort* on the port (then the flow is its input), or does it take the effort in?

``causal_class``
    When SCAP decides the element's free ports: :data:`FIXED` (no choice, e.g. a source),
    :data:`STORAGE` (integral causality preferred; the other causality is *derivative*),
    :data:`DISSIPATION` (a preference only), :data:`RELAY` (no preference: it only passes
    constraints on, e.g. junctions and transformers).
``preferred_causality(port) -> bool | None``
    True if the element prefers to set the effort on ``port``; None for no preference.
``allows_causality(port, sets_effort) -> bool``
    Whether the element can work in that causality (e.g. a law that cannot be inverted).
``propagate_causality(known) -> dict``
    Given the causality known on some ports (port name → bool, None if unknown), the
    causality this forces on others; raise :class:`CausalConflict` if ``known`` is impossible.

Equations (see :mod:`bondgraph.equations`):

``equations(ports, eqs)``
    Write the constitutive relations for the assigned causality.  ``ports`` maps port name →
    :class:`Port` (bond variables, sign, causality); ``eqs`` is an :class:`EquationBuilder`
    with which the element declares its states, their rates, and the variables it computes.
``describe() -> str``
    One-line constitutive relation for printouts.

Sign convention: every port uses the *power-in* convention (the flow into the element is
``port.f_in``; efforts are never sign-flipped).
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod
from functools import lru_cache
from typing import Mapping, Protocol

import sympy as sp

from ...support.errors import ModelError

#: placeholder symbols in stored laws, replaced by the port's variables when equations are built
Q, P, E, F = (sp.Dummy("q"), sp.Dummy("p"), sp.Dummy("e"), sp.Dummy("f"))

ONE_PORT = ("p",)

#: causal classes, in the order SCAP decides free ports
FIXED, STORAGE, DISSIPATION, RELAY = range(4)


class CausalConflict(Exception):
    """Raised by :meth:`Element.propagate_causality` when the known causality is impossible."""


def sympify(value, what: str) -> sp.Expr:
    """A number, string or sympy expression as a scalar sympy expression.

    Parameters
    ----------
    value : object
        A number, an expression string (``"k/2"``) or a sympy expression.
    what : str
        What the value is, named in the error message (``"C 'k' capacitance"``).

    Returns
    -------
    sympy.Expr
        The scalar expression.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If ``value`` cannot be read as a scalar expression.
    """
    try:
        expr = sp.sympify(value)
    except (sp.SympifyError, TypeError):
        raise ModelError(f"{what}: cannot use {value!r} as a number or expression") from None
    if not isinstance(expr, sp.Expr):
        raise ModelError(f"{what}: {value!r} is not a scalar expression")
    return expr


def law(fn_or_expr, placeholder: sp.Symbol, what: str) -> sp.Expr:
    """A constitutive law given as an expression or as a callable of the placeholder symbol.

    Parameters
    ----------
    fn_or_expr : callable or sympy.Expr or number
        The law: ``lambda q: q / Cp`` is called with ``placeholder``; an expression is
        taken as it is (written in the placeholder).
    placeholder : sympy.Symbol
        The symbol of the law's argument (:data:`Q`, :data:`P`, :data:`E` or :data:`F`).
    what : str
        What the law is, named in the error message.

    Returns
    -------
    sympy.Expr
        The law as an expression of ``placeholder``.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If the law does not give a scalar expression.
    """
    if callable(fn_or_expr) and not isinstance(fn_or_expr, sp.Basic):
        return sympify(fn_or_expr(placeholder), what)
    return sympify(fn_or_expr, what)


@lru_cache(maxsize=4096)
def invert(expr: sp.Expr, var: sp.Symbol, value: sp.Expr) -> sp.Expr | None:
    """Solve ``expr(var) = value`` for ``var`` (a law inverted).

    Parameters
    ----------
    expr : sympy.Expr
        The law, an expression of ``var``.
    var : sympy.Symbol
        The unknown.
    value : sympy.Expr
        The law's value.

    Returns
    -------
    sympy.Expr or None
        ``var`` as an expression of ``value``; None unless sympy finds exactly one solution.
    """
    if expr.is_polynomial(var) and sp.degree(expr, var) == 1:
        a = sp.diff(expr, var)
        return sp.cancel((value - expr.subs(var, 0)) / a)
    try:
        sols = sp.solve(sp.Eq(expr, value), var)
    except NotImplementedError:
        return None
    return sols[0] if len(sols) == 1 else None


class EquationBuilder(Protocol):
    """What an element may do in :meth:`Element.equations` (implemented by the deriver).

    A protocol: elements call its methods, the deriver of
    :mod:`bondgraph.equations.derivation` implements them.  ``model_name`` names the model
    in error messages.
    """

    model_name: str

    def assign(self, var: sp.Symbol, expr: sp.Expr, origin: str) -> None:
        """Record ``var = expr``: every bond variable is computed exactly once, by one element.

        Parameters
        ----------
        var : sympy.Symbol
            The variable computed (a bond effort or flow).
        expr : sympy.Expr
            Its value, in program variables, states, inputs and parameters.
        origin : str
            The element (and port) that computes it, for printouts and error messages.
        """

    def symbol(self, base: str) -> sp.Symbol:
        """A fresh real symbol.

        Parameters
        ----------
        base : str
            The name wanted; a suffix makes it unique in the model.

        Returns
        -------
        sympy.Symbol
            The new symbol.
        """

    def state(self, base: str, kind: str, x0: sp.Expr, origin: str) -> sp.Symbol:
        """Declare a new state variable.

        Parameters
        ----------
        base : str
            The state's name (made unique).
        kind : {"q", "p", "z"}
            ``q`` a generalized displacement (charge in C, position in m), ``p`` a momentum
            (N·s, V·s), ``z`` another internal state.
        x0 : sympy.Expr
            The initial value, in the state's unit.
        origin : str
            The element that owns the state.

        Returns
        -------
        sympy.Symbol
            The state's symbol; give its rate with :meth:`rate`.
        """

    def rate(self, state: sp.Symbol, expr: sp.Expr) -> None:
        """Give a state's time derivative, d(state)/dt = expr.

        Parameters
        ----------
        state : sympy.Symbol
            A state declared by :meth:`state`.
        expr : sympy.Expr
            Its rate, in the state's unit per s.
        """

    def derivative(self, base: str, stored: sp.Expr, origin: str) -> sp.Symbol:
        """A symbol for d(stored)/dt of a storage port in derivative causality.

        Parameters
        ----------
        base : str
            The symbol's name (made unique).
        stored : sympy.Expr
            The stored quantity, an algebraic function of states and inputs.
        origin : str
            The element (and port) it belongs to.

        Returns
        -------
        sympy.Symbol
            The symbol; the deriver solves for its value.
        """

    def quantity(self, what: str, key: str, expr: sp.Expr) -> None:
        """Give the value of a port quantity that user expressions (outputs) may name.

        Parameters
        ----------
        what : {"e", "f", "q", "p"}
            Effort, flow, displacement or momentum.
        key : str
            The endpoint (``elem`` or ``elem.port``).
        expr : sympy.Expr
            Its value.
        """


class Port:
    """One port of an element during equation derivation.

    Parameters
    ----------
    name : str
        The port's name in its element (``"p"`` for one-ports).
    key : str
        The port's name in user expressions: ``elem`` for one-ports and junctions,
        ``elem.port`` otherwise.
    e, f : sympy.Symbol
        The bond's effort and flow symbols (flow oriented by the half-arrow).
    sign : int
        +1 where the bond's half-arrow points into the element, else -1, so the power-in
        flow is ``f_in = sign·f`` and the power into the element is ``e·f_in``.
    sets_effort : bool
        The assigned causality: True if the element sets the effort on this port.
    origin : str
        The element (and port), for printouts and error messages.
    eqs : EquationBuilder
        The deriver the port's ``set_*`` methods record into.
    """

    __slots__ = ("name", "key", "e", "f", "sign", "sets_effort", "origin", "_eqs", "_f_in")

    def __init__(self, name, key, e, f, sign, sets_effort, origin, eqs: EquationBuilder):
        self.name, self.key, self.e, self.f, self.sign = name, key, e, f, sign
        self.sets_effort, self.origin, self._eqs = sets_effort, origin, eqs
        self._f_in = None

    @property
    def f_in(self) -> sp.Expr:
        """Flow into the element (power-in convention)."""
        if self._f_in is None:
            self._f_in = self.sign * self.f
        return self._f_in

    def set_effort(self, expr) -> None:
        """Set the bond effort (efforts are never sign-flipped).

        Parameters
        ----------
        expr : sympy.Expr
            The effort's value (V, N, ...).
        """
        self._eqs.assign(self.e, expr, self.origin)

    def set_flow(self, expr) -> None:
        """Set the bond flow as oriented by the half-arrow.

        Parameters
        ----------
        expr : sympy.Expr
            The flow's value (A, m/s, ...), positive from the half-arrow's tail to its head.
        """
        self._eqs.assign(self.f, expr, self.origin)

    def set_flow_in(self, expr) -> None:
        """Set the flow into the element (power-in convention).

        Parameters
        ----------
        expr : sympy.Expr
            The flow into the element; the bond flow becomes ``sign·expr``.
        """
        self._eqs.assign(self.f, self.sign * expr, self.origin)


class Element(ABC):
    """Base class: a named element with named ports; subclasses implement the protocol above.

    Parameters
    ----------
    name : str
        The element's name: a non-empty word without spaces or punctuation.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If the name is not such a word.
    """

    kind = "element"
    #: names of attributes holding sympy expressions (substituted on rename/extension)
    symbolic_attrs: tuple[str, ...] = ()
    #: storage elements hold a state per port in integral causality (C, I, C-field)
    is_storage = False
    #: what the element stands for in the physics ("stiffness", "damping", ...); see Component.tag
    role: str | None = None
    #: when SCAP decides the element's free ports (FIXED, STORAGE, DISSIPATION, RELAY)
    causal_class = RELAY

    def __init__(self, name: str):
        if not isinstance(name, str) or not name or any(c in name for c in " ,=()[]"):
            raise ModelError(f"element name {name!r} must be a non-empty word without spaces or punctuation")
        self.name = name

    @property
    def ports(self) -> tuple[str, ...]:
        """The port names, ``("p",)`` for a one-port."""
        return ONE_PORT

    # ---- causality ---------------------------------------------------------------------------
    def preferred_causality(self, port: str) -> bool | None:
        """The causality the element prefers on a port.

        Parameters
        ----------
        port : str
            A port name.

        Returns
        -------
        bool or None
            True: prefers to set the effort on ``port``; False: prefers to take it; None: no
            preference.
        """
        return None

    def allows_causality(self, port: str, sets_effort: bool) -> bool:
        """Whether the element can work in a causality.

        Parameters
        ----------
        port : str
            A port name.
        sets_effort : bool
            The causality asked about: True if the element would set the effort.

        Returns
        -------
        bool
            False if the element cannot (e.g. a law that cannot be inverted).
        """
        return True

    def propagate_causality(self, known: Mapping[str, bool | None]) -> dict[str, bool]:
        """The causality forced on other ports by the known ones.

        Parameters
        ----------
        known : mapping of str to bool or None
            Port name -> True if the element sets the effort there, False if not, None if
            not yet known.

        Returns
        -------
        dict of str to bool
            The ports whose causality follows, with that causality.

        Raises
        ------
        CausalConflict
            If ``known`` is impossible for the element.
        """
        return {}

    # ---- equations ---------------------------------------------------------------------------
    @abstractmethod
    def equations(self, ports: Mapping[str, Port], eqs: EquationBuilder) -> None:
        """Write the constitutive relations for the assigned causality.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element declares its states, their rates and the variables it computes.
        """

    def describe(self) -> str:
        """The constitutive relation, for printouts.

        Returns
        -------
        str
            One line in the element's own variables (``"e = q/Cp"``).
        """
        return self.kind

    # ---- symbols -----------------------------------------------------------------------------
    def renamed(self, name: str) -> "Element":
        """A copy under another name (when a component's elements are prefixed).

        Parameters
        ----------
        name : str
            The new name.

        Returns
        -------
        Element
            A shallow copy with ``name`` changed.
        """
        new = copy.copy(self)
        new.name = name
        return new

    def xreplace(self, mapping) -> "Element":
        """A copy with symbols replaced in every symbolic attribute.

        Parameters
        ----------
        mapping : dict of sympy.Symbol to sympy.Expr
            As for :meth:`sympy.Basic.xreplace` (e.g. a parameter's symbol -> its prefixed one).

        Returns
        -------
        Element
            The copy.
        """
        new = copy.copy(self)
        for attr in self.symbolic_attrs:
            val = getattr(self, attr)
            if isinstance(val, dict):
                setattr(new, attr, {k: v.xreplace(mapping) for k, v in val.items()})
            elif val is not None:
                setattr(new, attr, val.xreplace(mapping))
        return new

    def free_symbols(self) -> set:
        """The symbols the element's laws and initial values use (parameters, inputs).

        Returns
        -------
        set of sympy.Symbol
            Without the law placeholders.
        """
        out = set()
        for attr in self.symbolic_attrs:
            val = getattr(self, attr)
            vals = val.values() if isinstance(val, dict) else [val]
            for v in vals:
                if v is not None:
                    out |= v.free_symbols
        return out - {Q, P, E, F}

    def __repr__(self):
        return f"{self.kind}({self.name!r})"
