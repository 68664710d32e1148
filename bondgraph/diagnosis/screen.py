"""Screen before fitting: with effect kinds at every site of a model, the candidates grow
with sites × kinds, so those that can say quickly what they explain
(:meth:`~bondgraph.diagnosis.candidate.Candidate.screen`: a first-order regression of the
residual on the kind's regressor passed through the linear transfer from its site) are
screened before any is fitted in full.

**Chance floor** (rule ``chance``).  A candidate whose columns explain no more of the
residual than they would of measurement noise is not fitted: such a kind has nothing at its
site to grow from.  The hypothesis tested is that the residual r is noise, a stationary random
process with r's autocorrelation ρ_r and a variance σ² no larger than the noise floor's
(σ² = min(var r, σ_n²), σ_n the record's noise estimate: from a band the drive leaves quiet,
else an upper estimate from the residual, the larger of its spectrum's floor and its part
incoherent with the drive, so that coloured noise is not taken for a finding).  Residual and columns are
correlated in time, so the product of r with a unit-norm column u scatters far more than
σ: for independent stationary series its variance is σ²·Σ_k ρ_u(k)·ρ_r(k) over every lag k
(Bartlett, "Some aspects of the time-correlation problem in regard to tests of
significance", J. R. Stat. Soc. 98(3), 1935).  With the columns orthonormalised (u_j) beyond
the calibration's directions, X = Σ_j (u_j·r)²/(σ²·Σ_k ρ_uj(k)ρ_r(k)) is χ² with as many
degrees of freedom as columns under the hypothesis; ``chance`` is its tail probability, and
the candidate is left out when it exceeds ``diagnosis.screen_chance``.

A residual at the noise floor (a record with nothing to find) leaves X at the size of the
correlation test of two unrelated series; a residual far above the floor is a deterministic
mismatch, whose few effective samples would make any correlation look like chance, and the
factor var r/σ_n² then keeps every column that explains more of it than noise could.  A
false keep costs only a fit.

**Keep** (rule ``rank``).  Of the rest, when more than ``diagnosis.screen_keep`` remain, only
that many, those explaining most, are fitted in full."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from scipy.stats import chi2

from .candidate import Candidate
from .decision import autocovariance


@dataclass(frozen=True)
class FirstOrder:
    """What a candidate's columns explain of the residual to first order.

    Attributes
    ----------
    share : float
        The share (0-1) of the residual's energy on the fit part the columns explain beyond
        the calibration's directions.
    chance : float
        The probability (0-1) that columns unrelated to the residual explain as much, given
        both series' autocorrelation (module docstring); 1 when nothing is left to explain.
    n_eff : float
        The effective number of independent samples of the first orthonormal column's
        product with the residual (N / Σ_k ρ_u(k)·ρ_r(k)).
    """

    share: float
    chance: float = 1.0
    n_eff: float = 0.0


def _acf(x: np.ndarray) -> np.ndarray:
    """Autocorrelation of each column at lags 0..N-1 (biased, ρ(0) = 1)."""
    g = autocovariance(x)
    return g / np.where(g[:1] > 0, g[:1], 1.0)


def first_order(q: np.ndarray, r: np.ndarray, total: float, noise: float | None) -> FirstOrder:
    """The first-order share of columns q in residual r, and its chance level.

    Parameters
    ----------
    q : numpy.ndarray
        The columns beyond the calibration's directions (samples × columns), on the fit part.
    r : numpy.ndarray
        The residual beyond the calibration's directions (the offset among them: mean 0), on
        the same samples.
    total : float
        The residual's energy about its mean before the projection (the share's denominator).
    noise : float or None
        The measurement noise's RMS, in r's units (None: r's own RMS, the test of two
        unrelated series).

    Returns
    -------
    FirstOrder
        ``share`` is what q explains of ``total``; ``chance`` and ``n_eff`` as the module
        docstring says.
    """
    r0 = r - np.mean(r)
    rr = float(r0 @ r0)
    if rr <= 0 or total <= 0:
        return FirstOrder(0.0)
    u, s, _ = np.linalg.svd(q, full_matrices=False)  # an orthonormal basis of the columns' span
    u = u[:, s > 1e-12 * s[0]] if s.size and s[0] > 0 else u[:, :0]
    if u.shape[1] == 0:
        return FirstOrder(0.0)
    products = u.T @ r0
    share = min(float(products @ products) / total, 1.0)  # the projection's energy
    n = r0.size
    both = _acf(u) * _acf(r0[:, None])
    spread = np.maximum(2 * both.sum(axis=0) - both[0], 1e-12)  # lags ±k, k > 0, count twice
    var = rr / n if noise is None else min(rr / n, float(noise) ** 2)
    x = float(np.sum(products**2 / (var * spread)))
    return FirstOrder(share, float(chi2.sf(x, u.shape[1])), float(n / spread[0]))


def screen_out(
    view, candidates: Sequence[Candidate], pending: Sequence[int]
) -> tuple[dict[int, str], dict[int, FirstOrder]]:
    """The pending candidates left out by the screen, with the reason, and every share found.

    Parameters
    ----------
    view : View
        The current chain state as candidates see it.
    candidates : sequence of Candidate
        Every candidate of the diagnosis.
    pending : sequence of int
        Indices of the candidates this chain step tries.

    Returns
    -------
    left_out : dict
        index → why it is not fitted in full (the rule and its numbers).
    shares : dict
        index → what the candidate explains to first order, for every candidate that could
        say.
    """
    keep, level = int(view.settings.screen_keep), float(view.settings.screen_chance)
    shares: dict[int, FirstOrder] = {}
    for i in pending:
        cand = candidates[i]
        if type(cand).screen is Candidate.screen or cand.applies(view) is not True:
            continue
        try:
            found = cand.screen(view)
        except (ArithmeticError, ValueError, RuntimeError):  # the full fit reports its own failure
            found = None
        if found is not None:
            shares[i] = found
    left = {
        i: (
            f"screened out (rule chance): explains {f.share:.2%} of the residual to first order, "
            f"no more than of measurement noise (p = {f.chance:.2g} > diagnosis.screen_chance "
            f"{level:g}; {f.n_eff:.0f} effective samples)"
        )
        for i, f in shares.items()
        if f.chance > level
    }
    ranked = sorted((i for i in shares if i not in left), key=lambda i: -shares[i].share)
    if len(ranked) > keep:
        bar = shares[ranked[keep - 1]].share
        for i in ranked[keep:]:
            left[i] = (
                f"screened out (rule rank): explains {shares[i].share:.1%} of the residual to first order "
                f"(the {keep} fitted explain {bar:.1%} or more)"
            )
    return left, shares
