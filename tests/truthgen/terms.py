"""Nonlinear terms (pseudo-inputs ``g`` of :mod:`.system`), each evaluated once per step.

* :class:`FieldCharge` — extra polarization charge from field-domain laws (hysteresis,
  saturation).  The law is implicit, ``Q_x = law(e)`` with the field ``e = Q - C_sum - Q_x``
  (charge units, i.e. field times capacitance), evaluated once per step from the state and
  the previous ``Q_x``.  The stack is voltage-driven, so at the end of a step the charge
  already holds the previous ``Q_x`` and this is the field the source sets.
* :class:`OutputForce` — a force on a moving mass from its displacement (Maxwell-slip friction,
  an end stop).
* :class:`ModalForces` — forces on bimorph modes from the modal state (softening, nonlinear
  damping, drive-dependent stiffness).
"""

from __future__ import annotations

import numpy as np

from .system import Lin


class Term:
    pseudo: tuple = ()
    #: extrapolate the term linearly over a step (forces on lightly damped modes) or hold it
    extrapolate = False

    def bind(self, eq) -> None:
        """Turn the term's Lin combinations into state vectors of ``eq``."""

    def reset(self) -> None:
        """Back to the initial state (before the first step)."""


class FieldLaw:
    """A law ``e -> value``: ``strength * half * (op(u) - op(u_0))``, ``u = (e - centre) / half``
    for a memory operator (zero in the initial, remanent state: the device starts at rest), or
    ``strength * top * deficit(e / top)`` for a static saturating curve."""

    def __init__(self, strength, operator=None, centre=0.0, half=1.0, deficit=None, top=1.0):
        self.strength, self.operator, self.deficit = strength, operator, deficit
        self.centre, self.half, self.top = centre, half, top
        self.origin = None

    def reset(self):
        self.origin = None

    def __call__(self, e):
        if self.operator is not None:
            u = (e - self.centre) / self.half
            if self.origin is None:
                self.operator.start(u)
                self.origin = self.operator(u)
            return self.strength * self.half * (self.operator(u) - self.origin)
        return self.strength * self.top * float(self.deficit(np.asarray(e / self.top)))


class FieldCharge(Term):
    pseudo = ("Qx",)

    def __init__(self, field: Lin, laws):
        self.field, self.laws = field, list(laws)
        self.q = 0.0

    def bind(self, eq):
        self.e_vec = eq.vector(self.field)

    def reset(self):
        self.q = 0.0
        for law in self.laws:
            law.reset()

    def __call__(self, z, v):
        e = float(self.e_vec @ z) - self.q
        self.q = sum(law(e) for law in self.laws)
        return (self.q,)


class OutputForce(Term):
    pseudo = ("Fm",)

    def __init__(self, displacement: Lin, law):
        self.displacement, self.law = displacement, law

    def bind(self, eq):
        self.x_vec = eq.vector(self.displacement)

    def reset(self):
        if hasattr(self.law, "reset"):
            self.law.reset()

    def __call__(self, z, v):
        return (self.law(float(self.x_vec @ z)),)


class ModalForces(Term):
    """Forces on modes ``1..n`` from ``law(q, qd, V) -> forces`` (arrays of length n)."""

    extrapolate = True

    def __init__(self, q: list, qd: list, law):
        self.q, self.qd, self.law = q, qd, law
        self.pseudo = tuple(f"F{i + 1}" for i in range(len(q)))

    def bind(self, eq):
        self.Q = np.vstack([eq.vector(c) for c in self.q])
        self.QD = np.vstack([eq.vector(c) for c in self.qd])

    def reset(self):
        if hasattr(self.law, "reset"):
            self.law.reset()

    def __call__(self, z, v):
        return self.law(self.Q @ z, self.QD @ z, v)
