"""Model extensions for diagnosis: one candidate per physical effect a piezo model may miss.

Each candidate (a :class:`bondgraph.diagnose.Candidate`) rewrites the nominal bond graph with
the element of seed papers 000-004 that produces the effect, fits it, and says what in the
residual speaks for it.  Effects that act on the drive (hysteresis, creep, saturation, gain
expansion, an RC input stage) go in front of every source that uses the drive voltage, so they
work for any model; effects inside the structure (stiffness softening, nonlinear damping) find
their elements through roles (``stiffness``, ``damping``) that the library components tag;
a missing mode is a parallel resonator on the output.

Input-side and parallel extensions keep the model linear in its states, so they are fitted
with the exact linear recursion (Hammerstein bases solved by bounded least squares, jointly
with the calibration by variable projection); the structural ones are fitted with the
compiled integrator.
"""
from __future__ import annotations

import math
from abc import abstractmethod
from typing import Mapping

import numpy as np
import sympy as sp
from scipy import signal
from scipy.optimize import least_squares

from bondgraph import C, I, J0, J1, Quantity, R, Se
from bondgraph.diagnose import Candidate, Context, empirical_frf, model_frf
from bondgraph.elements import F as F_PLACEHOLDER, P as P_PLACEHOLDER, Q as Q_PLACEHOLDER
from bondgraph.identify import Spec
from bondgraph.lti import foh, recursion
from bondgraph.simulate import SimulationError
from library.hysteresis import PrandtlIshlinskii, bouc_wen_response, play_outputs, threshold_grid


# ---- helpers ----------------------------------------------------------------------------------
def _drive(ctx: Context) -> sp.Symbol:
    return ctx.model.inputs[ctx.ident.input].symbol


def _copy(ctx: Context, values: Mapping[str, float]):
    """Copy of the nominal model carrying the calibration values among ``values``."""
    m = ctx.model.copy()
    m.values.update(_calib_only(ctx, values))
    return m


def _with_input(ctx: Context, u_eff: sp.Expr, values: Mapping[str, float]):
    """Copy of the nominal model whose elements see ``u_eff`` instead of the drive input."""
    m = _copy(ctx, values)
    m.substitute({_drive(ctx): u_eff})
    return m


def lowpass(u: np.ndarray, tau: float, dt: float) -> np.ndarray:
    """First-order lag 1/(τs + 1) of a signal that is linear between samples (exact)."""
    a = math.exp(-dt / tau)
    b1 = 1.0 - tau / dt * (1.0 - a)
    b0 = tau / dt * (1.0 - a) - a
    zi = signal.lfiltic([b1, b0], [1.0, -a], [u[0]], [u[0]])
    return signal.lfilter([b1, b0], [1.0, -a], u, zi=zi)[0]


def resonator_response(u: np.ndarray, dt: float, omega: float, zeta: float) -> np.ndarray:
    """Displacement of q̈ + 2ζω·q̇ + ω²·q = u for u linear between samples, from rest (exact)."""
    A = np.array([[0.0, 1.0], [-omega ** 2, -2 * zeta * omega]])
    Phi, Gam, G1 = foh(A, np.array([[0.0], [1.0]]), dt)
    Y = np.empty((len(u), 1))
    U = np.ascontiguousarray(u, float).reshape(-1, 1)
    recursion(Phi, Gam, np.array([[1.0, 0.0]]), np.array([[G1[0, 0]]]), -G1[:, 0] * u[0], U, Y)
    return Y[:, 0]


def _calib_only(ctx: Context, values: Mapping[str, float]) -> dict[str, float]:
    return {k: v for k, v in values.items() if k in ctx.calibrate}


def _scale(ctx: Context) -> float:
    return float(np.max(np.abs(ctx.u))) or 1.0


def _loop_area(r: np.ndarray, u: np.ndarray) -> float:
    """|∮ r du| normalised by the bounding box: 0 for a single-valued residual, ~0.3 for a fat loop."""
    area = abs(float(np.sum(0.5 * (r[1:] + r[:-1]) * np.diff(u))))
    return area / max(float(np.ptp(r) * np.ptp(u)), 1e-300) / max(1.0, _cycles(u))


def _cycles(u: np.ndarray) -> float:
    """Number of input half-cycles (direction reversals) / 2."""
    d = np.diff(u)
    d = d[np.abs(d) > 1e-9 * np.ptp(u)]
    return max(1.0, float(np.sum(np.diff(np.sign(d)) != 0)) / 2)


def _corr(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a - a.mean(), b - b.mean()
    return float(a @ b / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300))


# ---- input-side effects -------------------------------------------------------------------------
class InputHysteresis(Candidate):
    """Rate-independent hysteresis of the drive: u = H[V], a Prandtl–Ishlinskii operator
    (play form) in front of the linear dynamics, as seed 000 models the bimorph and as the
    inverse of the polarization hysteresis of seed 002 acts at quasi-static rates."""

    cause = "hysteresis"
    label = "Prandtl-Ishlinskii operator on the drive"
    cost = 2
    n_plays = 10

    def applies(self, ctx):
        return ctx.fast()

    def thresholds(self, ctx):
        return threshold_grid(ctx.u, self.n_plays)

    def evidence(self, ctx):
        return {"loop_area": _loop_area(ctx.residual[ctx.ident.fit_mask], ctx.u[ctx.ident.fit_mask])}

    def fit(self, ctx):
        r = self.thresholds(ctx)
        plays = play_outputs(ctx.u, r)
        # the r = 0 play is the linear path (w ≥ 0); the others may have either sign, so loops of
        # both orientations (displacement lagging or leading the drive) are representable
        w, calib = ctx.fit_input_basis(list(plays.T), [0.0] + [-np.inf] * (len(r) - 1), [np.inf] * len(r),
                                       identity=False)
        return {**_calib_only(ctx, calib), **{f"H.w{i + 1}": float(wi) for i, wi in enumerate(w)}}

    def build(self, ctx, values):
        r = self.thresholds(ctx)
        w = [values[f"H.w{i + 1}"] for i in range(len(r))]
        m = _with_input(ctx, sp.Symbol("H", real=True), values)
        m.operator("H", PrandtlIshlinskii(r, w), _drive(ctx))
        return m


class InputBoucWen(Candidate):
    """Rate-independent hysteresis with a differential (Bouc–Wen) state on the drive,
    u = V + κ·V_r·z with dz/dt = A·v̇ − β·|v̇|·|z|^(n−1)·z − γ·v̇·|z|^n, v = V/V_r, A = 1:
    the DE-based model of seed 002 eq. 9, whose minor loops drift as Bouc–Wen loops do."""

    cause = "hysteresis"
    label = "Bouc-Wen state on the drive"
    cost = 2

    def applies(self, ctx):
        return ctx.fast()

    def fit(self, ctx):
        Vr = _scale(ctx)
        v = ctx.u / Vr

        def shape(z3):
            s, rho, n = math.exp(z3[0]), math.tanh(z3[1]), z3[2]
            return s * (1 + rho) / 2, s * (1 - rho) / 2, n

        best = None
        for s0 in (3.0, 30.0):
            z0 = np.array([math.log(s0), 0.0, 1.5])

            base = ctx.responses([ctx.u])[:, 0]
            idx = ctx.ident.fit_idx
            scale = max(float(np.std(ctx.y)), 1e-300)

            def resid(z3):
                beta, gamma, n = shape(z3)
                d = ctx.responses([Vr * bouc_wen_response(v, beta, gamma, n)])[:, 0][idx]
                r = (ctx.y - base)[idx]
                d, r = d - d.mean(), r - r.mean()
                kappa = (d @ r) / max(d @ d, 1e-300)
                return (r - kappa * d) / scale

            sol = least_squares(resid, z0, bounds=([math.log(0.05), -3.0, 1.0], [math.log(500.0), 3.0, 4.0]),
                                max_nfev=20, diff_step=1e-3)
            if best is None or sol.cost < best.cost:
                best = sol
        beta, gamma, n = shape(best.x)
        zb = bouc_wen_response(v, beta, gamma, n)
        kappa, calib = ctx.fit_input_basis([Vr * zb], [-np.inf], [np.inf])
        return {**_calib_only(ctx, calib), "bw.kappa": float(kappa[0]), "bw.beta": beta, "bw.gamma": gamma,
                "bw.n": n}

    def build(self, ctx, values):
        V = _drive(ctx)
        Vr_val = _scale(ctx)
        m = _copy(ctx, values)
        kappa = m.parameter("bw.kappa", values["bw.kappa"], "", "weight of the Bouc-Wen state in the drive")
        beta = m.parameter("bw.beta", values["bw.beta"], "", "Bouc-Wen beta")
        gamma = m.parameter("bw.gamma", values["bw.gamma"], "", "Bouc-Wen gamma")
        n = m.parameter("bw.n", values["bw.n"], "", "Bouc-Wen exponent")
        Vr = m.parameter("bw.Vr", Vr_val, "V", "reference drive (largest |V| of the data)")
        z = sp.Symbol("bw.z", real=True)
        m.substitute({V: V + kappa * Vr * z})
        vdot = m.input_rate(ctx.ident.input) / Vr
        m.state("bw.z", vdot - beta * sp.Abs(vdot) * sp.Abs(z) ** (n - 1) * z - gamma * vdot * sp.Abs(z) ** n,
                unit="", doc="Bouc-Wen hysteretic variable (units of V/V_r)")
        return m


class InputCreep(Candidate):
    """Creep: a generalized Kelvin–Voigt chain (seed 003 eq. 1) on the drive,
    u = V + Σ q_n with cells q̇_n = (c_n·V − q_n)/τ_n, i.e. a step response
    V0·[1 + Σ c_n(1 − e^(−t/τ_n))]; cells are C_n = c_n, R_n = τ_n/c_n on a 0-junction."""

    cause = "creep"
    label = "Kelvin-Voigt creep chain on the drive"

    def applies(self, ctx):
        return ctx.fast()

    def taus(self, ctx):
        lo = max(30 * ctx.dt, 2e-3)
        hi = min((ctx.t[-1] - ctx.t[0]) / 2, 100.0)
        n = max(2, int(round(math.log10(hi / lo) * 2)) + 1)
        return np.geomspace(lo, hi, n)

    def evidence(self, ctx):
        return {"step_drift": _step_drift(ctx)}

    def fit(self, ctx):
        taus = self.taus(ctx)
        basis = [lowpass(ctx.u, tau, ctx.dt) for tau in taus]
        c, calib = ctx.fit_input_basis(basis, [0.0] * len(taus), [np.inf] * len(taus))
        keep = [i for i in np.argsort(-c)[:3] if c[i] > 1e-4]
        if not keep:
            keep = [int(np.argmax(c))]
        values = dict(_calib_only(ctx, calib))
        for k, i in enumerate(sorted(keep, key=lambda i: taus[i])):
            values[f"creep.c{k + 1}"] = max(float(c[i]), 1e-4)
            values[f"creep.tau{k + 1}"] = float(taus[i])
        model = self.build(ctx, values)
        names = [n for n in values if n.startswith("creep.")]
        starts = {n: Spec(n, values[n], values[n] / 100, values[n] * 100, log=True) for n in names}
        saved, ctx.calibrated = ctx.calibrated, {**ctx.calibrated, **_calib_only(ctx, values)}
        try:
            return ctx.fit_model(model, names, starts, max_nfev=40)
        finally:
            ctx.calibrated = saved

    def build(self, ctx, values):
        n = sum(1 for k in values if k.startswith("creep.c"))
        V = _drive(ctx)
        m = _with_input(ctx, V + sum(Quantity("q", f"creep.C{k}") for k in range(1, n + 1)), values)
        m.add(Se("creep.src", V), J0("creep.node"))
        m.bond("creep.src", "creep.node")
        for k in range(1, n + 1):
            c = m.parameter(f"creep.c{k}", values[f"creep.c{k}"], "", f"creep ratio of cell {k}", bounds=(0, 1e3))
            tau = m.parameter(f"creep.tau{k}", values[f"creep.tau{k}"], "s", f"creep time constant of cell {k}",
                              bounds=(0, 1e4))
            m.add(J1(f"creep.cell{k}"), C(f"creep.C{k}", c), R(f"creep.R{k}", tau / c))
            m.bond("creep.node", f"creep.cell{k}")
            m.bond(f"creep.cell{k}", f"creep.C{k}")
            m.bond(f"creep.cell{k}", f"creep.R{k}")
        return m


def _step_drift(ctx: Context) -> float:
    """Mean drift of the residual over the holds that follow input steps, relative to the
    output range (0 when the data has no steps)."""
    u, r = ctx.u, ctx.residual
    du = np.abs(np.diff(u))
    big = np.nonzero(du > 0.2 * np.ptp(u))[0]
    if big.size == 0:
        return 0.0
    edges = np.concatenate([big[np.diff(big, prepend=-10) > 1], [len(u) - 1]])
    drifts = []
    for a, b in zip(edges[:-1], edges[1:]):
        seg = r[a + 2:b]
        if seg.size > 20:
            k = max(1, seg.size // 10)
            drifts.append(abs(seg[-k:].mean() - seg[:k].mean()))
    return float(np.mean(drifts)) / max(float(np.ptp(ctx.y)), 1e-300) if drifts else 0.0


class _InputPolynomial(Candidate):
    """Static odd nonlinearity of the drive: u = V + s·(a3·V³/Vr² + a5·V⁵/Vr⁴), a3, a5 ≥ 0."""

    sign = -1.0
    prefix = "sat"

    def applies(self, ctx):
        return ctx.fast()

    def evidence(self, ctx):
        u = ctx.u / _scale(ctx)
        cubic = u ** 3 - u * (u @ u ** 3) / max(u @ u, 1e-300)
        return {"cubic_corr": _corr(ctx.residual, ctx.responses([cubic * _scale(ctx)])[:, 0])}

    def fit(self, ctx):
        Vr = _scale(ctx)
        basis = [self.sign * ctx.u ** 3 / Vr ** 2, self.sign * ctx.u ** 5 / Vr ** 4]
        a, calib = ctx.fit_input_basis(basis, [0.0, 0.0], [np.inf, np.inf])
        return {**_calib_only(ctx, calib), f"{self.prefix}.a3": float(a[0]), f"{self.prefix}.a5": float(a[1])}

    def build(self, ctx, values):
        V = _drive(ctx)
        m = _copy(ctx, values)
        a3 = m.parameter(f"{self.prefix}.a3", values[f"{self.prefix}.a3"], "", "cubic drive coefficient",
                         bounds=(0, 1e6))
        a5 = m.parameter(f"{self.prefix}.a5", values[f"{self.prefix}.a5"], "", "quintic drive coefficient",
                         bounds=(0, 1e6))
        Vr = m.parameter(f"{self.prefix}.Vr", _scale(ctx), "V", "reference drive (largest |V| of the data)")
        m.substitute({V: V + self.sign * (a3 * V ** 3 / Vr ** 2 + a5 * V ** 5 / Vr ** 4)})
        return m


class InputSaturation(_InputPolynomial):
    """Saturation: the drive's effect compresses at high field (polarization saturates,
    P ≈ P_s·tanh(E/E_s) = E − E³/(3E_s²) + ...)."""

    cause = "saturation"
    label = "compressive drive nonlinearity (saturating polarization)"
    sign, prefix = -1.0, "sat"


class InputExpansion(_InputPolynomial):
    """Softening that shows as gain expansion: a field-dependent stiffness k_a(E) that falls
    with the drive (seed 003) makes the displacement per volt grow with amplitude."""

    cause = "softening"
    label = "expanding drive nonlinearity (field-dependent stiffness k_a(E))"
    sign, prefix = 1.0, "exp"


class InputRC(Candidate):
    """An RC input stage: the drive reaches the actuator through a series resistance into
    its capacitance, u = V/(1 + sRC) (amplifier output resistance, cables)."""

    cause = "electrical-rc"
    label = "series R with a capacitance on the drive (RC lag)"
    cap = 1e-6

    def applies(self, ctx):
        return ctx.fast()

    def evidence(self, ctx):
        du = np.gradient(ctx.u, ctx.t)
        lag = ctx.responses([du])[:, 0]
        return {"lag_corr": -_corr(ctx.residual, lag)}

    def fit(self, ctx):
        span = ctx.t[-1] - ctx.t[0]
        taus = np.geomspace(2 * ctx.dt, span / 20, 18)
        fit_idx = ctx.ident.fit_idx
        best = (math.inf, taus[0])
        Y = ctx.responses([lowpass(ctx.u, tau, ctx.dt) for tau in taus])
        for j, tau in enumerate(taus):
            r = (ctx.y - Y[:, j])[fit_idx]
            sse = float(np.sum((r - r.mean()) ** 2))
            best = min(best, (sse, tau))
        values = {"rc.R": best[1] / self.cap}
        model = self.build(ctx, values)
        starts = {"rc.R": Spec("rc.R", values["rc.R"], values["rc.R"] / 20, values["rc.R"] * 20, log=True)}
        return ctx.fit_model(model, ["rc.R"], starts, max_nfev=40)

    def build(self, ctx, values):
        V = _drive(ctx)
        m = _with_input(ctx, Quantity("e", "rc.C"), values)
        Rin = m.parameter("rc.R", values["rc.R"], "ohm", "series resistance of the input stage", bounds=(0, 1e12))
        Cin = m.parameter("rc.C", self.cap, "F", "capacitance of the input stage (only R·C matters)")
        m.add(Se("rc.src", V), J1("rc.i"), R("rc.Rs", Rin), J0("rc.node"), C("rc.C", Cin))
        m.chain("rc.src", "rc.i", "rc.node", "rc.C")
        m.bond("rc.i", "rc.Rs")
        return m


# ---- a missing mode ------------------------------------------------------------------------------
class ParallelMode(Candidate):
    """A mode the model lacks: a resonator q̈ + 2ζω·q̇ + ω²·q = g·V whose displacement adds to
    the output (modal superposition, as seed 000 adds bending modes)."""

    cause = "higher-mode"
    label = "extra resonator (mode) in parallel on the output"

    def applies(self, ctx):
        return ctx.fast()

    def _mismatch(self, ctx):
        w, H, coh = ctx.frf if ctx.frf is not None else empirical_frf(ctx)
        Hm = model_frf(ctx.lti, ctx.theta(), w)
        return w, np.abs(H - Hm) * coh / np.maximum(np.abs(Hm), 1e-300 + 1e-3 * np.abs(Hm).max())

    def evidence(self, ctx):
        w, mis = self._mismatch(ctx)
        k = int(np.argmax(mis)) if mis.size else 0
        return {"frf_mismatch": float(mis[k]) if mis.size else 0.0, "omega_peak": float(w[k]) if w.size else 0.0}

    def fit(self, ctx):
        w, mis = self._mismatch(ctx)
        peaks, _ = signal.find_peaks(mis)
        order = peaks[np.argsort(-mis[peaks])][:3] if peaks.size else np.array([int(np.argmax(mis))])
        # scan frequency and damping around each peak: the mode's output g·V/(s² + 2ζωs + ω²)
        # is a fixed filter of the drive, so each trial costs one small linear recursion
        r = ctx.residual[ctx.ident.fit_idx]
        trials = []
        for k in order:
            for om in float(w[k]) * np.geomspace(0.85, 1.15, 9):
                for ze in (0.005, 0.02, 0.06):
                    d = resonator_response(ctx.u, ctx.dt, om, ze)[ctx.ident.fit_idx]
                    d, rr = d - d.mean(), r - r.mean()
                    g = (d @ rr) / max(d @ d, 1e-300)
                    trials.append((float(np.sum((rr - g * d) ** 2)), om, ze, g))
        best = None
        for _, om, ze, g in sorted(trials)[:2]:
            values = {"hm.omega": om, "hm.zeta": ze, "hm.g": g}
            model = self.build(ctx, values)
            starts = {"hm.omega": Spec("hm.omega", om, om / 2, om * 2, log=True),
                      "hm.zeta": Spec("hm.zeta", ze, 1e-4, 1.0, log=True),
                      "hm.g": Spec("hm.g", g, -np.inf, np.inf, scale=abs(g) or 1.0, linear=True)}
            fitted = ctx.fit_model(model, list(starts), starts, linear=["hm.g"], max_nfev=30)
            ident = ctx.ident.like(model)
            score = ident.scores(ident.predict(fitted))[1]
            if best is None or score < best[0]:
                best = (score, fitted)
        return best[1]

    def build(self, ctx, values):
        V = _drive(ctx)
        m = _copy(ctx, values)
        om = m.parameter("hm.omega", values["hm.omega"], "rad/s", "natural frequency of the added mode")
        ze = m.parameter("hm.zeta", values["hm.zeta"], "", "damping ratio of the added mode")
        g = m.parameter("hm.g", values["hm.g"], "m*s^-2/V", "input gain of the added mode (unit modal mass)")
        m.add(Se("hm.force", g * V), J1("hm.mode"), I("hm.mass", 1), C("hm.spring", 1 / om ** 2),
              R("hm.damper", 2 * ze * om))
        m.bond("hm.force", "hm.mode")
        for e in ("hm.mass", "hm.spring", "hm.damper"):
            m.bond("hm.mode", e)
        out = m.outputs[ctx.ident.output]
        out.expr = out.expr + Quantity("q", "hm.spring")
        return m


class OutputMode(Candidate):
    """A mode of the output structure: a mass m2 on a spring k2 with damper c2 riding on the
    element tagged ``inertia`` (an APA's output plate or shell), the sensor on m2:
    k2 = m2·ω², c2 = 2ζ·m2·ω."""

    cause = "higher-mode"
    label = "compliant output stage (mass on a spring) on the inertia element"

    def applies(self, ctx):
        return ctx.fast() and bool(ctx.model.with_role("inertia"))

    def _mass(self, ctx) -> tuple[str, float]:
        el = ctx.model.with_role("inertia")[0]
        M = _number(ctx, 1 / sp.diff(ctx.model.elements[el].law, P_PLACEHOLDER))
        return el, M

    def fit(self, ctx):
        w, mis = ParallelMode()._mismatch(ctx)
        peaks, _ = signal.find_peaks(mis)
        order = peaks[np.argsort(-mis[peaks])][:3] if peaks.size else np.array([int(np.argmax(mis))])
        _, M = self._mass(ctx)
        best = None
        for k in order:
            om = float(w[k])
            starts = {"om.omega": Spec("om.omega", om, om / 3, om * 3, log=True),
                      "om.zeta": Spec("om.zeta", 0.03, 1e-4, 1.0, log=True),
                      "om.m2": Spec("om.m2", 0.2 * M, 1e-3 * M, 10 * M, log=True)}
            model = self.build(ctx, {n: s.start for n, s in starts.items()})
            fitted = ctx.fit_model(model, list(starts), starts, max_nfev=30)
            ident = ctx.ident.like(model)
            score = ident.scores(ident.predict(fitted))[1]
            if best is None or score < best[0]:
                best = (score, fitted)
        return best[1]

    def build(self, ctx, values):
        el, _ = self._mass(ctx)
        m = _copy(ctx, values)
        om = m.parameter("om.omega", values["om.omega"], "rad/s", "natural frequency of the output stage")
        ze = m.parameter("om.zeta", values["om.zeta"], "", "damping ratio of the output stage")
        m2 = m.parameter("om.m2", values["om.m2"], "kg", "mass of the output stage")
        junction = next(b.tail[0] if b.head[0] == el else b.head[0] for b in m.bonds_of(el))
        m.add(J0("om.k"), C("om.spring", 1 / (m2 * om ** 2)), J1("om.plate"), I("om.mass", m2),
              R("om.damper", 2 * ze * m2 * om))
        m.bond(junction, "om.k")
        m.bond("om.k", "om.spring")
        m.bond("om.k", "om.plate")
        m.bond("om.plate", "om.mass")
        m.bond("om.plate", "om.damper")
        out = m.outputs[ctx.ident.output]
        out.expr = out.expr - Quantity("q", "om.spring")  # the sensor sits on the plate
        return m


# ---- effects inside the structure ---------------------------------------------------------------------
def _state_stats(ctx: Context) -> tuple[dict[str, float], dict[str, float]]:
    """(largest |state|, mean square of each state) of the calibrated nominal model, by name;
    also the output velocity under the key ``"output rate"``."""
    res = ctx.ident.sim.run(ctx.t, {ctx.ident.input: ctx.ident.signal}, params=ctx.calibrated, rtol=1e-5)
    series = dict(res.states)
    series["output rate"] = np.gradient(res.outputs[ctx.ident.output], ctx.t)
    return ({k: float(np.max(np.abs(v))) or 1.0 for k, v in series.items()},
            {k: float(np.mean(v ** 2)) for k, v in series.items()})


def _state_of(ctx: Context, element: str) -> str:
    return next(str(s.symbol) for s in ctx.eqs.states if s.origin == element)


class _Centred(Candidate):
    """A structural nonlinearity, one coefficient per element of ``role``, centred on the
    data's amplitude (see the subclasses); fitted by :func:`_screen_then_fit`."""

    role = ""
    prefix = ""
    cost = 3

    def applies(self, ctx):
        return bool(ctx.model.with_role(self.role))

    @abstractmethod
    def refs(self, ctx) -> dict[str, tuple[float, float]]:
        """(scale of the coefficient, centring amplitude²) per element."""

    def fit(self, ctx):
        self._refs = self.refs(ctx)
        starts = {f"{self.prefix}_{el}": Spec(f"{self.prefix}_{el}", 0.0, 0.0, self.upper * sc, scale=sc)
                  for el, (sc, _) in self._refs.items()}
        return _screen_then_fit(ctx, self, starts)


class StiffnessSoftening(_Centred):
    """Amplitude-dependent stiffness: every element tagged ``stiffness`` gets a cubic softening
    term (seed 001's k1·q³, seed 003's k_a(E)), written centred on the data's amplitude,
    e = law(q) − k3·q·(q² − r²) with r² = 1.5·⟨q²⟩ of the calibrated model: the describing-
    function stiffness at the data's amplitude stays the calibrated one, so k3 (≥ 0) only
    moves the stiffness with amplitude and does not fight the calibration."""

    cause = "softening"
    label = "cubic softening of the stiffness elements"
    role, prefix, upper = "stiffness", "soft.k3", 2.0

    def refs(self, ctx) -> dict[str, tuple[float, float]]:
        """(scale of k3, r²) per stiffness element."""
        peaks, ms = _state_stats(ctx)
        out = {}
        for el in ctx.model.with_role("stiffness"):
            k_lin = _number(ctx, sp.diff(ctx.model.elements[el].law, Q_PLACEHOLDER).subs(Q_PLACEHOLDER, 0))
            name = _state_of(ctx, el)
            out[el] = (abs(k_lin) / peaks[name] ** 2, 1.5 * ms[name])
        return out

    def build(self, ctx, values):
        refs = getattr(self, "_refs", None) or self.refs(ctx)
        m = _copy(ctx, values)
        Qp = Q_PLACEHOLDER
        for el in ctx.model.with_role("stiffness"):
            k3 = m.parameter(f"soft.k3_{el}", values[f"soft.k3_{el}"], "", f"cubic softening of {el}", bounds=(0, 1e40))
            r2 = m.parameter(f"soft.r2_{el}", refs[el][1], "", f"centring amplitude² of {el} (1.5·mean q²)")
            law = m.elements[el].law
            m.replace(C(el, law=lambda q, law=law: law.xreplace({Qp: q}) - k3 * q * (q ** 2 - r2)))
        return m


def _screen_then_fit(ctx: Context, cand: Candidate, starts: Mapping[str, Spec]) -> dict[str, float]:
    """Fit a structural extension with the integrator.  A nonlinear resonance (jumps, shifted
    peaks) defeats a local fit from zero and biases the linear calibration, so the new
    parameters are scanned upwards on a log grid of their scales (stopping after three points
    when none of them helped or promised 1 %), each grid point improved by one Gauss–Newton
    step that also moves the calibration; the best of these points (simulated), if it beats
    the calibrated model by 2 %, starts the local fit."""
    new = list(starts)
    model = cand.build(ctx, {n: 0.0 for n in new})
    ident = ctx.ident.like(model, rtol=1e-5)
    base = {**ctx.calibrated, **{n: 0.0 for n in new}}
    base_pred = ident.predict(base)
    base_rms = ident.scores(base_pred)[1]
    best = (base_rms, base)
    # calibration sensitivities at the nominal point stand in for those at each grid point
    extra = {n: (0.01 * ctx.calibrated[n], col) for n, col in ctx.calibration_sensitivities().items()}
    # what moving the calibration alone promises (a calibration held at a bound promises
    # something): a grid point must promise more than that to be followed
    floor = min(base_rms, ctx.screen(ident, base, {}, extra, base_pred)[0])
    predicted = []
    for k, f in enumerate((0.001, 0.003, 0.01, 0.03, 0.1, 0.3)):
        if k == 3 and predicted and best[0] >= base_rms and min(p[0] for p in predicted) > 0.99 * floor:
            break  # weak nonlinearity neither helps nor promises anything: no trace of the effect
        at = {**ctx.calibrated, **{n: f * starts[n].scale for n in new}}
        try:
            pred_at = ident.predict(at)
            rms_at = ident.scores(pred_at)[1]
            rms_pred, values = ctx.screen(ident, at, {n: 0.3 * f * starts[n].scale for n in new}, extra, pred_at)
        except SimulationError:
            continue
        best = min(best, (rms_at, at), key=lambda b: b[0])
        predicted.append((rms_pred, at, values))
    # the Gauss–Newton steps overshoot in a nonlinear resonance: a line search on the two best
    for _, at, values in [p for p in sorted(predicted, key=lambda p: p[0])[:2] if p[0] < 0.98 * floor]:
        for alpha in (1.0, 0.5, 0.25):
            trial = {k: at[k] + alpha * (values[k] - at[k]) for k in values}
            try:
                rms = ident.scores(ident.predict(trial))[1]
            except SimulationError:
                continue
            best = min(best, (rms, trial), key=lambda b: b[0])
    if best[0] > 0.98 * base_rms:
        return base
    point = best[1]
    specs = {n: Spec(n, min(max(point[n], 0.0), starts[n].upper), starts[n].lower, starts[n].upper, starts[n].scale)
             for n in new}
    for n in ctx.calibrate:
        v = point[n]
        specs[n] = Spec(n, v, v / 10, v * 10, log=True) if v > 0 else Spec(n, v, scale=abs(v) or 1.0)
    return ctx.fit_model(model, list(specs), specs, max_nfev=15)


def _number(ctx: Context, expr: sp.Expr) -> float:
    """Value of a parameter expression with the calibrated parameters."""
    return float(expr.xreplace(dict(zip(ctx.eqs.params, ctx.theta()))))


class NonlinearDamping(_Centred):
    """Amplitude-dependent damping (Stanton type, seed 001): every element tagged ``damping``
    gets e = (c + μ1·q²)·f with q the displacement of the stiffness element on its junction
    (or, with ``velocity`` or when there is none, e = c·f + μ1·f³), μ1 ≥ 0."""

    cause = "nonlinear-damping"
    label = "amplitude-dependent (Stanton) damping of the damping elements"
    role, prefix, upper = "damping", "nld.mu1", 50.0

    def __init__(self, velocity: bool = False):
        self.velocity = velocity
        if velocity:
            self.label = "velocity-cubic damping of the damping elements"

    def applies(self, ctx):
        """The Stanton form only where some damping element has a stiffness partner (else it
        is the velocity-cubic form, tried by its own candidate)."""
        els = ctx.model.with_role(self.role)
        return bool(els) and (self.velocity or any(self._partner(ctx, el) is not None for el in els))

    def _partner(self, ctx, el):
        if self.velocity:
            return None
        m = ctx.model
        for b in m.bonds_of(el):
            j = b.tail[0] if b.head[0] == el else b.head[0]
            for b2 in m.bonds_of(j):
                other = b2.tail[0] if b2.head[0] == j else b2.head[0]
                if getattr(m.elements[other], "role", None) == "stiffness":
                    return other
        return None

    def refs(self, ctx) -> dict[str, tuple[float, float]]:
        """(scale of μ1, r²) per damping element; the law is centred like the softening one:
        (c + μ1·(a² − r²))·f with r² = ⟨a²⟩/2 for a = q, 1.5·⟨f²⟩ for the velocity-cubic form."""
        peaks, ms = _state_stats(ctx)
        out = {}
        for el in ctx.model.with_role("damping"):
            c_lin = _number(ctx, sp.diff(ctx.model.elements[el].law, F_PLACEHOLDER).subs(F_PLACEHOLDER, 0))
            partner = self._partner(ctx, el)
            if partner is not None:
                name = _state_of(ctx, partner)
                out[el] = (abs(c_lin) / peaks[name] ** 2, 0.5 * ms[name])
            else:
                out[el] = (abs(c_lin) / peaks["output rate"] ** 2, 1.5 * ms["output rate"])
        return out

    def build(self, ctx, values):
        refs = getattr(self, "_refs", None) or self.refs(ctx)
        m = _copy(ctx, values)
        for el in ctx.model.with_role("damping"):
            mu1 = m.parameter(f"nld.mu1_{el}", values[f"nld.mu1_{el}"], "", f"nonlinear damping of {el}",
                              bounds=(0, 1e40))
            r2 = m.parameter(f"nld.r2_{el}", refs[el][1], "", f"centring amplitude² of {el}")
            law = m.elements[el].law
            c_lin = sp.diff(law, F_PLACEHOLDER)
            partner = self._partner(ctx, el)
            if partner is not None:
                a = Quantity("q", partner)
                m.replace(R(el, law=lambda f, c=c_lin, a=a, mu=mu1, r2=r2: (c + mu * (a ** 2 - r2)) * f))
            else:
                m.replace(R(el, law=lambda f, c=c_lin, mu=mu1, r2=r2: (c + mu * (f ** 2 - r2)) * f))
        return m


def candidates() -> list[Candidate]:
    """The piezo candidate set (entry point ``bondgraph.diagnosis``: ``piezo``)."""
    return [InputHysteresis(), InputBoucWen(), InputCreep(), InputSaturation(), InputExpansion(), StiffnessSoftening(),
            ParallelMode(), OutputMode(), NonlinearDamping(), NonlinearDamping(velocity=True), InputRC()]
