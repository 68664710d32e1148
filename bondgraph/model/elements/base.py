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
    try:
        expr = sp.sympify(value)
    except (sp.SympifyError, TypeError):
        raise ModelError(f"{what}: cannot use {value!r} as a number or expression") from None
    if not isinstance(expr, sp.Expr):
        raise ModelError(f"{what}: {value!r} is not a scalar expression")
    return expr


def law(fn_or_expr, placeholder: sp.Symbol, what: str) -> sp.Expr:
    """A law given as an expression or as a callable of the placeholder symbol."""
    if callable(fn_or_expr) and not isinstance(fn_or_expr, sp.Basic):
        return sympify(fn_or_expr(placeholder), what)
    return sympify(fn_or_expr, what)


@lru_cache(maxsize=4096)
def invert(expr: sp.Expr, var: sp.Symbol, value: sp.Expr) -> sp.Expr | None:
    """``var`` such that ``expr(var) = value``; None unless sympy finds exactly one solution."""
    if expr.is_polynomial(var) and sp.degree(expr, var) == 1:
        a = sp.diff(expr, var)
        return sp.cancel((value - expr.subs(var, 0)) / a)
    try:
        sols = sp.solve(sp.Eq(expr, value), var)
    except NotImplementedError:
        return None
    return sols[0] if len(sols) == 1 else None


class EquationBuilder(Protocol):
    """What an element may do in :meth:`Element.equations` (implemented by the deriver)."""

    model_name: str

    def assign(self, var: sp.Symbol, expr: sp.Expr, origin: str) -> None:
        """``var = expr``: every bond variable is computed exactly once, by one element."""

    def symbol(self, base: str) -> sp.Symbol:
        """A fresh real symbol named ``base`` (made unique)."""

    def state(self, base: str, kind: str, x0: sp.Expr, origin: str) -> sp.Symbol:
        """A new state (``kind``: ``q`` displacement, ``p`` momentum, ``z`` other), initial value ``x0``."""

    def rate(self, state: sp.Symbol, expr: sp.Expr) -> None:
        """d(state)/dt = expr."""

    def derivative(self, base: str, stored: sp.Expr, origin: str) -> sp.Symbol:
        """A symbol for d(stored)/dt, where ``stored`` is an algebraic function of states and
        inputs (a storage port in derivative causality); the deriver solves for it."""

    def quantity(self, what: str, key: str, expr: sp.Expr) -> None:
        """The value of port quantity ``what`` (e, f, q, p) of endpoint ``key`` in user expressions."""


class Port:
    """One port of an element during equation derivation.

    ``e`` and ``f`` are the bond's effort and flow symbols; ``sign`` is +1 where the bond's
    half-arrow points into the element, else -1, so the power-in flow is ``f_in = sign·f``;
    ``sets_effort`` is the assigned causality; ``key`` names the port in user expressions
    (``elem`` for one-ports and junctions, ``elem.port`` otherwise)."""

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
        self._eqs.assign(self.e, expr, self.origin)

    def set_flow(self, expr) -> None:
        """Set the bond flow (as oriented by the half-arrow)."""
        self._eqs.assign(self.f, expr, self.origin)

    def set_flow_in(self, expr) -> None:
        """Set the flow into the element."""
        self._eqs.assign(self.f, self.sign * expr, self.origin)


class Element(ABC):
    """Base class: a named element with named ports; subclasses implement the protocol above."""

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
        return ONE_PORT

    # ---- causality ---------------------------------------------------------------------------
    def preferred_causality(self, port: str) -> bool | None:
        """True: prefers to set the effort on ``port``; False: prefers to take it; None: no preference."""
        return None

    def allows_causality(self, port: str, sets_effort: bool) -> bool:
        """Whether the element can work with ``sets_effort`` on ``port``."""
        return True

    def propagate_causality(self, known: Mapping[str, bool | None]) -> dict[str, bool]:
        """Causality forced on other ports by the ``known`` ones; CausalConflict if impossible."""
        return {}

    # ---- equations ---------------------------------------------------------------------------
    @abstractmethod
    def equations(self, ports: Mapping[str, Port], eqs: EquationBuilder) -> None:
        """Constitutive relations for the assigned causality (see the module docstring)."""

    def describe(self) -> str:
        """One-line constitutive relation in the element's own variables."""
        return self.kind

    # ---- symbols -----------------------------------------------------------------------------
    def renamed(self, name: str) -> "Element":
        new = copy.copy(self)
        new.name = name
        return new

    def xreplace(self, mapping) -> "Element":
        new = copy.copy(self)
        for attr in self.symbolic_attrs:
            val = getattr(self, attr)
            if isinstance(val, dict):
                setattr(new, attr, {k: v.xreplace(mapping) for k, v in val.items()})
            elif val is not None:
                setattr(new, attr, val.xreplace(mapping))
        return new

    def free_symbols(self) -> set:
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
