"""The diagnosis as a chain: calibrate, try every candidate, name the best that passes,
extend the model with it and try the others again on the extended model, until none passes."""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Generator, Iterator, Mapping, Sequence

import numpy as np

from ..data import Dataset
from ..model.graph import Model
from ..model.memory import not_monotone
from ..numerics.simulate import SimulationError
from ..support.errors import BondGraphError
from .account import account
from .calibration import calibrate, rms, score
from .candidate import LINEAR, Candidate, Extension
from .context import SENSOR_GAIN, Context, State, residual_floor
from .decision import Comparison, compare, judge, reference_prediction, regress
from .drift import SLOW_DRIVE, drift_explains, drift_like, drift_step, smooth_share
from .laws import law_kinds
from .modes import mode_kinds
from .pool import Pool, single_threaded_blas
from .projection import time_budget
from .report import CandidateResult, Report, Step
from .restoring import restoring_kinds
from .screen import screen_out
from .settings import Settings
from .view import View


@dataclass
class Outcome:
    """A candidate's result with what the parent needs to decide and to extend.

    Parameters
    ----------
    result : CandidateResult
        The candidate's result (scores filled in later by :func:`assess`).
    extension : Extension, optional
        What its fit returned (None when it was skipped or failed).
    raw : numpy.ndarray, optional
        The extended model's raw prediction.
    linear_refit : numpy.ndarray, optional
        The current model with its linear parameters refitted from where the candidate left
        them, raw.
    static : numpy.ndarray, optional
        The same freedom without memory (for a memory effect), raw.
    """

    result: CandidateResult
    extension: Extension | None = None
    raw: np.ndarray | None = None
    #: the current model with its linear parameters refitted from where the candidate left them
    linear_refit: np.ndarray | None = None
    #: the same freedom without memory (for a memory effect), raw
    static: np.ndarray | None = None


def run_candidate(
    ctx: Context,
    state: State,
    calibrated: Sequence[str],
    cand: Candidate,
    plausible: tuple[State, dict] | None = None,
    effort: float = 1.0,
) -> Outcome:
    """Fit one candidate on the chain state (in a worker or in the calling process).  A linear
    structural candidate starts from the plausible device instead, when one is given
    (``(state, bounds)``: the calibration within tolerance), and refits within its bounds.
    ``effort``: a factor on its optimisers' evaluation budgets (see :func:`polish_race`).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    calibrated : sequence of str
        The calibrated linear parameters.
    cand : Candidate
        The candidate.
    plausible : tuple of (State, dict) or None, optional
        The plausible device's state and bounds.
    effort : float, optional
        Factor on its optimisers' evaluation budgets.

    Returns
    -------
    Outcome
        The outcome; a candidate that raises gets its error in ``result.error``.
    """
    started = time.time()
    res = CandidateResult(cand.cause, cand.label, cand.kind, effort=float(effort), site=cand.site_name)
    if cand.kind == LINEAR and plausible is not None:
        view = View(ctx, plausible[0], calibrated, bounds=plausible[1], effort=effort)
        res.against = "plausible"
    else:
        view = View(ctx, state, calibrated, effort=effort)
    try:
        with time_budget(ctx.settings.candidate_seconds, ctx.settings.candidate_limit):
            return _fit_candidate(cand, view, res)
    except Exception as exc:  # noqa: BLE001 - one candidate's defect (a third party's too) is its FAILED line
        res.error = f"{type(exc).__name__}: {exc}"
        return Outcome(res)
    finally:
        res.seconds = time.time() - started


def _fit_candidate(cand: Candidate, view: View, res: CandidateResult) -> Outcome:
    ok = cand.applies(view)
    if ok is not True:
        res.skipped = ok if isinstance(ok, str) and ok else "does not apply to this model"
        return Outcome(res)
    res.evidence = {k: float(v) for k, v in cand.evidence(view).items()}
    ext = cand.fit(view)
    raw = ext.prediction if ext.prediction is not None else view.simulate(ext.model, ext.values)
    if not np.all(np.isfinite(raw)):
        raise FloatingPointError("the extended model's prediction is not finite")
    res.params = {k: float(ext.values[k]) for k in ext.new}
    res.site = ext.where or res.site
    if ext.cause:
        res.cause, res.label = ext.cause, f"{res.label}; {ext.why}" if ext.why else res.label
    res.n_params = len(ext.new)
    res.at_bounds = list(ext.at_bounds)
    res.success, res.message = ext.success, ext.message
    if cand.kind == LINEAR:
        res.implausible = cand.implausible(view, ext)
        res.recalibration = cand.mimics_recalibration(view, ext)
        res.need_share = cand.linear_share
    ext.prediction = None
    refit = refit_linear(view, ext.values, additive=ext.additive is not None)
    static = cand.without_memory(view)
    return Outcome(res, ext, np.asarray(raw, float), refit, None if static is None else np.asarray(static, float))


def refit_linear(view: View, start: Mapping[str, float], additive: bool = False) -> np.ndarray | None:
    """Raw prediction of the current model with only its calibrated linear parameters (and,
    with ``additive``, the weights of the additive drive's terms) refitted, from ``start``
    (where a candidate's joint fit left them): what that refit alone explains, so that a
    candidate is credited only with what its effect adds.  None when the current model is not
    a drive transform of its linear core or has nothing to refit.

    Parameters
    ----------
    view : View
        The chain state the candidate was fitted on.
    start : mapping of str to float
        Start values of the parameters refitted.
    additive : bool, optional
        Refit the additive drive's weights too.

    Returns
    -------
    numpy.ndarray or None
        The raw prediction on every sample, or None.
    """
    cur = view.current
    additive = additive and bool(cur.additive and cur.additive.terms)
    if cur.drive is None or not view.record.exact or not (cur.calibrated or additive):
        return None
    return view.fit_drive(start=start, max_nfev=20, names=[] if additive else None).prediction


def effect_errors(
    ctx: Context, oc: Outcome, e_state: np.ndarray, e_plaus: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """(errors before, errors after) of an outcome on every sample: after, its prediction with
    sensor gain and offset solved on ``ctx``'s fit part; before, the state's (or the plausible
    device's, for a candidate fitted on it), or the current model refitted from where the
    candidate left its linear parameters when that is better (only the effect is credited).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    oc : Outcome
        The candidate's outcome.
    e_state : numpy.ndarray
        Errors of the current state on every sample.
    e_plaus : numpy.ndarray or None
        Errors of the plausible device on every sample (for candidates fitted on it).

    Returns
    -------
    before : numpy.ndarray
        The errors before, output units.
    after : numpy.ndarray
        The errors after, output units.
    """
    y, val = ctx.y, ctx.ident.val_mask
    g, b, _, _ = score(ctx, oc.raw)
    before = e_plaus if oc.result.against == "plausible" and e_plaus is not None else e_state
    if oc.linear_refit is not None:
        gr, br, _, rv = score(ctx, oc.linear_refit)
        if rv < rms(before[val]):
            before = y - (gr * oc.linear_refit + br)
    return before, y - (g * oc.raw + b)


def second_fold(
    ctx: Context,
    state: State,
    calibrated: Sequence[str],
    cand: Candidate,
    plausible: tuple[State, dict] | None,
    e_plaus: np.ndarray | None,
    effort: float = 1.0,
) -> Comparison | None:
    """The candidate fitted again with other validation blocks (``ctx`` refolded) and compared
    there as on the first fold; None when it fails.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    calibrated : sequence of str
        The calibrated linear parameters.
    cand : Candidate
        The candidate.
    plausible : tuple of (State, dict) or None
        The plausible device's state and bounds.
    e_plaus : numpy.ndarray or None
        Errors of the plausible device on every sample (for candidates fitted on it).
    effort : float, optional
        Factor on its optimisers' evaluation budgets.

    Returns
    -------
    Comparison or None
        The comparison on the second fold.
    """
    oc = run_candidate(ctx, state, calibrated, cand, plausible, effort)
    return None if oc.raw is None else effect_comparison(ctx, state, oc, e_plaus)


def effect_comparison(ctx: Context, state: State, oc: Outcome, e_plaus: np.ndarray | None = None) -> Comparison:
    """The outcome's errors after against before (:func:`effect_errors`), compared on ``ctx``'s
    validation blocks.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    oc : Outcome
        The candidate's outcome.
    e_plaus : numpy.ndarray or None, optional
        Errors of the plausible device on every sample (for candidates fitted on it).

    Returns
    -------
    Comparison
        After against before.
    """
    return compare(*effect_errors(ctx, oc, ctx.y - state.prediction, e_plaus), ctx.blocks)


def assess(
    ctx: Context, state: State, view: View, outcomes: list[Outcome], plausible: State | None = None, confirm=None
) -> tuple[Step, Outcome | None]:
    """Score every outcome against the state and the flexible linear reference; pick the winner.
    Linear structural candidates fitted on the ``plausible`` device are compared with it, and
    must explain ``linear_share`` of what the best linear explanation (the null or the flexible
    reference, whichever is better) explains over it.  ``confirm(outcome, e_plaus)``: the
    comparison on a second fold (:func:`second_fold`), asked for candidates whose gain passes
    but whose significance falls short by less than ``diagnosis.confirm_margin`` standard
    errors (a record whose evidence sits in a few blocks); the two folds' z are combined.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    view : View
        The current state's view.
    outcomes : list of Outcome
        The candidates' outcomes (their results are filled in).
    plausible : State, optional
        The plausible device's state.
    confirm : callable, optional
        ``confirm(outcome, e_plaus)`` → the second fold's comparison.

    Returns
    -------
    step : Step
        The chain step.
    winner : Outcome or None
        The outcome named, or None.
    """
    idx, y = ctx.ident.fit_idx, ctx.y
    drive = state.drive if state.drive is not None else ctx.u
    ref_cols, ref_pred = reference_prediction(
        view.respond, drive, state.raw, y, idx, ctx.dt, ctx.span, ctx.settings.reference_poles
    )
    e_state = y - state.prediction
    e_ref = y - ref_pred
    val = ctx.ident.val_mask
    rms_state, rms_ref = rms(e_state[val]), rms(e_ref[val])
    e_plaus = y - plausible.prediction if plausible is not None else None
    rms_plaus = rms(e_plaus[val]) if plausible is not None else None
    scored = {}
    for oc in outcomes:
        if oc.raw is not None:
            _, _, oc.result.rms_fit, oc.result.rms_validation = score(ctx, oc.raw)
            before, e = effect_errors(ctx, oc, e_state, e_plaus)
            scored[id(oc)] = (before, e, compare(before, e, ctx.blocks))
    if confirm is not None:
        _confirm_borderline(outcomes, scored, confirm, e_plaus, bool(state.causes), ctx.settings)
    for oc in outcomes:
        r = oc.result
        if oc.raw is None:
            continue
        before, e, base = scored[id(oc)]
        r.gain, r.z, r.n_eff = base.gain, base.z, base.n_eff
        e_both = y - regress(np.column_stack([oc.raw, ref_cols]), y, idx)
        vr = compare(e_ref, e_both, ctx.blocks)
        r.gain_reference, r.z_reference = vr.gain, vr.z
        before = rms(before[val])
        explained_ref = before**2 - min(rms_ref, rms_state) ** 2
        r.share = (before**2 - r.rms_validation**2) / explained_ref if explained_ref > 0 else None
        vs = None
        if oc.static is not None and np.all(np.isfinite(oc.static)):
            # both with the reference's freedom: loops that only mimic a linear lag are no memory
            e_static = y - regress(np.column_stack([oc.static, ref_cols]), y, idx)
            vs = compare(e_static, e_both, ctx.blocks)
            r.gain_static = vs.gain
        v = judge(
            r.kind,
            base,
            vr,
            r.share,
            [n for n in r.at_bounds if n in r.params],
            r.implausible,
            later=bool(state.causes),
            recalibration=r.recalibration,
            need_share=r.need_share,
            versus_static=vs,
            settings=ctx.settings,
        )
        r.passed, r.verdict, r.rule = v.passed, v.reason, v.rule
        if not r.success and r.passed:
            r.verdict += " (optimiser not converged)"
    winner, rule = _simplest_of_best([oc for oc in outcomes if oc.result.passed], ctx.settings.equivalent)
    if winner is None:
        tried = [oc.result for oc in outcomes if oc.raw is not None]
        rule = max(tried, key=lambda r: r.gain).rule if tried else "no-candidate"
    why = _why(winner, outcomes, rms_state, rms_ref, ctx.noise)
    before = rms_plaus if winner is not None and winner.result.against == "plausible" else rms_state
    step = Step(
        winner.result.cause if winner else "none",
        winner.result.gain if winner else 1.0,
        before,
        winner.result.rms_validation if winner else rms_state,
        rms_ref,
        [oc.result for oc in outcomes],
        why,
        winner.result.site if winner else "",
        winner.result.label if winner else "",
        rule,
        winner.result if winner else None,
    )
    return step, winner


def _confirm_borderline(
    outcomes: list[Outcome], scored: dict, confirm, e_plaus, later: bool, settings: Settings
) -> None:
    """Combine the first fold's z with a second fold's (Stouffer: (z1 + z2)/√2) for at most
    ``settings.confirm_max`` candidates, the best gains first, whose gain passes and whose
    z falls short of ``settings.min_z`` by less than ``settings.confirm_margin``."""
    min_z = settings.min_z
    min_gain = settings.min_gain_chain if later else settings.min_gain
    margin = settings.confirm_margin
    near = [
        oc
        for oc in outcomes
        if id(oc) in scored
        and scored[id(oc)][2].gain >= min_gain
        and min_z - margin <= scored[id(oc)][2].z < min_z
        and not [n for n in oc.result.at_bounds if n in oc.result.params]
    ]
    for oc in sorted(near, key=lambda oc: -scored[id(oc)][2].gain)[: int(settings.confirm_max)]:
        second = confirm(oc, e_plaus)
        if second is None:
            continue
        before, e, first = scored[id(oc)]
        oc.result.z_second = second.z
        scored[id(oc)] = (
            before,
            e,
            Comparison(first.gain, (first.z + second.z) / math.sqrt(2), first.n_eff + second.n_eff),
        )


def near_the_bar(ctx: Context, state: State, oc: Outcome) -> bool:
    """Whether an outcome fitted with ``diagnosis.screen_effort`` of the budget is fitted again
    with the full budget before its chain step is judged: its validation gain reaches
    ``diagnosis.screen_gain``, a margin below the bar (a fit stopped early explains less than it
    can: the ones far below the bar stay below it).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    oc : Outcome
        The candidate's outcome.

    Returns
    -------
    bool
        Whether to fit it again.
    """
    return oc.raw is not None and effect_comparison(ctx, state, oc).gain >= ctx.settings.screen_gain


def polish_race(outcomes: list[Outcome], margin: float) -> list[Outcome]:
    """The outcomes to fit again with more effort before one is named: when two or more passing
    candidates are within ``diagnosis.polish_margin`` of the best gain over the flexible linear
    reference and one of them stopped before its optimiser converged, those of them that did
    not converge (the ranking must not reward the optimiser that got further in its budget).

    Parameters
    ----------
    outcomes : list of Outcome
        The assessed outcomes.
    margin : float
        The race's width, a factor on the gain over the reference (``diagnosis.polish_margin``).

    Returns
    -------
    list of Outcome
        Those to fit again (empty when there is no close race).
    """
    passing = [oc for oc in outcomes if oc.result.passed]
    if len(passing) < 2:
        return []
    top = max(oc.result.gain_reference for oc in passing)
    race = [oc for oc in passing if oc.result.gain_reference * margin >= top]
    if len(race) < 2:
        return []
    return [oc for oc in race if not oc.result.success]


def _simplest_of_best(passing: list[Outcome], margin: float) -> tuple[Outcome | None, str]:
    """The passing candidate to name: the best ranks by what it explains when every linear
    correction is allowed too (a linear cause gains little over the reference, an effect beyond
    any linear one more), then by its own gain; of the candidates the data cannot tell from the
    best (validation RMS within ``margin``, setting ``diagnosis.equivalent``, of it), the one with the fewest new parameters is named (a saturation curve that a 10-play operator
    reproduces is a saturation, not hysteresis), provided it also explains about as much as the
    best beyond the flexible linear reference (a lag that mimics a loop at one rate does not)."""
    if not passing:
        return None, ""
    best = max(passing, key=lambda oc: (round(oc.result.gain_reference, 2), oc.result.gain))
    tied = [
        oc
        for oc in passing
        if oc is best
        or (
            oc.result.gain_reference * margin >= best.result.gain_reference
            and oc.result.rms_validation <= margin * best.result.rms_validation
        )
    ]
    chosen = min(tied, key=lambda oc: (oc.result.n_params, -oc.result.gain))
    return chosen, "most-beyond-linear" if chosen is best else "simplest-of-equivalent"


def _why(winner, outcomes, rms_state, rms_ref, noise) -> str:
    if winner is not None:
        r = winner.result
        extra = (
            f", {r.gain_reference:.3g}× over the flexible linear reference"
            if r.kind != LINEAR
            else f", {r.share:.0%} of what a linear correction explains"
            if r.share is not None
            else ""
        )
        others = [oc.result for oc in outcomes if oc.result.passed and oc.result.cause != r.cause]
        if others:  # what the data could not rule out: the strongest other cause that passes too
            o = max(others, key=lambda o: o.gain)
            extra += (
                f"; {o.cause} passes too (×{o.gain:.3g}, validation RMS "
                f"{o.rms_validation / max(r.rms_validation, 1e-300):.3g}× the named one's)"
            )
        return f"named: validation RMS {r.gain:.3g}× lower (z = {r.z:.1f}, {r.n_eff:.0f} effective samples){extra}"
    parts = []
    if noise:
        parts.append(f"the residual is {rms_state / noise:.2g}× the noise floor")
    parts.append(f"a flexible linear correction gains {rms_state / max(rms_ref, 1e-300):.3g}×")
    tried = [oc.result for oc in outcomes if oc.raw is not None]
    if tried:
        best = max(tried, key=lambda r: r.gain)
        parts.append(f"the best candidate ({best.cause}, gain {best.gain:.3g}) {best.verdict}")
    else:
        parts.append("no candidate could be fitted")
    return "none: " + "; ".join(parts)


def advance(ctx: Context, state: State, oc: Outcome, view: View) -> State:
    """The chain state after naming ``oc``'s cause (``view``: the current state's).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    oc : Outcome
        The candidate's outcome.
    view : View
        The current state's view.

    Returns
    -------
    State
        The extended model's state.
    """
    ext = oc.extension
    g, b, _, _ = score(ctx, oc.raw)
    before = state.drive if state.drive is not None else state.core_drive
    core_model = state.core_model
    if before is None and ext.terms and view.record.exact and not view.record.reduced:
        # terms fitted on the current model itself (linear: e.g. with a compliant output stage
        # named before them): that model, under the drive, is the core they are held on
        before, core_model = np.asarray(view.record.u), state.model
    # what the linear core sees and the terms held on it, while the model stays a Lur'e system
    core = ext.drive if ext.drive is not None else before if ext.terms and before is not None else None
    terms = tuple(state.terms) + tuple(ext.terms) if core is not None else ()
    extra = (state.core_extra if state.terms else view.current.extra) if terms else None
    return State(
        ext.model,
        dict(ext.values),
        oc.raw,
        g,
        b,
        ext.drive,
        ext.drive_expr,
        state.causes + [oc.result.cause],
        state.linear and ext.drive is not None,
        terms,
        core,
        extra,
        additive=ext.additive if ext.drive is not None else None,
        core_model=core_model if terms else None,
    )


def load_candidates(model: Model | None = None) -> list[Candidate]:
    """The candidates a diagnosis of ``model`` tries by default: the framework's own effect
    kinds at every site of the model (law terms of its springs and dampers, :mod:`.laws`;
    missing modes, :mod:`.modes`) and the candidates of the ``bondgraph.diagnosis`` entry
    points (each a callable returning a list; a domain library's).  Without a model, the
    entry points' only.

    Parameters
    ----------
    model : Model, optional
        The model whose sites give the framework's candidates.

    Returns
    -------
    list of Candidate
        The framework's candidates for ``model``, then the entry points' (each entry point is
        loaded and called here).
    """
    from importlib.metadata import entry_points

    out: list[Candidate] = [] if model is None else law_kinds(model) + restoring_kinds(model) + mode_kinds(model)
    for ep in entry_points(group="bondgraph.diagnosis"):
        out += list(ep.load()())
    return out


def model_file_options(module) -> dict:
    """The diagnosis options a model file declares: ``CALIBRATE`` (calibrate_first) and
    ``TOLERANCE`` (tolerance).

    Parameters
    ----------
    module : module
        The loaded model file.

    Returns
    -------
    dict
        ``calibrate_first`` and ``tolerance``, keyword arguments of :func:`diagnose` (None
        where the file declares nothing).
    """
    return {"calibrate_first": getattr(module, "CALIBRATE", None), "tolerance": getattr(module, "TOLERANCE", None)}


def diagnose(
    model: Model,
    data: Dataset,
    *,
    candidates: Sequence[Candidate] | None = None,
    calibrate_first: Sequence[str] | None = None,
    input: str | None = None,
    output: str | None = None,
    data_input: str | None = None,
    data_output: str | None = None,
    validation: float = 0.3,
    workers: int = 2,
    chain: bool = True,
    progress=None,
    source: str = "",
    equations: bool = True,
    tolerance: Mapping[str, float] | None = None,
    drift: bool | None = None,
    settings: Settings | None = None,
) -> Report:
    """Diagnose what ``model`` misses in ``data`` (see the package docstring).

    ``candidates``: the causes to try (default: :func:`load_candidates` of the model);
    ``calibrate_first``: parameter names or glob patterns preferred when linear parameters
    cannot be told apart (e.g. the model file's ``CALIBRATE``); ``tolerance``: {pattern: factor}
    of plausible device-to-device spread (the model file's ``TOLERANCE``; others
    ``diagnosis.tolerance``); ``input``/``output``: the
    model's (default: its first declared); ``data_input``/``data_output``: the data columns
    (default: the same names); ``workers``: parallel processes; ``chain``: keep naming
    causes on the extended model until none passes; ``progress``: a
    :class:`bondgraph.support.progress.Progress` (one count per candidate fitted, notes for the
    stages) or any callable taking a line of text; ``drift``: solve a linear sensor drift with
    the calibration and remove it first (default: the setting ``diagnosis.drift``);
    ``settings``: the thresholds and limits (a keyword of :meth:`Settings.from_config` beats
    the configured default; the object is frozen and read, never rewritten).

    Parameters
    ----------
    model : Model
        The linear model of the device (its parameters at their nominal values).
    data : Dataset
        The measured record: the drive and the output against time (s).
    candidates : sequence of Candidate, optional
        The causes to try (default: :func:`load_candidates` of the model).
    calibrate_first : sequence of str, optional
        Parameter names or glob patterns preferred when linear parameters cannot be told
        apart (the model file's ``CALIBRATE``).
    input : str, optional
        The model input the data drive (default: the model's first declared input).
    output : str, optional
        The model output compared with the data (default: its first declared output).
    data_input : str, optional
        The data column of the drive (default: the same name as ``input``).
    data_output : str, optional
        The data column of the output (default: the same name as ``output``).
    validation : float, optional
        Share of the record held out as validation blocks, between 0 and 1.
    workers : int, optional
        Parallel processes fitting candidates.
    chain : bool, optional
        Keep naming causes on the extended model until none passes (False: one step).
    progress : Progress or callable, optional
        A :class:`bondgraph.support.progress.Progress` (one count per candidate fitted, notes
        for the stages) or any callable taking a line of text.
    source : str, optional
        What the model is called in the report (e.g. the model file's path).
    equations : bool, optional
        Render the extended model's equations into the report (:attr:`Report.equations`).
    tolerance : mapping of str to float, optional
        {pattern: factor} of plausible device-to-device spread of the parameters (the model
        file's ``TOLERANCE``; others ``diagnosis.tolerance``).
    drift : bool, optional
        Solve a linear sensor drift with the calibration and remove it first (default:
        ``settings.drift``).
    settings : Settings, optional
        The diagnosis's settings (default: :meth:`Settings.from_config`, the configured ones).

    Returns
    -------
    Report
        Every step of the chain, every candidate's verdict, the causes named and the gain.

    Raises
    ------
    DataError
        The output does not follow the drive (constant, or no coherence with it), or the
        record cannot be used (the message names the column and what to check).
    BondGraphError
        A bad input or output name, or a model that cannot be derived or simulated.
    """
    settings = settings if settings is not None else Settings.from_config()
    drift = bool(settings.drift) if drift is None else bool(drift)
    say = getattr(progress, "note", None) or progress or (lambda s: None)
    started = time.time()
    args = (model, data, candidates, calibrate_first, input, output, data_input, data_output, validation, workers)
    rest = (chain, progress, source, equations, tolerance, settings)

    def start(reading: str) -> tuple[Iterator, FirstStep]:
        """A hypothesis' chain run to its first step; when a straight drift explains that step
        as well as its cause, the same reading with the drift solved instead."""
        run = _chain(*args, *rest, reading, drift, started)
        first = next(run)
        if first.drift:
            run.close()
            run = _chain(*args, *rest, reading, True, started)
            first = dataclasses.replace(next(run), notes=[first.drift])
        return run, first

    with single_threaded_blas():
        # the hypotheses in turn: the drive read as band-limited between its samples; when the
        # two readings change the calibrated output beyond the noise, read as linear too, and
        # the chain goes on under the reading whose first step is the better one
        run, first = start("band-limited")
        notes = list(first.notes)
        if first.gap > settings.reading_gap * first.floor:
            say(
                f"the two readings of the drive between its samples change the calibrated model's output by "
                f"{first.gap / first.floor:.2g}× the noise floor: its first step with the drive read as linear "
                f"between samples"
            )
            other, second = start("linear")
            keep, why = _better_reading(first.key, second.key, settings.equivalent)
            if keep == 1:
                run, other, first = other, run, second
            other.close()
            notes = list(first.notes) + [f"drive read as {first.reading} between its samples: {why}"]
        report = _finish(run)
        report.notes += notes
        report.seconds = time.time() - started
        return report


@dataclass
class FirstStep:
    """What a hypothesis' chain says after its first step, for :func:`diagnose` to choose on.

    Attributes
    ----------
    reading : str
        How the drive is read between its samples ("band-limited" or "linear").
    cause : str
        The cause the first step names, or "none".
    rms : float
        The validation RMS after the first step (output units).
    gap : float
        RMS change of the calibrated model's output between the two readings (output units).
    floor : float
        The noise floor (RMS, output units).
    drift : str
        When a straight drift explains the record as well as the first step's winner: the note
        to add (the hypothesis is then run with the drift solved), else "".
    notes : list of str
        Notes the hypothesis adds to its report when it is the one chosen.
    """

    reading: str
    cause: str
    rms: float
    gap: float
    floor: float
    drift: str = ""
    notes: list = dataclasses.field(default_factory=list)

    @property
    def key(self) -> tuple[str, str, float]:
        """(reading, cause, validation RMS), as :func:`_better_reading` compares them."""
        return self.reading, self.cause, self.rms


def _finish(run: Iterator) -> Report:
    """Run a hypothesis' chain past its first step to the end: its report."""
    try:
        run.send(True)
    except StopIteration as stop:
        return stop.value
    raise RuntimeError("a diagnosis chain yields once, after its first step")


def _better_reading(a: tuple[str, str, float], b: tuple[str, str, float], equivalent: float) -> tuple[int, str]:
    """Which of two first steps, (reading, cause, validation RMS), under different readings of
    the drive to go on from (0: ``a``, 1: ``b``) and why: the better fit; when the two are within
    a factor ``equivalent`` (setting ``diagnosis.equivalent``) of each other and only one names a cause, the one naming none (the
    data cannot tell the readings apart, and a cause must not be credited with what a reading
    explains).  Two fits within that factor (or equal to the digits shown) are said to fit as
    well, never one better, and an RMS equal to the digits shown is given once."""
    shown = f"{a[2]:.4g}", f"{b[2]:.4g}"
    alike = max(a[2], b[2]) <= equivalent * min(a[2], b[2]) or shown[0] == shown[1]
    if alike and (a[1] == "none") != (b[1] == "none"):
        k = 0 if a[1] == "none" else 1
    else:
        k = 0 if a[2] <= b[2] else 1
    best, other = (a, b) if k == 0 else (b, a)
    rms = shown[k] if shown[0] == shown[1] else f"{shown[k]} against {shown[1 - k]}"
    named = f"both naming {best[1]}" if best[1] == other[1] else f"naming {best[1]} against {other[1]}"
    if not alike:
        return (
            k,
            f"its first step fits the validation part better than under the {other[0]} reading (validation RMS {rms}; {named})",
        )
    if best[1] == "none":
        return k, (
            f"its first step, naming no cause, fits as well as the {other[0]} reading's, which names {other[1]} "
            f"(validation RMS {rms}): the readings cannot be told apart, and no cause is credited with what a "
            "reading explains"
        )
    return (
        k,
        f"its first step fits the validation part as well as under the {other[0]} reading (validation RMS {rms}; {named})",
    )


def _chain(
    model,
    data,
    candidates,
    calibrate_first,
    input,
    output,
    data_input,
    data_output,
    validation,
    workers,
    chain,
    progress,
    source,
    equations,
    tolerance,
    settings,
    reading,
    drift: bool = False,
    since: float | None = None,
) -> Generator[FirstStep, bool, Report | None]:
    """One hypothesis of the diagnosis (see :func:`diagnose`): the drive read as ``reading``
    between its samples, with a linear sensor drift solved by the calibration or not.  A
    generator: it yields a :class:`FirstStep` after the first step and, sent True, goes on to
    the end and returns the report.  A first step with ``drift`` set ends it: the same
    hypothesis with the drift solved replaces it.  ``since``: when the whole diagnosis started
    (``time.time()``), for ``diagnosis.chain_seconds``."""
    started = time.time()
    say = getattr(progress, "note", None) or progress or (lambda s: None)
    tick = getattr(progress, "advance", None)
    cands = list(candidates) if candidates is not None else load_candidates(model)
    ctx = Context(model, data, input, output, data_input, data_output, validation, say, reading, settings)
    state, cal, pstate = calibrate(ctx, calibrate_first, say, tolerance, workers, drift=drift)
    plausible = (pstate, cal.plausible) if pstate is not state else None
    gap = ctx.reading_gap(state.values, state.gain)
    floor = ctx.noise or residual_floor(ctx.y - state.prediction, ctx.fs)
    say(f"calibrated in {time.time() - started:.1f} s: validation RMS {cal.rms_validation:.4g}")
    steps: list[Step] = []
    step_predictions: list[np.ndarray] = []  # the model's prediction after each named step
    folds: list[Context] = []  # the second fold's context, made when first needed
    baseline, from_plausible = state, False
    asked = False  # whether the first step was put to the caller
    slow_drive = smooth_share(ctx, np.asarray(ctx.u, float)) >= SLOW_DRIVE  # see rule 'effect-or-drift'
    with Pool(run_candidate, ctx, cal.free, cands, workers) as pool:
        for k in range(int(settings.max_chain) if chain else 1):
            spent = time.time() - (started if since is None else since)
            if k and spent > settings.chain_seconds:
                note = (
                    f"the chain stopped after step {k}: {spent:.0f} s spent, past the diagnosis' time budget "
                    f"(setting diagnosis.chain_seconds, {settings.chain_seconds:g} s); "
                    f"further causes were not examined"
                )
                say(note)
                ctx.notes.append(note)
                break
            pending = [i for i, c in enumerate(cands) if c.repeatable or c.cause not in state.causes]
            if not pending:
                break
            outcomes = {}
            first = plausible if k == 0 else None
            left_out, shares = screen_out(View(ctx, state, cal.free), cands, pending)
            for i, why in left_out.items():
                res = CandidateResult(cands[i].cause, cands[i].label, cands[i].kind, site=cands[i].site_name)
                res.skipped = why
                outcomes[i] = Outcome(res)
            fitted = [i for i in pending if i not in left_out]
            if left_out:
                say(f"step {k + 1}: {len(fitted)} of {len(pending)} candidates fitted in full after the screen")
            screen = settings.screen_effort if k else 1.0
            for n, (i, oc) in enumerate(pool.run(state, fitted, first, screen), 1):
                if i in shares:
                    oc.result.evidence["first_order_share"] = shares[i].share
                    oc.result.evidence["first_order_chance"] = shares[i].chance
                outcomes[i] = oc
                if tick is not None:
                    tick(status=_line(k + 1, n, len(fitted), oc.result))
                else:
                    say(_line(k + 1, n, len(fitted), oc.result))
            redo = [i for i in fitted if screen != 1.0 and near_the_bar(ctx, state, outcomes[i])]
            if redo:
                say(
                    f"step {k + 1}: {len(redo)} of {len(fitted)} candidates screened with {screen:g}× the "
                    f"evaluations come near the bar: fitted with the full budget"
                )
                outcomes.update(pool.run(state, redo, first))
            ordered = [outcomes[i] for i in pending]
            view = View(ctx, state, cal.free)
            of = {id(outcomes[i]): cands[i] for i in pending}

            efforts, seconds = {}, {}

            def confirm(oc, e_plaus, state=state, first=first):
                if not folds:
                    say("a second fold (other validation blocks) for borderline candidates")
                    folds.append(ctx.refold(2))
                key = (id(of[id(oc)]), efforts.get(id(oc), 1.0))  # (the candidate, the effort)
                if key not in seconds:
                    seconds[key] = second_fold(folds[0], state, cal.free, of[id(oc)], first, e_plaus, key[1])
                return seconds[key]

            step, winner = assess(ctx, state, view, ordered, first[0] if first else None, confirm)
            again = {id(oc) for oc in polish_race(ordered, ctx.settings.polish_margin)}
            if again:
                effort = settings.polish_effort
                say(
                    f"step {k + 1}: {len(again)} candidates in the race stopped before converging: "
                    f"fitted again with {effort:g}× the evaluations"
                )
                redo = [i for i in pending if id(outcomes[i]) in again]
                outcomes.update(pool.run(state, redo, first, effort))
                ordered = [outcomes[i] for i in pending]
                of = {id(outcomes[i]): cands[i] for i in pending}
                efforts = {id(outcomes[i]): effort for i in redo}
                step, winner = assess(ctx, state, view, ordered, first[0] if first else None, confirm)
            asides = []  # winners set aside by rule 'effect-or-drift', listed with the step
            while winner is not None and not slow_drive:
                share = drift_like(ctx, view, winner.raw, winner.result.rms_validation)
                if share is None:
                    break
                note = (
                    f"step {k + 1}: {winner.result.cause} ({winner.result.label}, gain {winner.result.gain:.3g}) set "
                    f"aside (rule 'effect-or-drift'): {share:.1%} of its effect is a slow curve in time that the drive "
                    f"does not follow, and a drift of the output predicts the record as well: the record cannot "
                    f"tell them apart"
                )
                say(note)
                ctx.notes.append(note)
                aside = winner.result
                ordered = [oc for oc in ordered if oc is not winner]
                step, winner = assess(ctx, state, view, ordered, first[0] if first else None, confirm)
                aside.passed, aside.rule = False, "effect-or-drift"
                aside.verdict = f"{share:.0%} of its effect is a slow curve in time: not told from a drift"
                asides.append(aside)
            step.candidates += asides
            if k == 0 and winner is not None and not drift and drift_explains(ctx, state, winner.result.rms_validation):
                say("a linear drift explains the record as well as the best candidate: solved as a sensor drift")
                note = (
                    f"a linear drift of the output explained the record as well as {winner.result.cause} "
                    f"(gain {winner.result.gain:.3g}): solved with the calibration as a sensor drift"
                )
                yield FirstStep(ctx.reading, step.cause, step.rms, gap, floor, drift=note)
                return None
            steps.append(step)
            if k == 0 and winner is not None and winner.result.against == "plausible":
                baseline, from_plausible = pstate, True  # a linear structural cause fitted on it
            say(f"step {k + 1}: {step.why}")
            if k == 0:
                asked = True
                if not (yield FirstStep(ctx.reading, step.cause, step.rms, gap, floor)):
                    return None
            if winner is None:
                break
            state = advance(ctx, state, winner, view)
            step_predictions.append(state.prediction)
    if not asked and not (yield FirstStep(ctx.reading, "none", cal.rms_validation, gap, floor)):
        return None  # no candidate to try: the first step is the calibration's
    final_prediction = state.prediction
    if steps and not any(s.cause != "none" for s in steps):
        drift = drift_step(ctx, state, cal.drift, floor)
        if drift is not None:
            step, final_prediction = drift
            say(f"step {len(steps) + 1}: {step.why}")
            steps.append(step)
    causes = [s.cause for s in steps if s.cause != "none"]
    final_rms = rms((ctx.y - final_prediction)[ctx.ident.val_mask])
    base_rms = cal.rms_plausible if from_plausible and cal.rms_plausible is not None else cal.rms_validation
    if causes == ["drift"]:  # against the record as measured, the drift the calibration removed included
        base_rms = steps[-1].rms_before
    report = Report(
        causes,
        base_rms / max(final_rms, 1e-300) if causes else 1.0,
        base_rms,
        final_rms if causes else base_rms,
        steps,
        cal.as_json(),
        {
            "file": data.path or "",
            "model": source,
            "samples": len(ctx.t),
            "rate_hz": ctx.fs,
            "source_samples": ctx.source_samples,
            "source_rate_hz": ctx.source_rate,
            "validation_share": validation,
            "blocks": ctx.n_blocks,
            "input": ctx.input,
            "output": ctx.output,
            "drive_band_hz": ctx.band_hz,
            "drive_reading": ctx.reading,
            "reading_gap_rms": gap,
            "reading_floor_rms": floor,
        },
        list(ctx.notes),
        noise=ctx.noise,
        baseline="plausible" if from_plausible else "calibrated",
        account=account(ctx.u, ctx.y, final_prediction, ctx.ident.val_mask, ctx.fs, ctx.noise),
        settings=ctx.settings,
    )
    report.predictions = {"t": ctx.t, "u": ctx.u_recorded, "y": ctx.y, "baseline": baseline.prediction}
    report.predictions["steps"] = step_predictions + ([final_prediction] if causes[-1:] == ["drift"] else [])
    if causes and causes[-1] == "drift":
        report.predictions["extended"] = final_prediction
    elif causes:
        ext_model = state.model.copy()
        ext_model.values.update({k: v for k, v in state.values.items() if k in ext_model.all_parameters()})
        ext_model.values[SENSOR_GAIN] = state.gain
        report.extended_model, report.extended_values = ext_model, dict(state.values)
        report.notes += [f"the extended model's {why}" for why in not_monotone(ext_model)]
        report.predictions["extended"] = state.prediction
        if equations:
            from ..equations.derivation import derive
            from ..equations.printing import render

            try:
                report.equations = render(derive(ext_model), "text")
            except BondGraphError as exc:  # the fits ran on the Lur'e route; the bond graph itself may not derive
                report.notes.append(
                    f"the extended model's equations could not be derived ({exc}); its fits and predictions "
                    f"ran on the Lur'e route, which does not need them"
                )
        if not ctx.n_fast and len(ctx.t) <= 200_000:
            report.extended_rms_integrated = _integrated(ctx, ext_model, state)
    report.seconds = time.time() - started
    return report


def _integrated(ctx: Context, model: Model, state: State) -> float | None:
    """Validation RMS of the extended bond graph integrated by the compiled solver (second route);
    None when it fails, needs more than ``diagnosis.check_max_steps`` steps (a stiff model) or
    divides by a parameter a later step refitted to 0 (the check is a second route, never a
    reason to lose the diagnosis)."""
    try:
        ident = ctx.ident.like(model, rtol=1e-7, method="dopri5")
        ident.lti = None
        known = {p.name for p in ident.sim.eqs.params}
        raw = ident.predict(
            {k: v for k, v in state.values.items() if k in known and k != SENSOR_GAIN},
            max_steps=int(ctx.settings.check_max_steps),
        )
    except (BondGraphError, SimulationError, ZeroDivisionError):
        return None
    return score(ctx, raw)[3]


def _line(step: int, k: int, n: int, r: CandidateResult) -> str:
    state = (
        f"not tried ({r.skipped})"
        if r.skipped
        else f"failed ({r.error[:70]})"
        if r.error
        else f"fitted ({r.n_params} new parameters)"
    )
    return f"step {step} [{k}/{n}] {r.cause} ({r.label}): {state}, {r.seconds:.1f} s"
