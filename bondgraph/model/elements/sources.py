"""Sources: an effort or a flow imposed on a bond (modulated when it depends on inputs)."""

from __future__ import annotations

from .base import FIXED, Element, sympify


class _Source(Element):
    """A one-port with fixed causality: it sets the effort (``sets_effort``) or the flow."""

    causal_class = FIXED
    sets_effort = True

    def __init__(self, name: str, value):
        super().__init__(name)
        attr = self.symbolic_attrs[0]
        setattr(self, attr, sympify(value, f"{self.kind} '{name}' {attr}"))

    def preferred_causality(self, port):
        return self.sets_effort

    def allows_causality(self, port, sets_effort):
        return sets_effort == self.sets_effort


class Se(_Source):
    """Effort source: e = effort."""

    kind = "Se"
    symbolic_attrs = ("effort",)

    def __init__(self, name: str, effort=0):
        super().__init__(name, effort)

    def equations(self, ports, eqs):
        ports["p"].set_effort(self.effort)

    def describe(self):
        return f"e = {self.effort}"


class Sf(_Source):
    """Flow source: f_out = flow (flow delivered by the source along its bond)."""

    kind = "Sf"
    symbolic_attrs = ("flow",)
    sets_effort = False

    def __init__(self, name: str, flow=0):
        super().__init__(name, flow)

    def equations(self, ports, eqs):
        ports["p"].set_flow_in(-self.flow)

    def describe(self):
        return f"f = {self.flow}"
