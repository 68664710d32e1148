"""Effects that act on the drive: the linear core of the model sees a transformed drive
u_eff = T[d] (d: the drive it saw so far), fitted exactly through the core's linear dynamics
(Hammerstein bases solved by bounded least squares, jointly with the calibration by variable
projection; :meth:`bondgraph.diagnosis.View.fit_drive`).

Papers: Rodriguez-Fortun et al., Mechatronics 20 (2010) 303–314 (polarization hysteresis,
Bouc–Wen and Prandtl–Ishlinskii); Ghafarirad et al., MCMDS 21(2) (2015) 130–152 (PI on the
bimorph's drive); Wood, Steltz & Fearing, ICRA 2005 (creep as a Kelvin–Voigt chain,
field-dependent stiffness k_a(E)).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import sympy as sp

from bondgraph import J0, J1, C, I, Quantity, R, Se
from bondgraph.diagnosis import LINEAR, NOT_A_DRIVE, Candidate, Extension, Term
from bondgraph.diagnosis.filters import lowpass, rate_limited, resonator
from library.hysteresis import PrandtlIshlinskii, bouc_wen_response, play_outputs, threshold_grid

from .circuit import not_a_voltage


def drive_scale(view) -> float:
    """Largest |base drive| (the drive the additive effects act on)."""
    return float(np.max(np.abs(view.current.additive.base))) or 1.0


def dwell_levels(d: np.ndarray, bins: int = 100) -> int:
    """How many of ``bins`` equal slices of the drive's range hold at least 0.2 % of its
    samples: ~100 for sines, triangles and chirps, about the number of held levels for steps."""
    h, _ = np.histogram(d, bins=bins)
    return int(np.count_nonzero(h >= 0.002 * h.sum()))


def static_curve(view, pieces: int) -> np.ndarray:
    """The best static curve of the drive with ``pieces`` parameters, through the linear core:
    a line and a kink at the drive's centre, and on each side of it ramps from knees at
    quantiles of that side's excursions (each ramp is carried by a fifth or more of its side's
    samples, so no coefficient is set by a few extreme ones and extrapolated from there); the
    twin a memory effect must beat (of the base drive, beside the effects named before, as the
    memory effect is fitted).  Asked on every drive: on steps held at a few levels, memory shows
    only where a level is reached from both sides, and loops that do not beat a static curve
    there have shown no memory (a saturation on steps reproduced by a play sum is a shape)."""
    d = np.asarray(view.current.additive.base)
    dev = d - 0.5 * (d.max() + d.min())
    levels = np.arange(1, pieces // 2) / (pieces // 2)
    basis = [dev, np.abs(dev)]
    for side in (dev, -dev):
        out = side[side > 0]
        knees = np.unique(np.quantile(out, levels)) if out.size else []
        basis += [np.maximum(side - k, 0.0) for k in knees]
    fit = view.fit_drive(
        basis,
        [-np.inf] * len(basis),
        [np.inf] * len(basis),
        identity=False,
        names=[f"static.k{i}" for i in range(len(basis))],
    )
    return fit.prediction


def best_on_grid(view, basis_of, grid, **fit_args):
    """The point of ``grid`` whose basis ``basis_of(point)`` fits the fit part best with the
    linear parameters held (one linear solve each): for a start of a basis that a local
    optimiser would find only from the right one (where the device's history left it)."""

    def cost(point):
        return view.score(view.fit_drive(basis_of(point), refit=False, **fit_args).prediction)[2]

    return min(grid, key=cost)


def best_response(view, drives) -> int:
    """Index of the drive of ``drives`` whose response through the linear core, with a sensor
    gain and offset solved (one linear least-squares solve each, the linear parameters held),
    fits the fit part best: the start of a stage's parameters."""
    idx = view.record.fit_idx
    Y = view.respond(drives)
    sse = []
    for j in range(Y.shape[1]):
        A = np.column_stack([Y[idx, j], np.ones(idx.size)])
        res = np.linalg.lstsq(A, view.record.y[idx], rcond=None)[1]
        sse.append(float(res[0]) if res.size else math.inf)
    return int(np.argmin(sse))


def even_term(base) -> tuple[np.ndarray, float, float]:
    """(column, c, h): the memoryless even term h·((d − c)/h)² of the drive d about the centre c
    of its range (half range h), in drive units: what makes a loop or a static curve of the
    drive asymmetric (its two ends bend by different amounts)."""
    d = np.asarray(base, float)
    centre, half = 0.5 * (float(d.max()) + float(d.min())), 0.5 * float(np.ptp(d)) or 1.0
    return half * ((d - centre) / half) ** 2, centre, half


def even_expr(model, prefix: str, q: float, centre: float, half: float, drive):
    """The model's expression of :func:`even_term` with weight ``q`` (parameters prefix.q, .c, .h)."""
    qs = model.parameter(f"{prefix}.q", q, "1", "weight of the memoryless even term (asymmetry)")
    cs = model.parameter(f"{prefix}.c", centre, "", "centre of the drive's range (the even term's origin)")
    hs = model.parameter(f"{prefix}.h", half, "", "half the drive's range (the even term's scale)")
    return qs * hs * ((drive - cs) / hs) ** 2


def loop_area(r: np.ndarray, u: np.ndarray) -> float:
    """|∮ r du| normalised by the bounding box and the number of cycles: 0 for a
    single-valued residual, ~0.3 for a fat loop."""
    area = abs(float(np.sum(0.5 * (r[1:] + r[:-1]) * np.diff(u))))
    d = np.diff(u)
    d = d[np.abs(d) > 1e-9 * np.ptp(u)]
    cycles = max(1.0, float(np.sum(np.diff(np.sign(d)) != 0)) / 2)
    return area / max(float(np.ptp(r) * np.ptp(u)), 1e-300) / cycles


class _DriveCandidate(Candidate):
    def applies(self, view):
        return True if view.current.drive is not None else NOT_A_DRIVE

    def extension(self, view, fit, model, new: dict, drive_expr) -> Extension:
        values = {**fit.values, **new}
        return Extension(
            model,
            values,
            list(new),
            fit.prediction,
            fit.drive,
            drive_expr,
            fit.at_bounds,
            fit.success,
            fit.message,
            additive=fit.additive,
        )


class InputHysteresis(_DriveCandidate):
    """Rate-independent hysteresis of the drive: a Prandtl–Ishlinskii operator (play form,
    ``n_plays`` thresholds over the drive's range), as Ghafarirad et al. model the bimorph and
    as polarization hysteresis acts at quasi-static rates, plus a memoryless even term
    q·h·((d − c)/h)² about the drive's centre c (half range h): play sums alone only make
    point-symmetric loops, and a stack's loops over part of its field range are not (the
    asymmetric PI of Gu, Zhu & Su, IEEE Trans. Ind. Electron. 61(3) (2014) 1583–1595, adds
    such a polynomial); only on drives that pass through their range (not on steps held at a
    few levels, where it would add a shape at the held levels).  Additive: it replaces the base
    drive's own term (its r = 0 play is the drive) beside the effects named before."""

    cause = "hysteresis"
    label = "Prandtl-Ishlinskii operator on the drive"
    cost = 2
    n_plays = 10

    def evidence(self, view):
        m = view.record.fit_mask
        return {"loop_area": loop_area(view.current.residual[m], view.current.drive[m])}

    def fit(self, view):
        base = view.current.additive.base
        r = threshold_grid(base, self.n_plays)
        names = [f"H.w{i + 1}" for i in range(len(r))]
        b0, reach = float(base[0]), float(r[-1]) or 1.0
        column, centre, half = even_term(base)
        # the even term only on drives that pass through their range: on a drive held at a few
        # levels it would be a shape at those levels (an end stop on steps), not part of a loop
        asymmetric = self.passes_through(base)
        even = [column] if asymmetric else []
        names = names + ["H.q"] if asymmetric else names
        bounds = dict(
            lower=[0.0] + [-np.inf] * (len(names) - 1), upper=[np.inf] * len(names), identity=False, names=names
        )

        def basis(prior):
            return list(play_outputs(base, r, prior).T) + even

        # the r = 0 play is the drive itself (w ≥ 0); the others may have either sign, so loops
        # of both orientations (displacement lagging or leading the drive) are representable.
        # The record starts where the device's history left it: the level the plays came from
        # (prior) is chosen on a grid over the widest play's reach of the first input (beyond
        # it every play is on its branch), with the old convention (from 0) among the points.
        priors = np.r_[b0 + np.linspace(-1.0, 1.0, 9) * reach, 0.0]
        prior = float(best_on_grid(view, basis, priors, **bounds))
        fit = view.fit_drive(basis(prior), **bounds)
        model = view.rewrite()
        B = view.current.additive.base_expr
        h = model.operator("H", PrandtlIshlinskii(r, fit.coef[: len(r)], prior), B)
        if asymmetric:
            h = h + even_expr(model, "H", float(fit.coef[-1]), centre, half, B)
        expr = view.current.drive_plus(h, identity=False)
        view.with_drive(model, expr)
        return self.extension(view, fit, model, {**dict(zip(names, map(float, fit.coef))), "H.prior": prior}, expr)

    def without_memory(self, view):
        """The operator's static twin, with as many knees: on a drive that passes through its
        range each of the n − 1 plays with r > 0 kinks once on each branch (at min + 2r rising,
        max − 2r falling), so the sum is, loops aside, a curve with n − 1 knees on each side of
        the centre, and a twin with fewer let the plays win as the more flexible curve (tanh
        saturations under sines beat a 10-piece twin by 1.08x and 1.7x).  On a drive held at a
        few levels the n-piece curve already passes through every level; more knees would only
        fit the steps' transitions."""
        return static_curve(view, 2 * self.n_plays if self.passes_through(view.current.additive.base) else self.n_plays)

    def passes_through(self, base) -> bool:
        """Whether the drive passes through its range (a sine, a triangle, a chirp), rather than
        being held at a few levels: more dwelling levels than twice the operator's plays."""
        return dwell_levels(base) > 2 * self.n_plays


class InputBoucWen(_DriveCandidate):
    """Rate-independent hysteresis with a differential (Bouc–Wen) state on the drive,
    u = V + κ·V_r·z, dz/dt = v̇ − β·|v̇|·z − γ·v̇·|z| (v = V/V_r, exponent 1): the DE-based
    polarization model of Rodriguez-Fortun et al. (eq. 9), whose minor loops drift as
    Bouc–Wen loops do.  β = s(1 + tanh ρ)/2, γ = s(1 − tanh ρ)/2; z(0) is fitted (the state
    the device's history left).  Additive: κ·V_r·z adds to the effects named before."""

    cause = "hysteresis"
    label = "Bouc-Wen state on the drive"

    def applies(self, view):
        if view.current.drive is None or view.current.additive.base_expr != view.record.input_symbol:
            return "needs the raw drive's rate (a drive-side stage was added first)"
        return True

    def without_memory(self, view):
        """The Prandtl–Ishlinskii candidate's static twin: a Bouc–Wen loop that does not beat a
        static curve of that freedom is a shape, not memory."""
        return static_curve(view, InputHysteresis.n_plays)

    @staticmethod
    def shape(z):
        s, rho = math.exp(z[0]), math.tanh(z[1])
        return s * (1 + rho) / 2, s * (1 - rho) / 2

    def fit(self, view):
        Vr = drive_scale(view)
        v = np.asarray(view.current.additive.base) / Vr

        def basis(z):
            beta, gamma = self.shape(z)
            return [Vr * bouc_wen_response(v, beta, gamma, 1.0, z[2] / (beta + gamma))]

        # z starts where the device's history left it: a fraction of its saturation 1/(β + γ)
        # (at ±1 it is saturated, so that bound is no limit), fitted from the best of a few
        # starts (slow and fast saturation; from rest and both branches), each one linear solve
        grid = [(math.log(s0), 0.0, f0) for s0 in (3.0, 30.0) for f0 in (0.0, 0.9, -0.9)]
        start = best_on_grid(view, basis, grid, lower=[-np.inf], upper=[np.inf], names=["bw.kappa"])
        fit = view.fit_drive(
            basis,
            [-np.inf],
            [np.inf],
            z0=list(start),
            z_bounds=[(math.log(0.05), math.log(500.0)), (-6.0, 6.0), (-1.0, 1.0)],
            z_names=["bw.s", "bw.rho", "bw.z0"],
            names=["bw.kappa"],
        )
        fit.at_bounds = [n for n in fit.at_bounds if n != "bw.z0"]
        beta, gamma = self.shape(fit.z)
        z_start = float(fit.z[2]) / (beta + gamma)
        model = view.rewrite()
        kappa = model.parameter("bw.kappa", float(fit.coef[0]), "1", "weight of the Bouc-Wen state in the drive")
        b = model.parameter("bw.beta", beta, "1", "Bouc-Wen beta")
        g = model.parameter("bw.gamma", gamma, "1", "Bouc-Wen gamma")
        vr = model.parameter("bw.Vr", Vr, "", "reference drive (largest |drive| of the data)")
        z = model.state("bw.z", z_start, unit="1", doc="Bouc-Wen hysteretic variable (units of V/V_r)")
        vdot = model.input_rate(view.record.input) / vr
        model.set_rate("bw.z", vdot - b * sp.Abs(vdot) * z - g * vdot * sp.Abs(z))
        expr = view.current.drive_plus(kappa * vr * z)
        view.with_drive(model, expr)
        return self.extension(
            view, fit, model, {"bw.kappa": float(fit.coef[0]), "bw.beta": beta, "bw.gamma": gamma}, expr
        )


class InputCreep(_DriveCandidate):
    """Creep: a generalized Kelvin–Voigt chain on the drive (Wood et al., eq. 1),
    u = d + Σ c_n·q_n with cells q̇_n = (d − q_n)/τ_n, i.e. a step response
    d0·[1 + Σ c_n(1 − e^(−t/τ_n))]; the c_n ≥ 0 of a fixed relaxation spectrum (two time
    constants per decade, from well above the model's own time constants to three record
    lengths) are solved exactly, so log-time creep is represented as well as a few cells.
    Cells are C_n = 1, R_n = τ_n on a 0-junction, their charges weighted by the ratios c_n (a
    ratio a later step refits to 0 leaves a regular model), starting in equilibrium with the
    level the device's history left them at (``creep.prior``, drive units; fitted on a grid).
    Additive: the cells act on the base drive beside the effects named before.
    The spectrum spans every time scale the data resolve (five samples to three record
    lengths): log-time and fractional creep relax over many decades, and on a periodic drive
    the decades slower than its period average out while the faster ones show as a loss that
    hardly depends on the frequency (a loop at every rate).  A lag faster than the model's own
    dynamics or than a quarter of the drive's main period (1 % of the record at most) is a
    phase lag, though, an electrical stage's or a misplaced damping's, unless it is one of
    many: when most of the weight lies there, the spectrum must be broad (at least
    ``min_spread`` of it outside its heaviest two neighbouring cells), not one lag.  The
    drive's period bounds it only where the drive keeps moving: when ``min_held`` of the record
    or more lies in holds three times that long (steps, holds, rests), a cell relaxes within
    the holds and shows its own tail, a rise after the elastic jump that no phase lag makes,
    and only the model's own dynamics bound it (its spectrum there starts at that bound: a
    faster cell only reshapes the transient of the model's own dynamics, standing in for a
    damping or stiffness the calibration bent).
    It is small: piezoelectric stacks creep by 1–2 % of their
    stroke per decade of time, so cells that move by more than ``max_ratio`` of the elastic
    response within the record (:meth:`creep_range`) are not creep.  The chain is of the flexible linear
    reference's own form (lags of the drive), so any linear mismatch, a phase error at the
    drive's frequency or a slow drift, lends it a part to explain: creep must explain nearly
    all (``linear_share``) of what the reference explains."""

    cause = "creep"
    label = "Kelvin-Voigt creep chain on the drive"
    kind = LINEAR
    max_ratio = 0.5
    linear_share = 0.9
    min_spread = 1 / 3
    min_held = 0.2

    @classmethod
    def taus(cls, view) -> np.ndarray:
        """The relaxation times (s), two per decade from five samples (from 10/ω of the
        model's slowest mode on a drive that holds: a faster cell there only reshapes the
        transient of the model's own dynamics) to three record lengths."""
        lo, hi = 5 * view.record.dt, 3 * float(view.record.t[-1] - view.record.t[0])
        if cls.holds(view):
            lo = max(lo, cls.model_lag(view))
        n = max(2, int(round(math.log10(hi / lo) * 2)) + 1)
        return np.geomspace(lo, hi, n)

    @staticmethod
    def model_lag(view) -> float:
        """10/ω (s) of the model's slowest mode (0 without one)."""
        slow = [f for f in view.record.modes_hz if f > 0]
        return 10.0 / (2 * math.pi * min(slow)) if slow else 0.0

    @staticmethod
    def drive_lag(view) -> float:
        """A quarter of the drive's main period (s), 1 % of the record at most."""
        return min(
            0.25 / view.record.main_hz if view.record.main_hz > 0 else 0.0,
            0.01 * float(view.record.t[-1] - view.record.t[0]),
        )

    @classmethod
    def holds(cls, view) -> bool:
        """Whether ``min_held`` of the record or more lies in holds of the drive three times
        :meth:`drive_lag` long (steps, holds, rests)."""
        return view.record.held_share(3 * cls.drive_lag(view)) >= cls.min_held

    @classmethod
    def lag_limit(cls, view) -> float:
        """Cells faster than this (s) are phase lags unless the spectrum is broad:
        :meth:`model_lag`, and :meth:`drive_lag` unless the drive :meth:`holds`."""
        model = cls.model_lag(view)
        return model if cls.holds(view) else max(model, cls.drive_lag(view))

    def fit(self, view):
        taus = self.taus(view)
        d = np.asarray(view.current.additive.base)
        d0 = float(d[0])
        steady = [lowpass(d, tau, view.record.dt) for tau in taus]
        decays = [np.exp(-np.arange(len(d)) * (view.record.dt / tau)) for tau in taus]

        def cells_from(prior):  # cells in equilibrium with the level ``prior`` at the start
            return [s + (prior - d0) * e for s, e in zip(steady, decays)]

        bounds = dict(
            lower=[0.0] * len(taus), upper=[np.inf] * len(taus), names=[f"creep.cell{i}" for i in range(len(taus))]
        )
        # the record starts where the device's history left it: the level the cells had
        # settled to (prior) is chosen on a grid over the drive's range, the first input among
        # the points (cells in equilibrium with it)
        prior = float(best_on_grid(view, cells_from, np.r_[d0, np.linspace(d.min(), d.max(), 7)], **bounds))
        cells = cells_from(prior)
        fit = view.fit_drive(cells, **bounds)
        keep = [i for i in range(len(taus)) if fit.coef[i] > 1e-6 * max(float(np.max(fit.coef)), 1e-300)]
        # only the cells that creep are kept, as terms named by their ratio parameters
        fit.additive = replace(
            fit.additive,
            terms=fit.additive.terms[: -len(taus)]
            + tuple(Term(f"creep.c{k}", cells[i], 0.0, np.inf) for k, i in enumerate(keep, 1)),
        )
        model = view.rewrite()
        D = view.current.additive.base_expr
        model.add(Se("creep.src", D), J0("creep.node"))
        model.bond("creep.src", "creep.node")
        new, qs = {}, []
        for k, i in enumerate(keep, 1):
            c = model.parameter(f"creep.c{k}", float(fit.coef[i]), "1", f"creep ratio of cell {k}", bounds=(0, 1e3))
            tau = model.parameter(
                f"creep.tau{k}", float(taus[i]), "s", f"creep time constant of cell {k}", bounds=(0, 1e6)
            )
            model.add(J1(f"creep.cell{k}"), C(f"creep.C{k}", 1.0, q0=prior), R(f"creep.R{k}", tau))
            model.bond("creep.node", f"creep.cell{k}")
            model.bond(f"creep.cell{k}", f"creep.C{k}")
            model.bond(f"creep.cell{k}", f"creep.R{k}")
            new[f"creep.c{k}"], new[f"creep.tau{k}"] = float(fit.coef[i]), float(taus[i])
            qs.append(c * Quantity("q", f"creep.C{k}"))
        new["creep.prior"] = prior
        expr = view.current.drive_plus(sum(qs))
        view.with_drive(model, expr)
        ext = self.extension(view, fit, model, new, expr)
        ext.values.update(new)
        return ext

    @staticmethod
    def elastic_slope(ext) -> float:
        """Drive units per base-drive unit of the effects beside the creep (1 for the base
        drive alone; the loading slope of a hysteresis operator named before): what the
        creep ratios are relative to."""
        a = ext.additive
        rest = replace(a, terms=tuple(t for t in a.terms if not t.name.startswith("creep."))).series(ext.values)
        b = a.base - np.mean(a.base)
        slope = float(b @ (rest - np.mean(rest))) / max(float(b @ b), 1e-300)
        return slope if slope > 0 else 1.0

    @staticmethod
    def creep_range(ext) -> float:
        """How far the cells' sum Σ c_n·q_n moves within the record, relative to the base drive's
        range: on a drive that steps from rest and holds, the step response's creep
        Σ c_n·(1 − e^(−t/τ_n)) at the record's end; on an oscillating drive, what the cells do
        at its time scale (a cell much slower than the drive's period integrates it,
        c_n/(ω·τ_n), whatever c_n and τ_n alone are)."""
        a = ext.additive
        cells = replace(a, identity=False, terms=tuple(t for t in a.terms if t.name.startswith("creep.")))
        s = cells.series(ext.values)
        return float(np.ptp(s)) / max(float(np.ptp(a.base)), 1e-300)

    def implausible(self, view, ext):
        cs = [v for k, v in ext.values.items() if k.startswith("creep.c") and k in ext.new]
        taus = [v for k, v in ext.values.items() if k.startswith("creep.tau") and k in ext.new]
        if not cs:
            return "no creep cell has a positive ratio"
        within = self.creep_range(ext) / self.elastic_slope(ext)
        if within > self.max_ratio:
            return f"it creeps by {within:.2g} of the elastic response within the record (more than {self.max_ratio:g})"
        cs, taus, limit = np.asarray(cs), np.asarray(taus), self.lag_limit(view)
        fast = float(cs[taus < limit].sum()) / float(cs.sum())
        spread = self.spread(self.taus(view), taus, cs)
        if fast > 0.5 and spread < self.min_spread:
            return (
                f"{fast:.0%} of it is faster than creep may be (τ < {limit:.3g} s) and it "
                f"is one lag, not a spectrum ({spread:.0%} outside its heaviest two neighbouring cells)"
            )
        return ""

    @staticmethod
    def spread(grid: np.ndarray, taus: np.ndarray, cs: np.ndarray) -> float:
        """Share of the weights ``cs`` of cells at ``taus`` (points of ``grid``) outside the
        heaviest two neighbouring points of the grid: 0 for one lag (a time constant between
        two grid points needs both), about 0.6 for equal weights over two decades."""
        w = np.zeros(grid.size)
        np.add.at(w, np.abs(np.log(taus)[:, None] - np.log(grid)[None, :]).argmin(axis=1), cs)
        pair = float(np.max(w[1:] + w[:-1])) if w.size > 1 else float(w.sum())
        return 1.0 - pair / float(w.sum())


def _cubic(x):
    return x**3


def _quintic(x):
    return x**5


def _cubic_less_quintic(x):
    return x**3 - x**5


class _InputPolynomial(_DriveCandidate):
    """Static odd nonlinearity of the drive, x = d/V_r (V_r: the largest |drive| of the data):
    u = d + s·V_r·(w_1·p_1(x) + w_2·p_2(x)) with weights w_1, w_2 ≥ 0 on the two odd
    ``shapes`` p_1, p_2 (s: ``sign``), with the even term q·h·((d − c)/h)² of
    :func:`even_term` (either sign) if ``asymmetric``."""

    sign = -1.0
    prefix = "sat"
    asymmetric = False
    #: (parameter suffix, description, shape of x) of the two weights: here the cubic and the quintic
    shapes = (("a3", "cubic drive coefficient", _cubic), ("a5", "quintic drive coefficient", _quintic))
    #: the prefixes of both polynomial candidates: once either is named, the other would only
    #: free the sign of the same terms
    prefixes = ("sat.", "exp.")

    def applies(self, view):
        ok = super().applies(view)
        if ok is True and any(t.name.startswith(self.prefixes) for t in view.current.additive.terms):
            return "a drive polynomial was named already (its terms are this candidate's, with the other sign)"
        return ok

    def evidence(self, view):
        d = np.asarray(view.current.drive) / drive_scale(view)
        cubic = d**3 - d * (d @ d**3) / max(d @ d, 1e-300)
        resp = view.respond([cubic])[:, 0]
        r = view.current.residual - view.current.residual.mean()
        resp = resp - resp.mean()
        return {"cubic_corr": float(r @ resp / max(np.linalg.norm(r) * np.linalg.norm(resp), 1e-300))}

    def fit(self, view):
        Vr = drive_scale(view)
        d = np.asarray(view.current.additive.base)
        p = self.prefix
        names = [f"{p}.{suffix}" for suffix, _, _ in self.shapes] + ([f"{p}.q"] if self.asymmetric else [])
        even = even_term(d) if self.asymmetric else None
        basis = [self.sign * Vr * shape(d / Vr) for _, _, shape in self.shapes] + ([even[0]] if even else [])
        fit = view.fit_drive(basis, [0.0, 0.0, -np.inf][: len(names)], [np.inf] * len(names), names=names)
        model = view.rewrite()
        vr = model.parameter(f"{p}.Vr", Vr, "", "reference drive (largest |drive| of the data)")
        D = view.current.additive.base_expr
        curve = (
            self.sign
            * vr
            * sum(
                model.parameter(name, float(w), "1", what, bounds=(0, 1e6)) * shape(D / vr)
                for name, w, (_, what, shape) in zip(names, fit.coef, self.shapes)
            )
        )
        if even:
            curve = curve + even_expr(model, p, float(fit.coef[2]), even[1], even[2], D)
        expr = view.current.drive_plus(curve)
        view.with_drive(model, expr)
        return self.extension(view, fit, model, dict(zip(names, map(float, fit.coef))), expr)


class InputSaturation(_InputPolynomial):
    """Saturation: the drive's effect compresses at high field (the polarization saturates,
    P ≈ P_s·tanh(E/E_s)), not necessarily alike at both ends of the drive's range (the even
    term: a polarization that saturates sooner along the poling direction than against it, a
    bimorph whose layers see the field with and against theirs).  A saturating curve's quintic
    term leans against its cubic one (tanh(kx)/k = x − k²x³/3 + 2k⁴x⁵/15 − ...), so the
    weights are on x³ − x⁵ (the compression of mid-range fields) and x⁵ (of the largest):
    every u = d − V_r·(a3·x³ + a5·x⁵) with a3 ≥ 0 and a3 + a5 ≥ 0, a curve below the line
    through the origin all across the drive's range (a3, a5 ≥ 0 alone missed a strong tanh:
    3.8x where a 10-play operator gained 7.8x)."""

    cause = "saturation"
    label = "compressive drive nonlinearity (saturating polarization)"
    sign, prefix, asymmetric = -1.0, "sat", True
    shapes = (
        ("m", "weight of the mid-range compression x³ − x⁵ (x: drive / Vr)", _cubic_less_quintic),
        ("e", "weight of the compression at the range's ends x⁵ (x: drive / Vr)", _quintic),
    )


class InputExpansion(_InputPolynomial):
    """Softening that shows as gain expansion: a field-dependent stiffness k_a(E) that falls
    with the drive (Wood et al.) makes the displacement per volt grow with amplitude."""

    cause = "softening"
    label = "expanding drive nonlinearity (field-dependent stiffness k_a(E))"
    sign, prefix = 1.0, "exp"


class _ElectricalStage(_DriveCandidate):
    """An electrical stage on the drive: it applies to a voltage drive only."""

    def applies(self, view):
        ok = super().applies(view)
        return (not_a_voltage(view) or True) if ok is True else ok


class InputRC(_ElectricalStage):
    """An RC input stage: the drive reaches the actuator through a series resistance into a
    capacitance, u = d/(1 + sRC) (amplifier output resistance, cables); on a voltage drive
    only."""

    cause = "electrical-rc"
    label = "series R with a capacitance on the drive (RC lag)"
    kind = LINEAR
    cap = 1e-6

    def _range(self, view):
        return view.record.dt / 10, float(view.record.t[-1] - view.record.t[0]) / 20

    def fit(self, view):
        d = np.asarray(view.current.drive)
        lo, hi = self._range(view)
        taus = np.geomspace(lo, hi, 16)
        tau0 = float(taus[best_response(view, [lowpass(d, tau, view.record.dt) for tau in taus])])
        fit = view.fit_drive(
            lambda z: [lowpass(d, math.exp(z[0]), view.record.dt)],
            [-np.inf],
            [np.inf],
            identity=False,
            z0=[math.log(tau0)],
            z_bounds=[(math.log(lo), math.log(hi))],
            z_names=["rc.R"],
        )
        tau = math.exp(fit.z[0])
        model = view.rewrite()
        Rin = model.parameter("rc.R", tau / self.cap, "ohm", "series resistance of the input stage", bounds=(0, 1e12))
        Cin = model.parameter("rc.C", self.cap, "F", "capacitance of the input stage (only R·C matters)")
        D = view.current.drive_expr
        model.add(
            Se("rc.src", D),
            J1("rc.i"),
            R("rc.Rs", Rin),
            J0("rc.node"),
            C("rc.C", Cin, q0=Cin * float(view.current.drive[0])),
        )
        model.chain("rc.src", "rc.i", "rc.node", "rc.C")
        model.bond("rc.i", "rc.Rs")
        expr = Quantity("e", "rc.C")
        view.with_drive(model, expr)
        # the stage passes the drive with unit gain; the fitted coefficient is the sensor gain's change
        fit.drive = lowpass(d, tau, view.record.dt)
        fit.prediction = view.respond([fit.drive], fit.values)[:, 0] + view.current.extra
        return self.extension(view, fit, model, {"rc.R": tau / self.cap}, expr)

    def implausible(self, view, ext):
        tau = ext.values["rc.R"] * self.cap
        f = 1 / (2 * math.pi * tau)
        if f > 0.45 * view.record.fs:
            return f"its corner ({f:.3g} Hz) is above the data's band"
        return ""


class InputCurrentLimit(_ElectricalStage):
    """A current-limited input stage: the drive charges a capacitance through a series
    resistance from a source whose output current saturates (an amplifier's current limit
    into a capacitive load), i = I_max·tanh(e_R/(R·I_max)), so that the stage is the RC lag
    u = d/(1 + sRC) for small steps and follows large ones at the slew rate S = I_max/C.  The
    lag and the slew rate are fitted through the linear core; a lag at its lower bound is a
    pure slew-rate limit, a slew rate at its upper bound no limit at all (the RC stage's
    business, not this one's).  On a voltage drive only.
    """

    cause = "electrical-rc"
    label = "current-limited input stage (slew rate)"
    cap = 1e-6
    #: slew rates tried first, from one swing of the drive over the record to twice the
    #: drive's fastest rate between samples (no limit)
    rates = 10
    lags = 4

    def _bounds(self, view, d):
        dt = view.record.dt
        span = float(view.record.t[-1] - view.record.t[0])
        fastest = float(np.max(np.abs(np.diff(d)))) / dt if d.size > 1 else 1.0
        swing = float(np.ptp(d)) / span
        return (dt / 10, span / 20), (max(swing, 1e-300), max(2.0 * fastest, 2.0 * swing, 1e-300))

    def fit(self, view):
        d = np.asarray(view.current.drive, float)
        dt = view.record.dt
        (tlo, thi), (slo, shi) = self._bounds(view, d)
        if shi <= slo:
            raise ValueError("the drive does not move: no slew rate to fit")
        grid = [(t, r) for t in np.geomspace(tlo, thi, self.lags) for r in np.geomspace(slo, shi, self.rates)]
        t0, r0 = grid[best_response(view, [rate_limited(d, t, r, dt) for t, r in grid])]
        fit = view.fit_drive(
            lambda z: [rate_limited(d, math.exp(z[0]), math.exp(z[1]), dt)],
            [-np.inf],
            [np.inf],
            identity=False,
            z0=[math.log(t0), math.log(r0)],
            z_bounds=[(math.log(tlo), math.log(thi)), (math.log(slo), math.log(shi))],
            z_names=["cl.R", "cl.Imax"],
        )
        tau, rate = math.exp(fit.z[0]), math.exp(fit.z[1])
        # a lag at its lower end is a pure slew-rate limit, not a search limit
        fit.at_bounds = [n for n in fit.at_bounds if not (n == "cl.R" and tau < 2 * tlo)]
        model = view.rewrite()
        Rs = model.parameter("cl.R", tau / self.cap, "ohm", "series resistance of the input stage", bounds=(0, 1e12))
        Imax = model.parameter(
            "cl.Imax", rate * self.cap, "A", "largest current of the stage's source", bounds=(0, 1e12)
        )
        Cs = model.parameter("cl.C", self.cap, "F", "capacitance of the input stage (only R·C and I_max/C matter)")
        model.add(
            Se("cl.src", view.current.drive_expr),
            J1("cl.i"),
            R("cl.Rs", conductance_law=lambda e: Imax * sp.tanh(e / (Rs * Imax))),
            J0("cl.node"),
            C("cl.C", Cs, q0=Cs * float(d[0])),
        )
        model.chain("cl.src", "cl.i", "cl.node", "cl.C")
        model.bond("cl.i", "cl.Rs")
        expr = Quantity("e", "cl.C")
        view.with_drive(model, expr)
        fit.drive = rate_limited(d, tau, rate, dt)
        fit.prediction = view.respond([fit.drive], fit.values)[:, 0] + view.current.extra
        return self.extension(view, fit, model, {"cl.R": tau / self.cap, "cl.Imax": rate * self.cap}, expr)


class InputRLC(_ElectricalStage):
    """A series R–L into the actuator's capacitance on the drive: u = d/(LCs² + RCs + 1), the
    electrical stage of a long cable or an inductive amplifier output (its resonance
    ω = 1/√(LC), damping ratio ζ = (R/2)·√(C/L)).  The resistance in series (the amplifier's
    output, the leads) damps it: a resonance sharper than ``min_damping`` is a mechanical mode
    seen through the same second-order shape, not an input stage.  On a voltage drive only."""

    cause = "electrical-rc"
    label = "series R-L with a capacitance on the drive (RLC stage)"
    kind = LINEAR
    cap = 1e-6

    def fit(self, view):
        d = np.asarray(view.current.drive)
        top = 2 * math.pi * 0.45 * view.record.fs
        low = 2 * math.pi / float(view.record.t[-1] - view.record.t[0]) * 10
        idx = view.record.fit_idx
        best = None
        for om in np.geomspace(low, top, 10):
            for ze in (0.1, 0.4, 1.0):
                col = view.respond([om**2 * resonator(d, view.record.dt, om, ze)])[:, 0]
                A = np.column_stack([col, np.ones(len(d))])[idx]
                res = np.linalg.lstsq(A, view.record.y[idx], rcond=None)[1]
                sse = float(res[0]) if res.size else math.inf
                if best is None or sse < best[0]:
                    best = (sse, om, ze)
        _, om0, ze0 = best
        fit = view.fit_drive(
            lambda z: [math.exp(2 * z[0]) * resonator(d, view.record.dt, math.exp(z[0]), math.exp(z[1]))],
            [-np.inf],
            [np.inf],
            identity=False,
            z0=[math.log(om0), math.log(ze0)],
            z_bounds=[(math.log(low), math.log(top)), (math.log(0.02), math.log(5.0))],
            z_names=["rlc.L", "rlc.R"],
        )
        om, ze = math.exp(fit.z[0]), math.exp(fit.z[1])
        L_val, R_val = 1 / (om**2 * self.cap), 2 * ze / (om * self.cap)
        model = view.rewrite()
        Rp = model.parameter("rlc.R", R_val, "ohm", "series resistance of the input stage", bounds=(0, 1e12))
        Lp = model.parameter("rlc.L", L_val, "H", "series inductance of the input stage", bounds=(0, 1e12))
        Cp = model.parameter("rlc.C", self.cap, "F", "capacitance of the input stage (only LC, RC matter)")
        model.add(
            Se("rlc.src", view.current.drive_expr),
            J1("rlc.loop"),
            R("rlc.Rs", Rp),
            I("rlc.Ls", Lp),
            C("rlc.Cs", Cp, q0=Cp * float(view.current.drive[0])),
        )
        model.bond("rlc.src", "rlc.loop")
        for e in ("rlc.Rs", "rlc.Ls", "rlc.Cs"):
            model.bond("rlc.loop", e)
        expr = Quantity("e", "rlc.Cs")
        view.with_drive(model, expr)
        fit.drive = om**2 * resonator(d, view.record.dt, om, ze)
        fit.prediction = view.respond([fit.drive], fit.values)[:, 0] + view.current.extra
        return self.extension(view, fit, model, {"rlc.R": R_val, "rlc.L": L_val}, expr)

    #: an electrical stage's resistance (amplifier output, leads) damps it at least this much
    min_damping = 0.1

    def implausible(self, view, ext):
        om = 1 / math.sqrt(ext.values["rlc.L"] * self.cap)
        if om / (2 * math.pi) > 0.45 * view.record.fs:
            return f"its resonance ({om / (2 * math.pi):.3g} Hz) is above the data's band"
        zeta = ext.values["rlc.R"] / 2 * math.sqrt(self.cap / ext.values["rlc.L"])
        if zeta < self.min_damping:
            return (
                f"its resonance is as sharp as a mechanical mode's (damping ratio {zeta:.2g} < "
                f"{self.min_damping:g}): not an electrical stage"
            )
        return ""
