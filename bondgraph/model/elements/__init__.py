"""Bond-graph elements and the protocol every element answers (see :mod:`.base`).

* :mod:`.base`         the :class:`Element` protocol, :class:`Port`, law helpers
* :mod:`.sources`      Se, Sf
* :mod:`.storage`      C, I, CField
* :mod:`.dissipation`  R
* :mod:`.structure`    TF, GY, J0, J1 (the power-conserving junction structure)

Sign convention: every port uses the *power-in* convention.  A bond's half-arrow points in
the direction of positive power; at the element at the arrow's head the flow into the
element equals the bond flow, at its tail it is minus the bond flow.  Efforts are never
sign-flipped.  Laws are given as numbers/sympy expressions (linear) or as Python callables of
sympy symbols (nonlinear); they may use parameters, inputs, internal states and operator outputs.
"""

from .base import (
    DISSIPATION,
    FIXED,
    ONE_PORT,
    RELAY,
    STORAGE,
    CausalConflict,
    E,
    Element,
    EquationBuilder,
    F,
    P,
    Port,
    Q,
    invert,
    law,
    sympify,
)
from .dissipation import R
from .sources import Se, Sf
from .storage import C, CField, I
from .structure import GY, J0, J1, TF, Junction, TwoPort

__all__ = [
    "Element",
    "Port",
    "EquationBuilder",
    "CausalConflict",
    "FIXED",
    "STORAGE",
    "DISSIPATION",
    "RELAY",
    "Q",
    "P",
    "E",
    "F",
    "ONE_PORT",
    "invert",
    "law",
    "sympify",
    "Se",
    "Sf",
    "C",
    "I",
    "CField",
    "R",
    "TF",
    "GY",
    "J0",
    "J1",
    "Junction",
    "TwoPort",
]
