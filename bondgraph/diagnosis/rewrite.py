"""Public helpers for rewriting a model's elements (what diagnosis candidates use instead of
the framework's internals): read an element's constitutive law as a function, change it,
evaluate its small-signal slope, add a term to an output."""

from __future__ import annotations

from typing import Callable, Mapping

import sympy as sp

from ..model.elements import J1, C, E, F, I, P, Q, R, Se
from ..model.graph import Model, Quantity, input_rate_symbol
from ..support.errors import ModelError
from .context import SENSOR_GAIN

_VAR = {C: Q, I: P}


def _variable(model: Model, element: str):
    el = model.elements.get(element)
    if isinstance(el, (C, I)):
        return el, _VAR[type(el)]
    if isinstance(el, R) and el.form == "resistance":
        return el, F
    if isinstance(el, R):
        return el, E
    raise ModelError(f"{model.name}: '{element}' is not a C, I or R element with a law")


def law(model: Model, element: str) -> Callable[[sp.Expr], sp.Expr]:
    """The element's law as a function of its own variable: C e(q), I f(p), R e(f) (or f(e)
    for a conductance law).

    Parameters
    ----------
    model : Model
        The model.
    element : str
        The element's name.

    Returns
    -------
    callable
        ``law(x)`` → the law's output (sympy expression) at the variable ``x``.

    Raises
    ------
    ModelError
        The element is not a C, I or R element with a law.
    """
    el, var = _variable(model, element)
    expr = el.law
    return lambda x: expr.xreplace({var: x})


def slope(model: Model, element: str, values: Mapping[str, float] | None = None) -> float:
    """d law / d variable at rest, with the model's parameter values (``values`` overriding):
    the element's variable, the inputs and any other element's variable in its law (a term
    with a partner, a law that moves with the drive) at 0.

    Parameters
    ----------
    model : Model
        The model.
    element : str
        The element's name.
    values : mapping of str to float, optional
        Parameter values overriding the model's.

    Returns
    -------
    float
        The small-signal slope (e.g. the stiffness 1/C of a C element, N/m for a spring).

    Raises
    ------
    ModelError
        The element is not a C, I or R element with a law, or its law uses a symbol that is
        neither a parameter, a port variable nor an input.
    """
    el, var = _variable(model, element)
    table = {s: v for s, v in model.parameter_table().items()}
    by_name = {str(s): s for s in table}
    for k, v in (values or {}).items():
        if k in by_name:
            table[by_name[k]] = v
    tangent = sp.sympify(sp.diff(el.law, var).xreplace(table))
    inputs = {i.symbol for i in model.inputs.values()}
    at_rest = inputs | {input_rate_symbol(u) for u in inputs} | {var}
    unknown = sorted(str(s) for s in tangent.free_symbols if not (s in at_rest or isinstance(s, Quantity)))
    if unknown:
        raise ModelError(f"{model.name}: the law of '{element}' uses {', '.join(unknown)}, not a parameter")
    return float(tangent.xreplace({s: 0 for s in tangent.free_symbols}))


def modify_law(model: Model, element: str, new: Callable[[sp.Expr, sp.Expr], sp.Expr]) -> None:
    """Replace the element's law by ``new(x, old(x))`` (same kind, name, ports and role).

    Parameters
    ----------
    model : Model
        The model, changed in place (use a copy).
    element : str
        The element's name.
    new : callable
        ``new(x, old)`` → the new law at the variable ``x``, given the old law's value there.

    Raises
    ------
    ModelError
        The element is not a C, I or R element with a law.
    """
    el, var = _variable(model, element)
    old = law(model, element)
    if isinstance(el, C):
        model.replace(C(element, law=lambda q: new(q, old(q)), q0=el.q0))
    elif isinstance(el, I):
        model.replace(I(element, law=lambda p: new(p, old(p)), p0=el.p0))
    elif el.form == "resistance":
        model.replace(R(element, law=lambda f: new(f, old(f))))
    else:
        model.replace(R(element, conductance_law=lambda e: new(e, old(e))))


def neighbours(model: Model, element: str) -> list[str]:
    """Elements bonded to the junction(s) the element is bonded to (the element excluded).

    Parameters
    ----------
    model : Model
        The model.
    element : str
        The element's name.

    Returns
    -------
    list of str
        Their names, in bond order, each once.
    """
    out = []
    for b in model.bonds_of(element):
        j = b.tail[0] if b.head[0] == element else b.head[0]
        for b2 in model.bonds_of(j):
            other = b2.tail[0] if b2.head[0] == j else b2.head[0]
            if other != element and other not in out:
                out.append(other)
    return out


def junction_of(model: Model, element: str) -> str:
    """The element (usually a junction) at the other end of a one-port element's bond.

    Parameters
    ----------
    model : Model
        The model.
    element : str
        A one-port element's name.

    Returns
    -------
    str
        The name of the element at the other end.

    Raises
    ------
    ModelError
        The element does not have exactly one bond.
    """
    bonds = model.bonds_of(element)
    if len(bonds) != 1:
        raise ModelError(f"{model.name}: '{element}' is not a one-port element with one bond")
    b = bonds[0]
    return b.tail[0] if b.head[0] == element else b.head[0]


def parameters_of(model: Model, element: str) -> list[str]:
    """Names of the model parameters in the element's law, sorted.

    Parameters
    ----------
    model : Model
        The model.
    element : str
        The element's name.

    Returns
    -------
    list of str
        The names (empty for an element without a law).
    """
    law = getattr(model.elements[element], "law", None)
    known = set(model.all_parameters())
    return sorted(str(s) for s in sp.sympify(law).free_symbols if str(s) in known) if law is not None else []


def drive_loop(model: Model, input: str) -> tuple[str, list[str]] | None:
    """(1-junction, resistances on it) of the loop driven by the effort source whose effort is
    ``input`` itself (e.g. a voltage source): the junction where the source, its series
    resistances and the load share one flow (the drive current of an electrical port); None
    when the model has no such source (an input that enters scaled, e.g. as modal forces).

    Parameters
    ----------
    model : Model
        The model.
    input : str
        The model input's name.

    Returns
    -------
    tuple of (str, list of str) or None
        The 1-junction's name and those of the resistances on it, or None.
    """
    symbol = model.inputs[input].symbol
    for name, el in model.elements.items():
        if isinstance(el, Se) and sp.sympify(el.effort) == symbol:
            j = junction_of(model, name)
            if isinstance(model.elements[j], J1):
                rs = [
                    n
                    for n in neighbours(model, name)
                    if isinstance(model.elements[n], R) and model.elements[n].form == "resistance"
                ]
                return j, rs
    return None


def add_to_output(model: Model, output: str, term) -> None:
    """output ← output + g·term, g the sensor gain (the parameter ``sensor.gain`` the diagnosis
    gives every model it extends), e.g. the displacement of an added mode.

    Parameters
    ----------
    model : Model
        The model to change (a copy); changed in place.
    output : str
        The compared output's name.
    term : sympy.Expr or float
        The term, in output units at sensor gain 1.
    """
    g = next(d.symbol for n, (d, _) in model.parameters.items() if n == SENSOR_GAIN)
    out = model.outputs[output]
    out.expr = out.expr + g * sp.sympify(term)
