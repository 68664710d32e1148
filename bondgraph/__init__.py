"""bondgraph: acausal bond-graph modelling, simulation, identification and diagnosis.

Build a :class:`Model` from elements (:class:`Se`, :class:`Sf`, :class:`C`, :class:`I`,
:class:`R`, :class:`TF`, :class:`GY`, :class:`J0`, :class:`J1`, :class:`CField`) and
components, then :func:`derive` its equations, :func:`simulate` it, or :func:`linearize` it.
New kinds of element subclass :class:`Element` (the element protocol, see
``docs/extending.md``).

The package is laid out as the pipeline a model goes through, each stage a subpackage that
imports only from the stages before it:

``support`` (errors, settings, progress, interrupts, atomic files) → ``data`` (measured
records) → ``model`` (elements, the graph, parameters, signals, model files) → ``equations``
(causality, derivation, printing) → ``numerics`` (code generation, integrators, simulation)
→ ``linear`` (linearisation, LTI filters) → ``fit`` (identification, compensation) →
``diagnosis`` → ``plotting`` → ``batch`` → ``cli``.

The names below are imported on first use (PEP 562), so ``import bondgraph`` and the
``bondgraph --help`` command stay fast: sympy and the compiled integrator load only when a
name that needs them is touched.
"""

from __future__ import annotations

import importlib

#: public name -> the module that defines it
_EXPORTS = {
    "BondGraphError": "support.errors",
    "CausalityError": "support.errors",
    "DataError": "support.errors",
    "ModelError": "support.errors",
    "ParameterError": "support.errors",
    "SignalError": "support.errors",
    "UsageError": "support.errors",
    "C": "model.elements",
    "CField": "model.elements",
    "GY": "model.elements",
    "I": "model.elements",
    "J0": "model.elements",
    "J1": "model.elements",
    "R": "model.elements",
    "Se": "model.elements",
    "Sf": "model.elements",
    "TF": "model.elements",
    "Element": "model.elements",
    "Component": "model.graph",
    "Model": "model.graph",
    "Quantity": "model.graph",
    "MemoryOperator": "model.memory",
    "CSource": "model.memory",
    "Parameter": "model.parameters",
    "Chirp": "model.signals",
    "Constant": "model.signals",
    "PiecewiseLinear": "model.signals",
    "Ramp": "model.signals",
    "Signal": "model.signals",
    "Sine": "model.signals",
    "Step": "model.signals",
    "Triangle": "model.signals",
    "Experiment": "model.experiment",
    "Causality": "equations.causality",
    "assign_causality": "equations.causality",
    "Equations": "equations.system",
    "derive": "equations.derivation",
    "SimResult": "numerics.simulate",
    "Simulator": "numerics.simulate",
    "simulate": "numerics.simulate",
    "LinearModel": "linear.linearize",
    "linearize": "linear.linearize",
}

#: public module -> its place in the package (``from bondgraph import config``)
_MODULES = {"config": "support.config"}

__all__ = list(_EXPORTS) + list(_MODULES)


def __getattr__(name: str):
    if name in _MODULES:
        value = importlib.import_module(f".{_MODULES[name]}", __name__)
    elif name in _EXPORTS:
        value = getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    else:
        raise AttributeError(f"module 'bondgraph' has no attribute {name!r}")
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
