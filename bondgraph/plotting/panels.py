"""Figures that a model file declares itself: curves in panels, and the numbers they show.

A model file's ``FIGURES`` maps a figure's name to a function that returns a :class:`Figure`
(see ``bondgraph figure``). The classes only hold numbers (no matplotlib until :func:`render`),
so a model file builds them without the ``plot`` extra and a test reads ``Figure.numbers``.

    Figure("response against field", [
        Panel([Curve(f, amp, "50 V"), Curve(f, amp2, "100 V")], xlabel="f (Hz)", ylabel="x (µm)"),
    ], numbers={"peak at 50 V (um)": 221.0})
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..support.errors import ModelError

SCALES = ("linear", "log", "symlog")


@dataclass
class Curve:
    """One line or set of markers: ``x``, ``y`` (equal lengths), a legend ``label`` (none if
    empty), a matplotlib format ``style`` ("-", "--", "o", "k:", ...) and a line ``width``.

    Parameters
    ----------
    x : array_like
        Abscissae (any unit; flattened to floats).
    y : array_like
        Ordinates, as many as ``x``.
    label : str, optional
        Legend entry ("" for none).
    style : str, optional
        matplotlib format string (default "-", a solid line).
    width : float, optional
        Line width, points.

    Raises
    ------
    ModelError
        ``x`` and ``y`` differ in length or are empty.
    """

    x: object
    y: object
    label: str = ""
    style: str = "-"
    width: float = 1.3

    def __post_init__(self):
        self.x = np.asarray(self.x, float).ravel()
        self.y = np.asarray(self.y, float).ravel()
        if self.x.size != self.y.size or self.x.size == 0:
            raise ModelError(f"figure curve {self.label!r}: x and y need the same, non-zero length")


@dataclass
class Panel:
    """One set of axes: ``curves``, a ``title``, axis labels, axis scales (linear, log, symlog),
    ``equal`` for equal x and y scales (an x-y path), and a ``note`` written in a corner.

    Parameters
    ----------
    curves : list of Curve
        The curves drawn on these axes.
    title : str, optional
        The panel's title.
    xlabel, ylabel : str, optional
        Axis labels, with units (e.g. "f (Hz)").
    xscale, yscale : {"linear", "log", "symlog"}, optional
        Axis scales.
    equal : bool, optional
        Equal x and y scales.
    note : str, optional
        Text written in the upper left corner (monospace).

    Raises
    ------
    ModelError
        An unknown scale, or a curve that is not a :class:`Curve`.
    """

    curves: list
    title: str = ""
    xlabel: str = ""
    ylabel: str = ""
    xscale: str = "linear"
    yscale: str = "linear"
    equal: bool = False
    note: str = ""

    def __post_init__(self):
        for s in (self.xscale, self.yscale):
            if s not in SCALES:
                raise ModelError(f"figure panel {self.title!r}: scale {s!r} is not one of {', '.join(SCALES)}")
        if not all(isinstance(c, Curve) for c in self.curves):
            raise ModelError(f"figure panel {self.title!r}: curves must be bondgraph.plotting.panels.Curve")


@dataclass
class Figure:
    """A figure: ``panels`` laid out ``columns`` wide, a ``title``, and ``numbers``, the values
    the figure shows that a reader (and a test) checks, name -> number.

    Parameters
    ----------
    title : str
        The figure's title.
    panels : list of Panel
        One or more panels, laid out row by row.
    numbers : dict of str to float, optional
        The values the figure shows, name (with unit) → number.
    columns : int, optional
        Panels per row (default 2).

    Raises
    ------
    ModelError
        No panel, or a panel that is not a :class:`Panel`.
    """

    title: str
    panels: list
    numbers: dict = field(default_factory=dict)
    columns: int = 2

    def __post_init__(self):
        if not self.panels or not all(isinstance(p, Panel) for p in self.panels):
            raise ModelError(f"figure {self.title!r}: give one or more bondgraph.plotting.panels.Panel")
        self.numbers = {str(k): float(v) for k, v in self.numbers.items()}


def render(figure: Figure, path: str) -> None:
    """Draw ``figure`` and write it atomically to ``path`` (png, pdf or svg).

    Parameters
    ----------
    figure : Figure
        The figure to draw.
    path : str
        The image to write.

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    from .figures import pyplot, save

    plt = pyplot()
    n = len(figure.panels)
    cols = max(1, min(figure.columns, n))
    rows = -(-n // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5.2 * cols, 3.9 * rows), squeeze=False)
    for ax, panel in zip(axes.ravel(), figure.panels):
        for c in panel.curves:
            ax.plot(c.x, c.y, c.style, lw=c.width, ms=4, label=c.label or None)
        ax.set_xscale(panel.xscale)
        ax.set_yscale(panel.yscale)
        ax.set_xlabel(panel.xlabel)
        ax.set_ylabel(panel.ylabel)
        ax.set_title(panel.title, fontsize=10)
        if panel.equal:
            ax.set_aspect("equal", adjustable="datalim")
        if any(c.label for c in panel.curves):
            ax.legend(fontsize=7)
        if panel.note:
            ax.text(0.02, 0.98, panel.note, transform=ax.transAxes, va="top", fontsize=7, family="monospace")
        ax.grid(alpha=0.3, which="both")
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    fig.suptitle(figure.title, fontsize=11)
    fig.tight_layout()
    save(fig, path)
