"""Evidence from the data: the flexible linear reference, paired comparisons of validation
errors with the residuals' autocorrelation taken into account, and the decision rules.

**Comparison.** Two predictions a and b are compared on the validation blocks through their
mean squared errors A and B: the statistic is log(A/B) (twice the log of the gain) over its
standard error, z.  Model errors are correlated in time, so n samples are worth far fewer
independent ones: the standard error comes from batches, each spanning four times the lag at
which the autocorrelation of e_a² − e_b² (about each block's mean) first falls to zero (a
whole period of a periodic error), never straddling two blocks; by the delta method,
se² = var_k(A_k/A − B_k/B)/K·(1 + ρ)/(1 − ρ) over the K batches' mean squared errors A_k,
B_k, where ρ ≥ 0 is the lag-one autocorrelation of the batch contributions in time order
beyond the 1/√K that independent batches show by chance (an error that changes slowly makes
neighbouring batches alike).  K(1 − ρ)/(1 + ρ) is the
effective sample size.  The ratio form weighs each regime by its error, as the RMS does, yet
is not dominated by the spread of error levels between regimes (sines, holds, a chirp).

**Flexible linear reference.** The current model plus the linear core driven by first-order
lags of its drive, G·(c0 + Σ c_k/(1 + sτ_k)), the lags τ_k spread from two samples to a third
of the record: a rational correction of modest order on the input side, fitted by linear least
squares.  What it gains over the calibrated model bounds what a linear mismatch explains.
The least squares ignore directions whose singular value is below ``RCOND`` of the largest
(columns scaled to unit norm): a narrow-band drive (one sine) makes every lag of it nearly a
combination of the others, and such a direction, unresolved by the fit part, would otherwise
carry huge cancelling coefficients that blow up wherever the columns differ slightly (the
record's ends) and make the reference worse than the model it extends.

**Rules** (:data:`RULES`, thresholds in the diagnosis's :class:`~.settings.Settings`): named
rule objects, checked in order; the first that refuses a candidate is its verdict's ``rule``:
``on-bound`` (no new parameter on a search bound), ``useful-gain`` (``min_gain``;
``min_gain_chain`` after the first step of a chain, whose residual holds what the named
extension, never quite the physics, left), ``significant`` (``min_z``), then for a nonlinear or
memory cause ``beyond-linear`` (given the reference's freedom too, it beats the reference by
``min_gain_reference`` with z ≥ ``min_z_reference``: that it explains something is
established against the calibrated model; this asks that it is not linear) and
``beyond-static`` (a memory effect beats its twin without memory the same way), and for a
linear structural cause ``linear-share`` (it explains at least ``linear_share`` of what the
reference explains, more if the candidate asks), ``plausible`` (its fitted values are
physically plausible: the candidate says) and ``not-a-recalibration`` (one that may be the
model's own structure recalibrated, a mode placed on one of the model's modes, must also beat
the reference as a nonlinear cause must).

Of the passing candidates, the one that explains most when the reference's freedom is
allowed too (its gain over the reference) is named, then the one with the larger own gain
(rule ``most-beyond-linear``): a linear cause gains little over the reference, so an effect
beyond any linear one is named first and the linear remainder is left to the next step of the
chain; of those the data cannot tell from it, the one with the fewest parameters
(``simplest-of-equivalent``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .filters import lowpass
from .settings import Settings


@dataclass
class Comparison:
    """b against a on the validation part: RMS ratio a/b, significance z, effective samples.

    Parameters
    ----------
    gain : float
        RMS of a over RMS of b (> 1: b is better).
    z : float
        Significance of log(A/B) over its standard error.
    n_eff : float
        Effective number of independent batches.
    """

    gain: float
    z: float
    n_eff: float


def autocovariance(x: np.ndarray) -> np.ndarray:
    """Σ_t x(t)·x(t + k) at lags k = 0..N-1 of each column of ``x`` (the biased estimate
    times N), by FFT with zero padding (no wrap-around).

    Parameters
    ----------
    x : numpy.ndarray
        A series, or one series per column (samples × columns).

    Returns
    -------
    numpy.ndarray
        The sums, shaped like ``x``.
    """
    n = x.shape[0]
    f = np.fft.rfft(x, 2 * n, axis=0)
    return np.fft.irfft(f * np.conj(f), axis=0)[:n]


def batch_length(d: np.ndarray, blocks: list[slice], offsets: list[int]) -> int:
    """Four times the first zero crossing of d's autocorrelation (about each block's mean).

    Parameters
    ----------
    d : numpy.ndarray
        The series on the validation samples, blocks concatenated.
    blocks : list of slice
        The validation blocks (their lengths are used).
    offsets : list of int
        Where each block starts in ``d``.

    Returns
    -------
    int
        The batch length in samples, between 1 and the longest block.
    """
    longest = max(s.stop - s.start for s in blocks)
    acf = np.zeros(longest)
    for s, o in zip(blocks, offsets):
        seg = d[o : o + (s.stop - s.start)]
        acf[: seg.size] += autocovariance(seg - seg.mean())
    if acf[0] <= 0:
        return 1
    below = np.nonzero(acf[1:] <= 0)[0]
    first = int(below[0]) + 1 if below.size else longest
    return max(1, min(4 * first, longest))


def compare(ea: np.ndarray, eb: np.ndarray, blocks: list[slice]) -> Comparison:
    """Compare residual series ``eb`` with ``ea`` (both over every sample) on ``blocks``.

    Parameters
    ----------
    ea : numpy.ndarray
        Residuals of the model compared against, on every sample.
    eb : numpy.ndarray
        Residuals of the model compared, on every sample.
    blocks : list of slice
        The validation blocks.

    Returns
    -------
    Comparison
        The gain RMS(ea)/RMS(eb), its significance and effective samples (module docstring).
    """
    idx = np.concatenate([np.arange(s.start, s.stop) for s in blocks])
    offsets = list(np.cumsum([0] + [s.stop - s.start for s in blocks])[:-1])
    with np.errstate(over="ignore", invalid="ignore"):
        a2, b2 = ea[idx] ** 2, eb[idx] ** 2
        ratio = float(a2.mean()) / max(float(b2.mean()), 1e-300)
    gain = math.sqrt(ratio) if math.isfinite(ratio) else 0.0
    L = batch_length(a2 - b2, blocks, offsets)
    A_k = np.concatenate([_batch_means(a2, o, s.stop - s.start, L) for s, o in zip(blocks, offsets)])
    B_k = np.concatenate([_batch_means(b2, o, s.stop - s.start, L) for s, o in zip(blocks, offsets)])
    K = A_k.size
    A, B = float(A_k.mean()) if K else 0.0, float(B_k.mean()) if K else 0.0
    if not (math.isfinite(A) and math.isfinite(B)) or A <= 0 or B <= 0 or K < 2:
        worse = B > A or not math.isfinite(B)
        return Comparison(gain, -math.inf if worse and K >= 2 else 0.0, float(K))
    d = A_k / A - B_k / B
    inflation = _serial_inflation(d)
    z = _z(math.log(A / B), float(np.std(d, ddof=1)) / math.sqrt(K) * math.sqrt(inflation))
    return Comparison(gain, z, float(K) / inflation)


def _batch_means(x: np.ndarray, start: int, m: int, L: int) -> np.ndarray:
    """Means of the consecutive length-``L`` batches of ``x[start:start + m]`` (the remainder
    dropped); a block shorter than ``L`` is one batch if it holds at least ``L // 2`` samples."""
    if m >= L:
        return x[start : start + m // L * L].reshape(-1, L).mean(axis=1)
    return x[start : start + m].mean(keepdims=True) if m >= L // 2 else np.zeros(0)


def _serial_inflation(d: np.ndarray) -> float:
    """(1 + ρ)/(1 − ρ) for the lag-one autocorrelation ρ of the batch contributions in time
    order, beyond the 1/√K that K independent batches show by chance (clipped to [0, 0.9]):
    batches of a slowly varying error are not independent."""
    c = d - d.mean()
    den = float(c @ c)
    rho = float(c[1:] @ c[:-1]) / den if den > 0 else 0.0
    rho = min(max(rho - 1 / math.sqrt(d.size), 0.0), 0.9)
    return (1 + rho) / (1 - rho)


def _z(stat: float, se: float) -> float:
    if se <= 0:
        return math.inf if stat > 0 else -math.inf if stat < 0 else 0.0
    return stat / se


def reference_taus(dt: float, span: float, n: int) -> np.ndarray:
    """Time constants of the flexible linear reference's lags (module docstring).

    Parameters
    ----------
    dt : float
        Sample interval, s.
    span : float
        The record's duration, s.
    n : int
        How many (setting ``diagnosis.reference_poles``).

    Returns
    -------
    numpy.ndarray
        ``n`` time constants, s, spread geometrically from two samples to a third of the
        record.
    """
    return np.geomspace(2 * dt, max(span / 3, 4 * dt), int(n))


#: relative singular value below which :func:`regress` leaves a direction out (module docstring)
RCOND = 1e-5


def regress(columns: np.ndarray, y: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Least-squares fit of ``columns`` (and a constant) to ``y`` on ``idx``; the fitted series.

    Parameters
    ----------
    columns : numpy.ndarray
        Regressors on every sample, one per column.
    y : numpy.ndarray
        The measured output on every sample.
    idx : numpy.ndarray
        Sample indices of the fit part.

    Returns
    -------
    numpy.ndarray
        The fitted series on every sample (directions below :data:`RCOND` left out).
    """
    A = np.column_stack([columns, np.ones(len(y))])
    norms = np.maximum(np.linalg.norm(A[idx], axis=0), 1e-300)
    coef, *_ = np.linalg.lstsq(A[idx] / norms, y[idx], rcond=RCOND)
    return A @ (coef / norms)


@dataclass
class Verdict:
    """Why a candidate passed or not: ``rule`` is the name of the rule that refused it ('' when
    it passed).

    Parameters
    ----------
    passed : bool
        Whether it passed every rule.
    reason : str
        The verdict in words.
    rule : str, optional
        The refusing rule's name.
    """

    passed: bool
    reason: str
    rule: str = ""


@dataclass(frozen=True)
class Evidence:
    """What the rules see of one candidate (see :data:`RULES`).

    Parameters
    ----------
    kind : {"nonlinear", "linear"}
        The kind of cause.
    base : Comparison
        The candidate against the model it extends.
    versus_reference : Comparison or None
        The candidate with the reference's freedom against the flexible linear reference.
    share : float or None
        The share of what the reference explains that the candidate explains.
    at_bounds : list of str
        New parameters that ended on a search bound.
    implausible : str
        For a linear cause, why its values are implausible ("" if they are not).
    later : bool, optional
        A chain step after the first (``diagnosis.min_gain_chain`` replaces ``min_gain``).
    recalibration : str, optional
        Why a linear cause may be the model's own structure recalibrated.
    need_share : float, optional
        The candidate's own ``linear_share`` (None: the setting).
    versus_static : Comparison, optional
        A memory effect against its twin without memory.
    settings : Settings, optional
        The thresholds (:meth:`Settings.from_config` when not given).
    """

    kind: str
    base: Comparison
    versus_reference: Comparison | None
    share: float | None
    at_bounds: list
    implausible: str
    later: bool = False
    recalibration: str = ""
    need_share: float | None = None
    versus_static: Comparison | None = None
    settings: Settings = field(default_factory=Settings.from_config)


@dataclass(frozen=True)
class Rule:
    """A named decision rule: it applies to candidates of ``kinds`` and ``check`` returns why
    it refuses one ('' when it does not).  ``why`` is the rule's reason, as docs/diagnosis.md
    gives it.

    Parameters
    ----------
    name : str
        The rule's name (a verdict's ``rule``).
    kinds : tuple of str
        The kinds of cause it applies to.
    why : str
        The rule's reason.
    check : callable
        ``check(evidence)`` → why it refuses the candidate, or "".
    """

    name: str
    kinds: tuple[str, ...]
    why: str
    check: Callable[[Evidence], str]


def _on_bound(e: Evidence) -> str:
    return f"{', '.join(e.at_bounds)} on a search bound" if e.at_bounds else ""


def _useful(e: Evidence) -> str:
    need = e.settings.min_gain_chain if e.later else e.settings.min_gain
    return f"gain {e.base.gain:.3g} < {need:g}" if e.base.gain < need else ""


def _significant(e: Evidence) -> str:
    need = e.settings.min_z
    if e.base.z < need:
        return f"not significant (z = {e.base.z:.2g} < {need:g}, {e.base.n_eff:.0f} effective samples)"
    return ""


def _beyond(vr: Comparison | None, settings: Settings) -> bool:
    return vr is not None and vr.gain >= settings.min_gain_reference and vr.z >= settings.min_z_reference


def _beyond_linear(e: Evidence) -> str:
    vr = e.versus_reference
    if _beyond(vr, e.settings):
        return ""
    return "does not beat the linear reference" + (f" (gain {vr.gain:.3g}, z = {vr.z:.2g})" if vr is not None else "")


def _linear_share(e: Evidence) -> str:
    need = e.settings.linear_share if e.need_share is None else e.need_share
    if e.share is not None and e.share < need:
        return f"explains {e.share:.0%} of the linear mismatch (< {need:.0%})"
    return ""


def _plausible(e: Evidence) -> str:
    return f"implausible: {e.implausible}" if e.implausible else ""


def _not_recalibration(e: Evidence) -> str:
    if e.recalibration and not _beyond(e.versus_reference, e.settings):
        vr = e.versus_reference
        return f"{e.recalibration} and does not beat the linear reference" + (
            f" (gain {vr.gain:.3g}, z = {vr.z:.2g})" if vr is not None else ""
        )
    return ""


def _beyond_static(e: Evidence) -> str:
    if e.versus_static is None or _beyond(e.versus_static, e.settings):
        return ""
    vs = e.versus_static
    return f"its loops explain no more than a static curve (gain {vs.gain:.3g}, z = {vs.z:.2g})"


#: the rules a candidate must pass, in the order they are checked (docs/diagnosis.md)
RULES = (
    Rule(
        "on-bound",
        ("nonlinear", "linear"),
        "a new parameter on its search bound stands in for something the kind cannot express",
        _on_bound,
    ),
    Rule(
        "useful-gain",
        ("nonlinear", "linear"),
        "the validation RMS must fall by a useful factor (diagnosis.min_gain, min_gain_chain after the first step)",
        _useful,
    ),
    Rule(
        "significant",
        ("nonlinear", "linear"),
        "the fall must be significant on the effective number of independent batches (diagnosis.min_z)",
        _significant,
    ),
    Rule(
        "beyond-linear",
        ("nonlinear",),
        "a nonlinear or memory effect must explain something no linear correction of the model does",
        _beyond_linear,
    ),
    Rule(
        "linear-share",
        ("linear",),
        "a linear structural cause must explain most of what a flexible linear correction explains",
        _linear_share,
    ),
    Rule(
        "plausible",
        ("linear",),
        "a linear structural cause must have physically plausible values (the candidate says)",
        _plausible,
    ),
    Rule(
        "not-a-recalibration",
        ("linear",),
        "a cause that may be the model's own structure recalibrated must beat the linear reference too",
        _not_recalibration,
    ),
    Rule(
        "beyond-static",
        ("nonlinear",),
        "a memory effect must beat a static curve with the same freedom: loops, not a curve",
        _beyond_static,
    ),
)


def judge(
    kind: str,
    base: Comparison,
    versus_reference: Comparison | None,
    share: float | None,
    at_bounds: list[str],
    implausible: str,
    later: bool = False,
    recalibration: str = "",
    need_share: float | None = None,
    versus_static: Comparison | None = None,
    rules: tuple[Rule, ...] = RULES,
    settings: Settings | None = None,
) -> Verdict:
    """Apply :data:`RULES` (or ``rules``) to one candidate; the first rule that refuses it
    decides (``later``: a chain step after the first, where ``diagnosis.min_gain_chain``
    replaces ``diagnosis.min_gain``; ``recalibration``: why a linear cause may be the model's
    own structure recalibrated; ``need_share``: the candidate's own ``linear_share``;
    ``versus_static``: a memory effect against its twin without memory).

    Parameters
    ----------
    kind : {"nonlinear", "linear"}
        The kind of cause.
    base : Comparison
        The candidate against the model it extends.
    versus_reference : Comparison or None
        The candidate with the reference's freedom against the flexible linear reference.
    share : float or None
        The share of what the reference explains that the candidate explains.
    at_bounds : list of str
        New parameters that ended on a search bound.
    implausible : str
        For a linear cause, why its values are implausible ("" if they are not).
    later : bool, optional
        A chain step after the first (``diagnosis.min_gain_chain`` replaces ``min_gain``).
    recalibration : str, optional
        Why a linear cause may be the model's own structure recalibrated.
    need_share : float, optional
        The candidate's own ``linear_share`` (None: the setting).
    versus_static : Comparison, optional
        A memory effect against its twin without memory.
    rules : tuple of Rule, optional
        The rules, in order.
    settings : Settings, optional
        The thresholds (:meth:`Settings.from_config` when not given).

    Returns
    -------
    Verdict
        Passed, or the first refusing rule and its reason.
    """
    e = Evidence(
        kind,
        base,
        versus_reference,
        share,
        list(at_bounds),
        implausible,
        later,
        recalibration,
        need_share,
        versus_static,
        settings if settings is not None else Settings.from_config(),
    )
    for rule in rules:
        if kind in rule.kinds:
            reason = rule.check(e)
            if reason:
                return Verdict(False, reason, rule.name)
    return Verdict(True, "passes")


#: the rules that apply to every cause (a drift of the output has no linear reference)
BASIC = tuple(r for r in RULES if r.name in ("on-bound", "useful-gain", "significant"))


def reference_prediction(
    view_respond,
    drive: np.ndarray,
    raw: np.ndarray,
    y: np.ndarray,
    idx: np.ndarray,
    dt: float,
    span: float,
    poles: int,
) -> tuple[np.ndarray, np.ndarray]:
    """(reference columns, the reference's prediction): ``raw`` plus the linear core driven by
    lags of ``drive``, fitted on ``idx``.

    Parameters
    ----------
    view_respond : callable
        ``view_respond(columns)`` → the linear core's response to each drive column.
    drive : numpy.ndarray
        The drive into the linear core.
    raw : numpy.ndarray
        The current model's raw prediction.
    y : numpy.ndarray
        The measured output.
    idx : numpy.ndarray
        Sample indices of the fit part.
    dt : float
        Sample interval, s.
    span : float
        The record's duration, s.
    poles : int
        How many lags (setting ``diagnosis.reference_poles``).

    Returns
    -------
    columns : numpy.ndarray
        The core's response to each lag.
    prediction : numpy.ndarray
        The reference's fitted prediction on every sample.
    """
    lags = [lowpass(drive, tau, dt) for tau in reference_taus(dt, span, poles)]
    cols = view_respond(lags)
    return cols, regress(np.column_stack([raw, cols]), y, idx)
