"""The power-conserving junction structure: transformers, gyrators, 0- and 1-junctions.

* TF (ratio n, 20-sim convention): e1 = n·e2,  f2_out = n·f1_in
* GY (ratio r): e1 = r·f2_out,  e2 = r·f1_in
* 0-junction: equal efforts, flows into the junction sum to zero
* 1-junction: equal flows, efforts (power-in signs) sum to zero

None of them has a causal preference; each passes the causality of one port on to the others.
"""

from __future__ import annotations

import sympy as sp

from .base import CausalConflict, Element, sympify


class TwoPort(Element):
    """A two-port with a ratio; ports ``p1`` and ``p2``.

    Subclasses set ``same_causality``: whether both ports set the effort together (gyrator)
    or exactly one does (transformer).  Power is conserved: e1·f1_in + e2·f2_in = 0.

    Parameters
    ----------
    name : str
        The element's name.
    ratio : float or str or sympy.Expr
        The ratio (n of a transformer, r of a gyrator), in the unit that relates the two
        ports' variables.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If the ratio is not a scalar expression.
    """

    symbolic_attrs = ("ratio",)
    same_causality = False

    def __init__(self, name: str, ratio):
        super().__init__(name)
        self.ratio = sympify(ratio, f"{self.kind} '{name}' ratio")

    @property
    def ports(self):
        """The port names, ``("p1", "p2")``."""
        return ("p1", "p2")

    def propagate_causality(self, known):
        """One port's causality fixes the other's: the same (gyrator) or the opposite (transformer).

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
        s1, s2 = known["p1"], known["p2"]
        flip = not self.same_causality
        if s1 is not None and s2 is not None:
            if (s1 != s2) != flip:
                raise CausalConflict(self.name)
            return {}
        if s1 is not None:
            return {"p2": s1 != flip}
        if s2 is not None:
            return {"p1": s2 != flip}
        return {}


class TF(TwoPort):
    """Transformer (lever, gear, amplification): e1 = n·e2, f2 = n·f1 (through power).

    Parameters
    ----------
    name : str
        The element's name.
    ratio : float or str or sympy.Expr
        n, in (unit of e1)/(unit of e2): V/N when p1 is electrical and p2 mechanical.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If the ratio is not a scalar expression.
    """

    kind = "TF"

    def equations(self, ports, eqs):
        """e1 = n·e2 and f2_in = -n·f1_in, solved for the assigned causality.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element records the variables it computes.
        """
        p1, p2, n = ports["p1"], ports["p2"], self.ratio
        if p1.sets_effort:
            p1.set_effort(n * p2.e)
            p2.set_flow_in(-n * p1.f_in)
        else:
            p2.set_effort(p1.e / n)
            p1.set_flow_in(-p2.f_in / n)

    def describe(self):
        """The transformer's law.

        Returns
        -------
        str
            ``"e1 = n·e2,  f2 = n·f1"`` with the ratio written out.
        """
        return f"e1 = {self.ratio}·e2,  f2 = {self.ratio}·f1"


class GY(TwoPort):
    """Gyrator: e1 = r·f2, e2 = r·f1 (through power).

    Parameters
    ----------
    name : str
        The element's name.
    ratio : float or str or sympy.Expr
        r, in (unit of e1)/(unit of f2), e.g. V·s/m (= N/A) for a voice coil.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If the ratio is not a scalar expression.
    """

    kind = "GY"
    same_causality = True

    def equations(self, ports, eqs):
        """e1 = -r·f2_in and e2 = r·f1_in (power-in), solved for the assigned causality.

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element records the variables it computes.
        """
        p1, p2, r = ports["p1"], ports["p2"], self.ratio
        if p1.sets_effort:
            p1.set_effort(-r * p2.f_in)
            p2.set_effort(r * p1.f_in)
        else:
            p2.set_flow_in(-p1.e / r)
            p1.set_flow_in(p2.e / r)

    def describe(self):
        """The gyrator's law.

        Returns
        -------
        str
            ``"e1 = r·f2,  e2 = r·f1"`` with the ratio written out.
        """
        return f"e1 = {self.ratio}·f2,  e2 = {self.ratio}·f1"


class Junction(Element):
    """Junction with any number of bonds (ports are created by bonding).

    One bond, the *strong* one, brings the common variable in; the junction passes it to every
    other bond and computes the strong bond's other variable from the balance.  Subclasses set
    ``common_is_effort``.

    Parameters
    ----------
    name : str
        The junction's name.
    """

    common_is_effort = True

    @property
    def ports(self):
        """No fixed ports: a junction's ports are its bonds."""
        return ()

    def propagate_causality(self, known):
        """Exactly one bond (the strong one) brings the common variable in.

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
        # 0-junction: exactly one port where the junction does not set the effort (it comes in);
        # 1-junction: exactly one port where the junction sets the effort (the flow comes in).
        strong_value = not self.common_is_effort
        n_strong = sum(1 for v in known.values() if v is strong_value)
        unknown = [p for p, v in known.items() if v is None]
        if n_strong > 1 or (n_strong == 0 and not unknown):
            raise CausalConflict(self.name)
        if n_strong == 1:
            return {p: not strong_value for p in unknown}
        if len(unknown) == 1:
            return {unknown[0]: strong_value}
        return {}

    def equations(self, ports, eqs):
        """The common variable passed from the strong bond to the others, and the strong bond's
        other variable from the balance (power-in signs).

        Parameters
        ----------
        ports : mapping of str to Port
            Port name -> its bond variables, sign and causality.
        eqs : EquationBuilder
            Where the element records the variables it computes.
        """
        strong_value = not self.common_is_effort
        (strong,) = [p for p in ports.values() if p.sets_effort is strong_value]
        common = (lambda p: p.e) if self.common_is_effort else (lambda p: p.f)
        summed = (lambda p: p.f) if self.common_is_effort else (lambda p: p.e)
        terms = []
        for p in ports.values():
            if p is strong:
                continue
            eqs.assign(common(p), common(strong), p.origin)
            terms.append(p.sign * summed(p))
        eqs.assign(summed(strong), -strong.sign * sp.Add(*terms), strong.origin)
        eqs.quantity("e" if self.common_is_effort else "f", self.name, common(strong))


class J0(Junction):
    """0-junction: common effort, flows into the junction sum to zero.

    Parameters
    ----------
    name : str
        The junction's name.
    """

    kind = "0"

    def describe(self):
        """The junction's law.

        Returns
        -------
        str
            ``"common effort; Σ f_in = 0"``.
        """
        return "common effort; Σ f_in = 0"


class J1(Junction):
    """1-junction: common flow, efforts (power-in signs) sum to zero.

    Parameters
    ----------
    name : str
        The junction's name.
    """

    kind = "1"
    common_is_effort = False

    def describe(self):
        """The junction's law.

        Returns
        -------
        str
            ``"common flow; Σ e_in = 0"``.
        """
        return "common flow; Σ e_in = 0"
