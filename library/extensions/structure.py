"""Nonlinear laws inside the structure, found through element roles (``stiffness``,
``damping``, ``polarization``): cubic softening and amplitude-dependent damping of a bender
(Shahabi, Ghafarirad & Taghvaeipour, C. R. Mécanique 347 (2019)), a saturating dipole of a
stack (Rodriguez-Fortun et al., Mechatronics 20 (2010): its polarization capacitor).  When
the rest of the model is linear, or a drive transform of its linear core (hysteresis or
creep on the drive named before), they are simulated on the exact linear route as a Lur'e
system (:meth:`bondgraph.diagnosis.View.lure`), else, or for parameter values that make that
route diverge, with the compiled integrator."""

from __future__ import annotations

from abc import abstractmethod

import numpy as np
import sympy as sp

from bondgraph import Quantity
from bondgraph.diagnosis import Candidate, Extension
from bondgraph.diagnosis.lure import DRIVE, NotConverged
from bondgraph.diagnosis.rewrite import modify_law, neighbours, slope
from bondgraph.fit.identify import Spec
from bondgraph.numerics.simulate import SimulationError


def field(view) -> tuple:
    """(expression, series) of the drive the structure sees: the drive into the linear core, or
    the model's input once the model is no drive transform of a linear core (a structural cause
    named before)."""
    if view.drive_expr is not None and view.drive is not None:
        return view.drive_expr, np.asarray(view.drive)
    return view.input_symbol, np.asarray(view.u)


class _Centred(Candidate):
    """A structural nonlinearity: each element of ``role`` gets law(x) + term(c, r², x, a),
    one coefficient c ≥ 0 per element, centred on the data's amplitude by r² (see the
    subclasses).  The coefficient is scanned upwards on a log grid of its scale, each point
    refitting the linear parameters briefly (a nonlinear resonance moves with the
    calibration), from the calibrated values and, when the calibration left one on its search
    bound (:meth:`~bondgraph.diagnosis.View.strained`: it may have bent the linear device to
    mimic the term), from the model file's values too; then fitted with the calibration from
    the best point.  An element whose coefficient ends on its upper bound (past it the law is
    no longer plausible) is held at 0 and the others are fitted again without it, unless no
    element would be left."""

    role = ""
    prefix = ""
    upper = 1.0
    cost = 3
    grid = (0.003, 0.01, 0.03, 0.1, 0.3, 1.0)

    def applies(self, view):
        if not view.model.with_role(self.role):
            return f"no element is tagged '{self.role}'"
        if view.reduced:
            return (
                f"the '{self.role}' elements act in modes faster than the data resolve (their "
                f"quasi-static effect is a drive nonlinearity)"
            )
        return True

    @staticmethod
    @abstractmethod
    def term(c, r2, x, a):
        """The term added to the law (sympy arithmetic: it is compiled; ``a`` is None without a
        partner)."""

    def partner(self, model, el) -> str | None:
        return None

    @abstractmethod
    def refs(self, view, el, x, a) -> tuple[float, float]:
        """(scale of the coefficient, r²) of element ``el`` from its variable's series ``x``
        (and the partner's ``a``) in the current model."""

    def build(self, view, coefs: dict, r2s: dict):
        """The current model with the term on each element of ``coefs``."""
        model = view.rewrite()
        for el in coefs:
            c = model.parameter(f"{self.prefix}_{el}", coefs[el], "", f"{self.label}: {el}", bounds=(0, 1e40))
            r2 = model.parameter(f"{self.prefix}_r2_{el}", r2s[el], "", f"centring amplitude² of {el}")
            p = self.partner(model, el)
            a = field(view)[0] if p == DRIVE else Quantity("q", p) if p else None
            modify_law(model, el, lambda x, old, c=c, r2=r2, a=a: old + self.term(c, r2, x, a))
        return model

    def fit(self, view):
        els = list(view.model.with_role(self.role))
        partners = {el: self.partner(view.model, el) for el in els}
        names = [f"{self.prefix}_{el}" for el in els]
        lure = view.lure(view.rewrite(), els, partners)
        if lure is not None:
            series = lure.linear_responses(dict(view.values), lure.drive, self.term)
            xs = {el: series[f"diag.x:{el}"] for el in els}
            az = {el: series.get(f"diag.a:{el}") for el in els}
        else:
            st = view.states()
            xs = {el: st[view.state_of(el)] if self.role != "damping" else st["output rate"] for el in els}
            az = {
                el: field(view)[1]
                if partners[el] == DRIVE
                else st[view.state_of(partners[el])]
                if partners[el]
                else None
                for el in els
            }
        refs = {el: self.refs(view, el, xs[el], az[el]) for el in els}
        r2s = {el: refs[el][1] for el in els}
        if lure is not None and len(els) > 1:
            base = series[view.output]
            effect = {}
            for el in els:  # what the term does at the top of the scan, element by element
                effect[el] = np.inf
                for f in (self.grid[-1], 0.1 * self.grid[-1]):
                    coefs = [(f * refs[e][0] if e == el else 0.0, r2s[e]) for e in els]
                    try:
                        raw = lure.simulate(dict(view.values), lure.drive, self.term, coefs)
                    except NotConverged:
                        continue
                    effect[el] = float(np.std(raw - base))
                    break
            floor = 0.05 * float(np.std(view.residual)) / max(abs(view.gain), 1e-300)
            held = [el for el in els if effect[el] < floor and effect[el] < max(effect.values())]
        else:
            held = []
        model = self.build(view, {el: 0.0 for el in els}, r2s)
        predict = None
        if lure is not None:

            def predict(values):
                coefs = [(values[n], r2s[el]) for n, el in zip(names, els)]
                try:
                    raw = lure.simulate(values, lure.drive, self.term, coefs)
                except NotConverged:  # integrate the rewritten model for these values instead,
                    try:  # within a bounded number of explicit steps
                        return view.simulate(model, values, max_steps=50 * len(view.y))
                    except SimulationError:  # it diverges: a fit as bad as no model at all
                        return np.zeros(len(view.y))
                return raw if lure.extra is None else raw + lure.extra

        def fitted(specs, nfev, start=None):
            return view.fit_model(model, specs, max_nfev=nfev, start=start, predict=predict)

        def spec(f, free=False):  # elements whose term cannot matter are held at 0
            return [
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

        best = None
        # from the calibration; when it left a parameter on its search bound, from the model
        # file's values too (the calibration may have bent the linear device to mimic this term)
        for start in [None] + ([view.model_file_values()] if view.strained() else []):
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
        start = {k: v for k, v in best[2].items() if k not in names}
        values, raw, ok, msg, at = fitted(spec(best[1], free=True), 12, start)
        at = [n for n in at if values[n] > 0]  # a coefficient of 0 is no such effect, not a search limit
        stuck = [el for n, el in zip(names, els) if n in at]
        if stuck and len(stuck) + len(held) < len(els):
            # beyond the bound the term is no longer plausible (a softening whose tangent
            # stiffness turns negative at the peak): that element's term stands in for something
            # else, so it is held at 0 and the others are refitted without it
            held += stuck
            values, raw, ok, msg, at = fitted(spec(best[1], free=True), 12, start)
            at = [n for n in at if values[n] > 0]
            msg = (
                f"{', '.join(f'{self.prefix}_{el}' for el in stuck)} went to "
                f"{'its search bound and is' if len(stuck) == 1 else 'their search bounds and are'} held at 0; {msg}"
            )
        kept = [(n, el) for n, el in zip(names, els) if el not in held]
        terms = [(el, partners[el], self.term, values[n], r2s[el]) for n, el in kept]
        return Extension(
            self.build(view, {el: values[n] for n, el in kept}, r2s),
            values,
            [n for n, _ in kept],
            raw,
            None,
            None,
            at,
            ok,
            msg,
            terms=terms,
        )


class StiffnessSoftening(_Centred):
    """Amplitude-dependent stiffness: every element tagged ``stiffness`` gets a cubic softening
    term, written centred on the data's amplitude, e = law(q) − k3·q·(q² − r²) with
    r² = 1.5·⟨q²⟩ of the current model: the describing-function stiffness at the data's
    amplitude stays the calibrated one, so k3 (≥ 0) only moves the stiffness with amplitude."""

    cause = "softening"
    label = "cubic softening of the stiffness elements"
    role, prefix, upper = "stiffness", "soft.k3", 0.5
    grid = (0.003, 0.01, 0.03, 0.1, 0.3)

    @staticmethod
    def term(c, r2, x, a):
        return -c * x * (x**2 - r2)

    def refs(self, view, el, x, a):
        peak = float(np.max(np.abs(x))) or 1.0
        return abs(slope(view.model, el, view.values)) / peak**2, 1.5 * float(np.mean(x**2))


class PolarizationSaturation(_Centred):
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
        self.power = power
        if power is not None:
            self.prefix = f"sat.k{power + 1}"

    def applies(self, view):
        n = len(view.model.with_role(self.role))
        if n > self.most:
            return f"{n} elements are tagged '{self.role}' (one coefficient each; at most {self.most})"
        return super().applies(view)

    def term(self, c, r, x, a):
        return c * x * (x**self.power - r)

    def refs(self, view, el, x, a):
        peak = float(np.max(np.abs(x))) or 1.0
        return (
            abs(slope(view.model, el, view.values)) / peak**self.power,
            (1.5 if self.power == 2 else 5 / 3) * float(np.mean(x**self.power)),
        )

    def fit(self, view):
        if self.power is not None:
            return super().fit(view)
        fits = [PolarizationSaturation(m).fit(view) for m in self.powers]
        return min(fits, key=lambda ext: view.score(ext.prediction)[2])


class FieldStiffness(_Centred):
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
        return abs(slope(view.model, el, view.values)) / peak**2, float(np.mean(a**2))


class NonlinearDamping(_Centred):
    """Amplitude-dependent damping: every element tagged ``damping`` gets e = (c + μ1·(a² − r²))·f
    with a the displacement of the stiffness element on its junction (Stanton type) or, with
    ``velocity`` or when there is none, a = f (velocity-cubic); r² = ⟨a²⟩/2 (1.5·⟨f²⟩ for the
    velocity form) centres it on the data's amplitude; μ1 ≥ 0."""

    cause = "nonlinear-damping"
    label = "amplitude-dependent (Stanton) damping of the damping elements"
    role, prefix, upper = "damping", "nld.mu1", 10.0

    def __init__(self, velocity: bool = False):
        self.velocity = velocity
        if velocity:
            self.label = "velocity-cubic damping of the damping elements"
            self.prefix = "nld.mu1v"

    def applies(self, view):
        ok = super().applies(view)
        if ok is not True or self.velocity:
            return ok
        if not any(self.partner(view.model, el) for el in view.model.with_role(self.role)):
            return "no damping element has a stiffness partner (the velocity-cubic form covers it)"
        return True

    def partner(self, model, el):
        if self.velocity:
            return None
        return next((o for o in neighbours(model, el) if getattr(model.elements[o], "role", None) == "stiffness"), None)

    @staticmethod
    def term(c, r2, x, a):
        return c * ((x if a is None else a) ** 2 - r2) * x

    def refs(self, view, el, x, a):
        amp = x if a is None else a
        peak = float(np.max(np.abs(amp))) or 1.0
        return (abs(slope(view.model, el, view.values)) / peak**2, (1.5 if a is None else 0.5) * float(np.mean(amp**2)))


class FrictionDamping(NonlinearDamping):
    """Friction in the structure (a clamp, a bond layer): every element tagged ``damping``
    gets a smoothed Coulomb force, e = law(f) + F·tanh(f/s), F = μ·s, μ ≥ 0 in units of the
    element's damping; s keeps the law smooth: 3 % of the data's peak velocity, or 10 or 30 %
    if these fit better (tried only when the first improves the fit part by 2 % or more).  Its
    equivalent viscous damping 4F/(πV) falls with the velocity amplitude V, where the cubic
    forms' rises.  Runs on the exact Lur'e route (one tanh is allowed beside the polynomial
    terms)."""

    label = "Coulomb friction (smoothed) in the damping elements"
    cost = 4  # up to three smoothing velocities, each a fit on the exact route
    upper = 300.0
    grid = (1.0, 8.0, 64.0)
    #: smoothing velocities tried, as shares of the data's peak velocity (the best fit is kept)
    smoothing = (0.03, 0.1, 0.3)

    def __init__(self, velocity_share: float | None = None):
        super().__init__(velocity=True)
        self.label = FrictionDamping.label
        self.prefix = "nld.fc"
        #: the smoothing velocity of this fit (share of the peak velocity); None: try ``smoothing``
        self.velocity_share = velocity_share

    @staticmethod
    def term(c, r2, x, a):
        return c * r2 * sp.tanh(x / r2)

    def refs(self, view, el, x, a):
        peak = float(np.max(np.abs(x))) or 1.0
        return abs(slope(view.model, el, view.values)), self.velocity_share * peak

    def fit(self, view):
        if self.velocity_share is not None:
            return super().fit(view)
        before = view.score(view.prediction)[2]
        best = None
        for share in self.smoothing:
            ext = FrictionDamping(share).fit(view)
            rf = view.score(ext.prediction)[2]
            if best is None or rf < best[0]:
                best = (rf, ext)
            if best[0] > 0.98 * before:
                break
        return best[1]
