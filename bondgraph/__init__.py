"""bondgraph: acausal bond-graph modelling, simulation, identification and diagnosis.

Build a :class:`Model` from elements (:class:`Se`, :class:`Sf`, :class:`C`, :class:`I`,
:class:`R`, :class:`TF`, :class:`GY`, :class:`J0`, :class:`J1`, :class:`CField`) and
components, then :func:`derive` its equations, :func:`simulate` it, or linearise it.
"""
from .causality import Causality, assign_causality
from .elements import C, CField, GY, I, J0, J1, R, Se, Sf, TF
from .equations import Equations, derive
from .errors import (BondGraphError, CausalityError, DataError, ModelError, ParameterError,
                     SignalError, UsageError)
from .graph import Component, Model, Quantity
from .linearize import LinearModel, linearize
from .memory import MemoryOperator
from .parameters import Parameter
from .signals import Chirp, Constant, PiecewiseLinear, Ramp, Signal, Sine, Step, Triangle
from .simulate import Experiment, SimResult, Simulator, simulate

__all__ = [
    "Causality", "assign_causality", "C", "CField", "GY", "I", "J0", "J1", "R", "Se", "Sf", "TF",
    "Equations", "derive", "BondGraphError", "CausalityError", "DataError", "ModelError",
    "ParameterError", "SignalError", "UsageError", "Component", "Model", "Quantity", "LinearModel", "linearize", "MemoryOperator",
    "Parameter", "Chirp", "Constant", "PiecewiseLinear", "Ramp", "Signal", "Sine", "Step",
    "Triangle", "Experiment", "SimResult", "Simulator", "simulate",
]
