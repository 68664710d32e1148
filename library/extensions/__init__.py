"""Diagnosis candidates for piezoelectric actuators: the physical effects a piezo model may
miss beyond the framework's generic kinds, each rewriting the model with the element of the
papers that produces it.

* :mod:`.drive` — effects on the drive (rate-independent hysteresis as a Prandtl–Ishlinskii
  operator or a Bouc–Wen state, creep as a Kelvin–Voigt relaxation spectrum, saturating or
  expanding polarization, an RC or RLC input stage, a current-limited one): the linear core
  sees a transformed drive, so they are fitted exactly through its linear dynamics;
* :mod:`.circuit` — a series inductance in the drive's own electrical loop (its resistance
  refitted): a linear rewrite that keeps the actuator's current, fitted on the exact linear route;
* :mod:`.structure` — nonlinear laws of a piezo layer's own elements: a dipole that saturates
  with the field across it (role ``polarization``) and a stiffness that softens with the field
  (role ``stiffness``), inside the dynamics.

The framework's generic kinds (laws of every spring and damper, missing modes, a sensor drift:
:mod:`bondgraph.diagnosis`) are tried beside them.  They use only :mod:`bondgraph.diagnosis`'s
public contract and are registered through the entry point ``bondgraph.diagnosis`` →
``piezo = library.extensions:candidates``.
"""

from bondgraph.diagnosis.modes import OutputMode, ParallelMode

from .circuit import LoopInductance
from .drive import (
    InputBoucWen,
    InputCreep,
    InputCurrentLimit,
    InputExpansion,
    InputHysteresis,
    InputRC,
    InputRLC,
    InputSaturation,
)
from .structure import FieldStiffness, FrictionDamping, NonlinearDamping, PolarizationSaturation, StiffnessSoftening

__all__ = [
    "FieldStiffness",
    "FrictionDamping",
    "InputBoucWen",
    "InputCreep",
    "InputExpansion",
    "InputHysteresis",
    "InputRC",
    "InputRLC",
    "InputCurrentLimit",
    "InputSaturation",
    "LoopInductance",
    "NonlinearDamping",
    "OutputMode",
    "ParallelMode",
    "PolarizationSaturation",
    "StiffnessSoftening",
    "candidates",
]


def candidates() -> list:
    """The piezo candidate set (beside the framework's generic kinds)."""
    return [
        InputHysteresis(),
        InputBoucWen(),
        InputCreep(),
        InputSaturation(),
        InputExpansion(),
        InputRC(),
        InputRLC(),
        InputCurrentLimit(),
        LoopInductance(),
        PolarizationSaturation(),
        FieldStiffness(),
    ]
