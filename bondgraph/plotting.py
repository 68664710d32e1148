"""Plots (optional extra ``plot``: matplotlib): simulations, Bode diagrams, bond graphs.

Axes carry the quantity and its unit (taken from the model's declared inputs and outputs);
signals that never change are left out (and listed in the title); curves that share a unit
share a panel, with a legend.  Every figure is written atomically, in the format of its file
name (png, pdf or svg); without matplotlib a one-line error names the extra to install.
"""
from __future__ import annotations

import os

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
    """Write ``fig`` atomically; the format follows the file name's suffix (png, pdf, svg)."""
    plt = _pyplot()
    fmt = os.path.splitext(os.fspath(path))[1].lstrip(".").lower() or "png"
    try:
        with atomic_write(path, "wb") as fh:
            fig.savefig(fh, format=fmt, dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)


def axis_label(name: str, unit: str) -> str:
    """``x (m)``, or just ``x`` for a quantity without unit (``(m)`` without a name)."""
    return f"{name} ({unit})".strip() if unit else name


def varies(y) -> bool:
    """Whether a sampled signal changes at all (beyond rounding)."""
    y = np.asarray(y, float)
    if y.size < 2:
        return False
    peak = float(np.max(np.abs(y)))
    return peak > 0 and float(np.ptp(y)) > 1e-12 * peak


def _envelope(t, y, limit: int = 20000):
    """At most about ``limit`` points that keep every bucket's minimum and maximum (a
    million-sample signal draws as fast as a short one and loses no peak)."""
    n = t.size
    if n <= limit:
        return t, y
    k = int(np.ceil(n / (limit // 2)))
    m = n // k * k
    tb, yb = t[:m].reshape(-1, k), y[:m].reshape(-1, k)
    lo, hi = yb.argmin(axis=1), yb.argmax(axis=1)
    rows = np.arange(tb.shape[0])
    first, second = np.minimum(lo, hi), np.maximum(lo, hi)
    tt = np.column_stack([tb[rows, first], tb[rows, second]]).ravel()
    yy = np.column_stack([yb[rows, first], yb[rows, second]]).ravel()
    return np.concatenate([tt, t[m:]]), np.concatenate([yy, y[m:]])


def plot_signals(t, signals: dict, units: dict, path: str, title: str = "") -> None:
    """Signals against time, one panel per unit: signals that share a unit share the panel
    (with a legend), the y axis says the unit; signals that never change are left out and
    listed in the title.  ``signals``: name → samples; ``units``: name → unit text."""
    plt = _pyplot()
    panels: dict = {}
    constant = []
    for name, y in signals.items():
        if not varies(y):
            constant.append(f"{name} = {float(np.asarray(y)[0]):.4g}" + (f" {units.get(name)}" if units.get(name) else ""))
            continue
        unit = units.get(name, "")
        panels.setdefault(unit if unit else ("", name), []).append(name)  # unitless: a panel each
    n = max(len(panels), 1)
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.9 * n + 0.8), sharex=True, squeeze=False)
    for ax, names in zip(axes[:, 0], panels.values()):
        unit = units.get(names[0], "")
        for name in names:
            ax.plot(*_envelope(np.asarray(t), np.asarray(signals[name], float)), lw=1.0, label=name)
        joined = ", ".join(names)
        ax.set_ylabel(axis_label(joined if len(joined) <= 24 else "", unit).strip() if unit else joined)
        if len(names) > 1:
            ax.legend(fontsize=8, loc="best")
        ax.grid(alpha=0.3)
    if not panels:
        axes[0, 0].text(0.5, 0.5, "every signal is constant", ha="center", va="center", transform=axes[0, 0].transAxes)
    axes[-1, 0].set_xlabel("t (s)")
    head = title + (": " if title and constant else "") + ("constant " + ", ".join(constant) if constant else "")
    if head:
        axes[0, 0].set_title(head, fontsize=9)
    save(fig, path)


def plot_simulation(res, path: str, title: str = "", units: dict | None = None, columns: dict | None = None) -> None:
    """Inputs and outputs of a :class:`~bondgraph.simulate.SimResult` against time (see
    :func:`plot_signals`); ``units`` name → unit (e.g. from the model's inputs and outputs),
    ``columns`` replaces the result's signals (e.g. outputs with a fit's offset added)."""
    plot_signals(res.t, columns if columns is not None else {**res.inputs, **res.outputs}, units or {}, path, title)


def plot_fit(t, measured, fitted, path: str, name: str = "y", unit: str = "", title: str = "") -> None:
    """Measured and fitted output (offset included) on one panel, the residual below."""
    plt = _pyplot()
    t = np.asarray(t, float)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    a1.plot(*_envelope(t, np.asarray(measured, float)), lw=0.8, label="measured")
    a1.plot(*_envelope(t, np.asarray(fitted, float)), lw=0.8, label="fitted model")
    a1.set_ylabel(axis_label(name, unit))
    a1.legend(fontsize=8, loc="best")
    a2.plot(*_envelope(t, np.asarray(measured, float) - np.asarray(fitted, float)), lw=0.6, color="tab:red")
    a2.set_ylabel(axis_label("residual", unit))
    a2.set_xlabel("t (s)")
    for a in (a1, a2):
        a.grid(alpha=0.3)
    if title:
        a1.set_title(title, fontsize=9)
    save(fig, path)


def plot_bode(w, H, path: str, title: str = "", input: tuple[str, str] = ("u", ""),
              output: tuple[str, str] = ("y", "")) -> None:
    """Magnitude and phase of the frequency response H(jω) of ``output`` to ``input``
    (each a (name, unit) pair; the magnitude's unit is theirs divided)."""
    plt = _pyplot()
    (u, uu), (y, yu) = input, output
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    a1.loglog(w, np.abs(H))
    unit = f"{yu or '1'}/{uu}" if uu else yu
    a1.set_ylabel(axis_label(f"|{y}/{u}|", unit))
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
    which = "calibrated" if report.baseline == "calibrated" else "plausible device"
    ax[0].plot(t, base, lw=0.8, label="calibrated model" if which == "calibrated" else
               "plausible device (calibrated within tolerance)")
    if ext is not None:
        ax[0].plot(t, ext, lw=0.8, ls="--", label=f"extended ({chain})")
    ax[0].set_xlabel("t (s)")
    ax[0].set_ylabel(out)
    ax[0].legend(fontsize=8)
    ax[1].plot(t, y - base, lw=0.6, label=f"residual, {which} (RMS {report.baseline_rms:.3g})")
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
