"""Resistors (dampers): e = law(f_in) or f_in = law(e); the resistance form is preferred."""

from __future__ import annotations

import sympy as sp

from ...support.errors import CausalityError, ModelError
from .base import DISSIPATION, E, Element, F, invert, law, sympify


class R(Element):
    """Resistor (damper): e = law(f_in) or f_in = law(e); dissipated power e·f_in >= 0 for a
    passive law.

    Give exactly one of ``R``, ``law`` and ``conductance_law``.

    Parameters
    ----------
    name : str
        The element's name.
    R : float or str or sympy.Expr, optional
        The resistance of a linear element, e = R·f: in Ω for a resistor, in N·s/m for a
        damper.
    law : callable or sympy.Expr, optional
        The effort as a function of the flow, ``law=lambda f: ...`` (resistance form).
    conductance_law : callable or sympy.Expr, optional
        The flow as a function of the effort, ``conductance_law=lambda e: ...``.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If not exactly one law is given or it is not a scalar expression.
    """

    kind = "R"
    symbolic_attrs = ("law",)
    causal_class = DISSIPATION

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
        """The effort as a function of the flow, inverting a conductance law if sympy can.

        Returns
        -------
        sympy.Expr or None
            e in the placeholder flow :data:`F`; None if not invertible.
        """
        return self.law if self.form == "resistance" else invert(self.law, E, F)

    def flow_of_effort(self) -> sp.Expr | None:
        """The flow as a function of the effort, inverting a resistance law if sympy can.

        Returns
        -------
        sympy.Expr or None
            f in the placeholder effort :data:`E`; None if not invertible.
        """
        return self.law if self.form == "conductance" else invert(self.law, F, E)

    def preferred_causality(self, port):
        """The law's own form: set the effort for a resistance law, the flow for a conductance law.

        Parameters
        ----------
        port : str
            The port, ``"p"``.

        Returns
        -------
        bool
            True for the resistance form.
        """
        return self.form == "resistance"

    def allows_causality(self, port, sets_effort):
        """Either causality whose law is known or can be inverted.

        Parameters
        ----------
        port : str
            The port, ``"p"``.
        sets_effort : bool
            The causality asked about.

        Returns
        -------
        bool
            Whether the law is available in that form.
        """
        return (self.effort_of_flow() if sets_effort else self.flow_of_effort()) is not None

    def equations(self, ports, eqs):
        """The effort from the flow into the element, or that flow from the effort.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element records the variables it computes.

        Raises
        ------
        bondgraph.support.errors.CausalityError
            If the law cannot be inverted for the assigned causality.
        """
        port = ports["p"]
        if port.sets_effort:
            law_ = self.effort_of_flow()
            if law_ is None:
                raise CausalityError(
                    f"{eqs.model_name}: R '{self.name}' must take flow and give effort, but its "
                    f"law f(e) cannot be inverted; give it as law=lambda f: ... or change the graph"
                )
            port.set_effort(law_.xreplace({F: port.f_in}))
        else:
            law_ = self.flow_of_effort()
            if law_ is None:
                raise CausalityError(
                    f"{eqs.model_name}: R '{self.name}' must take effort and give flow, but its "
                    f"law e(f) cannot be inverted; give it as conductance_law=lambda e: ..."
                )
            port.set_flow_in(law_.xreplace({E: port.e}))

    def describe(self):
        """The law in its own form.

        Returns
        -------
        str
            ``"e = ..."`` (resistance) or ``"f = ..."`` (conductance).
        """
        if self.form == "resistance":
            return f"e = {self.law.xreplace({F: sp.Symbol('f')})}"
        return f"f = {self.law.xreplace({E: sp.Symbol('e')})}"


_law = law  # the constructor's keyword argument of the same name hides the helper
