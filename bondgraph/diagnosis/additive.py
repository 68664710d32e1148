"""The drive the linear core sees, as a sum of effects of one base drive.

Several effects on the drive act side by side rather than one after the other: in a
piezoelectric actuator, hysteresis, creep and saturation are all parts of the polarization
that one field sets.  A chain that names them one at a time and freezes each (creep of the
hysteretic drive, with the hysteresis weights of the step before) credits the second effect
only with what the first one's frozen weights left, and those weights absorbed what they
could of it.  Written as a sum,

    u_eff = [b] + Σ_j w_j · T_j[b]        (b: the base drive, T_j: a named effect's column),

every weight w_j is a parameter of the model, and each later step refits the weights named
before jointly with its own (:meth:`bondgraph.diagnosis.View.fit_drive` with ``names``): the
forward stepwise regression of the effects, each step credited only with what it adds.  An
effect whose weights are not linear (an RC stage on the drive) ends the sum: the drive it
produces is the base of whatever comes after.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
import sympy as sp


@dataclass(frozen=True)
class Term:
    """One column of the sum: its weight is the model parameter ``name``, within
    [``lower``, ``upper``]; ``column`` is the effect's response to the base drive per unit
    weight, in drive units.

    Parameters
    ----------
    name : str
        The model parameter that weighs this column (dimensionless).
    column : numpy.ndarray
        The effect's response to the base drive per unit weight, sampled at the data's
        times, in drive units.
    lower, upper : float, optional
        Bounds of the weight (default unbounded).
    """

    name: str
    column: np.ndarray
    lower: float = -np.inf
    upper: float = np.inf


@dataclass(frozen=True)
class AdditiveDrive:
    """u_eff = identity·base + Σ values[term.name]·term.column (``identity``: the base drive
    itself is one of the terms, with weight 1).

    Parameters
    ----------
    base : numpy.ndarray
        The base drive b sampled at the data's times, in drive units.
    base_expr : sympy.Expr
        The base drive as an expression of the model's inputs.
    identity : bool, optional
        The base drive itself enters the sum with weight 1.
    terms : tuple of Term, optional
        The weighted effect columns.
    """

    base: np.ndarray
    base_expr: sp.Expr
    identity: bool = True
    terms: tuple[Term, ...] = ()

    def series(self, values: Mapping[str, float]) -> np.ndarray:
        """The effective drive u_eff at the given weights.

        Parameters
        ----------
        values : mapping of str to float
            Weight of each term, by its parameter name (every term's name must be there).

        Returns
        -------
        numpy.ndarray
            u_eff sampled at the data's times, in drive units.
        """
        out = np.array(self.base, float) if self.identity else np.zeros(len(self.base))
        for t in self.terms:
            out += float(values[t.name]) * t.column
        return out
