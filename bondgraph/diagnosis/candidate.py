"""The contract between the diagnosis engine and a candidate cause.

A candidate is a pure object: :meth:`Candidate.fit` receives a read-only
:class:`~bondgraph.diagnosis.view.View` (data, split, current model and its prediction) and
returns an :class:`Extension` (the rewritten model, the fitted values, and, when it computed
it on the way, its prediction).  It changes nothing else; the engine scores, compares and
decides.  Candidates are found through the entry point group ``bondgraph.diagnosis`` (each
entry a callable returning a list of candidates) or passed explicitly.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field

import numpy as np
import sympy as sp

from ..model.graph import Model

#: kinds of cause: a nonlinear or memory effect must beat the flexible linear reference; a
#: linear structural one must beat the full linear recalibration and be physically plausible
NONLINEAR, LINEAR = "nonlinear", "linear"

#: why a drive-side candidate does not apply once the model is no drive transform of its
#: linear core (a cause inside the dynamics was named)
NOT_A_DRIVE = "acts on the drive, and the model is no longer a transform of its drive"


@dataclass
class Extension:
    """What a candidate's fit returns.

    Parameters
    ----------
    model : Model
        The current model extended with the candidate's element(s), a new object.
    values : dict of str to float
        Every value the fit chose (the new parameters and the recalibrated linear ones), by
        name, in the parameters' units.
    new : list of str
        The names of the new parameters.
    prediction : numpy.ndarray, optional
        The extended model's output on every sample with sensor gain 1 and no offset, if the
        candidate computed it (else the engine simulates ``model``).
    drive : numpy.ndarray, optional
        For drive-side extensions, the signal the linear core now sees (drive units), so that
        a further cause can act on it.
    drive_expr : sympy.Expr, optional
        The expression of ``drive`` in the model's inputs.
    at_bounds : list of str, optional
        Parameters that ended on a search bound.
    success : bool, optional
        The optimiser's success flag.
    message : str, optional
        The optimiser's message.
    terms : list, optional
        The nonlinear terms added to elements' laws, one (element, partner or None, term, c,
        r2) each (see :class:`~bondgraph.diagnosis.lure.Lure`), so that a later cause can be
        fitted on the exact route with them held.
    additive : AdditiveDrive, optional
        The drive as a sum of effects after an additive drive-side fit
        (:attr:`DriveFit.additive <bondgraph.diagnosis.view.DriveFit>`), so that a later
        additive cause refits its weights.
    where : str, optional
        Where the fitted effect acts, when narrower than the candidate's site (the one element
        of a shared-role site whose term carries the effect); "" for the site itself.
    cause : str, optional
        The cause the fitted effect stands for, when the fit rather than the candidate names
        it (a spring law's fitted shape: :meth:`LawTerm.stands_for
        <bondgraph.diagnosis.laws.LawTerm.stands_for>`); "" for the candidate's own.
    why : str, optional
        With ``cause``: why the fit names it (appended to the candidate's line in the report).
    """

    model: Model
    values: dict[str, float]
    new: list[str]
    prediction: np.ndarray | None = None
    drive: np.ndarray | None = None
    drive_expr: sp.Expr | None = None
    at_bounds: list[str] = field(default_factory=list)
    success: bool = True
    message: str = ""
    terms: list = field(default_factory=list)
    additive: object | None = None
    where: str = ""
    cause: str = ""
    why: str = ""


class Candidate(ABC):
    """One possible missing effect: how to fit it and how to extend the model."""

    #: the cause it stands for (e.g. "hysteresis"); several candidates may share one
    cause: str = ""
    #: where it acts: an element site's name (:mod:`bondgraph.diagnosis.sites`), "output" for
    #: the sensor, "" for the drive
    site_name: str = ""
    #: whether it is tried again once its cause is named (at any site): a structure may lack several modes
    repeatable: bool = False
    #: a short description of the extension
    label: str = ""
    #: NONLINEAR or LINEAR (see the module constants)
    kind: str = NONLINEAR
    #: relative cost; costly candidates start first so parallel workers finish together
    cost: int = 1
    #: for a linear cause, the share of what the flexible linear reference explains that it
    #: must explain (None: the setting ``diagnosis.linear_share``); a cause of the reference's
    #: own form (lags of the drive) asks for nearly all of it, since any linear mismatch gives
    #: such a cause a part to explain
    linear_share: float | None = None

    def applies(self, view) -> bool | str:
        """True, or a short reason why the candidate does not apply to this model and data.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        bool or str
            True when the candidate applies; otherwise a short reason (shown in the report).
        """
        return True

    def screen(self, view):
        """What the candidate explains of the current residual to first order, computed
        quickly (:meth:`View.first_order` of its columns), or None when it cannot say (it is
        then fitted in full).  The engine leaves out a candidate that explains no more than
        chance allows, and when more remain than ``diagnosis.screen_keep``, fits only those
        that explain most (:mod:`~bondgraph.diagnosis.screen`).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        FirstOrder or None
            The share of the residual explained (0-1) and its chance level, or None.
        """
        return None

    def evidence(self, view) -> dict[str, float]:
        """Numbers from the current residual that speak for this cause (shown, not decisive).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        dict of str to float
            Name → number (empty by default).
        """
        return {}

    @abstractmethod
    def fit(self, view) -> Extension:
        """Fit the extension to the data seen through ``view``.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The extended model, the values chosen and, when computed, its prediction.
        """

    def without_memory(self, view) -> np.ndarray | None:
        """For a memory effect: the raw prediction (sensor gain 1) of the same freedom without
        memory (e.g. a static curve with the operator's thresholds), or None.  The engine
        names the memory effect only if it beats this as a nonlinear cause must beat the
        flexible linear reference, both with that reference's freedom: its loops must explain
        something that no static curve, and no linear lag, does.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        numpy.ndarray or None
            The raw prediction on every sample (output units, sensor gain 1, no offset), or
            None for an effect without memory.
        """
        return None

    def implausible(self, view, ext: Extension) -> str:
        """Why the fitted extension is not physically plausible ('' if it is); checked for
        linear structural causes, which could otherwise absorb any linear mismatch.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        ext : Extension
            The fitted extension.

        Returns
        -------
        str
            The reason, or "" when the extension is plausible.
        """
        return ""

    def mimics_recalibration(self, view, ext: Extension) -> str:
        """Why the fitted linear extension may be the model's own structure recalibrated ('' if
        not), e.g. a mode placed on one of the model's modes.  The engine then names it only if
        it also beats the flexible linear reference on the freely calibrated model, as a
        nonlinear cause must: what it explains is then beyond any recalibration.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        ext : Extension
            The fitted extension.

        Returns
        -------
        str
            The reason, or "" when it does not mimic a recalibration.
        """
        return ""

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.cause}: {self.label})"
