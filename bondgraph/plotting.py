"""Plots (optional extra ``plot``: matplotlib): simulations, Bode diagrams, bond graphs.

Every figure is written atomically to a PNG; without matplotlib a one-line error names the
extra to install.
"""
from __future__ import annotations

import numpy as np

from .atomic import atomic_write
from .errors import UsageError


def _pyplot():
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise UsageError("plots need matplotlib: pip install 'bondgraph[plot]'") from None
    return plt


def save(fig, path: str) -> None:
    plt = _pyplot()
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)


def plot_simulation(res, path: str, title: str = "") -> None:
    """Inputs on top, each output below, against time."""
    plt = _pyplot()
    n = len(res.inputs) + len(res.outputs)
    fig, axes = plt.subplots(max(n, 1), 1, figsize=(8, 1.9 * max(n, 1) + 0.6), sharex=True, squeeze=False)
    for ax, (name, y) in zip(axes[:, 0], list(res.inputs.items()) + list(res.outputs.items())):
        ax.plot(res.t, y, lw=1.0)
        ax.set_ylabel(name)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t (s)")
    if title:
        axes[0, 0].set_title(title)
    save(fig, path)


def plot_bode(w, H, path: str, title: str = "") -> None:
    plt = _pyplot()
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    a1.loglog(w, np.abs(H))
    a1.set_ylabel("|H|")
    a2.semilogx(w, np.degrees(np.unwrap(np.angle(H))))
    a2.set_ylabel("phase (deg)")
    a2.set_xlabel("ω (rad/s)")
    for a in (a1, a2):
        a.grid(alpha=0.3, which="both")
    if title:
        a1.set_title(title)
    save(fig, path)


def plot_bond_graph(causality, path: str) -> None:
    """Elements as labelled nodes, bonds with half-arrows (power) and causal strokes."""
    import networkx as nx

    plt = _pyplot()
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
        ax.text(x, y, label, ha="center", va="center", fontsize=8,
                bbox=dict(boxstyle="round,pad=0.25", fc="mistyrose" if name in deriv else "white",
                          ec="tab:red" if name in deriv else "0.5"))
    ax.set_title(f"{m.name}: half-arrows show power, red strokes causality"
                 + (" (red boxes: derivative causality)" if deriv else ""), fontsize=9)
    ax.set_axis_off()
    ax.set_aspect("equal")
    save(fig, path)


def plot_diagnosis(report, path: str) -> None:
    """Measured vs calibrated vs extended output (after each named cause), residuals, and
    residual-vs-input loops."""
    plt = _pyplot()
    p = report.predictions
    t, u, y, base = p["t"], p["u"], p["y"], p["baseline"]
    ext = p.get("extended")
    chain = " → ".join(report.causes) or "none"
    inp, out = report.data.get("input", "input"), report.data.get("output", "output")
    fig, ax = plt.subplots(3, 1, figsize=(9, 9))
    ax[0].plot(t, y, lw=0.8, label="measured")
    ax[0].plot(t, base, lw=0.8, label="calibrated model")
    if ext is not None:
        ax[0].plot(t, ext, lw=0.8, ls="--", label=f"extended ({chain})")
    ax[0].set_xlabel("t (s)")
    ax[0].set_ylabel(out)
    ax[0].legend(fontsize=8)
    ax[1].plot(t, y - base, lw=0.6, label=f"residual, calibrated (RMS {report.baseline_rms:.3g})")
    if ext is not None:
        ax[1].plot(t, y - ext, lw=0.6, label=f"residual, extended (RMS {report.extended_rms:.3g})")
    if report.noise:
        ax[1].axhspan(-report.noise, report.noise, color="0.85", label="noise floor (±1σ)")
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel(f"{out} residual")
    ax[1].legend(fontsize=8)
    ax[2].plot(u, y - base, lw=0.4, label="calibrated")
    if ext is not None:
        ax[2].plot(u, y - ext, lw=0.4, label="extended")
    ax[2].set_xlabel(inp)
    ax[2].set_ylabel(f"{out} residual")
    ax[2].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(f"diagnosis: {chain} (gain {report.gain:.3g})")
    fig.tight_layout()
    save(fig, path)
