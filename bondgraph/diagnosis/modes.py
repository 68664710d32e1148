"""A mode the model lacks: a resonator added on the output (modal superposition, as
Ghafarirad et al., "Continuous dynamic modelling of bimorph piezoelectric cantilevered
actuators considering hysteresis effect and dynamic behaviour analysis", Mathematical and
Computer Modelling of Dynamical Systems 21(2) (2015) 130–152, superpose bending modes), or a
mass of the model split in two by a spring.  Both keep the model linear, so they are fitted
on the exact linear route.  Both may be named again in one chain: a structure may lack
several modes."""

from __future__ import annotations

import itertools
import math

import numpy as np
import sympy as sp
from scipy import signal

from ..equations.derivation import derive
from ..fit.identify import Spec
from ..model.elements import J0, J1, C, I, R, Se
from ..model.graph import Quantity
from ..support.errors import ModelError
from .calibration import cross_spectra
from .candidate import LINEAR, NOT_A_DRIVE, Candidate, Extension
from .context import welch
from .filters import resonator
from .projection import projected_fit
from .rewrite import add_to_output, junction_of, law, modify_law
from .sites import Site, each_element, generic_sites


def frf_mismatch(view):
    """(ω rad/s, mismatch): |H_measured − H_model| relative to the model, weighted by coherence.

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.

    Returns
    -------
    omega : numpy.ndarray
        Angular frequencies of the Welch bins, rad/s.
    mismatch : numpy.ndarray
        The relative mismatch (dimensionless) at each.
    """
    w, H, coh = view.record.empirical_frf()
    Hm = view.current.gain * view.frequency_response(w)
    return w, np.abs(H - Hm) * coh / np.maximum(np.abs(Hm), 1e-300 + 1e-3 * np.abs(Hm).max(initial=0.0))


def driving(view) -> np.ndarray:
    """The series that drives the current model: the drive its linear core sees (a transform
    of the recorded drive), or, after a linear structural extension, the recorded drive itself.

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.

    Returns
    -------
    numpy.ndarray
        The series on every sample, drive units.
    """
    return np.asarray(view.current.drive if view.current.drive is not None else view.record.u)


def unresolved(view) -> str:
    """Why no mode can be placed from the record's frequency response ('' if one can): the
    record resolves the response at no frequency (output and drive coherent nowhere).

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.

    Returns
    -------
    str
        The reason, or "".
    """
    if view.record.empirical_frf()[0].size:
        return ""
    return (
        f"the record resolves the response at no frequency (coherence of output and drive "
        f"≤ {view.record.resolved_coherence:g} everywhere): no mismatch to place a mode at"
    )


def resolved_share(view, raw: np.ndarray) -> float:
    """The share (0-1) of the residual power a raw prediction removes (its sensor gain and
    offset solved) that lies where the record resolves the response
    (:meth:`~bondgraph.diagnosis.view.Record.resolution_near`'s rule, bin by bin); 0 when it
    removes none.

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.
    raw : numpy.ndarray
        A raw prediction on every sample.

    Returns
    -------
    float
        The share, between 0 and 1.
    """
    g, b = view.score(raw)[:2]
    u, y, fs = view.record.u_recorded, view.record.y, view.record.fs
    ok = view.record.resolved[2]
    before = cross_spectra(u, view.current.residual, fs)[2][1:]
    after = cross_spectra(u, y - (g * np.asarray(raw) + b), fs)[2][1:]
    drop = np.maximum(before - after, 0.0)
    return float(drop[ok].sum() / drop.sum()) if drop.sum() > 0 else 0.0


def mismatch_peaks(view, n: int = 3) -> list[float]:
    """Frequencies (rad/s) of the ``n`` largest peaks of the frequency-response mismatch.

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.
    n : int, optional
        Most peaks returned.

    Returns
    -------
    list of float
        Angular frequencies, rad/s, largest peak first (the maximum when there is no peak).
    """
    w, mis = frf_mismatch(view)
    if w.size == 0:
        return []
    peaks, _ = signal.find_peaks(mis)
    order = peaks[np.argsort(-mis[peaks])][:n] if peaks.size else np.array([int(np.argmax(mis))])
    return [float(w[k]) for k in order]


def mode_on_own(view, omega: float) -> str:
    """Why an added mode at ``omega`` (rad/s) may be a recalibration of one of the model's own
    modes ('' if it is not within 15 % of any).

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.
    omega : float
        The added mode's natural angular frequency, rad/s.

    Returns
    -------
    str
        The reason, or "".
    """
    f = omega / (2 * math.pi)
    for fm in view.record.resonances_hz:
        if fm > 0 and abs(f / fm - 1) < 0.15:
            return f"it sits on the model's own mode at {fm:.4g} Hz"
    return ""


#: the drive's power spectrum within this share of its peak (20 dB) is its band, which must
#: span :data:`SKIRT_SPAN` in frequency (highest over lowest) for a mode the drive does not
#: excite to be seen by its skirt: a skirt is a gain and phase that change with frequency, and
#: at one line (a sine) it is only a gain and a phase, which the calibration has as well
DRIVE_BAND_LEVEL = 0.01
#: see :data:`DRIVE_BAND_LEVEL`
SKIRT_SPAN = 1.25


def mode_implausible(view, omega: float, zeta: float, raw: np.ndarray | None = None) -> str:
    """Why an added mode at ``omega`` (rad/s) with damping ratio ``zeta`` is not plausible.  A
    mode the drive does not excite, or where the record does not resolve the response, is
    refused unless what it explains (``raw``, the extended model's prediction) lies mostly
    where the record does resolve it: a mode above the drive's band shows by its skirt inside
    the band (a gain and phase that change with frequency), not by noise near its own
    frequency.  A mode the drive does not excite also needs a drive whose band spans
    :data:`SKIRT_SPAN` in frequency.

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.
    omega : float
        The mode's natural angular frequency, rad/s.
    zeta : float
        Its damping ratio.
    raw : numpy.ndarray, optional
        The extended model's raw prediction.

    Returns
    -------
    str
        The reason (beyond Nyquist, below half the lowest mode, not excited, not resolved,
        not a resonance), or "" when plausible.
    """
    f = omega / (2 * math.pi)
    if f > 0.45 * view.record.fs:
        return f"its frequency ({f:.4g} Hz) is beyond the data's Nyquist frequency"
    low = view.record.lowest_resonance_hz
    if low is not None and f < 0.5 * low:
        return (
            f"its frequency ({f:.4g} Hz) is below half the model's lowest mode ({low:.4g} Hz): not a "
            f"higher mode of this structure"
        )
    fr, P = welch(driving(view), view.record.fs, 4096)
    near = np.abs(fr - f) <= max(0.1 * f, fr[1])
    excited = bool(near.any() and P[near].max() >= 1e-6 * P.max())
    strong = fr[(P >= DRIVE_BAND_LEVEL * P.max()) & (fr > 0)]
    span = float(strong.max() / strong.min()) if strong.size else 1.0
    if not excited and span < SKIRT_SPAN:
        return (
            f"the drive does not excite {f:.4g} Hz, and its band (within "
            f"{-10 * math.log10(DRIVE_BAND_LEVEL):.0f} dB of its peak) spans "
            f"{span:.3g}× in frequency, too narrow to show a skirt"
        )
    coh, resolved = view.record.resolution_near(omega)
    share = None if raw is None or (excited and resolved) else resolved_share(view, raw)
    skirt = "" if share is None else f" and {share:.0%} of what it explains lies where the record resolves it"
    if not excited and (share is None or share < 0.5):
        return f"the drive does not excite {f:.4g} Hz" + skirt
    if not resolved and (share is None or share < 0.5):
        return (
            f"the record does not resolve the response near {f:.4g} Hz (coherence {coh:.2g} < "
            f"{view.record.resolved_coherence:g}: as much noise as response there)" + skirt
        )
    if zeta > 0.3:
        return f"it is not a resonance (damping ratio {zeta:.2g})"
    return ""


def resonance_trials(view) -> list[tuple[float, float, float]]:
    """(residual sum of squares, ω rad/s, ζ) of a resonator driven by the drive and fitted by
    its gain alone to the current residual, scanned around each frequency-response mismatch
    peak, best first (each trial is one small recursion).

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.

    Returns
    -------
    list of tuple of float
        (residual sum of squares on the fit part, ω rad/s, ζ), ascending.

    Raises
    ------
    ValueError
        No frequency-response mismatch to place a mode at.
    """
    d = driving(view)
    idx = view.record.fit_idx
    r = view.current.residual[idx] - view.current.residual[idx].mean()
    trials = []
    for om0 in mismatch_peaks(view):
        for om in om0 * np.geomspace(0.85, 1.15, 7):
            for ze in (0.005, 0.02, 0.06):
                q = resonator(d, view.record.dt, om, ze)[idx]
                q = q - q.mean()
                g = (q @ r) / max(q @ q, 1e-300)
                trials.append((float(np.sum((r - g * q) ** 2)), float(om), ze))
    if not trials:
        raise ValueError("no frequency-response mismatch to place a mode at")
    return sorted(trials)


def free_prefix(model, base: str) -> str:
    """``base``, or ``base2``, ``base3``, ... : the first whose parameters are not in ``model``
    yet (a mode named before keeps its names).

    Parameters
    ----------
    model : Model
        The current model.
    base : str
        The prefix wanted.

    Returns
    -------
    str
        The first free prefix.
    """
    known = set(model.all_parameters())
    k = 1
    while f"{base if k == 1 else base + str(k)}.omega" in known:
        k += 1
    return base if k == 1 else f"{base}{k}"


class ParallelMode(Candidate):
    """A mode the model lacks: a resonator q̈ + 2ζω·q̇ + ω²·q = d driven by the drive d, whose
    displacement and velocity add to the output as g·q + h·q̇ (modal superposition; the two
    coefficients are the real and imaginary parts of the pole pair's residue, which a mode
    seen through the rest of the structure has in general).  Its site is the sensor.

    Parameters
    ----------
    site : Site, optional
        The sensor site (default: named "output").
    """

    cause = "higher-mode"
    label = "extra resonator (mode) in parallel on the output"
    kind = LINEAR
    repeatable = True

    def __init__(self, site: Site | None = None):
        self.site_name = site.name if site is not None else "output"

    def applies(self, view):
        """True, unless the model is neither a drive transform nor linear (a linear structural
        extension named before keeps it linear: the mode is then added beside the current
        model, :meth:`fit`), or the record resolves no frequency.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        bool or str
            True, or why it does not apply.
        """
        if view.current.drive is None and not view.linear_current:
            return NOT_A_DRIVE
        return unresolved(view) or True

    def evidence(self, view):
        """The largest frequency-response mismatch and where it is.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        dict of str to float
            ``frf_mismatch`` (relative) and ``omega_peak`` (rad/s).
        """
        w, mis = frf_mismatch(view)
        k = int(np.argmax(mis)) if mis.size else 0
        return {"frf_mismatch": float(mis[k]) if mis.size else 0.0, "omega_peak": float(w[k]) if w.size else 0.0}

    def fit(self, view):
        """Fit ω, ζ and the output coefficients g, h of the resonator by variable projection,
        from the best trials of :func:`resonance_trials`.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The model with the mode (parameters ``hm.omega`` rad/s, ``hm.zeta``, ``hm.g``,
            ``hm.h``).
        """
        if view.current.drive is None:
            return self._fit_beside(view)
        p = free_prefix(view.current.model, "hm")
        d = np.asarray(view.current.drive)
        trials = resonance_trials(view)
        _, om, ze = trials[0]
        starts = [[math.log(t[1]), math.log(t[2])] for t in trials[1:3]]
        fit, best = None, np.inf
        # a device bent to mimic the missing mode keeps the added one from fitting (the refit
        # only moves it locally): from the model file's values too, then
        for start in view.fit_starts():
            trial = view.fit_drive(
                direct=lambda z: list(resonator(d, view.record.dt, math.exp(z[0]), math.exp(z[1]), velocity=True).T),
                z0=[math.log(om), math.log(ze)],
                z_bounds=[(math.log(om / 2), math.log(om * 2)), (math.log(1e-4), math.log(0.5))],
                z_names=[f"{p}.omega", f"{p}.zeta"],
                starts=starts,
                start=start,
            )
            rms_fit = view.score(trial.prediction)[2]
            if fit is None or rms_fit < best:
                fit, best = trial, rms_fit
        om, ze = math.exp(fit.z[0]), math.exp(fit.z[1])
        g, h = (float(c) for c in fit.direct)
        model = self._build(view, p, om, ze, g, h, view.current.drive_expr)
        new = {f"{p}.omega": om, f"{p}.zeta": ze, f"{p}.g": g, f"{p}.h": h}
        return Extension(
            model,
            {**fit.values, **new},
            list(new),
            fit.prediction,
            view.current.drive,
            view.current.drive_expr,
            fit.at_bounds,
            fit.success,
            fit.message,
        )

    def _fit_beside(self, view):
        """The mode beside a linear current model that is no drive transform of its core (a
        mass split before): driven by the recorded drive, fitted by variable projection with
        the current prediction as one more column (its weight, the sensor gain, refitted), so
        that the extended model contains the current one (g = h = 0).  The current model's
        own parameters keep their values.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The current model with the mode added on the output.
        """
        p = free_prefix(view.current.model, "hm")
        d, dt = driving(view), view.record.dt
        trials = resonance_trials(view)
        pred = np.asarray(view.current.prediction)

        def columns(z, rows):
            q = resonator(d, dt, math.exp(z[0]), math.exp(z[1]), velocity=True)
            A = np.column_stack([pred, q, np.ones(pred.size)])
            return A if rows is None else A[rows]

        sol, best = None, np.inf
        for _, om, ze in trials[:3]:
            trial = projected_fit(
                columns,
                np.asarray(view.record.y),
                view.record.fit_idx,
                [math.log(om), math.log(ze)],
                [math.log(om / 2), math.log(1e-4)],
                [math.log(om * 2), math.log(0.5)],
                [-np.inf] * 4,
                [np.inf] * 4,
                max_nfev=view.budget(30),
            )
            if trial.cost < best:
                sol, best = trial, trial.cost
        om, ze = math.exp(sol.z[0]), math.exp(sol.z[1])
        weight = sol.coef[0] if sol.coef[0] != 0 else 1.0
        g, h = (float(c / (weight * view.current.gain)) for c in sol.coef[1:3])
        new = {f"{p}.omega": om, f"{p}.zeta": ze, f"{p}.g": g, f"{p}.h": h}
        at = [list(new)[i] for i in sol.at_bounds]
        q = sol.columns[:, 1:3]
        raw = pred / view.current.gain + q @ np.array([g, h])
        return Extension(
            self._build(view, p, om, ze, g, h, view.record.input_symbol),
            {**view.current.values, **new},
            list(new),
            raw,
            None,
            None,
            at,
            sol.success,
            sol.message,
        )

    def _build(self, view, p, om, ze, g, h, drive_expr):
        """A copy of the current model with the resonator, driven by ``drive_expr``, added on
        the output."""
        model = view.rewrite()
        o = model.parameter(f"{p}.omega", om, "rad/s", "natural frequency of the added mode")
        z = model.parameter(f"{p}.zeta", ze, "1", "damping ratio of the added mode")
        gg = model.parameter(f"{p}.g", g, "", "output coefficient of the added mode's displacement (unit modal mass)")
        hh = model.parameter(f"{p}.h", h, "", "output coefficient of the added mode's velocity (unit modal mass)")
        model.add(
            Se(f"{p}.force", drive_expr),
            J1(f"{p}.mode"),
            I(f"{p}.mass", 1),
            C(f"{p}.spring", 1 / o**2),
            R(f"{p}.damper", 2 * z * o),
        )
        model.bond(f"{p}.force", f"{p}.mode")
        for e in ("mass", "spring", "damper"):
            model.bond(f"{p}.mode", f"{p}.{e}")
        add_to_output(model, view.record.output, gg * Quantity("q", f"{p}.spring") + hh * Quantity("p", f"{p}.mass"))
        return model

    def implausible(self, view, ext):
        """Why the fitted mode is not plausible (:func:`mode_implausible`).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        ext : Extension
            The fitted extension (its first new parameter is the mode's ω).

        Returns
        -------
        str
            The reason, or "".
        """
        p = ext.new[0].rsplit(".", 1)[0]
        return mode_implausible(view, ext.values[f"{p}.omega"], ext.values[f"{p}.zeta"], ext.prediction)

    def mimics_recalibration(self, view, ext):
        """Why the mode may be one of the model's own (:func:`mode_on_own`).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        ext : Extension
            The fitted extension (its first new parameter is the mode's ω).

        Returns
        -------
        str
            The reason, or "".
        """
        return mode_on_own(view, ext.values[ext.new[0]])


class OutputMode(Candidate):
    """A mode of a mass of the model: the mass M at its site (without one, the element tagged
    ``inertia``: an amplified actuator's shell and output plate) split into m1 = μ·M, driven
    as before, and m2 = (1 − μ)·M, joined by a spring k2 and damper c2 tuned to the two-mass
    mode ω, ζ: k2 = ω²·m1·m2/M, c2 = 2ζω·m1·m2/M (the total mass is unchanged).  The sensor
    either sits on m2 (a plate: its displacement relative to m1 adds to the output) or stays
    where it was (m2 hangs on the structure, as a mass elsewhere in a chain splits); both are
    fitted and the better kept.

    Parameters
    ----------
    site : Site, optional
        The I site whose mass is split (without one, the element tagged ``inertia``).
    """

    cause = "higher-mode"
    label = "compliant mass (a share of it on a spring)"
    kind = LINEAR
    repeatable = True
    role = "inertia"

    def __init__(self, site: Site | None = None):
        self.site = site
        self.site_name = site.name if site is not None else self.role

    def element(self, model) -> str | None:
        """The mass it splits in ``model``.

        Parameters
        ----------
        model : Model
            The model to look in.

        Returns
        -------
        str or None
            The I element's name, or None when it is not there.
        """
        if self.site is not None:
            return self.site.elements[0] if self.site.present(model) else None
        return next(iter(model.with_role(self.role)), None)

    def applies(self, view):
        """True, or why not: no mass, fast dynamics, or a model that is not linear.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        bool or str
            True, or why it does not apply.
        """
        if self.element(view.current.model) is None:
            return (
                f"no element is tagged '{self.role}'"
                if self.site is None
                else f"'{self.site_name}' is not in the model"
            )
        if view.record.reduced:
            return "the mass's dynamics are faster than the data resolve"
        if not view.record.exact:
            return "needs a model linear in its states"
        if view.current.drive is None and not view.linear_current:
            return "needs a model linear in its states (a nonlinear term was named)"
        return unresolved(view) or True

    def _plate_fits(self, view) -> bool:
        """Whether the sensor can sit on the split mass's plate: the extended model's equations
        derive (not when the output, a voltage across a capacitor, say, and the plate's
        displacement have different units)."""
        try:
            derive(self.build(view, view.rewrite(), 1.0, 0.1, 0.5, free_prefix(view.current.model, "om")))
        except ModelError:
            return False
        return True

    def build(self, view, model, omega, zeta, mu, p: str = "om", plate: bool = True):
        """``model`` (the current model or its linear core) with the mass split.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        model : Model
            The model to change (a copy), changed in place.
        omega : float
            The two-mass mode's natural angular frequency, rad/s.
        zeta : float
            Its damping ratio.
        mu : float
            The share μ of the mass on the driven side, between 0 and 1.
        p : str, optional
            The new parameters' prefix.
        plate : bool, optional
            The sensor sits on m2 (its displacement relative to m1 adds to the output).

        Returns
        -------
        Model
            ``model`` itself.
        """
        el = self.element(view.current.model)
        x = sp.Dummy("p")
        M = 1 / sp.diff(law(model, el)(x), x)
        om = model.parameter(f"{p}.omega", omega, "rad/s", "natural frequency of the two-mass mode")
        ze = model.parameter(f"{p}.zeta", zeta, "1", "damping ratio of the two-mass mode")
        share = model.parameter(f"{p}.mu", mu, "1", f"share of {el}'s mass on the driven side of the spring")
        reduced = share * (1 - share) * M
        modify_law(model, el, lambda q, old: old / share)
        model.add(
            J0(f"{p}.k"),
            C(f"{p}.spring", 1 / (reduced * om**2)),
            J1(f"{p}.plate"),
            I(f"{p}.mass", (1 - share) * M),
            R(f"{p}.damper", 2 * ze * om * reduced),
        )
        model.bond(junction_of(model, el), f"{p}.k")
        model.bond(f"{p}.k", f"{p}.spring")
        model.bond(f"{p}.k", f"{p}.plate")
        model.bond(f"{p}.plate", f"{p}.mass")
        model.bond(f"{p}.plate", f"{p}.damper")
        if plate:
            add_to_output(model, view.record.output, -Quantity("q", f"{p}.spring"))  # the sensor sits on the plate
        return model

    def fit(self, view):
        """Fit ω, ζ and μ from the two largest mismatch peaks, the sensor on the plate or not,
        keeping the best.

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.

        Returns
        -------
        Extension
            The model with the mass split (parameters ``om.omega`` rad/s, ``om.zeta``,
            ``om.mu``).
        """
        p = free_prefix(view.current.model, "om")
        best = None
        on_core = view.on_core  # fitted on the linear core, driven by what it sees (exact route)
        drive = view.current.drive if on_core else None
        # starts: the resonator scan's best frequency and damping at each of the two largest
        # mismatch peaks, with the mass share that fits best before any refit
        peaks = []
        for _, om, ze in resonance_trials(view):
            if all(abs(om / q[0] - 1) > 0.2 for q in peaks):
                peaks.append((om, max(ze, 0.01)))
            if len(peaks) == 2:
                break
        plates = (True, False) if self._plate_fits(view) else (False,)
        for (om, ze), plate in itertools.product(peaks, plates):
            model = self.build(view, view.core() if on_core else view.rewrite(), om, ze, 0.5, p, plate)
            predict, known = view.predictor(model, drive)
            base = {k: v for k, v in view.current.values.items() if k in known}
            mu = min(
                (0.1, 0.3, 0.5, 0.8, 0.95),
                key=lambda m: view.score(predict({**base, f"{p}.omega": om, f"{p}.zeta": ze, f"{p}.mu": m}))[2],
            )
            specs = [
                Spec(f"{p}.omega", om, om / 3, om * 3, log=True),
                Spec(f"{p}.zeta", ze, 1e-4, 1.0, log=True),
                Spec(f"{p}.mu", mu, 0.02, 0.98),
            ]
            values, raw, ok, msg, at = view.fit_model(model, specs, max_nfev=20, drive=drive)
            rf = view.score(raw)[2]
            if best is None or rf < best[0]:
                best = (rf, values, raw, ok, msg, at, plate)
        _, values, raw, ok, msg, at, plate = best
        model = self.build(view, view.rewrite(), values[f"{p}.omega"], values[f"{p}.zeta"], values[f"{p}.mu"], p, plate)
        new = [f"{p}.omega", f"{p}.zeta", f"{p}.mu"]
        return Extension(model, values, new, raw, None, None, at, ok, msg)

    def implausible(self, view, ext):
        """Why the fitted mode is not plausible (:func:`mode_implausible`).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        ext : Extension
            The fitted extension (its first new parameter is the mode's ω).

        Returns
        -------
        str
            The reason, or "".
        """
        p = ext.new[0].rsplit(".", 1)[0]
        return mode_implausible(view, ext.values[f"{p}.omega"], ext.values[f"{p}.zeta"], ext.prediction)

    def mimics_recalibration(self, view, ext):
        """Why the mode may be one of the model's own (:func:`mode_on_own`).

        Parameters
        ----------
        view : View
            The read-only view of the data, the split and the current model.
        ext : Extension
            The fitted extension (its first new parameter is the mode's ω).

        Returns
        -------
        str
            The reason, or "".
        """
        return mode_on_own(view, ext.values[ext.new[0]])


def mode_kinds(model) -> list[Candidate]:
    """A resonator on the output, and a split of every mass at a generic site (of each mass of
    a site shared by a few: :func:`~bondgraph.diagnosis.sites.each_element`).

    Parameters
    ----------
    model : Model
        The model.

    Returns
    -------
    list of Candidate
        A :class:`ParallelMode`, then the :class:`OutputMode` candidates.
    """
    return [ParallelMode()] + [OutputMode(s) for site in generic_sites(model, "I") for s in each_element(site)]
