"""Plots (optional extra ``plot``: matplotlib): simulations, fits, Bode diagrams, bond graphs
and diagnoses.  :mod:`.figures` holds what every plot shares (atomic saving, axis labels)."""

from .diagnosis import plot_diagnosis
from .figures import axis_label, pyplot, save, varies
from .graph import plot_bond_graph
from .panels import Curve, Figure, Panel
from .timeseries import plot_bode, plot_fit, plot_signals, plot_simulation

__all__ = [
    "Curve",
    "Figure",
    "Panel",
    "axis_label",
    "plot_bode",
    "plot_bond_graph",
    "plot_diagnosis",
    "plot_fit",
    "plot_signals",
    "plot_simulation",
    "pyplot",
    "save",
    "varies",
]
