"""Storage elements: capacitors (C), inertias (I) and multiport capacitors (C-fields).

* C:  e = law(q), dq/dt = f_in        (q: generalized displacement, e.g. charge C or m)
* I:  f_in = law(p), dp/dt = e        (p: generalized momentum, e.g. N·s)
* C-field: e_i = ∂U/∂q_i for an energy U(q_1..q_n), dq_i/dt = f_in,i

Integral causality (the state is integrated) is preferred; a port forced into the other,
*derivative*, causality has no state of its own: its stored quantity follows from the law
inverted, and the deriver expresses its time derivative through the other states.
"""

from __future__ import annotations

from typing import Callable, Sequence

import sympy as sp

from ...support.errors import CausalityError, ModelError
from .base import STORAGE, E, Element, F, P, Q, invert, law, sympify


class _OnePortStorage(Element):
    """A one-port storage element: ``law`` maps the stored quantity (placeholder ``_var``)
    to the port variable it sets in integral causality."""

    is_storage = True
    causal_class = STORAGE
    _var: sp.Symbol  # placeholder of the stored quantity (Q or P)
    _value: sp.Symbol  # placeholder of the port variable the law gives (E or F)
    _state: str  # "q" or "p"
    _law_gives_effort: bool  # C: the law gives the effort; I: the flow
    _modulus: str  # "capacitance" or "inertia"

    def __init__(self, name, modulus, law_, energy, x0):
        super().__init__(name)
        given = [x is not None for x in (modulus, law_, energy)]
        if sum(given) != 1:
            raise ModelError(
                f"{self.kind} '{name}': give exactly one of {'a' if self.kind == 'C' else 'an'} "
                f"{self._modulus}, law= or energy="
            )
        v = self._var
        if modulus is not None:
            mod = sympify(modulus, f"{self.kind} '{name}' {self._modulus}")
            self.law, self.energy, self.linear_modulus = v / mod, v**2 / (2 * mod), mod
        elif law_ is not None:
            self.law, self.energy, self.linear_modulus = law(law_, v, f"{self.kind} '{name}' law"), None, None
        else:
            self.energy = law(energy, v, f"{self.kind} '{name}' energy")
            self.law, self.linear_modulus = sp.diff(self.energy, v), None
        setattr(self, f"{self._state}0", sympify(x0, f"{self.kind} '{name}' {self._state}0"))

    @property
    def symbolic_attrs(self) -> tuple[str, ...]:
        return ("law", f"{self._state}0", "energy")

    def stored(self, value: sp.Expr) -> sp.Expr | None:
        """The stored quantity for a value of the port variable the law gives (law inverted)."""
        inv = invert(self.law, self._var, self._value)
        return None if inv is None else inv.xreplace({self._value: value})

    def preferred_causality(self, port):
        return self._law_gives_effort

    def allows_causality(self, port, sets_effort):
        return sets_effort == self._law_gives_effort or invert(self.law, self._var, self._value) is not None

    def equations(self, ports, eqs):
        port = ports["p"]
        gives_effort = self._law_gives_effort
        value, rate = (port.e, port.f_in) if gives_effort else (port.f_in, port.e)
        set_value, set_rate = (
            (port.set_effort, port.set_flow_in) if gives_effort else (port.set_flow_in, port.set_effort)
        )
        if port.sets_effort == gives_effort:  # integral causality
            x = eqs.state(f"{self._state}_{self.name}", self._state, getattr(self, f"{self._state}0"), port.origin)
            set_value(self.law.xreplace({self._var: x}))
            eqs.rate(x, rate)
        else:
            x = self.stored(value)
            if x is None:
                raise CausalityError(
                    f"{eqs.model_name}: {self.kind} '{self.name}' is in derivative causality but "
                    f"its law cannot be inverted; make it linear or add a compliance/inertia next "
                    f"to it"
                )
            set_rate(eqs.derivative(f"{'f' if gives_effort else 'e'}_in_{self.name}", x, port.origin))
        eqs.quantity(self._state, port.key, x)

    def describe(self):
        return f"{'e' if self._law_gives_effort else 'f'} = {self.law.xreplace({self._var: sp.Symbol(self._state)})}"


class C(_OnePortStorage):
    """Capacitor (spring, capacitance).  ``C(name, 1e-6)`` is linear e = q/C;
    ``law=lambda q: ...`` gives e(q); ``energy=lambda q: ...`` gives e = dU/dq.
    ``q0`` is the initial displacement."""

    kind = "C"
    _var, _value, _state, _law_gives_effort, _modulus = Q, E, "q", True, "capacitance"

    def __init__(self, name: str, C=None, *, law=None, energy=None, q0=0):
        super().__init__(name, C, law, energy, q0)


class I(_OnePortStorage):
    """Inertia (mass, inductance).  ``I(name, m)`` is linear f = p/m; ``law=lambda p: ...``
    gives f(p); ``energy=lambda p: ...`` gives f = dT/dp.  ``p0`` is the initial momentum."""

    kind = "I"
    _var, _value, _state, _law_gives_effort, _modulus = P, F, "p", False, "inertia"

    def __init__(self, name: str, I=None, *, law=None, energy=None, p0=0):
        super().__init__(name, I, law, energy, p0)


class CField(Element):
    """Multiport capacitor.  Efforts e_i = ∂U/∂q_i for an energy U of the port
    displacements.  Give ``stiffness`` K (e = K·q), ``compliance`` S (q = S·e), or
    ``energy=lambda q: ...`` where ``q`` maps port name → symbol.  ``q0`` maps port
    names to initial displacements."""

    kind = "C-field"
    symbolic_attrs = ("energy_expr", "q0")
    is_storage = True
    causal_class = STORAGE

    def __init__(
        self,
        name: str,
        ports: Sequence[str],
        *,
        stiffness=None,
        compliance=None,
        energy: Callable | None = None,
        q0=None,
    ):
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

    def preferred_causality(self, port):
        return True

    def equations(self, ports, eqs):
        efforts = self.efforts()
        deriv = [pn for pn in self._ports if not ports[pn].sets_effort]
        q = {}
        for pn in self._ports:
            base, origin = f"q_{self.name}.{pn}", ports[pn].origin
            q[pn] = eqs.symbol(base) if pn in deriv else eqs.state(base, "q", self.q0[pn], origin)
        sub = {self.placeholders[pn]: q[pn] for pn in self._ports}
        if deriv:  # dependent displacements from e_i = dU/dq_i on the derivative ports
            residuals = [efforts[pn].xreplace(sub) - ports[pn].e for pn in deriv]
            try:
                A, rhs = sp.linear_eq_to_matrix(residuals, [q[pn] for pn in deriv])
                sol = A.LUsolve(rhs)
            except (sp.matrices.common.NonSquareMatrixError, ValueError, ZeroDivisionError):
                raise CausalityError(
                    f"{eqs.model_name}: ports {', '.join(deriv)} of C-field '{self.name}' are in derivative "
                    f"causality and its law cannot be inverted for them; make the field linear or add "
                    f"compliance"
                ) from None
            for i, pn in enumerate(deriv):
                q[pn] = sp.simplify(sol[i])
                sub[self.placeholders[pn]] = q[pn]
        for pn in self._ports:
            port = ports[pn]
            if pn in deriv:
                port.set_flow_in(eqs.derivative(f"f_in_{self.name}.{pn}", q[pn], port.origin))
            else:
                port.set_effort(efforts[pn].xreplace(sub))
                eqs.rate(q[pn], port.f_in)
            eqs.quantity("q", port.key, q[pn])

    def describe(self):
        named = {v: sp.Symbol(f"q_{k}") for k, v in self.placeholders.items()}
        return f"U = {self.energy_expr.xreplace(named)}"
