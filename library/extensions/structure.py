"""Nonlinear laws inside the structure, found through element roles (``stiffness``,
``damping``) and fitted with the compiled integrator (Shahabi, Ghafarirad & Taghvaeipour,
C. R. Mécanique 347 (2019): cubic softening and amplitude-dependent damping of a bender)."""
from __future__ import annotations

from abc import abstractmethod

import numpy as np
import sympy as sp

from bondgraph import Quantity
from bondgraph.diagnosis import Candidate, Extension
from bondgraph.diagnosis.rewrite import modify_law, neighbours, slope
from bondgraph.identify import Spec
from bondgraph.simulate import SimulationError


class _Centred(Candidate):
    """A structural nonlinearity, one coefficient per element of ``role``, centred on the
    data's amplitude (see the subclasses): scanned upwards on a log grid of its scale with
    the integrator, then fitted with the calibration from the best grid point."""

    role = ""
    prefix = ""
    upper = 1.0
    cost = 3
    grid = (0.003, 0.01, 0.03, 0.1, 0.3, 1.0)

    def applies(self, view):
        if not view.model.with_role(self.role):
            return f"no element is tagged '{self.role}'"
        if view.reduced:
            return (f"the '{self.role}' elements act in modes faster than the data resolve (their "
                    f"quasi-static effect is a drive nonlinearity)")
        return True

    @abstractmethod
    def refs(self, view, series) -> dict[str, tuple[float, float]]:
        """(scale of the coefficient, centring amplitude²) per element."""

    @abstractmethod
    def rewrite(self, view, model, el, coef, r2) -> None:
        """Give element ``el`` of ``model`` the nonlinear law."""

    def build(self, view, coefs: dict, refs: dict):
        model = view.rewrite()
        for el in view.model.with_role(self.role):
            c = model.parameter(f"{self.prefix}_{el}", coefs[el], "", f"{self.label}: {el}", bounds=(0, 1e40))
            r2 = model.parameter(f"{self.prefix}_r2_{el}", refs[el][1], "", f"centring amplitude² of {el}")
            self.rewrite(view, model, el, c, r2)
        return model

    def fit(self, view):
        refs = self.refs(view, view.states())
        els = list(refs)
        model = self.build(view, {el: 0.0 for el in els}, refs)
        names = [f"{self.prefix}_{el}" for el in els]

        def spec(f, lo=None, hi=None):
            return [Spec(n, f * refs[el][0], f * refs[el][0] if lo is None else lo,
                         f * refs[el][0] if hi is None else hi, scale=refs[el][0]) for n, el in zip(names, els)]

        # a nonlinear resonance moves with the calibration: each grid point refits the linear
        # parameters briefly (the coefficient held); the scan stops once two points in a row
        # do not improve
        best, worse = None, 0
        for f in self.grid:
            try:
                values, raw, *_ = view.fit_model(model, spec(f), max_nfev=3)
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
        fitted = view.fit_model(model, [Spec(n, best[1] * refs[el][0], 0.0, self.upper * refs[el][0],
                                             scale=refs[el][0]) for n, el in zip(names, els)],
                                max_nfev=12, start=start)
        values, raw, ok, msg, at = fitted
        return Extension(self.build(view, {el: values[n] for n, el in zip(names, els)}, refs), values, names,
                         raw, None, None, at, ok, msg)


class StiffnessSoftening(_Centred):
    """Amplitude-dependent stiffness: every element tagged ``stiffness`` gets a cubic softening
    term, written centred on the data's amplitude, e = law(q) − k3·q·(q² − r²) with
    r² = 1.5·⟨q²⟩ of the current model: the describing-function stiffness at the data's
    amplitude stays the calibrated one, so k3 (≥ 0) only moves the stiffness with amplitude."""

    cause = "softening"
    label = "cubic softening of the stiffness elements"
    role, prefix, upper = "stiffness", "soft.k3", 2.0

    def refs(self, view, series):
        out = {}
        for el in view.model.with_role(self.role):
            q = series[view.state_of(el)]
            peak = float(np.max(np.abs(q))) or 1.0
            out[el] = (abs(slope(view.model, el, view.values)) / peak ** 2, 1.5 * float(np.mean(q ** 2)))
        return out

    def rewrite(self, view, model, el, coef, r2):
        modify_law(model, el, lambda q, old: old - coef * q * (q ** 2 - r2))


class NonlinearDamping(_Centred):
    """Amplitude-dependent damping: every element tagged ``damping`` gets e = (c + μ1·(a² − r²))·f
    with a the displacement of the stiffness element on its junction (Stanton type) or, with
    ``velocity`` or when there is none, a = f (velocity-cubic); r² = ⟨a²⟩/2 (1.5·⟨f²⟩ for the
    velocity form) centres it on the data's amplitude; μ1 ≥ 0."""

    cause = "nonlinear-damping"
    label = "amplitude-dependent (Stanton) damping of the damping elements"
    role, prefix, upper = "damping", "nld.mu1", 50.0

    def __init__(self, velocity: bool = False):
        self.velocity = velocity
        if velocity:
            self.label = "velocity-cubic damping of the damping elements"
            self.prefix = "nld.mu1v"

    def applies(self, view):
        ok = super().applies(view)
        if ok is not True or self.velocity:
            return ok
        if not any(self._partner(view.model, el) for el in view.model.with_role(self.role)):
            return "no damping element has a stiffness partner (the velocity-cubic form covers it)"
        return True

    def _partner(self, model, el):
        if self.velocity:
            return None
        return next((o for o in neighbours(model, el) if getattr(model.elements[o], "role", None) == "stiffness"),
                    None)

    def refs(self, view, series):
        out = {}
        for el in view.model.with_role(self.role):
            c_lin = abs(slope(view.model, el, view.values))
            partner = self._partner(view.model, el)
            a = series[view.state_of(partner)] if partner else series["output rate"]
            peak = float(np.max(np.abs(a))) or 1.0
            out[el] = (c_lin / peak ** 2, (0.5 if partner else 1.5) * float(np.mean(a ** 2)))
        return out

    def rewrite(self, view, model, el, coef, r2):
        partner = self._partner(model, el)
        if partner:
            a = Quantity("q", partner)
            modify_law(model, el, lambda f, old: old + coef * (a ** 2 - r2) * f)
        else:
            modify_law(model, el, lambda f, old: old + coef * (f ** 2 - r2) * f)
