"""A mode the model lacks.  Both candidates keep the model linear, so they are fitted on the
exact linear route; Ghafarirad et al. (MCMDS 21(2), 2015) superpose bending modes the same way."""

from __future__ import annotations

import math

import numpy as np
import sympy as sp
from scipy import signal

from bondgraph import J0, J1, C, I, Quantity, R, Se
from bondgraph.diagnosis import LINEAR, Candidate, Extension
from bondgraph.diagnosis.context import welch
from bondgraph.diagnosis.filters import resonator
from bondgraph.diagnosis.rewrite import junction_of, law, modify_law
from bondgraph.fit.identify import Spec

from .drive import NOT_A_DRIVE


def frf_mismatch(view):
    """(ω rad/s, mismatch): |H_measured − H_model| relative to the model, weighted by coherence."""
    w, H, coh = view.empirical_frf()
    Hm = view.gain * view.frequency_response(w)
    return w, np.abs(H - Hm) * coh / np.maximum(np.abs(Hm), 1e-300 + 1e-3 * np.abs(Hm).max(initial=0.0))


def unresolved(view) -> str:
    """Why no mode can be placed from the record's frequency response ('' if one can): the
    record resolves the response at no frequency (output and drive coherent nowhere)."""
    if view.empirical_frf()[0].size:
        return ""
    return (
        f"the record resolves the response at no frequency (coherence of output and drive "
        f"≤ {view.resolved_coherence:g} everywhere): no mismatch to place a mode at"
    )


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


def mode_implausible(view, omega: float, zeta: float, raw: np.ndarray | None = None) -> str:
    """Why an added mode at ``omega`` (rad/s) with damping ratio ``zeta`` is not plausible.  A
    mode where the record does not resolve the response is refused unless what it explains
    (``raw``, the extended model's prediction) lies mostly where the record does resolve it
    (its skirt below the drive's band, not noise near its own frequency)."""
    f = omega / (2 * math.pi)
    if f > 0.45 * view.fs:
        return f"its frequency ({f:.4g} Hz) is beyond the data's Nyquist frequency"
    low = view.lowest_resonance_hz
    if low is not None and f < 0.5 * low:
        return (
            f"its frequency ({f:.4g} Hz) is below half the model's lowest mode ({low:.4g} Hz): not a "
            f"higher mode of this structure"
        )
    d = np.asarray(view.drive if view.drive is not None else view.u)
    fr, P = welch(d, view.fs, 4096)
    near = np.abs(fr - f) <= max(0.1 * f, fr[1])
    if not near.any() or P[near].max() < 1e-6 * P.max():
        return f"the drive does not excite {f:.4g} Hz"
    coh = view.coherence_near(omega)
    share = None if raw is None or coh >= view.resolved_coherence else view.resolved_share(raw)
    if coh < view.resolved_coherence and (share is None or share < 0.5):
        return (
            f"the record does not resolve the response near {f:.4g} Hz (coherence {coh:.2g} < "
            f"{view.resolved_coherence:g}: as much noise as response there)"
            + ("" if share is None else f" and {share:.0%} of what it explains lies where the record resolves it")
        )
    if zeta > 0.3:
        return f"it is not a resonance (damping ratio {zeta:.2g})"
    return ""


def resonance_trials(view) -> list[tuple[float, float, float]]:
    """(residual sum of squares, ω rad/s, ζ) of a resonator driven by the drive and fitted by
    its gain alone to the current residual, scanned around each frequency-response mismatch
    peak, best first (each trial is one small recursion)."""
    d = np.asarray(view.drive)
    idx = view.fit_idx
    r = view.residual[idx] - view.residual[idx].mean()
    trials = []
    for om0 in mismatch_peaks(view):
        for om in om0 * np.geomspace(0.85, 1.15, 7):
            for ze in (0.005, 0.02, 0.06):
                q = resonator(d, view.dt, om, ze)[idx]
                q = q - q.mean()
                g = (q @ r) / max(q @ q, 1e-300)
                trials.append((float(np.sum((r - g * q) ** 2)), float(om), ze))
    if not trials:
        raise ValueError("no frequency-response mismatch to place a mode at")
    return sorted(trials)


class ParallelMode(Candidate):
    """A mode the model lacks: a resonator q̈ + 2ζω·q̇ + ω²·q = g·d whose displacement adds to
    the output (modal superposition)."""

    cause = "higher-mode"
    label = "extra resonator (mode) in parallel on the output"
    kind = LINEAR

    def applies(self, view):
        return NOT_A_DRIVE if view.drive is None else unresolved(view) or True

    def evidence(self, view):
        w, mis = frf_mismatch(view)
        k = int(np.argmax(mis)) if mis.size else 0
        return {"frf_mismatch": float(mis[k]) if mis.size else 0.0, "omega_peak": float(w[k]) if w.size else 0.0}

    def fit(self, view):
        d = np.asarray(view.drive)
        trials = resonance_trials(view)
        _, om, ze = trials[0]
        starts = [[math.log(t[1]), math.log(t[2])] for t in trials[1:3]]
        fit = view.fit_drive(
            direct=lambda z: [resonator(d, view.dt, math.exp(z[0]), math.exp(z[1]))],
            z0=[math.log(om), math.log(ze)],
            z_bounds=[(math.log(om / 2), math.log(om * 2)), (math.log(1e-4), math.log(0.5))],
            z_names=["hm.omega", "hm.zeta"],
            starts=starts,
        )
        om, ze, g = math.exp(fit.z[0]), math.exp(fit.z[1]), float(fit.direct[0])
        model = view.rewrite()
        o = model.parameter("hm.omega", om, "rad/s", "natural frequency of the added mode")
        z = model.parameter("hm.zeta", ze, "1", "damping ratio of the added mode")
        gg = model.parameter("hm.g", g, "", "input gain of the added mode (unit modal mass)")
        model.add(
            Se("hm.force", gg * view.drive_expr),
            J1("hm.mode"),
            I("hm.mass", 1),
            C("hm.spring", 1 / o**2),
            R("hm.damper", 2 * z * o),
        )
        model.bond("hm.force", "hm.mode")
        for e in ("hm.mass", "hm.spring", "hm.damper"):
            model.bond("hm.mode", e)
        view.add_to_output(model, Quantity("q", "hm.spring"))
        new = {"hm.omega": om, "hm.zeta": ze, "hm.g": g}
        return Extension(
            model,
            {**fit.values, **new},
            list(new),
            fit.prediction,
            view.drive,
            view.drive_expr,
            fit.at_bounds,
            fit.success,
            fit.message,
        )

    def implausible(self, view, ext):
        return mode_implausible(view, ext.values["hm.omega"], ext.values["hm.zeta"], ext.prediction)

    def mimics_recalibration(self, view, ext):
        return mode_on_own(view, ext.values["hm.omega"])


class OutputMode(Candidate):
    """A mode of the moving mass itself: the element tagged ``inertia`` (mass M, an amplified
    actuator's shell and output plate) split into m1 = μ·M, driven by the actuator, and
    m2 = (1 − μ)·M, carrying the sensor, joined by a spring k2 and damper c2 tuned to the
    two-mass mode ω, ζ: k2 = ω²·m1·m2/M, c2 = 2ζω·m1·m2/M (the total mass is unchanged)."""

    cause = "higher-mode"
    label = "compliant moving mass (a share of it on a spring) on the inertia element"
    kind = LINEAR

    def applies(self, view):
        if not view.model.with_role("inertia"):
            return "no element is tagged 'inertia'"
        if view.reduced:
            return "the inertia's dynamics are faster than the data resolve"
        if view.drive is None:
            return NOT_A_DRIVE
        return unresolved(view) or True if view.exact else "needs a model linear in its states"

    def build(self, view, model, omega, zeta, mu):
        """``model`` (the current model or its linear core) with its inertia split."""
        el = view.model.with_role("inertia")[0]
        x = sp.Dummy("p")
        M = 1 / sp.diff(law(model, el)(x), x)
        om = model.parameter("om.omega", omega, "rad/s", "natural frequency of the two-mass mode")
        ze = model.parameter("om.zeta", zeta, "1", "damping ratio of the two-mass mode")
        share = model.parameter("om.mu", mu, "1", "share of the inertia's mass on the actuator's side of the spring")
        reduced = share * (1 - share) * M
        modify_law(model, el, lambda p, old: old / share)
        model.add(
            J0("om.k"),
            C("om.spring", 1 / (reduced * om**2)),
            J1("om.plate"),
            I("om.mass", (1 - share) * M),
            R("om.damper", 2 * ze * om * reduced),
        )
        model.bond(junction_of(model, el), "om.k")
        model.bond("om.k", "om.spring")
        model.bond("om.k", "om.plate")
        model.bond("om.plate", "om.mass")
        model.bond("om.plate", "om.damper")
        view.add_to_output(model, -Quantity("q", "om.spring"))  # the sensor sits on the plate
        return model

    def fit(self, view):
        best = None
        on_core = view.on_core  # fitted on the linear core, driven by what it sees (exact route)
        drive = view.drive if on_core else None
        # starts: the resonator scan's best frequency and damping at each of the two largest
        # mismatch peaks, with the mass share that fits best before any refit
        peaks = []
        for _, om, ze in resonance_trials(view):
            if all(abs(om / p[0] - 1) > 0.2 for p in peaks):
                peaks.append((om, max(ze, 0.01)))
            if len(peaks) == 2:
                break
        for om, ze in peaks:
            model = self.build(view, view.core() if on_core else view.rewrite(), om, ze, 0.5)
            predict, known = view.predictor(model, drive)
            base = {k: v for k, v in view.values.items() if k in known}
            mu = min(
                (0.1, 0.3, 0.5, 0.8, 0.95),
                key=lambda m: view.score(predict({**base, "om.omega": om, "om.zeta": ze, "om.mu": m}))[2],
            )
            specs = [
                Spec("om.omega", om, om / 3, om * 3, log=True),
                Spec("om.zeta", ze, 1e-4, 1.0, log=True),
                Spec("om.mu", mu, 0.02, 0.98),
            ]
            values, raw, ok, msg, at = view.fit_model(model, specs, max_nfev=20, drive=drive)
            rf = view.score(raw)[2]
            if best is None or rf < best[0]:
                best = (rf, values, raw, ok, msg, at)
        _, values, raw, ok, msg, at = best
        model = self.build(view, view.rewrite(), values["om.omega"], values["om.zeta"], values["om.mu"])
        new = ["om.omega", "om.zeta", "om.mu"]
        return Extension(model, values, new, raw, None, None, at, ok, msg)

    def implausible(self, view, ext):
        return mode_implausible(view, ext.values["om.omega"], ext.values["om.zeta"], ext.prediction)

    def mimics_recalibration(self, view, ext):
        return mode_on_own(view, ext.values["om.omega"])
