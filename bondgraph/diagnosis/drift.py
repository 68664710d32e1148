"""A slow drift of the output: a smooth curve in time that no drive explains.

A drift (a sensor's thermal drift, a slow wander of its zero, a random walk) is sought in
the residual as a cubic B-spline in time (:func:`drift_basis`).  Its knots are spaced so that
a drift cannot pass for the response to the drive: at least
:data:`PERIODS` periods of the calibrated model's slowest mode apart, and at least
:data:`BLOCKS` validation blocks apart, so that every piece of the spline is fitted on the
fit part at both sides of a validation block and judged on what it predicts there (a curve
that only follows the fit part's detail predicts nothing between them).  Drifts that bend
more often than that are not told from the dynamics and are not sought.

Three rules use it: ``drift-when-nothing`` (:func:`drift_step`) names a drift when nothing else
explains the record; ``effect-or-drift`` (:func:`drift_like`) sets a step's winner aside when
its effect is such a curve, the drive is not (:func:`smooth_share` of the effect at least
:data:`SMOOTH`, of the drive below :data:`SLOW_DRIVE`), and a drift predicts the record as
well as the winner: the record cannot tell the effect from a drift, which needs no drive, so
the drift is tried when nothing else is named; and the first
step asks whether a straight line explains the record as well as the best candidate
(:func:`drift_explains`; the diagnosis then restarts with the drift solved).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import BSpline

from .calibration import rms
from .context import Context, State
from .decision import BASIC, Verdict, compare, judge, regress
from .report import CandidateResult, Step

#: the drift's knots are at least this many periods of the model's slowest mode apart
PERIODS = 10.0
#: ... and at least this many validation blocks apart
BLOCKS = 3.0
#: at most this many spline pieces over the record
MAX_PIECES = 16
#: an effect whose contribution to the output the drift curve reproduces to this share of its
#: variance on the validation blocks, under a drive the curve does not follow, is not told from
#: a drift by the record (on the blind generator's creep records, which follow their drive's
#: bursts and steps, the share is at most 0.94)
SMOOTH = 0.98
#: a drive the drift curve reproduces to this share of its variance is slow enough for an
#: effect that follows it to be a slow curve too: the rule above does not apply
SLOW_DRIVE = 0.5


def drift_basis(ctx: Context) -> np.ndarray:
    """The columns a drift is a combination of: cubic B-splines in time over the record, on
    uniform knots spaced as the module docstring says (at least one piece: a cubic in time).

    Parameters
    ----------
    ctx : Context
        The prepared record.

    Returns
    -------
    numpy.ndarray
        (samples, pieces + 3) basis; its columns sum to one on every sample.
    """
    t = np.asarray(ctx.t, float)
    span = max(float(t[-1] - t[0]), 1e-300)
    slow = [f for f in ctx.slow_hz if f > 0]
    spacing = max(BLOCKS * span / max(ctx.n_blocks, 1), PERIODS / min(slow) if slow else 0.0)
    pieces = int(min(max(np.floor(span / spacing), 1), MAX_PIECES))
    knots = np.concatenate([[0.0] * 3, np.linspace(0.0, 1.0, pieces + 1), [1.0] * 3])
    x = np.clip((t - t[0]) / span, 0.0, 1.0)
    return BSpline.design_matrix(x, knots, 3).toarray()


def smooth_share(ctx: Context, effect: np.ndarray) -> float:
    """The share (R², at most 1) of an effect's variance on the validation blocks that the drift
    curve (:func:`drift_basis`) fitted to it on the fit part reproduces: 1 for an effect that is
    a slow curve in time whatever the drive does, low for one that follows the drive.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    effect : numpy.ndarray
        What the effect adds to the output on every sample (output units).

    Returns
    -------
    float
        The share; 0 for an effect without variance.
    """
    idx, val = ctx.ident.fit_idx, ctx.ident.val_mask
    left = effect - regress(drift_basis(ctx), effect, idx)
    spread = float(np.sum((effect[val] - effect[val].mean()) ** 2))
    return 1.0 - float(np.sum(left[val] ** 2)) / spread if spread > 0 else 0.0


def drift_like(ctx: Context, view, raw: np.ndarray, rms_winner: float) -> float | None:
    """Rule ``effect-or-drift``: the :func:`smooth_share` of what a step's winner adds to the
    output (its raw prediction with the sensor gain and offset solved, less the current
    prediction) when it is at least :data:`SMOOTH` and a drift predicts the validation part as
    well as the winner (validation RMS within ``diagnosis.equivalent`` of ``rms_winner``), else
    None.  The drift is the curve of :func:`drift_basis` fitted with the same freedom the
    winner had: on the exact linear route jointly with the calibrated linear parameters (a
    drift in the record also bends the calibration), else to the current residual.  An effect
    that is a slow curve but predicts the validation blocks better than any drift is told from
    one by the record.  The engine applies the rule only under a drive whose own smooth share
    is below :data:`SLOW_DRIVE`.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    view : View
        The step's view of the record and the current model.
    raw : numpy.ndarray
        The winner's raw prediction on every sample.
    rms_winner : float
        The winner's validation RMS (output units).

    Returns
    -------
    float or None
        The share (0-1) when the winner's effect cannot be told from a drift, else None.
    """
    g, b = view.score(raw)[:2]
    share = smooth_share(ctx, g * np.asarray(raw) + b - view.current.prediction)
    if share < SMOOTH:
        return None
    basis = drift_basis(ctx)[:, 1:]  # its columns sum to one: the offset is solved anyway
    e = view.current.residual
    drift_rms = rms((e - regress(basis, e, ctx.ident.fit_idx))[ctx.ident.val_mask])
    if view.on_core:
        drift_rms = min(drift_rms, view.score(view.fit_drive(direct=list(basis.T), max_nfev=20).prediction)[3])
    return share if drift_rms <= ctx.settings.equivalent * rms_winner else None


def drift_step(ctx: Context, state: State, solved: float | None, floor: float) -> tuple[Step, np.ndarray] | None:
    """When nothing else was named: a slow drift of the output named ``drift`` at the output
    (rule ``drift-when-nothing``), or None.

    The drift is :func:`drift_basis` fitted to the residual on the fit part, plus the linear
    sensor drift the calibration solved and removed from the record (``solved``, output units
    per second), if any.  It is named when, put back into the record, it passes the rules every
    cause must (``on-bound``, ``useful-gain``, ``significant``) and its RMS is at least
    ``diagnosis.drift_noise`` times the noise floor: a drift that stands out of the noise is a
    finding about the measurement, where a smaller one is removed as a nuisance (and said in a
    note).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The chain's current state.
    solved : float or None
        The linear sensor drift the calibration removed, output units per second.
    floor : float
        The noise floor (RMS, output units).

    Returns
    -------
    (Step, ndarray) or None
        The step and the prediction of the record as it was measured, drift included.
    """
    idx, val = ctx.ident.fit_idx, ctx.ident.val_mask
    removed = 0.0 if solved is None else solved * 0.5 * (ctx.t[-1] - ctx.t[0]) * ctx.trend
    y = ctx.y + removed  # the record as measured
    e_state = y - state.prediction
    basis = drift_basis(ctx)
    drift = regress(basis, e_state, idx)
    drift = drift - np.mean(drift[idx])  # the offset stays the calibration's
    e_drift = e_state - drift
    cmp = compare(e_state, e_drift, ctx.blocks)
    before, after = rms(e_state[val]), rms(e_drift[val])
    size = float(np.std(drift)) / max(float(np.std(y)), 1e-300)
    above = float(np.std(drift)) / max(floor, 1e-300)
    res = CandidateResult("drift", "a slow drift of the output (a smooth curve in time)", site="output")
    res.gain, res.z, res.n_eff, res.rms_validation, res.n_params = cmp.gain, cmp.z, cmp.n_eff, after, basis.shape[1]
    res.params = {"drift.rms_share": size, "drift.noise_ratio": above}
    verdict = judge("nonlinear", cmp, None, None, [], "", rules=BASIC, settings=ctx.settings)
    least = ctx.settings.drift_noise
    if verdict.passed and above < least:
        verdict = Verdict(
            False, f"its RMS is {above:.2g}× the noise floor (< {least:g}): a nuisance, not a finding", "drift-size"
        )
    res.passed, res.verdict, res.rule = verdict.passed, verdict.reason, verdict.rule
    if not res.passed:
        if res.rule == "drift-size":
            ctx.notes.append(
                f"a slow drift of the output ({'with the sensor drift the calibration removed, ' if solved else ''}"
                f"{size:.1%} of its RMS, {above:.2g}× the noise floor) lowers the validation RMS {cmp.gain:.3g}× "
                f"(z = {cmp.z:.1f}); it is below diagnosis.drift_noise ({least:g}× the noise floor), so it is "
                f"treated as a nuisance, not named a cause"
            )
        return None
    why = (
        f"named: nothing else explains the record, and a slow drift of the output, {size:.0%} of its RMS "
        f"({above:.3g}× the noise floor), lowers the validation RMS {cmp.gain:.3g}× (z = {cmp.z:.1f})"
    )
    step = Step("drift", cmp.gain, before, after, before, [res], why, "output", res.label, "drift-when-nothing", res)
    return step, state.prediction + drift - removed


def drift_explains(ctx: Context, state: State, rms_winner: float) -> bool:
    """Whether a straight line added to the calibrated model (a sensor drift) passes the rules
    a cause must (``diagnosis.min_gain``, ``diagnosis.min_z``) and explains the validation part
    as well as the first step's winner (validation RMS ``rms_winner``, within
    ``diagnosis.equivalent``): then the winner may be a drift passing for an effect, and the
    diagnosis starts again with the drift solved.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    state : State
        The calibrated state.
    rms_winner : float
        The first step's winner's validation RMS (output units).

    Returns
    -------
    bool
    """
    idx, val, y = ctx.ident.fit_idx, ctx.ident.val_mask, ctx.y
    e_state = y - state.prediction
    e_drift = y - regress(np.column_stack([state.raw, ctx.trend]), y, idx)
    base = compare(e_state, e_drift, ctx.blocks)
    if base.gain < ctx.settings.min_gain or base.z < ctx.settings.min_z:
        return False
    return rms(e_drift[val]) <= ctx.settings.equivalent * rms_winner
