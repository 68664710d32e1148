"""Resistors (dampers): e = law(f_in) or f_in = law(e); the resistance form is preferred."""

from __future__ import annotations

import sympy as sp

from ...support.errors import CausalityError, ModelError
from .base import DISSIPATION, E, Element, F, invert, law, sympify


class R(Element):
    """Resistor (damper).  ``R(name, c)`` is e = c·f; ``law=lambda f: ...`` gives e(f);
    ``conductance_law=lambda e: ...`` gives f(e)."""

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
        """e(f), inverting a conductance law if sympy can; None if not invertible."""
        return self.law if self.form == "resistance" else invert(self.law, E, F)

    def flow_of_effort(self) -> sp.Expr | None:
        """f(e), inverting a resistance law if sympy can; None if not invertible."""
        return self.law if self.form == "conductance" else invert(self.law, F, E)

    def preferred_causality(self, port):
        return self.form == "resistance"

    def allows_causality(self, port, sets_effort):
        return (self.effort_of_flow() if sets_effort else self.flow_of_effort()) is not None

    def equations(self, ports, eqs):
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
        if self.form == "resistance":
            return f"e = {self.law.xreplace({F: sp.Symbol('f')})}"
        return f"f = {self.law.xreplace({E: sp.Symbol('e')})}"


_law = law  # the constructor's keyword argument of the same name hides the helper
