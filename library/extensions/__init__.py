"""Diagnosis candidates for piezoelectric actuators: one per physical effect a piezo model
may miss, each rewriting the model with the element of the papers that produces it.

* :mod:`.drive` — effects on the drive (rate-independent hysteresis as a Prandtl–Ishlinskii
  operator or a Bouc–Wen state, creep as a Kelvin–Voigt relaxation spectrum, saturating or
  expanding polarization, an RC or RLC input stage): the linear core sees a transformed drive, so
  they are fitted exactly through its linear dynamics;
* :mod:`.circuit` — a series inductance in the drive's own electrical loop (its resistance
  refitted): a linear rewrite that keeps the actuator's current, fitted on the exact linear route;
* :mod:`.modes` — a mode the model lacks (a resonator on the output, or a compliant output
  stage on the element tagged ``inertia``): linear rewrites, fitted on the exact linear route;
* :mod:`.structure` — nonlinear laws of the elements tagged ``stiffness`` (amplitude- or
  field-dependent), ``damping`` and ``polarization`` (a dipole that saturates with the field
  across it, inside the dynamics), fitted on the exact Lur'e route or with the compiled
  integrator.

They use only :mod:`bondgraph.diagnosis`'s public contract and are registered through the
entry point ``bondgraph.diagnosis`` → ``piezo = library.extensions:candidates``.
"""

from .circuit import LoopInductance
from .drive import InputBoucWen, InputCreep, InputExpansion, InputHysteresis, InputRC, InputRLC, InputSaturation
from .modes import OutputMode, ParallelMode
from .structure import FieldStiffness, FrictionDamping, NonlinearDamping, PolarizationSaturation, StiffnessSoftening


def candidates() -> list:
    """The piezo candidate set."""
    return [
        InputHysteresis(),
        InputBoucWen(),
        InputCreep(),
        InputSaturation(),
        InputExpansion(),
        InputRC(),
        InputRLC(),
        LoopInductance(),
        ParallelMode(),
        OutputMode(),
        PolarizationSaturation(),
        StiffnessSoftening(),
        FieldStiffness(),
        NonlinearDamping(),
        NonlinearDamping(velocity=True),
        FrictionDamping(),
    ]
