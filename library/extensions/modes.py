"""A mode the model lacks.  Both candidates keep the model linear, so they are fitted on the
exact linear route; Ghafarirad et al. (MCMDS 21(2), 2015) superpose bending modes the same way."""
from __future__ import annotations

import math

import numpy as np
from scipy import signal

from bondgraph import C, I, J0, J1, Quantity, R, Se
from bondgraph.diagnosis import LINEAR, Candidate, Extension
from bondgraph.diagnosis.context import welch
from bondgraph.diagnosis.filters import resonator
from bondgraph.diagnosis.rewrite import junction_of, slope
from bondgraph.identify import Spec

from .drive import NOT_A_DRIVE


def frf_mismatch(view):
    """(ω rad/s, mismatch): |H_measured − H_model| relative to the model, weighted by coherence."""
    w, H, coh = view.empirical_frf()
    Hm = view.gain * view.frequency_response(w)
    return w, np.abs(H - Hm) * coh / np.maximum(np.abs(Hm), 1e-300 + 1e-3 * np.abs(Hm).max())


def mismatch_peaks(view, n: int = 3) -> list[float]:
    """Frequencies (rad/s) of the ``n`` largest peaks of the frequency-response mismatch."""
    w, mis = frf_mismatch(view)
    if w.size == 0:
        return []
    peaks, _ = signal.find_peaks(mis)
    order = peaks[np.argsort(-mis[peaks])][:n] if peaks.size else np.array([int(np.argmax(mis))])
    return [float(w[k]) for k in order]


def mode_on_own(view, omega: float) -> str:
    """Why an added mode at ``omega`` (rad/s) may be a recalibration of one of the model's own
    modes ('' if it is not within 15 % of any)."""
    f = omega / (2 * math.pi)
    for fm in view.resonances_hz:
        if fm > 0 and abs(f / fm - 1) < 0.15:
            return f"it sits on the model's own mode at {fm:.4g} Hz"
    return ""


def mode_implausible(view, omega: float, zeta: float) -> str:
    """Why an added mode at ``omega`` (rad/s) with damping ratio ``zeta`` is not plausible."""
    f = omega / (2 * math.pi)
    if f > 0.45 * view.fs:
        return f"its frequency ({f:.4g} Hz) is beyond the data's Nyquist frequency"
    low = view.lowest_resonance_hz
    if low is not None and f < 0.5 * low:
        return (f"its frequency ({f:.4g} Hz) is below half the model's lowest mode ({low:.4g} Hz): not a "
                f"higher mode of this structure")
    d = np.asarray(view.drive if view.drive is not None else view.u)
    fr, P = welch(d, view.fs, 4096)
    near = np.abs(fr - f) <= max(0.1 * f, fr[1])
    if not near.any() or P[near].max() < 1e-6 * P.max():
        return f"the drive does not excite {f:.4g} Hz"
    coh = view.coherence_near(omega)
    if coh < view.resolved_coherence:
        return (f"the record does not resolve the response near {f:.4g} Hz (coherence {coh:.2g} < "
                f"{view.resolved_coherence:g}: as much noise as response there)")
    if zeta > 0.3:
        return f"it is not a resonance (damping ratio {zeta:.2g})"
    return ""


class ParallelMode(Candidate):
    """A mode the model lacks: a resonator q̈ + 2ζω·q̇ + ω²·q = g·d whose displacement adds to
    the output (modal superposition)."""

    cause = "higher-mode"
    label = "extra resonator (mode) in parallel on the output"
    kind = LINEAR

    def applies(self, view):
        return True if view.drive is not None else NOT_A_DRIVE

    def evidence(self, view):
        w, mis = frf_mismatch(view)
        k = int(np.argmax(mis)) if mis.size else 0
        return {"frf_mismatch": float(mis[k]) if mis.size else 0.0, "omega_peak": float(w[k]) if w.size else 0.0}

    def fit(self, view):
        d = np.asarray(view.drive)
        idx = view.fit_idx
        r = view.residual[idx] - view.residual[idx].mean()
        trials = []
        # scan frequency and damping around each mismatch peak: each trial is one small recursion
        for om0 in mismatch_peaks(view):
            for om in om0 * np.geomspace(0.85, 1.15, 7):
                for ze in (0.005, 0.02, 0.06):
                    q = resonator(d, view.dt, om, ze)[idx]
                    q = q - q.mean()
                    g = (q @ r) / max(q @ q, 1e-300)
                    trials.append((float(np.sum((r - g * q) ** 2)), om, ze))
        if not trials:
            raise ValueError("no frequency-response mismatch to place a mode at")
        trials.sort()
        _, om, ze = trials[0]
        starts = [[math.log(t[1]), math.log(t[2])] for t in trials[1:3]]
        fit = view.fit_drive(direct=lambda z: [resonator(d, view.dt, math.exp(z[0]), math.exp(z[1]))],
                             z0=[math.log(om), math.log(ze)],
                             z_bounds=[(math.log(om / 2), math.log(om * 2)), (math.log(1e-4), math.log(0.5))],
                             z_names=["hm.omega", "hm.zeta"], starts=starts)
        om, ze, g = math.exp(fit.z[0]), math.exp(fit.z[1]), float(fit.direct[0])
        model = view.rewrite()
        o = model.parameter("hm.omega", om, "rad/s", "natural frequency of the added mode")
        z = model.parameter("hm.zeta", ze, "", "damping ratio of the added mode")
        gg = model.parameter("hm.g", g, "", "input gain of the added mode (unit modal mass)")
        model.add(Se("hm.force", gg * view.drive_expr), J1("hm.mode"), I("hm.mass", 1), C("hm.spring", 1 / o ** 2),
                  R("hm.damper", 2 * z * o))
        model.bond("hm.force", "hm.mode")
        for e in ("hm.mass", "hm.spring", "hm.damper"):
            model.bond("hm.mode", e)
        view.add_to_output(model, Quantity("q", "hm.spring"))
        new = {"hm.omega": om, "hm.zeta": ze, "hm.g": g}
        return Extension(model, {**fit.values, **new}, list(new), fit.prediction, view.drive, view.drive_expr,
                         fit.at_bounds, fit.success, fit.message)

    def implausible(self, view, ext):
        return mode_implausible(view, ext.values["hm.omega"], ext.values["hm.zeta"])

    def mimics_recalibration(self, view, ext):
        return mode_on_own(view, ext.values["hm.omega"])


class OutputMode(Candidate):
    """A mode of the output structure: a mass m2 on a spring k2 with damper c2 riding on the
    element tagged ``inertia`` (an amplified actuator's output plate or shell), the sensor on
    m2: k2 = m2·ω², c2 = 2ζ·m2·ω."""

    cause = "higher-mode"
    label = "compliant output stage (mass on a spring) on the inertia element"
    kind = LINEAR

    def applies(self, view):
        if not view.model.with_role("inertia"):
            return "no element is tagged 'inertia'"
        if view.reduced:
            return "the inertia's dynamics are faster than the data resolve"
        if view.drive is None:
            return NOT_A_DRIVE
        return True if view.exact else "needs a model linear in its states"

    def build(self, view, model, omega, zeta, m2):
        """``model`` (the current model or its linear core) with the output stage added."""
        el = view.model.with_role("inertia")[0]
        om = model.parameter("om.omega", omega, "rad/s", "natural frequency of the output stage")
        ze = model.parameter("om.zeta", zeta, "", "damping ratio of the output stage")
        m = model.parameter("om.m2", m2, "kg", "mass of the output stage")
        model.add(J0("om.k"), C("om.spring", 1 / (m * om ** 2)), J1("om.plate"), I("om.mass", m),
                  R("om.damper", 2 * ze * m * om))
        model.bond(junction_of(model, el), "om.k")
        model.bond("om.k", "om.spring")
        model.bond("om.k", "om.plate")
        model.bond("om.plate", "om.mass")
        model.bond("om.plate", "om.damper")
        view.add_to_output(model, -Quantity("q", "om.spring"))  # the sensor sits on the plate
        return model

    def fit(self, view):
        el = view.model.with_role("inertia")[0]
        M = 1.0 / slope(view.model, el, view.values)
        best = None
        on_core = view.on_core   # fitted on the linear core, driven by what it sees (exact route)
        for om in mismatch_peaks(view)[:2]:
            specs = [Spec("om.omega", om, om / 3, om * 3, log=True), Spec("om.zeta", 0.03, 1e-4, 1.0, log=True),
                     Spec("om.m2", 0.2 * M, 1e-3 * M, 10 * M, log=True)]
            model = self.build(view, view.core() if on_core else view.rewrite(), om, 0.03, 0.2 * M)
            values, raw, ok, msg, at = view.fit_model(model, specs, max_nfev=20,
                                                      drive=view.drive if on_core else None)
            rf = view.score(raw)[2]
            if best is None or rf < best[0]:
                best = (rf, values, raw, ok, msg, at)
        if best is None:
            raise ValueError("no frequency-response mismatch to place a mode at")
        _, values, raw, ok, msg, at = best
        model = self.build(view, view.rewrite(), values["om.omega"], values["om.zeta"], values["om.m2"])
        new = ["om.omega", "om.zeta", "om.m2"]
        return Extension(model, values, new, raw, None, None, at, ok, msg)

    def implausible(self, view, ext):
        return mode_implausible(view, ext.values["om.omega"], ext.values["om.zeta"])

    def mimics_recalibration(self, view, ext):
        return mode_on_own(view, ext.values["om.omega"])
