"""Screen before fitting: with effect kinds at every site of a model, the candidates grow
with sites × kinds, so those that can say quickly what they explain
(:meth:`~bondgraph.diagnosis.candidate.Candidate.screen`: a first-order regression of the
residual on the kind's regressor passed through the linear transfer from its site) are
ranked, and only the best ``diagnosis.screen_keep`` of them are fitted in full."""

from __future__ import annotations

from typing import Sequence

from .candidate import Candidate


def screen_out(
    view, candidates: Sequence[Candidate], pending: Sequence[int]
) -> tuple[dict[int, str], dict[int, float]]:
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
        index → why it is not fitted in full.
    shares : dict
        index → the share (0-1) of the residual's energy on the fit part the candidate
        explains to first order, for every candidate that could say.
    """
    keep = int(view.settings.screen_keep)
    shares: dict[int, float] = {}
    for i in pending:
        cand = candidates[i]
        if type(cand).screen is Candidate.screen or cand.applies(view) is not True:
            continue
        try:
            share = cand.screen(view)
        except (ArithmeticError, ValueError, RuntimeError):  # the full fit reports its own failure
            share = None
        if share is not None:
            shares[i] = share
    if len(shares) <= keep:
        return {}, shares
    ranked = sorted(shares, key=lambda i: -shares[i])
    bar = shares[ranked[keep - 1]]
    left = {
        i: (
            f"screened out: explains {shares[i]:.1%} of the residual to first order "
            f"(the {keep} fitted explain {bar:.1%} or more)"
        )
        for i in ranked[keep:]
    }
    return left, shares
