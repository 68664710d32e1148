"""Diagnosis: what does the model miss, given measured data?

1. **Calibrate** the nominal model's linear parameters (the model file's ``CALIBRATE`` list,
   glob patterns allowed) to the data: first on the empirical frequency response (multi-start,
   weighted by coherence; cheap and free of the local minima that lightly damped modes give a
   time-domain fit), then on the time series.
2. **Residual** of the calibrated model on the held-out validation blocks: ``baseline_rms``.
3. **Evidence** for each candidate cause, computed from the residual by the candidate.
4. **Extend and refit**: every candidate rewrites the bond graph with its element (found
   through element roles or acting on the input), fits the new parameters together with the
   calibrated ones, and the extended graph is simulated once on the whole record for its
   validation RMS.  Candidates run in parallel worker processes.
5. **Decide**: the candidate with the largest validation gain names the cause if its gain is
   at least ``MIN_GAIN`` *and* the Bayesian information criterion on the validation part,
   ΔBIC = n·ln(RSS_base/RSS_ext) − k·ln(n), exceeds ``MIN_DELTA_BIC`` (k: parameters it
   fitted); candidates whose gain is within ``TIE`` of the best compete on ΔBIC.  Otherwise
   the cause is ``none``.

The candidates (the physics) are not part of the framework: they are found through the
``bondgraph.diagnosis`` entry point (``library.extensions`` provides the piezo set) and
implement :class:`Candidate`.
"""
from __future__ import annotations

import fnmatch
import math
import multiprocessing as mp
import os
import time
from abc import ABC, abstractmethod
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np
from scipy import signal
from scipy.optimize import least_squares, lsq_linear

from .data import Dataset
from .equations import Equations, derive
from .errors import BondGraphError, UsageError
from .graph import Model
from .identify import FitResult, Identification, Spec, default_spec, uniform_step
from .lti import LTI
from .signals import PiecewiseLinear
from .simulate import SimulationError, Simulator

CAUSES = ("none", "hysteresis", "creep", "saturation", "softening", "higher-mode", "nonlinear-damping",
          "electrical-rc")
MIN_GAIN = 1.2
MIN_DELTA_BIC = 10.0
TIE = 0.05


@dataclass
class Context:
    """Everything a candidate needs: data, split, nominal model, calibration, residual."""

    model: Model
    eqs: Equations
    ident: Identification
    lti: LTI | None
    calibrate: list[str]
    calibrated: dict[str, float] = field(default_factory=dict)
    nominal: dict[str, float] = field(default_factory=dict)
    baseline: FitResult | None = None
    frf: tuple | None = None  # (omega rad/s, H, coherence)

    @property
    def t(self) -> np.ndarray:
        return self.ident.t

    @property
    def u(self) -> np.ndarray:
        return self.ident.u

    @property
    def y(self) -> np.ndarray:
        return self.ident.y

    @property
    def dt(self) -> float | None:
        """The sample interval when the data is uniformly sampled (the LTI fast path needs it)."""
        return self.ident.dt

    @property
    def residual(self) -> np.ndarray:
        return self.y - self.baseline.prediction

    def fast(self) -> bool:
        return self.lti is not None and self.lti.exact and self.dt is not None

    def theta(self, values: Mapping[str, float] | None = None) -> np.ndarray:
        return self.ident.sim.theta({**self.calibrated, **(values or {})})

    def responses(self, columns: Sequence[np.ndarray], values: Mapping[str, float] | None = None) -> np.ndarray:
        """Output of the (calibrated) nominal model driven by each input column (LTI, exact)."""
        U = np.column_stack(columns)
        return self.lti.response(self.theta(values), self.dt, U)

    def fit_input_basis(self, basis: Sequence[np.ndarray], lower: Sequence[float], upper: Sequence[float],
                        identity: bool = True, refit: bool = True, max_nfev: int = 15):
        """Fit u_eff = [u] + Σ θ_k·basis_k through the nominal linear dynamics (a Hammerstein
        model): θ by bounded linear least squares (non-negative where ``lower`` is 0), jointly
        with the calibration parameters by variable projection.  Returns (θ, calibration values)."""
        fit_idx = self.ident.fit_idx
        cols = ([self.u] if identity else []) + list(basis)

        def solve(values):
            Y = self.responses(cols, values)
            base = Y[:, 0] if identity else 0.0
            A = np.column_stack([Y[:, 1:] if identity else Y, np.ones(len(self.u))])[fit_idx]
            rhs = (self.y - base)[fit_idx]
            coef = bounded_lstsq(A, rhs, list(lower) + [-np.inf], list(upper) + [np.inf])
            return coef[:-1], A @ coef - rhs

        if not (refit and self.calibrate):
            return solve(self.calibrated)[0], dict(self.calibrated)
        specs = [_calib_spec(n, self.nominal[n]) for n in self.calibrate]
        scale = max(float(np.std(self.y[fit_idx])), 1e-300)

        def resid(z):
            vals = {s.name: s.from_z(zi) for s, zi in zip(specs, z)}
            return solve(vals)[1] / scale

        lb, ub = np.array([s.z_bounds() for s in specs]).T
        best = None
        # from the calibration (which may have bent to mimic the missing effect) and from nominal
        far = any(abs(math.log(self.calibrated[n] / self.nominal[n])) > 0.3 for n in self.calibrate
                  if self.calibrated[n] > 0 and self.nominal[n] > 0)
        for start in (self.calibrated, self.nominal) if far else (self.calibrated,):
            z0 = np.clip([s.to_z(start[s.name]) for s in specs], lb, ub)
            sol = least_squares(resid, z0, bounds=(lb, ub), max_nfev=max_nfev, diff_step=1e-4)
            if best is None or sol.cost < best.cost:
                best = sol
        vals = {s.name: s.from_z(zi) for s, zi in zip(specs, best.x)}
        return solve(vals)[0], vals

    def calibration_sensitivities(self, rel: float = 0.01) -> dict[str, np.ndarray]:
        """Output change of the calibrated nominal model for a relative step of each calibration
        parameter (exact linear route when available)."""
        base = self.ident.predict(self.calibrated)
        return {n: self.ident.predict({**self.calibrated, n: self.calibrated[n] * (1 + rel)}) - base
                for n in self.calibrate if self.calibrated[n] != 0}

    def screen(self, ident: Identification, at: Mapping[str, float], steps: Mapping[str, float],
               extra: Mapping[str, tuple[float, np.ndarray]] | None = None,
               base: np.ndarray | None = None) -> tuple[float, dict[str, float]]:
        """One Gauss–Newton step from ``at``: the output changes for each (non-negative) new
        parameter's step, and the given ``extra`` columns (name → (step, change), e.g. the
        calibration sensitivities), are combined by bounded least squares to explain the
        residual (``base``: the prediction at ``at``, if already simulated).  Returns the RMS
        (fit part) the linearised step predicts, and its values."""
        base = ident.predict(at) if base is None else base
        cols = [ident.predict({**at, k: at[k] + v}) - base for k, v in steps.items()]
        extra = dict(extra or {})
        cols += [c for _, c in extra.values()]
        idx = self.ident.fit_idx
        A = np.column_stack(cols + [np.ones(len(base))])[idx]
        r = (self.y - base)[idx]
        lo = [-at[k] / v for k, v in steps.items()] + [-np.inf] * (len(extra) + 1)
        coef = bounded_lstsq(A, r, lo, [np.inf] * len(lo))
        values = dict(at)
        for (k, v), c in zip(list(steps.items()) + [(k, st) for k, (st, _) in extra.items()], coef):
            values[k] = at[k] + float(c) * v
            if k in self.calibrated and self.calibrated[k] > 0:  # keep calibration steps modest
                values[k] = float(np.clip(values[k], 0.5 * at[k], 2 * at[k]))
        return float(np.sqrt(np.mean((r - A @ coef) ** 2))), values

    def fit_model(self, model: Model, names: Sequence[str], starts: Mapping[str, Spec] | None = None,
                  linear: Sequence[str] = (), max_nfev: int = 30, rtol: float = 1e-7) -> dict[str, float]:
        """Fit ``names`` of an extended ``model`` (plus the calibration parameters) to the data."""
        ident = self.ident.like(model, rtol=rtol)
        fixed = dict(self.calibrated)
        specs = []
        for n in list(self.calibrate) + [n for n in names if n not in self.calibrate]:
            if starts and n in starts:
                specs.append(starts[n])
            elif n in self.calibrated:
                specs.append(_calib_spec(n, self.calibrated[n]))
            else:
                specs.extend(ident.specs([n], linear))
            fixed.pop(n, None)
        res = ident.fit(specs, fixed=fixed, max_nfev=max_nfev, rounds=2, stderr=False)
        return {**fixed, **res.values}


def bounded_lstsq(A: np.ndarray, b: np.ndarray, lower, upper) -> np.ndarray:
    """min ||A·x − b|| with lower ≤ x ≤ upper, for tall A: reduced to the small triangular
    factor R of the (column-scaled) normal matrix, ||Ax − b||² = ||Rx − R⁻ᵀAᵀb||² + const,
    and solved there by scipy's bounded least squares."""
    norms = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    An = A / norms
    G = An.T @ An
    G[np.diag_indices_from(G)] *= 1 + 1e-12
    try:
        Rm = np.linalg.cholesky(G).T
    except np.linalg.LinAlgError:
        Rm = np.linalg.qr(An, mode="r")
    rhs = np.linalg.solve(Rm.T, An.T @ b)
    sol = lsq_linear(Rm, rhs, bounds=(np.asarray(lower, float) * norms, np.asarray(upper, float) * norms),
                     method="bvls")
    return sol.x / norms


def _calib_spec(name: str, value: float) -> Spec:
    """Calibration parameters move within ×/÷ 10 of the nominal value (devices of the same kind)."""
    if value > 0:
        return Spec(name, value, value / 10, value * 10, log=True)
    return default_spec(name, value)


class Candidate(ABC):
    """One possible missing effect: how to find evidence for it and how to extend the model."""

    #: the cause it stands for (one of CAUSES or a new name)
    cause: str = ""
    #: a short description of the extension
    label: str = ""
    #: relative cost; costly candidates start first so parallel workers finish together
    cost: int = 1

    def applies(self, ctx: Context) -> bool:
        return True

    def evidence(self, ctx: Context) -> dict[str, float]:
        """Numbers from the baseline residual that speak for this cause."""
        return {}

    @abstractmethod
    def fit(self, ctx: Context) -> dict[str, float]:
        """Fitted values: the extension's new parameters and the refitted calibration ones."""

    @abstractmethod
    def build(self, ctx: Context, values: Mapping[str, float]) -> Model:
        """The nominal model extended with this candidate's element(s), for ``values`` from
        :meth:`fit` (the structure may depend on which parameters are present)."""


@dataclass
class CandidateResult:
    cause: str
    label: str
    gain: float = 0.0
    rms_fit: float = math.inf
    rms_validation: float = math.inf
    n_params: int = 0
    delta_bic: float = -math.inf
    params: dict = field(default_factory=dict)
    evidence: dict = field(default_factory=dict)
    seconds: float = 0.0
    error: str = ""

    def as_json(self) -> dict:
        return {"cause": self.cause, "label": self.label, "gain": self.gain, "rms_fit": self.rms_fit,
                "rms_validation": self.rms_validation, "n_params": self.n_params, "delta_bic": self.delta_bic,
                "params": self.params, "evidence": self.evidence, "seconds": round(self.seconds, 2),
                **({"error": self.error} if self.error else {})}


@dataclass
class Report:
    cause: str
    gain: float
    baseline_rms: float
    extended_rms: float
    candidates: list[CandidateResult]
    calibration: dict
    data: dict
    equations: str = ""
    winner: CandidateResult | None = None
    extended_model: Model | None = None
    #: the winner's validation RMS from the compiled integrator (a second route to extended_rms)
    extended_rms_integrated: float | None = None
    predictions: dict = field(default_factory=dict)

    def as_json(self) -> dict:
        return {"cause": self.cause, "gain": self.gain, "baseline_rms": self.baseline_rms,
                "extended_rms": self.extended_rms,
                "candidates": [c.as_json() for c in self.candidates],
                "extended_rms_integrated": self.extended_rms_integrated,
                "calibration": self.calibration, "data": self.data,
                "criterion": {"min_gain": MIN_GAIN, "min_delta_bic": MIN_DELTA_BIC, "tie": TIE,
                              "rule": "largest validation gain, if gain >= min_gain and delta BIC on the "
                                      "validation part >= min_delta_bic; within 'tie' of the best gain the "
                                      "larger delta BIC wins"},
                "equations": self.equations}

    def text(self) -> str:
        lines = [f"Diagnosis of {self.data.get('model', '')} against {self.data.get('file', '')}",
                 f"  {self.data['samples']} samples at {self.data['rate_hz']:.6g} Hz, "
                 f"validation {self.data['validation_share']:.0%} in interleaved blocks",
                 f"  calibrated: " + ", ".join(f"{k} = {v:.5g}" for k, v in self.calibration["params"].items()),
                 f"  baseline validation RMS: {self.baseline_rms:.4g}", "",
                 f"  {'cause':<18} {'gain':>7} {'val. RMS':>11} {'k':>3} {'ΔBIC':>10}  extension / evidence"]
        for c in sorted(self.candidates, key=lambda c: -c.gain):
            ev = ", ".join(f"{k}={v:.3g}" for k, v in c.evidence.items())
            lines.append(f"  {c.cause:<18} {c.gain:>7.3f} {c.rms_validation:>11.4g} {c.n_params:>3} "
                         f"{c.delta_bic:>10.1f}  {c.label}" + (f" [{ev}]" if ev else "")
                         + (f" (failed: {c.error})" if c.error else ""))
        lines += ["", f"Cause: {self.cause}" + (f" (gain {self.gain:.3g}, validation RMS "
                                                f"{self.baseline_rms:.4g} → {self.extended_rms:.4g})"
                                                if self.cause != "none" else
                                                " (no extension beats the calibrated model by the criterion)")]
        if self.equations:
            lines += ["", "Equations of the extended model:", self.equations]
        return "\n".join(lines) + "\n"


# ---- calibration ------------------------------------------------------------------------------
def calibration_names(module, model: Model) -> list[str]:
    """Parameters to calibrate: the model file's CALIBRATE patterns, else every symbolic real
    parameter of the file."""
    known = [p.name for p in model.parameter_table()]
    patterns = getattr(module, "CALIBRATE", None)
    if patterns is None:
        return [d.name for d in model.declared if d.symbolic]
    out = []
    for pat in patterns:
        hits = [n for n in known if fnmatch.fnmatchcase(n, pat)]
        if not hits:
            raise UsageError(f"CALIBRATE entry '{pat}' matches no parameter of {model.name}")
        out += [h for h in hits if h not in out]
    return out


def empirical_frf(ctx: Context):
    """(ω, H, coherence) of output/input from Welch estimates (detrended segments)."""
    fs = 1.0 / ctx.dt
    n = len(ctx.u)
    nper = int(2 ** min(15, max(8, math.floor(math.log2(n / 8)))))
    f, Puu = signal.welch(ctx.u, fs, nperseg=nper, detrend="linear")
    _, Puy = signal.csd(ctx.u, ctx.y, fs, nperseg=nper, detrend="linear")
    _, coh = signal.coherence(ctx.u, ctx.y, fs, nperseg=nper, detrend="linear")
    keep = (f > 0) & (Puu > 1e-8 * Puu.max()) & (coh > 0.5)
    return 2 * np.pi * f[keep], (Puy / np.maximum(Puu, 1e-300))[keep], coh[keep]


def model_frf(lti: LTI, th: np.ndarray, omega: np.ndarray) -> np.ndarray:
    A, B, C, D = lti.matrices(th)
    n = A.shape[0]
    jw = 1j * omega[:, None, None] * np.eye(n)[None]
    X = np.linalg.solve(jw - A[None], np.broadcast_to(B, (omega.size, n, 1)))
    return (C[None] @ X)[:, 0, 0] + D[0, 0]


def calibrate(ctx: Context, starts: int = 12, progress: Callable | None = None) -> None:
    """Fit the calibration parameters (frequency response first, then time series)."""
    names = ctx.calibrate
    ctx.nominal = {n: ctx.ident.current(n) for n in names}
    if not names:
        ctx.baseline = ctx.ident.evaluate(ctx.calibrated)
        return
    specs = [_calib_spec(n, ctx.ident.current(n)) for n in names]
    if ctx.fast():
        w, H, coh = ctx.frf = empirical_frf(ctx)
        if w.size >= len(names):
            wt = np.sqrt(coh)

            def fres(z):
                th = ctx.ident.sim.theta({s.name: s.from_z(zi) for s, zi in zip(specs, z)})
                Hm = model_frf(ctx.lti, th, w)
                d = np.log(Hm + 1e-300) - np.log(H + 1e-300)
                d = d.real + 1j * np.angle(np.exp(1j * d.imag))
                return np.concatenate([wt * d.real, wt * d.imag])

            lb, ub = np.array([s.z_bounds() for s in specs]).T
            rng = np.random.default_rng(1)
            best = None
            z_nom = np.array([s.to_z(s.start) for s in specs])
            for k in range(starts):
                z0 = z_nom if k == 0 else np.clip(z_nom + rng.normal(0, 0.35, z_nom.size), lb, ub)
                try:
                    sol = least_squares(fres, z0, bounds=(lb, ub), max_nfev=60)
                except (ValueError, np.linalg.LinAlgError):
                    continue
                if best is None or sol.cost < best.cost:
                    best = sol
            if best is not None:
                specs = [Spec(s.name, s.from_z(zi), s.lower, s.upper, s.scale, s.log)
                         for s, zi in zip(specs, best.x)]
    res = ctx.ident.fit(specs, max_nfev=40, progress=progress)
    ctx.calibrated = dict(res.values)
    ctx.baseline = res


# ---- running candidates ------------------------------------------------------------------------
_CTX: Context | None = None
_CANDIDATES: list[Candidate] = []


def _run_one(index: int) -> CandidateResult:
    ctx, cand = _CTX, _CANDIDATES[index]
    started = time.time()
    res = CandidateResult(cand.cause, cand.label)
    try:
        res.evidence = {k: float(v) for k, v in cand.evidence(ctx).items()}
        values = cand.fit(ctx)
        model = cand.build(ctx, values)
        ev = evaluate_extension(ctx, model, values)
        res.rms_fit, res.rms_validation = ev.rms_fit, ev.rms_validation
        res.params = {k: float(v) for k, v in values.items()}
        res.n_params = len(res.params) + 1  # + the output offset
        _score(ctx, res)
    except (BondGraphError, SimulationError, np.linalg.LinAlgError, ValueError, FloatingPointError) as exc:
        res.error = f"{type(exc).__name__}: {exc}"
    res.seconds = time.time() - started
    return res


def evaluate_extension(ctx: Context, model: Model, values: Mapping[str, float], ode: bool = False) -> FitResult:
    """Simulate the extended bond graph over the whole record (the authoritative score): by the
    exact linear recursion when the extension keeps the model linear, else (or with ``ode``)
    by the compiled integrator."""
    ident = ctx.ident.like(model, rtol=1e-6)
    if ode:
        ident.lti = None
    known = {p.name for p in ident.sim.eqs.params}
    pred = ident.predict({k: v for k, v in values.items() if k in known})
    b, rf, rv = ctx.ident.scores(pred)
    return FitResult(dict(values), {}, b, rf, rv, 1, True, "exact linear" if ident.lti else "integrated", pred + b)


def _score(ctx: Context, res: CandidateResult) -> None:
    base = ctx.baseline.rms_validation
    res.gain = base / max(res.rms_validation, 1e-300)
    n = int(np.sum(ctx.ident.val_mask))
    extra = res.n_params - len(ctx.calibrate)
    res.delta_bic = n * math.log(max(base, 1e-300) ** 2 / max(res.rms_validation, 1e-300) ** 2) \
        - max(extra, 1) * math.log(n)


def run_candidates(ctx: Context, candidates: Sequence[Candidate], workers: int = 2,
                   progress: Callable[[str], None] | None = None) -> list[CandidateResult]:
    global _CTX, _CANDIDATES
    _CTX, _CANDIDATES = ctx, [c for c in candidates if c.applies(ctx)]
    results: list[CandidateResult] = []
    if workers > 1 and len(_CANDIDATES) > 1 and "fork" in mp.get_all_start_methods():
        with ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context("fork")) as pool:
            order = sorted(range(len(_CANDIDATES)), key=lambda i: -_CANDIDATES[i].cost)
            futures = {pool.submit(_run_one, i): i for i in order}
            for fut in as_completed(futures):
                results.append(fut.result())
                if progress:
                    progress(_progress_line(results[-1], len(results), len(_CANDIDATES)))
    else:
        for i in range(len(_CANDIDATES)):
            results.append(_run_one(i))
            if progress:
                progress(_progress_line(results[-1], len(results), len(_CANDIDATES)))
    labels = [(c.cause, c.label) for c in _CANDIDATES]
    return sorted(results, key=lambda r: labels.index((r.cause, r.label)))


def _progress_line(r: CandidateResult, k: int, n: int) -> str:
    state = f"gain {r.gain:.3g}" if not r.error else f"failed ({r.error[:60]})"
    return f"[{k}/{n}] {r.cause} ({r.label}): {state}, {r.seconds:.1f} s"


def decide(results: Sequence[CandidateResult]) -> CandidateResult | None:
    ok = [r for r in results if not r.error and np.isfinite(r.gain)]
    if not ok:
        return None
    best_gain = max(r.gain for r in ok)
    close = [r for r in ok if r.gain >= best_gain * (1 - TIE)]
    best = max(close, key=lambda r: r.delta_bic)
    if best.gain >= MIN_GAIN and best.delta_bic >= MIN_DELTA_BIC:
        return best
    return None


def load_candidates() -> list[Candidate]:
    """Candidates from the ``bondgraph.diagnosis`` entry points (each a callable returning a list)."""
    from importlib.metadata import entry_points
    out: list[Candidate] = []
    for ep in entry_points(group="bondgraph.diagnosis"):
        out += list(ep.load()())
    if not out:
        raise UsageError("no diagnosis candidates are installed (entry point group 'bondgraph.diagnosis'); "
                         "reinstall with pip install -e .")
    return out


def diagnose(model: Model, data: Dataset, calibrate_names: Sequence[str], candidates: Sequence[Candidate],
             input: str = "V", output: str = "x", data_input: str | None = None, data_output: str | None = None,
             validation: float = 0.3, workers: int = 2, progress: Callable[[str], None] | None = None,
             source: str = "") -> Report:
    """Run the whole diagnosis (see the module docstring)."""
    say = progress or (lambda s: None)
    if uniform_step(data.t) is None:  # the exact linear route needs a uniform grid: resample at the median step
        dt = float(np.median(np.diff(data.t)))
        say(f"data not uniformly sampled: resampled at its median step {dt:.4g} s")
        data = data.resample(dt)
    eqs = derive(model)
    ident = Identification(Simulator(eqs), data, input, output, data_input, data_output, validation)
    lti = LTI(eqs, input, output)
    ctx = Context(model, eqs, ident, lti, list(calibrate_names))
    started = time.time()
    say(f"calibrating {', '.join(ctx.calibrate) or 'nothing'} ({'exact linear' if ctx.fast() else 'ODE'} path)")
    calibrate(ctx)
    say(f"calibrated in {time.time() - started:.1f} s: validation RMS {ctx.baseline.rms_validation:.4g}")
    results = run_candidates(ctx, candidates, workers, say)
    winner = decide(results)
    report = Report(
        cause=winner.cause if winner else "none",
        gain=winner.gain if winner else 1.0,
        baseline_rms=ctx.baseline.rms_validation,
        extended_rms=winner.rms_validation if winner else ctx.baseline.rms_validation,
        candidates=list(results),
        calibration={"params": ctx.calibrated, "rms_fit": ctx.baseline.rms_fit,
                     "rms_validation": ctx.baseline.rms_validation},
        data={"file": data.path or "", "model": source, "samples": len(data), "rate_hz": 1.0 / float(np.median(np.diff(data.t))),
              "validation_share": validation},
        winner=winner)
    report.predictions = {"baseline": ctx.baseline.prediction}
    if winner:
        from .printing import render
        cand = next(c for c in _CANDIDATES if c.cause == winner.cause and c.label == winner.label)
        model_ext = cand.build(ctx, winner.params)
        report.extended_model = model_ext
        report.equations = render(derive(model_ext), "text")
        ev = evaluate_extension(ctx, model_ext, winner.params, ode=True)
        report.predictions["extended"] = ev.prediction
        report.extended_rms_integrated = ev.rms_validation
    return report
