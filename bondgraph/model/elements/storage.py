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
        """The attributes holding sympy expressions: the law, the initial value, the energy."""
        return ("law", f"{self._state}0", "energy")

    def stored(self, value: sp.Expr) -> sp.Expr | None:
        """The stored quantity for a value of the port variable the law gives (law inverted).

        Parameters
        ----------
        value : sympy.Expr
            The effort (for C) or flow (for I) on the port.

        Returns
        -------
        sympy.Expr or None
            The displacement q (C) or momentum p (I) that gives it; None if the law cannot
            be inverted.
        """
        inv = invert(self.law, self._var, self._value)
        return None if inv is None else inv.xreplace({self._value: value})

    def preferred_causality(self, port):
        """Integral causality: a C prefers to set the effort, an I to take it.

        Parameters
        ----------
        port : str
            The port, ``"p"``.

        Returns
        -------
        bool
            True for C, False for I.
        """
        return self._law_gives_effort

    def allows_causality(self, port, sets_effort):
        """Integral causality always; derivative causality only when the law can be inverted.

        Parameters
        ----------
        port : str
            The port, ``"p"``.
        sets_effort : bool
            The causality asked about.

        Returns
        -------
        bool
            Whether the element can work in it.
        """
        return sets_effort == self._law_gives_effort or invert(self.law, self._var, self._value) is not None

    def equations(self, ports, eqs):
        """In integral causality a state (q or p) with rate f_in (C) or e (I) and the law
        setting the port variable; in derivative causality the stored quantity from the law
        inverted and its time derivative.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element declares its states, their rates and the variables it computes.

        Raises
        ------
        bondgraph.support.errors.CausalityError
            If the port is in derivative causality and the law cannot be inverted.
        """
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
        """The law in the element's own variable.

        Returns
        -------
        str
            ``"e = q/C"`` for a C, ``"f = p/m"`` for an I.
        """
        return f"{'e' if self._law_gives_effort else 'f'} = {self.law.xreplace({self._var: sp.Symbol(self._state)})}"


class C(_OnePortStorage):
    """Capacitor (spring, capacitance): e = law(q), dq/dt = f_in (power-in).

    Give exactly one of ``C``, ``law`` and ``energy``.

    Parameters
    ----------
    name : str
        The element's name.
    C : float or str or sympy.Expr, optional
        The capacitance of a linear element, e = q/C: in F for a capacitor (q in C, e in V),
        in m/N (a compliance) for a spring (q in m, e in N).
    law : callable or sympy.Expr, optional
        The effort as a function of the displacement, ``law=lambda q: ...``.
    energy : callable or sympy.Expr, optional
        The stored energy U(q) in J, ``energy=lambda q: ...``; the effort is e = dU/dq.
    q0 : float or str or sympy.Expr, optional
        The initial displacement (C or m), 0 by default.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If not exactly one of ``C``, ``law`` and ``energy`` is given, or a value is not a
        scalar expression.
    """

    kind = "C"
    _var, _value, _state, _law_gives_effort, _modulus = Q, E, "q", True, "capacitance"

    def __init__(self, name: str, C=None, *, law=None, energy=None, q0=0):
        super().__init__(name, C, law, energy, q0)


class I(_OnePortStorage):
    """Inertia (mass, inductance): f_in = law(p), dp/dt = e (power-in).

    Give exactly one of ``I``, ``law`` and ``energy``.

    Parameters
    ----------
    name : str
        The element's name.
    I : float or str or sympy.Expr, optional
        The inertia of a linear element, f = p/I: a mass in kg (p in N·s, f in m/s) or an
        inductance in H (p in V·s, f in A).
    law : callable or sympy.Expr, optional
        The flow as a function of the momentum, ``law=lambda p: ...``.
    energy : callable or sympy.Expr, optional
        The kinetic energy T(p) in J, ``energy=lambda p: ...``; the flow is f = dT/dp.
    p0 : float or str or sympy.Expr, optional
        The initial momentum (N·s or V·s), 0 by default.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If not exactly one of ``I``, ``law`` and ``energy`` is given, or a value is not a
        scalar expression.
    """

    kind = "I"
    _var, _value, _state, _law_gives_effort, _modulus = P, F, "p", False, "inertia"

    def __init__(self, name: str, I=None, *, law=None, energy=None, p0=0):
        super().__init__(name, I, law, energy, p0)


class CField(Element):
    """Multiport capacitor: efforts e_i = ∂U/∂q_i for an energy U of the port displacements,
    dq_i/dt = f_in,i (power-in at every port).

    Give exactly one of ``stiffness``, ``compliance`` and ``energy``.  A piezoelectric
    transducer is a two-port C-field of charge (C) and displacement (m).

    Parameters
    ----------
    name : str
        The element's name.
    ports : sequence of str
        Two or more distinct port names.
    stiffness : array_like, optional
        The symmetric matrix K with e = K·q (entries in the units effort/displacement of the
        ports, e.g. N/m, V/C, V/m).
    compliance : array_like, optional
        The symmetric matrix S with q = S·e (the inverse of K).
    energy : callable, optional
        ``energy=lambda q: ...`` gives U in J, where ``q`` maps port name -> its
        displacement symbol.
    q0 : mapping of str to float, optional
        Port name -> initial displacement; 0 for ports not named.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If fewer than two or repeated port names are given, not exactly one of the laws, a
        matrix of the wrong shape or not symmetric, or ``q0`` names an unknown port.
    """

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
        """The port names, in the order of the matrix rows."""
        return self._ports

    def efforts(self) -> dict[str, sp.Expr]:
        """The efforts as functions of the displacements.

        Returns
        -------
        dict of str to sympy.Expr
            Port name -> e_i = ∂U/∂q_i, in the placeholder symbols ``self.placeholders``.
        """
        return {pn: sp.diff(self.energy_expr, self.placeholders[pn]) for pn in self._ports}

    def stiffness_matrix(self) -> sp.Matrix:
        """The Hessian of the energy, ∂²U/∂q_i∂q_j (the matrix K of a linear field).

        Returns
        -------
        sympy.Matrix
            n x n in port order, in the placeholder symbols for a nonlinear field.
        """
        qs = [self.placeholders[pn] for pn in self._ports]
        return sp.hessian(self.energy_expr, qs)

    def free_symbols(self):
        """The symbols of the energy and initial values, without the placeholders.

        Returns
        -------
        set of sympy.Symbol
            Parameters and inputs the field uses.
        """
        return super().free_symbols() - set(self.placeholders.values())

    def preferred_causality(self, port):
        """Integral causality: the field prefers to set the effort on every port.

        Parameters
        ----------
        port : str
            A port name.

        Returns
        -------
        bool
            True.
        """
        return True

    def equations(self, ports, eqs):
        """A state q_i per port in integral causality with e_i = ∂U/∂q_i; the displacements of
        ports in derivative causality solved from their given efforts.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element declares its states, their rates and the variables it computes.

        Raises
        ------
        bondgraph.support.errors.CausalityError
            If ports are in derivative causality and the field cannot be solved for them.
        """
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
        """The field's energy.

        Returns
        -------
        str
            ``"U = ..."`` in the port displacements ``q_<port>``.
        """
        named = {v: sp.Symbol(f"q_{k}") for k, v in self.placeholders.items()}
        return f"U = {self.energy_expr.xreplace(named)}"
