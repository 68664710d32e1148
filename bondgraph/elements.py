"""Bond-graph elements: sources, storage, dissipation, two-ports, junctions, C-fields.

Sign convention: every port uses the *power-in* convention.  A bond's half-arrow points in
the direction of positive power; at the element at the arrow's head the flow into the
element equals the bond flow, at its tail it is minus the bond flow.  Efforts are never
sign-flipped.  Laws are written in port (power-in) variables:

* C:  e = law(q), dq/dt = f_in        (q: generalized displacement, e.g. charge C or m)
* I:  f_in = law(p), dp/dt = e        (p: generalized momentum, e.g. N·s)
* R:  e = law(f_in)  or  f_in = law(e)
* TF (ratio n, 20-sim convention): e1 = n·e2,  f2_out = n·f1_in
* GY (ratio r): e1 = r·f2_out,  e2 = r·f1_in
* 0-junction: equal efforts, flows into the junction sum to zero
* 1-junction: equal flows, efforts (power-in signs) sum to zero
* C-field: e_i = ∂U/∂q_i for an energy U(q_1..q_n), dq_i/dt = f_in,i

Laws are given as numbers/sympy expressions (linear) or as Python callables of sympy
symbols (nonlinear); they may use parameters, inputs, internal states and operator outputs.
"""
from __future__ import annotations

import copy
from typing import Callable, Sequence

import sympy as sp

from .errors import ModelError

#: placeholder symbols in stored laws, replaced by the port's variables when equations are built
Q, P, E, F = (sp.Dummy("q"), sp.Dummy("p"), sp.Dummy("e"), sp.Dummy("f"))

ONE_PORT = ("p",)


def sympify(value, what: str) -> sp.Expr:
    try:
        expr = sp.sympify(value)
    except (sp.SympifyError, TypeError):
        raise ModelError(f"{what}: cannot use {value!r} as a number or expression") from None
    if not isinstance(expr, sp.Expr):
        raise ModelError(f"{what}: {value!r} is not a scalar expression")
    return expr


def _law(fn_or_expr, placeholder: sp.Symbol, what: str) -> sp.Expr:
    if callable(fn_or_expr) and not isinstance(fn_or_expr, sp.Basic):
        return sympify(fn_or_expr(placeholder), what)
    return sympify(fn_or_expr, what)


class Element:
    """Base class: a named element with named ports and sympy-valued attributes."""

    kind = "element"
    #: names of attributes holding sympy expressions (substituted on rename/extension)
    symbolic_attrs: tuple[str, ...] = ()
    #: storage elements hold a state per port (C, I, C-field)
    is_storage = False
    #: what the element stands for in the physics ("stiffness", "damping", ...); see Component.tag
    role: str | None = None

    def __init__(self, name: str):
        if not isinstance(name, str) or not name or any(c in name for c in " ,=()[]"):
            raise ModelError(f"element name {name!r} must be a non-empty word without spaces or punctuation")
        self.name = name

    @property
    def ports(self) -> tuple[str, ...]:
        return ONE_PORT

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

    def describe(self) -> str:
        """One-line constitutive relation in the element's own variables."""
        return self.kind

    def __repr__(self):
        return f"{self.kind}({self.name!r})"


class Se(Element):
    """Effort source (modulated when ``effort`` depends on inputs): e = effort."""

    kind = "Se"
    symbolic_attrs = ("effort",)

    def __init__(self, name: str, effort=0):
        super().__init__(name)
        self.effort = sympify(effort, f"Se '{name}' effort")

    def describe(self):
        return f"e = {self.effort}"


class Sf(Element):
    """Flow source: f_out = flow (flow delivered by the source along its bond)."""

    kind = "Sf"
    symbolic_attrs = ("flow",)

    def __init__(self, name: str, flow=0):
        super().__init__(name)
        self.flow = sympify(flow, f"Sf '{name}' flow")

    def describe(self):
        return f"f = {self.flow}"


class C(Element):
    """Capacitor (spring, capacitance).  ``C(name, 1e-6)`` is linear e = q/C;
    ``law=lambda q: ...`` gives e(q); ``energy=lambda q: ...`` gives e = dU/dq.
    ``q0`` is the initial displacement."""

    kind = "C"
    symbolic_attrs = ("law", "q0", "energy")
    is_storage = True

    def __init__(self, name: str, C=None, *, law=None, energy=None, q0=0):
        super().__init__(name)
        given = [x is not None for x in (C, law, energy)]
        if sum(given) != 1:
            raise ModelError(f"C '{name}': give exactly one of a capacitance, law= or energy=")
        if C is not None:
            cap = sympify(C, f"C '{name}' capacitance")
            self.law = Q / cap
            self.energy = Q**2 / (2 * cap)
            self.linear_modulus = cap
        elif law is not None:
            self.law = _law(law, Q, f"C '{name}' law")
            self.energy = None
            self.linear_modulus = None
        else:
            self.energy = _law(energy, Q, f"C '{name}' energy")
            self.law = sp.diff(self.energy, Q)
            self.linear_modulus = None
        self.q0 = sympify(q0, f"C '{name}' q0")

    def describe(self):
        return f"e = {self.law.xreplace({Q: sp.Symbol('q')})}"


class I(Element):
    """Inertia (mass, inductance).  ``I(name, m)`` is linear f = p/m; ``law=lambda p: ...``
    gives f(p); ``energy=lambda p: ...`` gives f = dT/dp.  ``p0`` is the initial momentum."""

    kind = "I"
    symbolic_attrs = ("law", "p0", "energy")
    is_storage = True

    def __init__(self, name: str, I=None, *, law=None, energy=None, p0=0):
        super().__init__(name)
        given = [x is not None for x in (I, law, energy)]
        if sum(given) != 1:
            raise ModelError(f"I '{name}': give exactly one of an inertia, law= or energy=")
        if I is not None:
            ine = sympify(I, f"I '{name}' inertia")
            self.law = P / ine
            self.energy = P**2 / (2 * ine)
            self.linear_modulus = ine
        elif law is not None:
            self.law = _law(law, P, f"I '{name}' law")
            self.energy = None
            self.linear_modulus = None
        else:
            self.energy = _law(energy, P, f"I '{name}' energy")
            self.law = sp.diff(self.energy, P)
            self.linear_modulus = None
        self.p0 = sympify(p0, f"I '{name}' p0")

    def describe(self):
        return f"f = {self.law.xreplace({P: sp.Symbol('p')})}"


class R(Element):
    """Resistor (damper).  ``R(name, c)`` is e = c·f; ``law=lambda f: ...`` gives e(f);
    ``conductance_law=lambda e: ...`` gives f(e)."""

    kind = "R"
    symbolic_attrs = ("law",)

    def __init__(self, name: str, R=None, *, law=None, conductance_law=None):
        super().__init__(name)
        given = [x is not None for x in (R, law, conductance_law)]
        if sum(given) != 1:
            raise ModelError(f"R '{name}': give exactly one of a resistance, law= or conductance_law=")
        if R is not None:
            self.law = sympify(R, f"R '{name}' resistance") * F
            self.form = "resistance"
        elif law is not None:
            self.law = _law(law, F, f"R '{name}' law")
            self.form = "resistance"
        else:
            self.law = _law(conductance_law, E, f"R '{name}' conductance law")
            self.form = "conductance"

    def effort_of_flow(self) -> sp.Expr | None:
        """e(f), inverting a conductance law if sympy can; None if not invertible."""
        return self.law if self.form == "resistance" else _invert(self.law, E, F)

    def flow_of_effort(self) -> sp.Expr | None:
        return self.law if self.form == "conductance" else _invert(self.law, F, E)

    def describe(self):
        if self.form == "resistance":
            return f"e = {self.law.xreplace({F: sp.Symbol('f')})}"
        return f"f = {self.law.xreplace({E: sp.Symbol('e')})}"


def _invert(law: sp.Expr, var: sp.Symbol, new: sp.Symbol) -> sp.Expr | None:
    """Solve new = law(var) for var; None if there is not exactly one real solution."""
    if law.is_polynomial(var) and sp.degree(law, var) == 1:
        a = sp.diff(law, var)
        return (new - law.subs(var, 0)) / a
    try:
        sols = sp.solve(sp.Eq(law, new), var)
    except NotImplementedError:
        return None
    return sols[0] if len(sols) == 1 else None


class TwoPort(Element):
    symbolic_attrs = ("ratio",)

    def __init__(self, name: str, ratio):
        super().__init__(name)
        self.ratio = sympify(ratio, f"{self.kind} '{name}' ratio")

    @property
    def ports(self):
        return ("p1", "p2")


class TF(TwoPort):
    """Transformer (lever, gear, amplification): e1 = n·e2, f2 = n·f1 (through power)."""

    kind = "TF"

    def describe(self):
        return f"e1 = {self.ratio}·e2,  f2 = {self.ratio}·f1"


class GY(TwoPort):
    """Gyrator: e1 = r·f2, e2 = r·f1 (through power)."""

    kind = "GY"

    def describe(self):
        return f"e1 = {self.ratio}·f2,  e2 = {self.ratio}·f1"


class Junction(Element):
    """Junction with any number of bonds (ports are created by bonding)."""

    @property
    def ports(self):
        return ()


class J0(Junction):
    """0-junction (common effort, flows sum to zero)."""

    kind = "0"

    def describe(self):
        return "common effort; Σ f_in = 0"


class J1(Junction):
    """1-junction (common flow, efforts sum to zero)."""

    kind = "1"

    def describe(self):
        return "common flow; Σ e_in = 0"


class CField(Element):
    """Multiport capacitor.  Efforts e_i = ∂U/∂q_i for an energy U of the port
    displacements.  Give ``stiffness`` K (e = K·q), ``compliance`` S (q = S·e), or
    ``energy=lambda q: ...`` where ``q`` maps port name → symbol.  ``q0`` maps port
    names to initial displacements."""

    kind = "C-field"
    symbolic_attrs = ("energy_expr", "q0")
    is_storage = True

    def __init__(self, name: str, ports: Sequence[str], *, stiffness=None, compliance=None,
                 energy: Callable | None = None, q0=None):
        super().__init__(name)
        ports = tuple(ports)
        if len(ports) < 2 or len(set(ports)) != len(ports):
            raise ModelError(f"C-field '{name}' needs two or more distinct port names, got {ports}")
        self._ports = ports
        self.placeholders = {pn: sp.Dummy(f"q_{pn}") for pn in ports}
        qv = sp.Matrix([self.placeholders[pn] for pn in ports])
        n = len(ports)
        given = [x is not None for x in (stiffness, compliance, energy)]
        if sum(given) != 1:
            raise ModelError(f"C-field '{name}': give exactly one of stiffness=, compliance= or energy=")
        if energy is not None:
            self.energy_expr = sympify(energy(dict(self.placeholders)), f"C-field '{name}' energy")
        else:
            mat = sp.Matrix(stiffness if stiffness is not None else compliance)
            if mat.shape != (n, n):
                raise ModelError(f"C-field '{name}': matrix must be {n}x{n} for ports {ports}")
            if (mat - mat.T).applyfunc(sp.simplify) != sp.zeros(n, n):
                raise ModelError(f"C-field '{name}': matrix must be symmetric (a C-field stores energy)")
            if compliance is not None:
                mat = mat.inv()
            self.energy_expr = sp.expand((qv.T * mat * qv)[0, 0] / 2)
        q0 = q0 or {}
        unknown = set(q0) - set(ports)
        if unknown:
            raise ModelError(f"C-field '{name}': q0 names unknown ports {sorted(unknown)}; ports are {ports}")
        self.q0 = {pn: sympify(q0.get(pn, 0), f"C-field '{name}' q0") for pn in ports}

    @property
    def ports(self):
        return self._ports

    def efforts(self) -> dict[str, sp.Expr]:
        """e_i(q) in placeholder symbols."""
        return {pn: sp.diff(self.energy_expr, self.placeholders[pn]) for pn in self._ports}

    def stiffness_matrix(self) -> sp.Matrix:
        qs = [self.placeholders[pn] for pn in self._ports]
        return sp.hessian(self.energy_expr, qs)

    def free_symbols(self):
        return super().free_symbols() - set(self.placeholders.values())

    def describe(self):
        named = {v: sp.Symbol(f"q_{k}") for k, v in self.placeholders.items()}
        return f"U = {self.energy_expr.xreplace(named)}"


STORAGE_KINDS = (C, I, CField)
