"""The bond graph drawn: where its elements sit, its bonds with their power half-arrows and,
once causality is assigned, their causal strokes.

:func:`layout` places the elements (a Kamada–Kawai layout of the element graph) and says
which end of each bond carries its stroke; :func:`svg` draws it as SVG text, with no plotting
library (the notebook display of :class:`~bondgraph.model.graph.Model` and of a causal
assignment); :func:`bondgraph.plotting.plot_bond_graph` draws the same layout with matplotlib.

Conventions: the half-arrow sits at the head of a bond (power flows tail → head, power-in at
every port); the causal stroke sits at the end where the effort arrives, i.e. at the end
that does *not* set the effort.
"""

from __future__ import annotations

from dataclasses import dataclass
from html import escape

import numpy as np

#: above this many elements the graph is not drawn (a layout of a big stack says nothing)
MAX_ELEMENTS = 150


@dataclass
class BondMark:
    """One bond to draw: its index, its tail and head elements, and whether its causal stroke
    sits at the head (``True``), at the tail (``False``) or is not known yet (``None``)."""

    index: int
    tail: str
    head: str
    stroke_at_head: bool | None


@dataclass
class Layout:
    """The bond graph's geometry: element positions (layout units, y up) and labels, the bonds,
    and the elements in derivative causality (drawn highlighted)."""

    name: str
    positions: dict[str, np.ndarray]
    labels: dict[str, str]
    bonds: list[BondMark]
    derivative: set[str]
    causal: bool


def layout(model, stroke_end=None, derivative=()) -> Layout:
    """Where the elements of ``model``'s bond graph sit, and what each bond carries.

    Parameters
    ----------
    model : Model or Component
        The bond graph (its ``elements`` and ``bonds``).
    stroke_end : callable, optional
        ``stroke_end(bond) -> (element, port)``: the end of a bond that carries the causal
        stroke (:meth:`bondgraph.Causality.stroke_end`); without it no stroke is drawn.
    derivative : iterable of str, optional
        Elements in derivative causality.

    Returns
    -------
    Layout
    """
    import networkx as nx

    g = nx.Graph()
    g.add_nodes_from(model.elements)
    for b in model.bonds:
        g.add_edge(b.tail[0], b.head[0])
    pos = nx.kamada_kawai_layout(g) if len(g) > 2 else nx.spring_layout(g, seed=1)
    bonds = [
        BondMark(b.index, b.tail[0], b.head[0], None if stroke_end is None else stroke_end(b) == b.head)
        for b in model.bonds
    ]
    labels = {name: el.kind if el.kind in ("0", "1") else f"{el.kind}:{name}" for name, el in model.elements.items()}
    return Layout(
        model.name,
        {k: np.asarray(v, float) for k, v in pos.items()},
        labels,
        bonds,
        set(derivative),
        stroke_end is not None,
    )


def caption(lay: Layout) -> str:
    """The drawing's title: what its marks mean."""
    if not lay.causal:
        return f"{lay.name}: half-arrows show power (causality not assigned yet)"
    return f"{lay.name}: half-arrows show power, red strokes causality" + (
        " (red boxes: derivative causality)" if lay.derivative else ""
    )


def svg(model, stroke_end=None, derivative=(), px: float | None = None) -> str:
    """The bond graph of ``model`` as an SVG document (text).

    Parameters
    ----------
    model, stroke_end, derivative
        As for :func:`layout`.
    px : float, optional
        Width of the drawing in pixels (default: grows with the number of elements).

    Returns
    -------
    str
        An ``<svg>`` element; for more than :data:`MAX_ELEMENTS` elements, a short one that
        says the graph is too big to draw.
    """
    n = len(model.elements)
    if n > MAX_ELEMENTS:
        return (
            '<svg xmlns="http://www.w3.org/2000/svg" width="560" height="30">'
            f'<text x="4" y="20" font-family="sans-serif" font-size="13">{escape(model.name)}: {n} elements, '
            f"{len(model.bonds)} bonds (more than {MAX_ELEMENTS}: not drawn)</text></svg>"
        )
    lay = layout(model, stroke_end, derivative)
    pts = np.array(list(lay.positions.values()))
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = max((hi - lo).max(), 1e-9)
    width = px or float(max(np.clip(160 * n**0.5, 320, 900), 6.5 * len(caption(lay)) + 10))  # the caption fits
    pad, top = 60.0, 24.0
    k = (width - 2 * pad) / span
    height = (hi[1] - lo[1]) * k + 2 * pad + top
    at = {
        name: np.array([pad + (p[0] - lo[0]) * k, top + pad + (hi[1] - p[1]) * k]) for name, p in lay.positions.items()
    }
    half = {name: np.array([3.5 * len(label) + 8, 13.0]) for name, label in lay.labels.items()}  # box + margin

    def edge(centre, hw, u):  # where the ray from a box's centre along u leaves the box
        return centre + u * min(hw[0] / max(abs(u[0]), 1e-12), hw[1] / max(abs(u[1]), 1e-12))

    def line(p, q, colour, w, cls=""):
        return (
            f'<line{cls} x1="{p[0]:.1f}" y1="{p[1]:.1f}" x2="{q[0]:.1f}" y2="{q[1]:.1f}" stroke="{colour}" '
            f'stroke-width="{w}" stroke-linecap="round"/>'
        )

    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height:.0f}" '
        f'viewBox="0 0 {width:.0f} {height:.0f}" font-family="sans-serif" class="bondgraph">',
        f'<text x="4" y="15" font-size="12">{escape(caption(lay))}</text>',
    ]
    for b in lay.bonds:
        d = at[b.head] - at[b.tail]
        u = d / (np.hypot(*d) or 1.0)
        nrm = np.array([u[1], -u[0]])  # left of the bond on screen (y down)
        a, z = edge(at[b.tail], half[b.tail], u), edge(at[b.head], half[b.head], -u)
        out.append(f'<g class="bond" data-bond="{b.index}">')
        out.append(line(a, z, "black", 1.5))
        out.append(line(z, z - 10 * u + 7 * nrm, "black", 1.5))  # the half-arrow at the head
        if b.stroke_at_head is not None:
            s = z if b.stroke_at_head else a
            out.append(line(s - 8 * nrm, s + 8 * nrm, "#d62728", 3, ' class="stroke"'))
        m = (a + z) / 2 - 9 * nrm
        out.append(
            f'<text x="{m[0]:.1f}" y="{m[1] + 4:.1f}" font-size="10" fill="#666" text-anchor="middle">{b.index}</text>'
        )
        out.append("</g>")
    for name, (x, y) in at.items():
        label, w = lay.labels[name], 2 * half[name][0] - 6
        deriv = name in lay.derivative
        out.append(
            f'<g class="element" data-element="{escape(name)}">'
            f'<rect x="{x - w / 2:.1f}" y="{y - 10:.1f}" width="{w:.1f}" height="20" rx="6" '
            f'fill="{"mistyrose" if deriv else "white"}" stroke="{"#d62728" if deriv else "#888"}"/>'
            f'<text x="{x:.1f}" y="{y + 4:.1f}" font-size="12" text-anchor="middle">{escape(label)}</text></g>'
        )
    out.append("</svg>")
    return "\n".join(out)
