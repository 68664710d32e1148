"""Hysteresis inside the dynamics: a spring whose restoring force has memory.

At a C site the law becomes e = law(q) + k_h·z, with z a Bouc–Wen state of the element's own
displacement (Bouc, 1967; Wen, "Method for random vibration of hysteretic systems", J. Eng.
Mech. Div. ASCE 102 (1976) 249–263), n = 1:

    ż = q̇ − (β·sign(q̇·z) + γ)·|z|·q̇,   β = γ = 1 / (2·z_max)

so z follows q with slope 1 near a reversal and saturates at ±z_max: a loop of height
2·k_h·z_max whose width the data set.  A drive-side operator (a Prandtl–Ishlinskii operator
on the drive) cannot follow it, because the element's displacement lags the drive by the
structure's own dynamics.

The screen computes z from the current model's displacement at the site and passes k_h·z
through the linear transfer from the site to the output (:meth:`Lure.site_response
<bondgraph.diagnosis.lure.Lure.site_response>`); the fit integrates the extended model with
the compiled integrator.  Its twin without memory (:meth:`RestoringHysteresis.without_memory`)
is the loop's backbone, a saturating term k_h·z_max·tanh(q/z_max) at the same site: the loop
must explain more than the curve it is drawn around.
"""

from __future__ import annotations

import numpy as np
import sympy as sp
from numba import njit

from ..fit.identify import Spec
from ..numerics.simulate import SimulationError
from .candidate import Candidate, Extension
from .laws import LawTerm, _peak
from .lure import NotConverged, _bouc_wen_increment
from .rewrite import modify_law, slope
from .sites import Site, each_element, generic_sites


@njit(cache=True)
def bouc_wen_path(x: np.ndarray, zmax: float) -> np.ndarray:
    """The Bouc–Wen state z (n = 1, β = γ = 1/(2·z_max)) along the samples of ``x``, from
    z = 0, exact per increment of x (the equation is rate-independent).

    Parameters
    ----------
    x : ndarray
        The displacement's samples.
    zmax : float
        The level at which z saturates (units of x).

    Returns
    -------
    ndarray
    """
    z = np.zeros(x.size)
    for k in range(1, x.size):
        z[k] = _bouc_wen_increment(z[k - 1], x[k] - x[k - 1], zmax)
    return z


class RestoringHysteresis(Candidate):
    """A spring whose restoring force has memory (see the module docstring).

    Parameters
    ----------
    site : Site
        The C site (its first element carries the term).
    """

    cause = "hysteresis"
    label = "hysteretic restoring force (Bouc–Wen) in the spring law"
    cost = 5
    #: saturation levels z_max tried, as shares of the peak displacement
    levels = (0.05, 0.15, 0.5)

    def __init__(self, site: Site):
        self.site = site
        self.site_name = site.name

    def _element(self, model) -> str | None:
        return self.site.elements[0] if self.site.present(model) else None

    def applies(self, view):
        """True, unless the site is gone or acts in modes faster than the data resolve.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        bool or str
            True, or why it does not apply.
        """
        if self._element(view.current.model) is None:
            return f"'{self.site_name}' is not in the model"
        if view.record.reduced:
            return f"{self.site_name} acts in modes faster than the data resolve"
        return True

    def _columns(self, view):
        """(lure, displacement series at the element, {level: filtered unit column})."""
        el = self._element(view.current.model)
        lure = view.lure(view.rewrite(), [el], {el: None})
        if lure is None:
            return None
        series = lure.linear_responses(dict(view.current.values), lure.drive, lambda c, r2, x, a: 0 * x)
        x = series[f"diag.x:{el}"]
        peak = _peak(x)
        cols = {}
        for share in self.levels:
            z = bouc_wen_path(np.ascontiguousarray(x, float), share * peak)
            cols[share] = lure.site_response(dict(view.current.values), z, el) * view.current.gain
        return lure, x, cols

    def screen(self, view):
        """What k_h·z explains of the residual to first order at the saturation level of
        :attr:`levels` where it explains most, or None off the exact linear route.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        FirstOrder or None
            The :meth:`View.first_order` of the largest share over the levels, or None.
        """
        try:
            out = self._columns(view)
        except (NotConverged, SimulationError):
            return None
        if out is None:
            return None
        return max((view.first_order(col) for col in out[2].values()), key=lambda f: f.share)

    def build(self, view, kh: float, zmax: float):
        """The current model with the hysteretic term on the site's element.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        kh : float
            k_h, the loop's force per unit z (effort per displacement, N/m for a spring).
        zmax : float
            z_max, the level at which z saturates (displacement, m).

        Returns
        -------
        Model
            A new model with parameters ``hy.k_EL``, ``hy.zmax_EL`` and the state ``hy.z_EL``.
        """
        el = self._element(view.current.model)
        model = view.rewrite()
        k = model.parameter(f"hy.k_{el}", kh, "", f"{self.label}: height of the loop's force per unit z at {el}")
        zm = model.parameter(f"hy.zmax_{el}", zmax, "", f"saturation level of the Bouc–Wen state at {el}")
        z = model.state(f"hy.z_{el}", 0, doc=f"Bouc–Wen state of {el}'s displacement")
        qd = model.flow(el)
        beta = 1 / (2 * zm)
        model.set_rate(f"hy.z_{el}", qd - beta * sp.Abs(qd) * z - beta * qd * sp.Abs(z))
        modify_law(model, el, lambda q, old: old + k * z)
        return model

    def fit(self, view):
        """Fit k_h and z_max from the two best first-order trials, from the calibration and
        from the model file's values, keeping the best (off the Lur'e route, where every
        evaluation integrates the model, from the best trial and the calibration only).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The model with the hysteretic restoring force.

        Raises
        ------
        SimulationError
            The extended model cannot be simulated from any start.
        """
        el = self._element(view.current.model)
        stiffness = abs(slope(view.current.model, el, view.current.values))
        out = self._columns(view)
        peak = _peak(out[1]) if out is not None else _peak(view.states()[view.record.state_of[el]])
        # the levels and heights that explain most to first order start the fits
        trials = [(0.0, self.levels[1], 0.1 * stiffness)]
        if out is not None:
            idx = view.record.fit_idx
            r = view.current.residual[idx] - view.current.residual[idx].mean()
            trials = []
            for share, col in out[2].items():
                q = col[idx] - col[idx].mean()
                if float(q @ q) > 0:
                    c = float(q @ r) / float(q @ q)
                    trials.append((float(np.sum((r - c * q) ** 2)), share, max(c, 1e-3 * stiffness)))
            trials.sort()
        # from the calibration, and from the model file's values: a calibration that took the
        # loop's loss for viscous damping has moved away from the device.  Off the Lur'e route
        # (terms named before are held: every evaluation integrates the model) from the
        # calibration only, which the chain's earlier steps have refitted, and the best first-order
        # trial only
        lure = out[0] if out is not None else None
        fast = lure is not None and not lure.fixed
        starts = view.fit_starts(always=True) if fast else [None]
        best = None
        for _, share, kh in trials[: 2 if fast else 1]:
            for start in starts:
                model = self.build(view, kh, share * peak)
                predict = None
                if fast:

                    def predict(values):
                        try:
                            raw = lure.hysteretic(values, lure.drive, el, values[f"hy.k_{el}"], values[f"hy.zmax_{el}"])
                        except NotConverged:  # it diverges: a fit as bad as no model at all
                            return np.zeros(len(view.record.y))
                        return raw if lure.extra is None else raw + lure.extra

                specs = [
                    Spec(f"hy.k_{el}", kh, 0.0, 10.0 * stiffness, scale=stiffness),
                    Spec(f"hy.zmax_{el}", share * peak, 0.01 * peak, 2.0 * peak, log=True),
                ]
                try:
                    values, raw, ok, msg, at = view.fit_model(model, specs, max_nfev=20, start=start, predict=predict)
                except SimulationError:
                    continue
                rf = view.score(raw)[2]
                if best is None or rf < best[0]:
                    best = (rf, values, raw, ok, msg, at, specs)
        if best is None:
            raise SimulationError(f"{self.cause}: the extended model could not be simulated")
        _, values, raw, ok, msg, at, specs = best
        # k_h at or near 0 (the optimiser flags a thousandth of its range from either end) is
        # no such effect, not a search limit: only its upper end counts
        at = [n for n in at if not (n.startswith("hy.k_") and values[n] < 5.0 * stiffness)]
        final = self.build(view, values[f"hy.k_{el}"], values[f"hy.zmax_{el}"])
        return Extension(final, values, [s.name for s in specs], raw, None, None, at, ok, msg)

    def without_memory(self, view):
        """The loop's backbone at the same site, fitted (its raw prediction), or None.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        numpy.ndarray or None
            The backbone's raw prediction on every sample, or None when it cannot be fitted.
        """
        try:
            ext = Backbone(self.site).fit(view)
        except (NotConverged, SimulationError):
            return None
        return ext.prediction


class Backbone(LawTerm):
    """The curve a restoring-force loop is drawn around: a saturating term
    e = law(q) + c·r·tanh(q/r) (c ≥ 0, r a share of the peak displacement): the same freedom
    as :class:`RestoringHysteresis` without its memory.

    Parameters
    ----------
    site : Site, optional
        The C site it acts at.
    """

    cause = "hysteresis"
    label = "backbone of a restoring-force loop (no memory)"
    prefix, upper = "bb.k", 10.0
    grid = (0.03, 0.1, 0.3, 1.0)

    @staticmethod
    def term(c, r2, x, a):
        """c·r·tanh(q/r), the saturating backbone.

        Parameters
        ----------
        c : sympy.Expr or float
            c ≥ 0, effort per displacement (N/m for a spring).
        r2 : sympy.Expr or float
            Here the saturation level r, displacement (m), not a square.
        x : sympy.Expr or numpy.ndarray
            The displacement q.
        a : sympy.Expr or numpy.ndarray or None
            Unused (no partner).

        Returns
        -------
        sympy.Expr or numpy.ndarray
            The term, in effort units (N for a spring).
        """
        return c * r2 * sp.tanh(x / r2)

    def refs(self, view, el, x, a):
        """The coefficient's scale k (the law's slope) and r at the middle saturation level.

        Parameters
        ----------
        view : View
            The read-only view of the data and the current model.
        el : str
            The element.
        x : numpy.ndarray
            The displacement q in the current model.
        a : numpy.ndarray or None
            Unused (no partner).

        Returns
        -------
        scale : float
            |slope of the law|, effort per displacement.
        r2 : float
            r = 0.15 · q_peak, displacement.
        """
        return abs(slope(view.current.model, el, view.current.values)), RestoringHysteresis.levels[1] * _peak(x)


def restoring_kinds(model) -> list[Candidate]:
    """A hysteretic restoring force at every generic C site of ``model``: at each element of
    a site shared by a few (:func:`~bondgraph.diagnosis.sites.each_element`).

    Parameters
    ----------
    model : Model
        The model.

    Returns
    -------
    list of Candidate
        The :class:`RestoringHysteresis` candidates.
    """
    return [RestoringHysteresis(s) for site in generic_sites(model, "C") for s in each_element(site)]
