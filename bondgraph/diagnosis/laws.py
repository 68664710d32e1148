"""Effects in an element's own law: a term added to the law of the C or R elements at a site.

Each kind adds law(x) + term(c, r², x, a) to every element of its site, one coefficient c per
element (a pair (c, d) for a kind with an even part: d, of free sign, weighs an even term, the
law's asymmetry), where x is the element's own variable (the displacement q of a C, the flow f
of an R) and a, when the kind has a *partner*, the displacement of another element or the drive.  The
term is written *centred* where it can be: r² is chosen from the current model's amplitude at
the element so that the law's describing-function slope at the data's amplitude stays the
calibrated one, and c only says how the slope moves with amplitude.

When the rest of the model is linear (or a drive transform of its linear core), the extended
model is a Lur'e system, simulated on the exact linear route
(:meth:`~bondgraph.diagnosis.view.View.lure`); otherwise, or where that route diverges, with
the compiled integrator.

**The screen** (:meth:`LawTerm.screen`): around the current model, a small term ε·g(x) at a
site moves the output by ε times the term's regressor g(x(t)) passed through the linear
transfer from that site to the output (a first-order, Lur'e view).  One least-squares fit of
the residual on that filtered regressor says, in the time of two simulations, how much the
kind could explain there; the engine fully fits only the kinds and sites that explain most.

The kinds (:func:`generic_kinds`): at a C site :class:`Softening`, :class:`Hardening` (a cubic
term of either sign, each with a quadratic term of free sign for a spring stiffer one way than
the other) and :class:`Clearance` (a gap: little stiffness near the rest position);
at an R site :class:`NonlinearDamping` (velocity-cubic, or Stanton: with the displacement of a
stiffness partner) and :class:`Friction` (Coulomb, smoothed).
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np
import sympy as sp

from ..fit.identify import Spec
from ..model.elements import C
from ..model.graph import Quantity
from ..numerics.simulate import SimulationError
from .candidate import Candidate, Extension
from .lure import DRIVE, NotConverged
from .rewrite import modify_law, neighbours, slope
from .sites import Site, generic_sites


def field(view) -> tuple:
    """(expression, series) of the drive the structure sees: the drive into the linear core,
    or the model's input once the model is no drive transform of a linear core (a structural
    cause named before).

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.

    Returns
    -------
    expression : sympy.Expr
        The drive as an expression of the model's inputs.
    series : numpy.ndarray
        Its samples, drive units.
    """
    if view.current.drive_expr is not None and view.current.drive is not None:
        return view.current.drive_expr, np.asarray(view.current.drive)
    return view.record.input_symbol, np.asarray(view.record.u)


#: the even part's further starts in the final fit, in units of its scale (beside 0)
EVEN_STARTS = (0.3, -0.3)

#: an element whose term alone carries at least this share of a shared-role site's summed
#: effects names the step's site (the site's name otherwise)
CARRIER_SHARE = 0.8


class LawTerm(Candidate):
    """A term in the laws of a site's elements (see the module docstring).

    Parameters
    ----------
    site : Site, optional
        Where it acts.  Without one, the elements tagged :attr:`role` (a domain library's
        candidate bound to a role).

    Notes
    -----
    The coefficient is scanned upwards on a log grid of its scale (:attr:`grid`), each point
    refitting the linear parameters briefly (a nonlinear resonance moves with the
    calibration), from the calibrated values and, when the calibration left one on its
    search bound or outside the plausible device's tolerance
    (:meth:`~bondgraph.diagnosis.view.View.fit_starts`), from the model file's values too;
    then fitted with the calibration from the best point (a kind's even part, held at 0 in
    the scan, from 0 and from ±:data:`EVEN_STARTS` of its scale).  An element whose
    coefficient ends on its upper bound (past it the law is no longer plausible) is held at 0
    and the others are fitted again without it, unless no element would be left.  Only the plausibility ends
    count as search bounds: a coefficient at or near 0 (the optimiser flags values within a
    thousandth of the bounds' width of either end) is no such effect, not a limit.
    """

    #: the element kind the term acts on ("C" or "R")
    element_kind = "C"
    #: without a site: the role whose elements it acts on
    role = ""
    #: parameter name prefix
    prefix = ""
    #: upper bound of the coefficient, in units of its scale
    upper = 1.0
    cost = 3
    #: the scan of the coefficient, in units of its scale
    grid = (0.003, 0.01, 0.03, 0.1, 0.3, 1.0)
    #: the coefficient (in units of its scale) at which the screen evaluates the regressor
    probe = 1e-3
    #: parameter name prefix of the even part's coefficient d (free sign, the law's
    #: asymmetry; :meth:`term` then gets the pair (c, d)), or "" for a kind without one
    even_prefix = ""
    #: bound of |d|, in units of its scale (:meth:`even_scale`)
    even_upper = 1.0

    def __init__(self, site: Site | None = None):
        self.site = site
        self.site_name = site.name if site is not None else self.role

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.cause} at {self.site_name})"

    def elements(self, model) -> list[str]:
        """The elements it acts on in ``model``.

        Parameters
        ----------
        model : Model
            The model to look in.

        Returns
        -------
        list of str
            The site's elements when the site is in ``model``, else none; without a site, the
            elements tagged :attr:`role`.
        """
        if self.site is not None:
            return list(self.site.elements) if self.site.present(model) else []
        return list(model.with_role(self.role))

    def applies(self, view):
        """True, or why the term cannot act here: no element at the site (or with the role), the
        site's modes are faster than the data resolve, or the term is in an element's law
        already (named at an earlier step, perhaps under another cause: rule
        ``secant-trend``).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        bool or str
            True when the candidate applies; otherwise a short reason.
        """
        if not self.elements(view.current.model):
            return (
                f"no element is tagged '{self.role}'"
                if self.site is None
                else f"'{self.site.name}' is not in the model"
            )
        if view.record.reduced:
            return (
                f"the elements at {self.site_name} act in modes faster than the data resolve (their "
                f"quasi-static effect is a drive nonlinearity)"
            )
        known = view.current.model.all_parameters()
        held = [el for el in self.elements(view.current.model) if f"{self.prefix}_{el}" in known]
        if held:
            return f"its term is in the law of {', '.join(held)} already (named at an earlier step)"
        return True

    @staticmethod
    @abstractmethod
    def term(c, r2, x, a):
        """The term added to the law (sympy arithmetic: it is compiled; ``a`` is None without a
        partner).

        Parameters
        ----------
        c : sympy.Expr or float or tuple
            The coefficient (the new parameter; 0 leaves the law as it was); the pair (c, d)
            for a kind with an :attr:`even_prefix`.
        r2 : sympy.Expr or float
            The centring amplitude², in the square of the variable's unit.
        x : sympy.Expr or numpy.ndarray
            The element's own variable: displacement q of a C, flow f of an R.
        a : sympy.Expr or numpy.ndarray or None
            The partner's displacement or the drive, or None without a partner.

        Returns
        -------
        sympy.Expr or numpy.ndarray
            The term, in the unit of the law's output (effort of a C or an R); evaluated on
            arrays as well for the exact linear route.
        """

    def partner(self, model, el) -> str | None:
        """The element whose displacement the term of ``el`` uses, :data:`DRIVE`, or None.

        Parameters
        ----------
        model : Model
            The current model.
        el : str
            The element the term acts on.

        Returns
        -------
        str or None
            The partner element's name, :data:`DRIVE`, or None (the default: no partner).
        """
        return None

    @abstractmethod
    def refs(self, view, el, x, a) -> tuple[float, float]:
        """(scale of the coefficient, r²) of element ``el`` from its variable's series ``x``
        (and the partner's ``a``) in the current model.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        el : str
            The element.
        x : numpy.ndarray
            Its variable's series in the current model (q of a C, f of an R).
        a : numpy.ndarray or None
            The partner's series, or None without a partner.

        Returns
        -------
        scale : float
            The coefficient's scale: the coefficient at which the term is comparable to the law.
        r2 : float
            The centring amplitude², in the square of the variable's unit.
        """

    def even_scale(self, view, el, x) -> float:
        """The scale of the even coefficient d of element ``el``: |slope of its law| / peak of
        ``x``, at which d·x² is the linear law at the peak.

        Parameters
        ----------
        view : View
            The read-only view of the data and the current model.
        el : str
            The element.
        x : numpy.ndarray
            Its variable's series in the current model.

        Returns
        -------
        float
            Effort per (variable unit)² (N/m² for a spring).
        """
        return abs(slope(view.current.model, el, view.current.values)) / _peak(x)

    def _pair(self, c, d=0.0):
        """The coefficient :meth:`term` takes: c, or (c, d) for a kind with an even part."""
        return (c, d) if self.even_prefix else c

    def build(self, view, coefs: dict, r2s: dict):
        """The current model with the term on each element of ``coefs``.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        coefs : dict of str to float or tuple
            Element → coefficient (the new parameter's value), or the pair (c, d) for a kind
            with an even part.
        r2s : dict of str to float
            Element → centring amplitude².

        Returns
        -------
        Model
            A new model: the current one rewritten, with parameters ``PREFIX_EL``,
            ``EVEN_PREFIX_EL`` for a kind with an even part, and ``PREFIX_r2_EL``, and the term
            added to each element's law.
        """
        model = view.rewrite()
        for el in coefs:
            cv, dv = coefs[el] if self.even_prefix else (coefs[el], 0.0)
            c = model.parameter(f"{self.prefix}_{el}", cv, "", f"{self.label}: {el}", bounds=(0, 1e40))
            if self.even_prefix:
                d = model.parameter(
                    f"{self.even_prefix}_{el}", dv, "", f"{self.label}, even part: {el}", bounds=(-1e40, 1e40)
                )
                c = (c, d)
            r2 = model.parameter(f"{self.prefix}_r2_{el}", r2s[el], "", f"centring amplitude² of {el}")
            p = self.partner(model, el)
            a = field(view)[0] if p == DRIVE else Quantity("q", p) if p else None
            modify_law(model, el, lambda x, old, c=c, r2=r2, a=a: old + self.term(c, r2, x, a))
        return model

    def _series(self, view, els, partners):
        """(lure or None, {el: x}, {el: a}, output series of the current model or None)."""
        lure = view.lure(view.rewrite(), els, partners)
        if lure is not None:
            series = lure.linear_responses(dict(view.current.values), lure.drive, self.term)
            xs = {el: series[f"diag.x:{el}"] for el in els}
            az = {el: series.get(f"diag.a:{el}") for el in els}
            return lure, xs, az, series[view.record.output]
        st = view.states()
        xs = {el: st[view.record.state_of[el]] if self.element_kind == "C" else st["output rate"] for el in els}
        az = {
            el: field(view)[1]
            if partners[el] == DRIVE
            else st[view.record.state_of[partners[el]]]
            if partners[el]
            else None
            for el in els
        }
        return None, xs, az, None

    def screen(self, view):
        """What the term explains of the current residual's energy on the fit part to first
        order (module docstring), or None when the model is no Lur'e system (the kind is then
        fitted in full).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        FirstOrder or None
            What the filtered regressor (with an even part, both of them) explains of the
            residual with the calibration (:meth:`View.first_order`), or None.
        """
        els = self.elements(view.current.model)
        partners = {el: self.partner(view.current.model, el) for el in els}
        try:
            lure, xs, az, base = self._series(view, els, partners)
        except (NotConverged, SimulationError):
            return None
        if lure is None:
            return None
        refs = {el: self.refs(view, el, xs[el], az[el]) for el in els}
        probes = [[(self._pair(self.probe * refs[el][0]), refs[el][1]) for el in els]]
        if self.even_prefix:  # the even part's own regressor
            probes.append(
                [(self._pair(0.0, self.probe * self.even_scale(view, el, xs[el])), refs[el][1]) for el in els]
            )
        try:
            moved = [lure.simulate(dict(view.current.values), lure.drive, self.term, coefs) for coefs in probes]
        except NotConverged:
            return None
        return view.first_order(np.column_stack([(m - base) * view.current.gain / self.probe for m in moved]))

    def fit(self, view):
        """Fit the coefficients with the calibration (the scan of the class notes).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The model with the term on the site's elements, the values fitted and the
            prediction.

        Raises
        ------
        SimulationError
            The extended model cannot be simulated at any point of the scan.
        """
        els = self.elements(view.current.model)
        partners = {el: self.partner(view.current.model, el) for el in els}
        names = [f"{self.prefix}_{el}" for el in els]
        evens = [f"{self.even_prefix}_{el}" for el in els] if self.even_prefix else []
        lure, xs, az, base = self._series(view, els, partners)
        refs = {el: self.refs(view, el, xs[el], az[el]) for el in els}
        escale = {el: self.even_scale(view, el, xs[el]) for el in els} if evens else {}
        r2s = {el: refs[el][1] for el in els}
        held = self._idle(view, lure, els, refs, r2s, base) if lure is not None and len(els) > 1 else []
        model = self.build(view, {el: self._pair(0.0) for el in els}, r2s)
        predict = None
        if lure is not None:

            def predict(values):
                coefs = [
                    (self._pair(values[n], values[e] if evens else 0.0), r2s[el])
                    for n, e, el in zip(names, evens or names, els)
                ]
                try:
                    raw = lure.simulate(values, lure.drive, self.term, coefs)
                except NotConverged:  # it diverges: a fit as bad as no model at all
                    return np.zeros(len(view.record.y))
                return raw if lure.extra is None else raw + lure.extra

        def fitted(specs, nfev, start=None):
            return view.fit_model(model, specs, max_nfev=nfev, start=start, predict=predict)

        def spec(f, free=False, d0=0.0):  # elements whose term cannot matter are held at 0
            odd = [
                Spec(n, 0.0, 0.0, 0.0, scale=refs[el][0])
                if el in held
                else Spec(
                    n,
                    f * refs[el][0],
                    0.0 if free else f * refs[el][0],
                    self.upper * refs[el][0] if free else f * refs[el][0],
                    scale=refs[el][0],
                )
                for n, el in zip(names, els)
            ]
            return odd + [  # the even part is held at 0 in the scan, free in the fit
                Spec(e, 0.0, 0.0, 0.0, scale=escale[el])
                if el in held or not free
                else Spec(
                    e,
                    d0 * escale[el],
                    -self.even_upper * escale[el],
                    self.even_upper * escale[el],
                    scale=escale[el],
                )
                for e, el in zip(evens, els)
            ]

        best = None
        # from the calibration; when it left a parameter on its search bound, from the model
        # file's values too (the calibration may have bent the linear device to mimic this term)
        for start in view.fit_starts():
            worse = 0
            for f in self.grid:
                try:
                    values, raw, *_ = fitted(spec(f), 3, start)
                except SimulationError:
                    break
                rf = view.score(raw)[2]
                if best is None or rf < best[0]:
                    best, worse = (rf, f, values), 0
                else:
                    worse += 1
                    if worse == 2:
                        break
        if best is None:
            raise SimulationError(f"{self.cause}: the extended model could not be simulated")
        limit = {n: self.upper * refs[el][0] for n, el in zip(names, els)}
        limit.update({e: self.even_upper * escale[el] for e, el in zip(evens, els)})

        def plausibility_ends(at):  # a coefficient at or near 0 is no such effect, not a search limit
            return [n for n in at if n not in limit or abs(values[n]) > 0.5 * limit[n]]

        start = {k: v for k, v in best[2].items() if k not in names}
        values, raw, ok, msg, at = fitted(spec(best[1], free=True), 12, start)
        # the even part's sign is not known: the fit also starts from either side of 0 (one
        # descent from 0 did not reach a one-sided spring's optimum), keeping the best
        for d0 in EVEN_STARTS if evens else ():
            other = fitted(spec(best[1], free=True, d0=d0), 12, start)
            if view.score(other[1])[2] < view.score(raw)[2]:
                values, raw, ok, msg, at = other
        at = plausibility_ends(at)
        stuck = [el for n, el in zip(names, els) if n in at]
        if stuck and len(stuck) + len(held) < len(els):
            # beyond the bound the term is no longer plausible (a softening whose tangent
            # stiffness turns negative at the peak): that element's term stands in for something
            # else, so it is held at 0 and the others are refitted without it
            held += stuck
            values, raw, ok, msg, at = fitted(spec(best[1], free=True), 12, start)
            at = plausibility_ends(at)
            msg = (
                f"{', '.join(f'{self.prefix}_{el}' for el in stuck)} went to "
                f"{'its search bound and is' if len(stuck) == 1 else 'their search bounds and are'} held at 0; {msg}"
            )
        kept = [(n, el) for n, el in zip(names, els) if el not in held]
        coefs = {el: self._pair(values[n], values.get(f"{self.even_prefix}_{el}", 0.0)) for n, el in kept}
        terms = [(el, partners[el], self.term, coefs[el], r2s[el]) for _, el in kept]
        where = self._carrier(view, lure, values, coefs, r2s, els) if len(kept) > 1 else ""
        cause = self.stands_for(coefs, r2s, xs)
        cause = cause if cause != self.cause else ""
        why = self.renamed_because(cause) if cause else ""
        return Extension(
            self.build(view, coefs, r2s),
            values,
            [n for n, _ in kept] + [f"{self.even_prefix}_{el}" for _, el in kept if evens],
            raw,
            None,
            None,
            at,
            ok,
            msg,
            terms=terms,
            where=kept[0][1] if len(kept) == 1 and len(els) > 1 else where,
            cause=cause,
            why=why,
        )

    def stands_for(self, coefs: dict, r2s: dict, xs: dict) -> str:
        """The cause the fitted terms stand for, when the fit rather than the kind names it;
        "" (the default) for the kind's own :attr:`cause`.

        Parameters
        ----------
        coefs : dict of str to float or tuple
            Element → its fitted coefficient (the pair (c, d) for a kind with an even part).
        r2s : dict of str to float
            Element → centring amplitude².
        xs : dict of str to numpy.ndarray
            Element → its variable's series in the current model.

        Returns
        -------
        str
            A cause, or "".
        """
        return ""

    def renamed_because(self, cause: str) -> str:
        """Why the fit names ``cause`` rather than the kind's own, with the rule's name (the
        candidate table's verdict line).

        Parameters
        ----------
        cause : str
            The cause :meth:`stands_for` returned.

        Returns
        -------
        str
            The reason.
        """
        return f"the fitted law is {cause} where the record takes it (rule 'secant-trend')"

    def _carrier(self, view, lure, values, coefs, r2s, els) -> str:
        """The element whose fitted term alone moves the output at least
        :data:`CARRIER_SHARE` of the terms' summed effects (RMS), or "" (the site as a whole),
        on the exact linear route only."""
        if lure is None:
            return ""
        effect = {}
        try:
            without = lure.simulate(values, lure.drive, self.term, [(self._pair(0.0), r2s[e]) for e in els])
            for el in coefs:
                one = [(coefs[el] if e == el else self._pair(0.0), r2s[e]) for e in els]
                effect[el] = float(np.std(lure.simulate(values, lure.drive, self.term, one) - without))
        except NotConverged:
            return ""
        total = sum(effect.values())
        top = max(effect, key=effect.get)
        return top if total > 0 and effect[top] >= CARRIER_SHARE * total else ""

    def _idle(self, view, lure, els, refs, r2s, base) -> list[str]:
        """Elements whose term, at the top of the scan, moves the output by less than 5 % of the
        residual's spread where another element's moves it more: held at 0."""
        effect = {}
        for el in els:
            effect[el] = np.inf
            for f in (self.grid[-1], 0.1 * self.grid[-1]):
                coefs = [(self._pair(f * refs[e][0] if e == el else 0.0), r2s[e]) for e in els]
                try:
                    raw = lure.simulate(dict(view.current.values), lure.drive, self.term, coefs)
                except NotConverged:
                    continue
                effect[el] = float(np.std(raw - base))
                break
        floor = 0.05 * float(np.std(view.current.residual)) / max(abs(view.current.gain), 1e-300)
        return [el for el in els if effect[el] < floor and effect[el] < max(effect.values())]


def _peak(x) -> float:
    return float(np.max(np.abs(x))) or 1.0


class Softening(LawTerm):
    """A stiffness that falls with amplitude: e = law(q) − k3·q·(q² − r²) + k2·q², r² = 1.5·⟨q²⟩
    of the current model, k3 ≥ 0 (a cubic whose describing-function stiffness at the data's
    amplitude stays the calibrated one); k2 of either sign, |k2| ≤ k/q_peak, makes the spring
    stiffer one way than the other (a preloaded or one-sided spring: its even part).

    Parameters
    ----------
    site : Site, optional
        The C site it acts at (without one, the elements of :attr:`role`).
    """

    cause = "softening"
    label = "cubic softening of the spring law"
    prefix, upper = "soft.k3", 0.5
    even_prefix = "soft.k2"
    grid = (0.003, 0.01, 0.03, 0.1, 0.3)

    @staticmethod
    def term(c, r2, x, a):
        """−k3·q·(q² − r²) + k2·q², the softening term.

        Parameters
        ----------
        c : tuple
            (k3, k2): k3 ≥ 0, effort per displacement³ (N/m³ for a spring); k2 of either sign,
            effort per displacement² (N/m²).
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
        k3, k2 = c
        return -k3 * x * (x**2 - r2) + k2 * x**2

    def refs(self, view, el, x, a):
        """The coefficient's scale k/q_peak² and r² = 1.5·⟨q²⟩ of the current model.

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
            |slope of the law| / q_peak², effort per displacement³.
        r2 : float
            1.5·⟨q²⟩, displacement².
        """
        return abs(slope(view.current.model, el, view.current.values)) / _peak(x) ** 2, 1.5 * float(np.mean(x**2))

    def stands_for(self, coefs, r2s, xs):
        """Hardening or softening by the fitted law's own shape where the record takes the
        spring (rule ``secant-trend``): a stiffness that rises with the distance from rest is
        hardening, one that falls softening, whichever sign the kind gives its cubic.  With
        the even part free, a record that takes the spring one way only (steps from rest, a
        drive with an offset) cannot tell the cubic from the quadratic, and a cubic of either
        sign fits with the quadratic's help; what the fitted law does on the displacements the
        record visits is what it knows.  The measure is the slope of the secant stiffness
        (e(q) − e(0))/q over |q| (least squares over the samples beyond a twentieth of the
        peak, so weighted by the time the record spends there) times the range of |q|: the
        change of the secant stiffness across the visited range, summed over the elements.

        Parameters
        ----------
        coefs : dict of str to tuple
            Element → (k3, k2) fitted.
        r2s : dict of str to float
            Element → centring amplitude r².
        xs : dict of str to numpy.ndarray
            Element → displacement series q in the current model.

        Returns
        -------
        str
            "hardening" or "softening" ("" when the record leaves no displacement to judge).
        """
        trend = 0.0
        for el, c in coefs.items():
            q = np.asarray(xs[el], float)
            q = q[np.abs(q) > 0.05 * _peak(q)]
            if q.size < 3 or np.ptp(np.abs(q)) <= 0:
                continue
            secant = (self.term(c, r2s[el], q, None) - self.term(c, r2s[el], 0.0, None)) / q  # beyond the linear law's
            trend += np.polyfit(np.abs(q), secant, 1)[0] * np.ptp(np.abs(q))
        return "" if trend == 0 else "hardening" if trend > 0 else "softening"


class Hardening(Softening):
    """A stiffness that rises with amplitude (a Duffing spring): e = law(q) + k3·q·(q² − r²)
    + k2·q², centred as :class:`Softening`, k3 ≥ 0; up to many times the linear stiffness at the
    peak (a hardening spring has no turning point to stop at); |k2| ≤ 2·k/q_peak (the cubic
    keeps such a spring's tangent stiffness positive where a softening one could not).

    Parameters
    ----------
    site : Site, optional
        The C site it acts at (without one, the elements of :attr:`role`).
    """

    cause = "hardening"
    label = "cubic hardening of the spring law"
    prefix, upper = "hard.k3", 30.0
    even_prefix, even_upper = "hard.k2", 2.0
    grid = (0.003, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0)

    @staticmethod
    def term(c, r2, x, a):
        """+k3·q·(q² − r²) + k2·q², the hardening (Duffing) term.

        Parameters
        ----------
        c : tuple
            (k3, k2): k3 ≥ 0, effort per displacement³ (N/m³ for a spring); k2 of either sign,
            effort per displacement² (N/m²).
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
        k3, k2 = c
        return k3 * x * (x**2 - r2) + k2 * x**2


class Clearance(LawTerm):
    """A gap or backlash in a spring: little stiffness within ±d of the rest position, the
    full stiffness beyond: e = law(q) − k_g·d·tanh(q/d), 0 ≤ k_g ≤ 1.2·k (k_g = k: no
    stiffness at rest), the half-width d a share of the data's peak displacement (10 %, or
    3 % or 30 % if these fit better).  Runs on the exact Lur'e route.

    Parameters
    ----------
    site : Site, optional
        The C site it acts at (without one, the elements of :attr:`role`).
    width : float, optional
        The half-width d as a share of the peak displacement (None: try :attr:`widths`).
    """

    cause = "clearance"
    label = "clearance (gap, backlash) in the spring law"
    prefix, upper = "gap.k", 1.2
    grid = (0.1, 0.3, 0.6, 1.0)
    cost = 4
    #: half-widths tried, as shares of the peak displacement
    widths = (0.1, 0.03, 0.3)

    def __init__(self, site: Site | None = None, width: float | None = None):
        super().__init__(site)
        #: the half-width of this fit (share of the peak); None: try :attr:`widths`
        self.width = width

    @staticmethod
    def term(c, r2, x, a):
        """−k_g·d·tanh(q/d): the stiffness removed within the gap.

        Parameters
        ----------
        c : sympy.Expr or float
            k_g ≥ 0, effort per displacement (N/m for a spring).
        r2 : sympy.Expr or float
            Here the gap's half-width d, displacement (m), not a square.
        x : sympy.Expr or numpy.ndarray
            The displacement q.
        a : sympy.Expr or numpy.ndarray or None
            Unused (no partner).

        Returns
        -------
        sympy.Expr or numpy.ndarray
            The term, in effort units (N for a spring).
        """
        return -c * r2 * sp.tanh(x / r2)

    def refs(self, view, el, x, a):
        """The coefficient's scale k (the law's slope) and the half-width d.

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
            The half-width d = width · q_peak, displacement.
        """
        return abs(slope(view.current.model, el, view.current.values)), (self.width or self.widths[0]) * _peak(x)

    def fit(self, view):
        """Fit at this half-width, or, without one, at each of :attr:`widths`, keeping the best.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The best fit's extension.
        """
        if self.width is not None:
            return super().fit(view)
        return _best_of(view, [type(self)(self.site, w) if self.site else type(self)(None, w) for w in self.widths])


class NonlinearDamping(LawTerm):
    """Amplitude-dependent damping: e = (c + μ·(a² − r²))·f with a the displacement of the
    stiffness element on its junction (Stanton type) or, with ``velocity`` or when there is
    none, a = f (velocity-cubic); r² = ⟨a²⟩/2 (1.5·⟨f²⟩ for the velocity form) centres it on
    the data's amplitude; μ ≥ 0.

    Parameters
    ----------
    site : Site, optional
        The R site it acts at (without one, the elements of :attr:`role`).
    velocity : bool, optional
        The velocity-cubic form (a = f) instead of the Stanton form.
    """

    element_kind = "R"
    cause = "nonlinear-damping"
    label = "amplitude-dependent (Stanton) damping"
    prefix, upper = "nld.mu1", 10.0

    def __init__(self, site: Site | None = None, velocity: bool = False):
        self.velocity = velocity
        if velocity:
            self.label = "velocity-cubic damping"
            self.prefix = "nld.mu1v"
        super().__init__(site)

    def applies(self, view):
        """As :meth:`LawTerm.applies`; the Stanton form also needs a stiffness partner.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        bool or str
            True, or why it does not apply.
        """
        ok = super().applies(view)
        if ok is not True or self.velocity:
            return ok
        if not any(self.partner(view.current.model, el) for el in self.elements(view.current.model)):
            return "no damping element has a stiffness partner (the velocity-cubic form covers it)"
        return True

    def partner(self, model, el):
        """The spring bonded to the damper's junction (Stanton form), or None.

        Parameters
        ----------
        model : Model
            The current model.
        el : str
            The damper.

        Returns
        -------
        str or None
            The first neighbouring C element acting as a stiffness; None for the velocity form.
        """
        if self.velocity:
            return None
        return next((o for o in neighbours(model, el) if _is_spring(model, o)), None)

    @staticmethod
    def term(c, r2, x, a):
        """μ·(a² − r²)·f (a = f for the velocity-cubic form).

        Parameters
        ----------
        c : sympy.Expr or float
            μ ≥ 0, damping per amplitude² (N·s/m³ for a mechanical damper).
        r2 : sympy.Expr or float
            The centring amplitude r², in a's units squared.
        x : sympy.Expr or numpy.ndarray
            The flow f (velocity, m/s).
        a : sympy.Expr or numpy.ndarray or None
            The partner's displacement, or None (then a = f).

        Returns
        -------
        sympy.Expr or numpy.ndarray
            The term, in effort units (N).
        """
        return c * ((x if a is None else a) ** 2 - r2) * x

    def refs(self, view, el, x, a):
        """The coefficient's scale c/a_peak² and r² = ⟨a²⟩/2 (1.5·⟨f²⟩ for the velocity form).

        Parameters
        ----------
        view : View
            The read-only view of the data and the current model.
        el : str
            The element.
        x : numpy.ndarray
            The flow f in the current model.
        a : numpy.ndarray or None
            The partner's displacement, or None.

        Returns
        -------
        scale : float
            |damping| / a_peak².
        r2 : float
            The centring amplitude², in a's units squared.
        """
        amp = x if a is None else a
        return (
            abs(slope(view.current.model, el, view.current.values)) / _peak(amp) ** 2,
            (1.5 if a is None else 0.5) * float(np.mean(amp**2)),
        )


def _is_spring(model, name: str) -> bool:
    """A C element that acts as a stiffness: tagged so, or untagged (a generic model's)."""
    el = model.elements[name]
    return isinstance(el, C) and getattr(el, "role", None) in (None, "stiffness")


#: a friction fit whose smoothing velocity is at least this share of the peak velocity is a
#: damping that thins with speed (rule ``knee-width``, :meth:`Friction.stands_for`)
KNEE_SHARE = 0.1


class Friction(LawTerm):
    """Friction (Coulomb, smoothed) in a damper: e = law(f) + F·tanh(f/s), F = μ·s, μ ≥ 0 in
    units of the element's damping; s keeps the law smooth: 3 % of the data's peak velocity,
    or 10 or 30 % if these fit better (tried only when the first improves the fit part by 2 %
    or more).  Its equivalent viscous damping 4F/(πV) falls with the velocity amplitude V,
    where the cubic forms' rises.  Runs on the exact Lur'e route.  A fit that needs a wide
    knee (s ≥ :data:`KNEE_SHARE` of the peak velocity) is named ``nonlinear-damping``: a
    force viscous at low speed that levels off gradually is a damping that thins with speed,
    not a dry friction, whose force turns over at rest (rule ``knee-width``).

    Parameters
    ----------
    site : Site, optional
        The R site it acts at (without one, the elements of :attr:`role`).
    velocity_share : float, optional
        The smoothing velocity s as a share of the peak velocity (None: try :attr:`smoothing`).
    """

    element_kind = "R"
    cause = "friction"
    label = "Coulomb friction (smoothed) in the damper law"
    prefix = "fr.F"
    cost = 4
    upper = 300.0
    grid = (1.0, 8.0, 64.0)
    #: smoothing velocities tried, as shares of the data's peak velocity (the best fit is kept)
    smoothing = (0.03, 0.1, 0.3)

    def __init__(self, site: Site | None = None, velocity_share: float | None = None):
        super().__init__(site)
        #: the smoothing velocity of this fit (share of the peak velocity); None: try ``smoothing``
        self.velocity_share = velocity_share

    @staticmethod
    def term(c, r2, x, a):
        """μ·s·tanh(f/s): Coulomb friction F = μ·s, smoothed over ±s.

        Parameters
        ----------
        c : sympy.Expr or float
            μ ≥ 0, in units of the element's damping (N·s/m).
        r2 : sympy.Expr or float
            Here the smoothing velocity s (m/s), not a square.
        x : sympy.Expr or numpy.ndarray
            The flow f (velocity).
        a : sympy.Expr or numpy.ndarray or None
            Unused (no partner).

        Returns
        -------
        sympy.Expr or numpy.ndarray
            The friction effort (N), of the sign of f.
        """
        return c * r2 * sp.tanh(x / r2)

    def refs(self, view, el, x, a):
        """The coefficient's scale (the damping) and the smoothing velocity s.

        Parameters
        ----------
        view : View
            The read-only view of the data and the current model.
        el : str
            The element.
        x : numpy.ndarray
            The flow f in the current model.
        a : numpy.ndarray or None
            Unused (no partner).

        Returns
        -------
        scale : float
            |slope of the law| (the damping).
        r2 : float
            s = share · f_peak, velocity.
        """
        return abs(slope(view.current.model, el, view.current.values)), self._share * _peak(x)

    @property
    def _share(self) -> float:
        """The smoothing velocity of this fit as a share of the peak velocity."""
        return self.velocity_share or self.smoothing[0]

    def stands_for(self, coefs, r2s, xs):
        """``nonlinear-damping`` when this fit's knee is wide (rule ``knee-width``): dry friction
        (Coulomb, Stribeck) turns its force over within a small share of the velocity range
        around rest, so its fit prefers the narrowest smoothing; a force that is viscous at low
        speed and levels off over :data:`KNEE_SHARE` of the peak velocity or more is a damping
        that thins with speed (a shear-thinning damper, c·v/(1 + |v|/v₀) with v₀ a sizeable
        share of the speeds visited).

        Parameters
        ----------
        coefs : dict of str to float
            Element → its fitted coefficient μ.
        r2s : dict of str to float
            Element → the smoothing velocity s.
        xs : dict of str to numpy.ndarray
            Element → its flow series in the current model.

        Returns
        -------
        str
            "nonlinear-damping", or "" (friction).
        """
        return "nonlinear-damping" if self._share >= KNEE_SHARE and any(coefs.values()) else ""

    def renamed_because(self, cause):
        """The knee's width, with the rule's name.

        Parameters
        ----------
        cause : str
            The cause :meth:`stands_for` returned.

        Returns
        -------
        str
            The reason.
        """
        return (
            f"the fitted force levels off across {self._share:.0%} of the peak velocity, not at rest: a damping "
            f"that thins with speed (rule 'knee-width')"
        )

    def fit(self, view):
        """Fit at this smoothing, or, without one, at each of :attr:`smoothing` while it helps.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The best fit's extension.
        """
        if self.velocity_share is not None:
            return super().fit(view)
        make = [type(self)(self.site, s) for s in self.smoothing]
        return _best_of(view, make, stop_unless=0.98)


def _best_of(view, candidates, stop_unless: float | None = None):
    """The best fit of several variants of one kind (validation RMS on the fit part); with
    ``stop_unless``, the later variants only while the best improves the fit part by more than
    that factor."""
    before = view.score(view.current.prediction)[2]
    best = None
    for cand in candidates:
        ext = cand.fit(view)
        rf = view.score(ext.prediction)[2]
        if best is None or rf < best[0]:
            best = (rf, ext)
        if stop_unless is not None and best[0] > stop_unless * before:
            break
    return best[1]


def law_kinds(model) -> list[Candidate]:
    """The law-term kinds at every generic site of ``model`` (:func:`~.sites.generic_sites`).

    Parameters
    ----------
    model : Model
        The model.

    Returns
    -------
    list of Candidate
        Softening, hardening and clearance at each C site; velocity-cubic and Stanton damping
        and friction at each R site.
    """
    out: list[Candidate] = []
    for site in generic_sites(model, "C"):
        out += [Softening(site), Hardening(site), Clearance(site)]
    for site in generic_sites(model, "R"):
        out += [NonlinearDamping(site, velocity=True), NonlinearDamping(site), Friction(site)]
    return out
