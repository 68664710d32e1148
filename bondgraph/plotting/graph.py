"""The bond graph drawn with its power half-arrows and causal strokes."""

from __future__ import annotations

import numpy as np

from . import figures


def plot_bond_graph(causality, path: str) -> None:
    """Elements as labelled nodes, bonds with half-arrows (power) and causal strokes."""
    import networkx as nx

    plt = figures.pyplot()
    m = causality.model
    g = nx.Graph()
    g.add_nodes_from(m.elements)
    for b in m.bonds:
        g.add_edge(b.tail[0], b.head[0])
    pos = nx.kamada_kawai_layout(g) if len(g) > 2 else nx.spring_layout(g, seed=1)
    size = max(6.0, 1.1 * len(g) ** 0.5 * 3)
    fig, ax = plt.subplots(figsize=(size, size * 0.75))
    scale = max(np.ptp(np.array(list(pos.values())), axis=0).max(), 1e-9)
    r = 0.045 * scale
    for b in m.bonds:
        p0, p1 = np.array(pos[b.tail[0]]), np.array(pos[b.head[0]])
        d = p1 - p0
        L = np.hypot(*d) or 1.0
        u = d / L
        nrm = np.array([-u[1], u[0]])
        a, z = p0 + u * r, p1 - u * r
        ax.plot(*zip(a, z), color="k", lw=1.2)
        barb = z - u * 0.6 * r + nrm * 0.45 * r  # half-arrow at the head
        ax.plot(*zip(z, barb), color="k", lw=1.2)
        stroke_at = causality.stroke_end(b)
        s = z if stroke_at == b.head else a
        ax.plot(*zip(s - nrm * 0.5 * r, s + nrm * 0.5 * r), color="tab:red", lw=2.2)
        mid = (a + z) / 2 + nrm * 0.25 * r
        ax.text(*mid, str(b.index), fontsize=7, color="0.4", ha="center", va="center")
    deriv = {e for e, _ in causality.derivative}
    for name, (x, y) in pos.items():
        el = m.elements[name]
        label = el.kind if el.kind in ("0", "1") else f"{el.kind}:{name}"
        ax.text(
            x,
            y,
            label,
            ha="center",
            va="center",
            fontsize=8,
            bbox=dict(
                boxstyle="round,pad=0.25",
                fc="mistyrose" if name in deriv else "white",
                ec="tab:red" if name in deriv else "0.5",
            ),
        )
    ax.set_title(
        f"{m.name}: half-arrows show power, red strokes causality"
        + (" (red boxes: derivative causality)" if deriv else ""),
        fontsize=9,
    )
    ax.set_axis_off()
    ax.set_aspect("equal")
    figures.save(fig, path)
