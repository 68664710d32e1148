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
        """The source's fixed causality.

        Parameters
        ----------
        port : str
            The port, ``"p"``.

        Returns
        -------
        bool
            True for an effort source, False for a flow source.
        """
        return self.sets_effort

    def allows_causality(self, port, sets_effort):
        """Only the source's fixed causality.

        Parameters
        ----------
        port : str
            The port, ``"p"``.
        sets_effort : bool
            The causality asked about.

        Returns
        -------
        bool
            Whether it is the source's own.
        """
        return sets_effort == self.sets_effort


class Se(_Source):
    """Effort source: e = effort on its bond.

    Parameters
    ----------
    name : str
        The element's name.
    effort : float or str or sympy.Expr, optional
        The imposed effort (V, N, ...): a constant, a parameter or an expression of the
        model's inputs (a modulated source); 0 by default.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If ``effort`` is not a scalar expression.
    """

    kind = "Se"
    symbolic_attrs = ("effort",)

    def __init__(self, name: str, effort=0):
        super().__init__(name, effort)

    def equations(self, ports, eqs):
        """Set the port's effort.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element records the variables it computes.
        """
        ports["p"].set_effort(self.effort)

    def describe(self):
        """The source's law.

        Returns
        -------
        str
            ``"e = ..."``.
        """
        return f"e = {self.effort}"


class Sf(_Source):
    """Flow source: f_out = flow (flow delivered by the source along its bond).

    The flow into the source is ``-flow`` (power-in convention).

    Parameters
    ----------
    name : str
        The element's name.
    flow : float or str or sympy.Expr, optional
        The delivered flow (A, m/s, ...): a constant, a parameter or an expression of the
        model's inputs; 0 by default.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If ``flow`` is not a scalar expression.
    """

    kind = "Sf"
    symbolic_attrs = ("flow",)
    sets_effort = False

    def __init__(self, name: str, flow=0):
        super().__init__(name, flow)

    def equations(self, ports, eqs):
        """Set the port's flow: ``-flow`` into the source.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element records the variables it computes.
        """
        ports["p"].set_flow_in(-self.flow)

    def describe(self):
        """The source's law.

        Returns
        -------
        str
            ``"f = ..."``.
        """
        return f"f = {self.flow}"
