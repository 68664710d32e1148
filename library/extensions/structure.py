"""Nonlinear laws of a piezoelectric actuator's own elements, found through the roles its
library components give them: a saturating dipole of a stack (Rodriguez-Fortun et al.,
"General bond graph model for piezoelectric actuators and methodology for experimental
identification", Mechatronics 20 (2010) 303–314: its polarization capacitor) and a stiffness
that softens with the field across the layer (Wood, Steltz & Fearing, "Nonlinear performance
limits for high energy density piezoelectric bending actuators", ICRA 2005).  They are law
terms of the framework (:class:`bondgraph.diagnosis.LawTerm`): fitted on the exact Lur'e
route when the rest of the model is linear.

The generic kinds at the ``stiffness`` and ``damping`` roles (cubic softening of a bender,
Shahabi, Ghafarirad & Taghvaeipour, C. R. Mécanique 347 (2019); amplitude-dependent damping;
friction) are the framework's own; the names below bind them to those roles for callers that
want one kind on one role.
"""

from __future__ import annotations

import numpy as np

from bondgraph.diagnosis import DRIVE, LawTerm, laws
from bondgraph.diagnosis.rewrite import slope


class StiffnessSoftening(laws.Softening):
    """:class:`~bondgraph.diagnosis.laws.Softening` on every element tagged ``stiffness``,
    without the even part: a poled ceramic driven about its poled state softens alike both
    ways, so k3 alone is fitted (one parameter per element, as the piezo benches measured)."""

    role = "stiffness"
    label = "cubic softening of the stiffness elements"
    even_prefix = ""

    @staticmethod
    def term(c, r2, x, a):
        """−k3·q·(q² − r²), the cubic alone.

        Parameters
        ----------
        c : sympy.Expr or float
            k3 ≥ 0, effort per displacement³ (N/m³ for a spring).
        r2 : sympy.Expr or float
            The centring amplitude r², displacement² (m²).
        x : sympy.Expr or numpy.ndarray
            The displacement q.
        a : sympy.Expr or numpy.ndarray or None
            Unused (no partner).

        Returns
        -------
        sympy.Expr or numpy.ndarray
            The term, in effort units (N for a spring).
        """
        return laws.Softening.term((c, 0), r2, x, a)


class NonlinearDamping(laws.NonlinearDamping):
    """:class:`~bondgraph.diagnosis.laws.NonlinearDamping` on every element tagged ``damping``."""

    role = "damping"

    def __init__(self, velocity: bool = False):
        super().__init__(None, velocity=velocity)
        self.label = (
            "velocity-cubic damping of the damping elements"
            if velocity
            else "amplitude-dependent (Stanton) damping of the damping elements"
        )


class FrictionDamping(laws.Friction):
    """:class:`~bondgraph.diagnosis.laws.Friction` on every element tagged ``damping``."""

    role = "damping"
    label = "Coulomb friction (smoothed) in the damping elements"


class PolarizationSaturation(LawTerm):
    """A polarization that saturates inside the dynamics: every element tagged ``polarization``
    (a layer's dipole capacitance, E = k_x·p) gets a hardening term, E = law(p) + k·p·(p^m − r)
    (m = 2, a cubic, or m = 4, a quintic: the sharper knee; the better fit is kept) with
    r = ⟨p^m⟩·(1.5 or 5/3) of the current model, the describing-function value under a sine, so
    the slope at the data's amplitude stays the calibrated one and k (≥ 0) makes the dipole
    grow less than linearly with the field across the layer.  That field is the drive less the
    series resistance's drop and the mechanics' back-coupling, so near a resonance, or behind a
    slow input stage, the curve acts on another signal than the drive: a drive-side curve
    (:class:`InputSaturation`) cannot follow it there.  Only for models with at most
    :attr:`most` such elements (one coefficient each: a stack of many layers is left to the
    drive-side curve)."""

    cause = "saturation"
    label = "saturating polarization inside the dynamics"
    role, prefix, upper = "polarization", "sat.k", 3.0
    grid = (0.01, 0.03, 0.1, 0.3, 1.0)
    cost = 4  # two shapes, each a fit on the exact route
    #: the most elements tagged ``polarization`` it is fitted on
    most = 2
    #: the powers m tried (the better fit is kept)
    powers = (2, 4)

    def __init__(self, power: int | None = None):
        super().__init__()
        self.power = power
        if power is not None:
            self.prefix = f"sat.k{power + 1}"

    def applies(self, view):
        n = len(view.current.model.with_role(self.role))
        if n > self.most:
            return f"{n} elements are tagged '{self.role}' (one coefficient each; at most {self.most})"
        return super().applies(view)

    def term(self, c, r, x, a):
        return c * x * (x**self.power - r)

    def refs(self, view, el, x, a):
        peak = float(np.max(np.abs(x))) or 1.0
        return (
            abs(slope(view.current.model, el, view.current.values)) / peak**self.power,
            (1.5 if self.power == 2 else 5 / 3) * float(np.mean(x**self.power)),
        )

    def screen(self, view):
        if self.power is not None:
            return super().screen(view)
        shares = [PolarizationSaturation(m).screen(view) for m in self.powers]
        return None if any(s is None for s in shares) else max(shares, key=lambda f: f.share)

    def fit(self, view):
        if self.power is not None:
            return super().fit(view)
        fits = [PolarizationSaturation(m).fit(view) for m in self.powers]
        return min(fits, key=lambda ext: view.score(ext.prediction)[2])


class FieldStiffness(LawTerm):
    """Field-dependent stiffness: the stiffness of a piezoelectric layer softens with the field
    across it (the bender's k_a(E), Wood, Steltz & Fearing, ICRA 2005, Sec. III-B): every element tagged
    ``stiffness`` gets e = law(q) − k_E·q·(d² − r²), d the drive as the linear core sees it,
    r² = ⟨d²⟩ of the record, so that the stiffness at the record's mean-square field stays the
    calibrated one and k_E (≥ 0) softens it where the field is larger (even in the field: either
    polarity softens).  Inside the dynamics: near a resonance it moves the resonance with the
    drive's level, which a drive-side curve (a quasi-static k_a(E)) cannot."""

    cause = "softening"
    label = "field-dependent stiffness of the stiffness elements"
    role, prefix, upper = "stiffness", "soft.kE", 0.5
    grid = (0.003, 0.01, 0.03, 0.1, 0.3)

    def partner(self, model, el):
        return DRIVE

    @staticmethod
    def term(c, r2, x, a):
        return -c * x * (a**2 - r2)

    def refs(self, view, el, x, a):
        peak = float(np.max(np.abs(a))) or 1.0
        return abs(slope(view.current.model, el, view.current.values)) / peak**2, float(np.mean(a**2))
