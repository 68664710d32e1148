"""Plausibility checks of measured piezo-actuator records, installed into
:func:`bondgraph.data.check_units` through the ``bondgraph.data_checks`` entry point."""

from __future__ import annotations

import numpy as np

#: A displacement column ``x`` reaching beyond this (metres) draws a warning: piezo actuators
#: (stacks, amplified stacks, benders) move micrometres to about a millimetre.
X_MAX_METRES = 1e-2


def displacement_in_metres(ds) -> list[str]:
    """A column ``x`` beyond :data:`X_MAX_METRES` is almost surely in µm (or mm), not metres."""
    x = ds.columns.get("x")
    if x is None:
        return []
    peak = float(np.max(np.abs(x)))
    if peak <= X_MAX_METRES:
        return []
    return [
        f"{ds.path or 'dataset'}: column 'x' reaches |x| = {peak:.4g}, which is {peak:.4g} m if in "
        f"metres; piezo displacements are micrometres, so 'x' is probably in µm: "
        f"scale it by 1e-6 (by 1e-3 if in mm)"
    ]
