"""Sources: an effort or a flow imposed on a bond (modulated when it depends on inputs)."""
from __future__ import annotations

from .base import FIXED, Element, sympify


class Se(Element):
    """Effort source: e = effort."""

    kind = "Se"
    symbolic_attrs = ("effort",)
    causal_class = FIXED

    def __init__(self, name: str, effort=0):
        super().__init__(name)
        self.effort = sympify(effort, f"Se '{name}' effort")

    def preferred_causality(self, port):
        return True

    def allows_causality(self, port, sets_effort):
        return sets_effort

    def equations(self, ports, eqs):
        ports["p"].set_effort(self.effort)

    def describe(self):
        return f"e = {self.effort}"


class Sf(Element):
    """Flow source: f_out = flow (flow delivered by the source along its bond)."""

    kind = "Sf"
    symbolic_attrs = ("flow",)
    causal_class = FIXED

    def __init__(self, name: str, flow=0):
        super().__init__(name)
        self.flow = sympify(flow, f"Sf '{name}' flow")

    def preferred_causality(self, port):
        return False

    def allows_causality(self, port, sets_effort):
        return not sets_effort

    def equations(self, ports, eqs):
        ports["p"].set_flow_in(-self.flow)

    def describe(self):
        return f"f = {self.flow}"
