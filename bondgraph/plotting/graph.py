"""The bond graph drawn with its power half-arrows and causal strokes."""

from __future__ import annotations

import numpy as np

from ..model.drawing import caption, layout
from . import figures


def plot_bond_graph(causality, path: str) -> None:
    """Elements as labelled nodes, bonds with half-arrows (power) and causal strokes (the
    layout of :func:`bondgraph.model.drawing.layout`).

    Parameters
    ----------
    causality : Causality
        The model with its assigned causality (:func:`~bondgraph.assign_causality`); elements
        in derivative causality are marked.
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = figures.pyplot()
    lay = layout(causality.model, causality.stroke_end, {e for e, _ in causality.derivative})
    pos = lay.positions
    size = max(6.0, 1.1 * len(pos) ** 0.5 * 3)
    fig, ax = plt.subplots(figsize=(size, size * 0.75))
    scale = max(np.ptp(np.array(list(pos.values())), axis=0).max(), 1e-9)
    r = 0.045 * scale
    for b in lay.bonds:
        p0, p1 = pos[b.tail], pos[b.head]
        d = p1 - p0
        u = d / (np.hypot(*d) or 1.0)
        nrm = np.array([-u[1], u[0]])
        a, z = p0 + u * r, p1 - u * r
        ax.plot(*zip(a, z), color="k", lw=1.2)
        barb = z - u * 0.6 * r + nrm * 0.45 * r  # half-arrow at the head
        ax.plot(*zip(z, barb), color="k", lw=1.2)
        s = z if b.stroke_at_head else a
        ax.plot(*zip(s - nrm * 0.5 * r, s + nrm * 0.5 * r), color="tab:red", lw=2.2)
        mid = (a + z) / 2 + nrm * 0.25 * r
        ax.text(*mid, str(b.index), fontsize=7, color="0.4", ha="center", va="center")
    for name, (x, y) in pos.items():
        deriv = name in lay.derivative
        ax.text(
            x,
            y,
            lay.labels[name],
            ha="center",
            va="center",
            fontsize=8,
            bbox=dict(
                boxstyle="round,pad=0.25",
                fc="mistyrose" if deriv else "white",
                ec="tab:red" if deriv else "0.5",
            ),
        )
    ax.set_title(caption(lay), fontsize=9)
    ax.margins(0.12)  # the element labels are text, which the data limits do not include
    ax.set_axis_off()
    ax.set_aspect("equal")
    figures.save(fig, path)
