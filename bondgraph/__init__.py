"""bondgraph: acausal bond-graph modelling, simulation, identification and diagnosis.

Build a :class:`Model` from elements (:class:`Se`, :class:`Sf`, :class:`C`, :class:`I`,
:class:`R`, :class:`TF`, :class:`GY`, :class:`J0`, :class:`J1`, :class:`CField`) and
components, then :func:`derive` its equations, :func:`simulate` it, or linearise it.  New
kinds of element subclass :class:`Element` (the element protocol, see ``docs/extending.md``).

The names below are imported on first use (PEP 562), so ``import bondgraph`` and the
``bondgraph --help`` command stay fast: sympy and the compiled integrator load only when
a name that needs them is touched.
"""
from __future__ import annotations

import importlib
import sys
import types

#: public name -> submodule that defines it
_EXPORTS = {
    "Causality": "causality", "assign_causality": "causality",
    "C": "elements", "CField": "elements", "GY": "elements", "I": "elements", "J0": "elements",
    "J1": "elements", "R": "elements", "Se": "elements", "Sf": "elements", "TF": "elements",
    "Element": "elements",
    "Equations": "equations", "derive": "equations",
    "BondGraphError": "errors", "CausalityError": "errors", "DataError": "errors", "ModelError": "errors",
    "ParameterError": "errors", "SignalError": "errors", "UsageError": "errors",
    "Component": "graph", "Model": "graph", "Quantity": "graph",
    "LinearModel": "linearize", "linearize": "linearize",
    "MemoryOperator": "memory",
    "Parameter": "parameters",
    "Chirp": "signals", "Constant": "signals", "PiecewiseLinear": "signals", "Ramp": "signals",
    "Signal": "signals", "Sine": "signals", "Step": "signals", "Triangle": "signals",
    "Experiment": "experiment", "SimResult": "simulate", "Simulator": "simulate", "simulate": "simulate",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'bondgraph' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))


class _Package(types.ModuleType):
    """Keeps ``bondgraph.simulate`` and ``bondgraph.linearize`` the functions: importing the
    submodules of the same name would otherwise rebind them to the modules."""

    def __setattr__(self, name, value):
        if _EXPORTS.get(name) == name and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
