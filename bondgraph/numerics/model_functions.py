"""The numeric functions of a model: their one calling convention and the record that holds them.

Every function has the signature ``f(t, x, u, du, th, mem, aux, out)`` — time (s), then
contiguous float64 arrays: states, inputs, input rates, parameters θ, operator memory, the
model's auxiliary data, and the output — and returns nothing.  One compiled integrator serves
every model because these functions are passed to it as first-class function values of
:data:`FUNCTION_TYPE`.

* ``rhs``    out = dx/dt
* ``output`` out = named outputs
* ``opin``   out = inputs of the memory operators (for step-reversal checks)
* ``commit`` advance the operators' memory to the current input (accepted steps only);
  out receives the operator inputs
* ``jac``    out = the local partials of the sparse Jacobian program (implicit solvers only;
  compiled on its own, see :func:`bondgraph.numerics.codegen.compile_jacobian`)

``mem`` is the operator memory and nothing else; ``aux`` is read-only data and scratch space a
route needs (the tape interpreter's program and registers; empty for generated code).
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np
from numba import types

ARGUMENTS = ("t", "x", "u", "du", "th", "mem", "aux", "out")
FUNCTION_TYPE = types.FunctionType(types.void(types.float64, *([types.float64[::1]] * (len(ARGUMENTS) - 1))))
#: the same signature as numba text, for ``@njit(SIGNATURE)`` in generated source
SIGNATURE = "void(float64, " + ", ".join(["float64[::1]"] * (len(ARGUMENTS) - 1)) + ")"


class ModelFunctions(NamedTuple):
    """The compiled functions of a model (see the module docstring), its array layout and aux data.

    Parameters
    ----------
    rhs : callable
        out = dx/dt.
    output : callable
        out = the named outputs.
    opin : callable
        out = the memory operators' inputs.
    commit : callable
        Advances the operators' memory (accepted steps only).
    layout : Layout
        Where every symbol lives in the arrays.
    aux : numpy.ndarray
        Read-only data and scratch space of the route.
    source : str, optional
        The generated module's file (numba route).
    route : {"numba", "tape"}, optional
        How the functions were compiled.
    """

    rhs: Callable
    output: Callable
    opin: Callable
    commit: Callable
    layout: object
    aux: np.ndarray
    source: str | None = None
    route: str = "numba"  # or "tape"

    @property
    def integrator_functions(self) -> tuple:
        """(rhs, output, opin, commit), in the order the integrator takes them."""
        return self.rhs, self.output, self.opin, self.commit
