"""C source of a model's equations: the straight-line program printed by sympy's C99 printer.

The generated ``bg_model.c`` holds the model's numeric functions with the calling convention of
:mod:`bondgraph.numerics.model_functions` (time, states, inputs, input rates, parameters θ,
operator memory, output array), laid out as the numba code of
:mod:`bondgraph.numerics.codegen` lays them out (same :func:`~bondgraph.numerics.codegen.layout`:
same statement order, θ vector and memory slices), so the two routes compute the same
numbers:

* ``bg_rhs`` dx/dt, ``bg_output`` the named outputs, ``bg_opin`` the operator inputs;
* ``bg_commit`` advances the operators' memory to the current input (accepted steps only);
* ``bg_init_memory`` the memory at rest (two passes, so cascaded operators settle, as
  :meth:`~bondgraph.numerics.simulate.Simulator.initial_memory` does);
* ``bg_x0`` the initial states from θ.

Memory operators are called through their C twins (:meth:`MemoryOperator.c_source`).  What
cannot be carried to C is refused with a :class:`~bondgraph.support.errors.ModelError` naming
the element: an operator without C source, a law with a function that has no C translation, a
law that reads an input's rate from an input the FMU receives from outside.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import sympy as sp
from sympy.printing.c import C99CodePrinter

from ..equations.system import Equations
from ..model.memory import CSource
from ..numerics.codegen import Layout, layout
from ..support.errors import ModelError

#: arguments of the generated model functions (see the module docstring)
ARGS = "double t, const double *x, const double *u, const double *du, const double *th"


class _CPrinter(C99CodePrinter):
    """C99 for scalar sympy expressions, with symbols mapped to array slots; numbers printed as
    the numba code prints them (shortest round-trip decimal), so both routes use the same
    constants."""

    def __init__(self, names: dict):
        super().__init__({"strict": True})
        self.math_macros = {}  # M_PI, M_SQRT2, ... are not standard C: numbers instead
        self.names = names

    def _print_Symbol(self, expr):
        try:
            return self.names[expr]
        except KeyError:
            raise _Unprintable(f"the symbol {expr} has no value in the exported code") from None

    _print_Dummy = _print_Symbol

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Rational(self, expr):
        return repr(float(expr))

    def _print_NumberSymbol(self, expr):
        return repr(float(expr))

    _print_Pi = _print_Exp1 = _print_NumberSymbol

    def _print_sign(self, expr):
        a = self._print(expr.args[0])
        return f"(({a}) != 0.0 ? copysign(1.0, {a}) : 0.0)"

    def _print_Heaviside(self, expr):
        a = self._print(expr.args[0])
        return f"(({a}) > 0.0 ? 1.0 : (({a}) < 0.0 ? 0.0 : 0.5))"

    def _print_not_supported(self, expr):
        raise _Unprintable(f"{type(expr).__name__} has no C translation")


class _Unprintable(Exception):
    pass


@dataclass
class ModelC:
    """The generated model code: ``source`` (bg_model.c) and its ``layout``.

    Parameters
    ----------
    source : str
        The C source of bg_model.c.
    layout : Layout
        Where every symbol lives in the C functions' arrays.
    """

    source: str
    layout: Layout


def refuse_input_rates(eqs: Equations, external: set[str]) -> None:
    """ModelError naming the element whose law reads the rate of an input the FMU receives from
    outside (FMI 2.0 model-exchange inputs carry no derivatives).

    Parameters
    ----------
    eqs : Equations
        The derived model.
    external : set of str
        The inputs the FMU receives from outside.

    Raises
    ------
    ModelError
        A law reads the rate of an external input (the message names the element).
    """
    rates = {du: str(u) for u, du in zip(eqs.inputs, eqs.input_rates) if str(u) in external}
    if not rates:
        return
    roots = [*eqs.rates.values(), *eqs.outputs.values(), *(s.x0 for s in eqs.states)]
    if not eqs.needed(roots)[1] & set(rates):
        return
    for where, expr in _laws(eqs):
        used = expr.free_symbols & set(rates)
        if used:
            name = rates[sorted(used, key=str)[0]]
            raise ModelError(
                f"{eqs.model.name}: element '{where}' uses the rate d{name}/dt of input {name}, which an FMI "
                f"input does not carry; export with the input driven inside the FMU (--input {name}=SIGNAL "
                f"or --experiment)"
            )


def _laws(eqs: Equations):
    """(element, expression) of every law of the equations: program statements, state rates,
    initial states, outputs."""
    for st in eqs.program:
        yield st.origin, st.expr
    for s in eqs.states:
        yield s.origin, eqs.rates[s.symbol]
        yield s.origin, s.x0
    for name, expr in eqs.outputs.items():
        yield f"output {name}", expr


def operator_sources(eqs: Equations) -> list[CSource]:
    """Each operator block's :class:`CSource`; ModelError naming the first operator without one.

    Parameters
    ----------
    eqs : Equations
        The derived model.

    Returns
    -------
    list of CSource
        One per memory operator, in the order of ``eqs.operators``.

    Raises
    ------
    ModelError
        An operator has no C source, or ``c_source()`` returned something else.
    """
    out = []
    for ob in eqs.operators:
        src = ob.operator.c_source()
        if src is None:
            kind = type(ob.operator)
            raise ModelError(
                f"{eqs.model.name}: memory operator '{ob.symbol}' ({kind.__qualname__}, kind '{ob.operator.kind}') "
                f"has no C source, so it cannot be exported; give the class a c_source() method "
                f"(see docs/fmi.md)"
            )
        if not isinstance(src, CSource):
            raise ModelError(
                f"{eqs.model.name}: memory operator '{ob.symbol}': c_source() must return a bondgraph.CSource, "
                f"got {type(src).__name__}"
            )
        out.append(src)
    return out


_HELPER_NAME = re.compile(r"\b([A-Za-z_]\w*)\s*\(")


def helpers(sources: list[CSource], names: list[str]) -> list[str]:
    """The operators' helper definitions, each text once; ModelError if one name carries two
    texts (``names``: the operators', for the message).

    Parameters
    ----------
    sources : list of CSource
        The operators' C sources.
    names : list of str
        The operators' names, in the same order.

    Returns
    -------
    list of str
        The helper definitions, first occurrence order.

    Raises
    ------
    ModelError
        Two operators define one helper name differently.
    """
    seen: dict[str, str] = {}
    out = []
    for who, src in zip(names, sources):
        for text in src.helpers:
            m = _HELPER_NAME.search(text)
            name = m.group(1) if m else text
            if name in seen and seen[name] != text:
                raise ModelError(
                    f"memory operator '{who}' defines the C helper {name} differently from another operator; "
                    f"give one of them another name"
                )
            if name not in seen:
                seen[name] = text
                out.append(text)
    return out


def model_source(eqs: Equations, header: str) -> ModelC:
    """``bg_model.c`` for ``eqs`` (see the module docstring); ``header`` is the comment on top.

    Parameters
    ----------
    eqs : Equations
        The derived model.
    header : str
        The comment on top of the file.

    Returns
    -------
    ModelC
        The source and its layout.

    Raises
    ------
    ModelError
        an operator without C source, or a law the C printer cannot print (naming the element).
    """
    lay = layout(eqs)
    pr = _CPrinter(lay.names)
    sources = operator_sources(eqs)
    op_index = {ob.symbol: k for k, ob in enumerate(eqs.operators)}

    def c(expr, where: str) -> str:
        try:
            return pr.doprint(expr)
        except _Unprintable as exc:
            raise ModelError(f"{eqs.model.name}: element '{where}' cannot be exported to C: {exc}") from None

    def slices(j: int) -> str:
        (a, b), (p, q) = lay.mem_slices[j], lay.prm_slices[j]
        return f"mem + {a}, {b - a}, th + {p}, {q - p}"

    def program(targets: list[sp.Expr]) -> list[str]:
        lines = []
        for st in eqs.needed(targets)[0]:
            rhs = c(st.expr, st.origin)
            if st.op is not None:
                rhs = f"op{op_index[st.var]}_output({rhs}, {slices(op_index[st.var])})"
            lines.append(f"    const double {lay.names[st.var]} = {rhs};")
        return lines

    def function(name: str, mem: str, targets: list[tuple[sp.Expr, str]], tail: list[str] | None = None) -> list[str]:
        body = program([e for e, _ in targets])
        body += [f"    out[{i}] = {c(e, where)};" for i, (e, where) in enumerate(targets)]
        head = f"void {name}({ARGS}, {mem} *mem, double *out)"
        return [
            "",
            head,
            "{",
            "    (void)t; (void)x; (void)u; (void)du; (void)th; (void)mem;",
            *body,
            *(tail or []),
            "}",
        ]

    states = eqs.state_symbols
    origin = {s.symbol: s.origin for s in eqs.states}
    ops = [st for st in eqs.program if st.op is not None]
    lines = [header, "#include <math.h>", '#include "bg_model.h"', ""]
    lines += helpers(sources, [str(ob.symbol) for ob in eqs.operators])
    for k, (ob, src) in enumerate(zip(eqs.operators, sources)):
        lines += operator_functions(
            k, f"{ob.symbol}: {type(ob.operator).__module__}.{type(ob.operator).__qualname__}", src
        )
    lines += function("bg_rhs", "const double", [(eqs.rates[s], origin[s]) for s in states])
    lines += function("bg_output", "const double", [(e, f"output {n}") for n, e in eqs.outputs.items()])
    lines += function("bg_opin", "const double", [(st.expr, st.origin) for st in ops])
    kernel = [op_index[st.var] for st in ops]  # the j-th operator input feeds operator kernel[j]
    commits = [f"    op{k}_commit(out[{j}], {slices(k)});" for j, k in enumerate(kernel)]
    lines += function("bg_commit", "double", [(st.expr, st.origin) for st in ops], commits)
    x0 = [f"    x[{i}] = {c(s.x0, s.origin)};" for i, s in enumerate(eqs.states)]
    lines += ["", "void bg_x0(const double *th, double *x)", "{", "    (void)th; (void)x;", *x0, "}"]
    init = [f"        op{k}_initial(vin[{j}], {slices(k)});" for j, k in enumerate(kernel)]
    lines += [
        "",
        f"void bg_init_memory({ARGS}, double *mem)",
        "{",
        "    double vin[BG_NOPS1] = {0.0};",
        "    for (int pass = 0; pass < 2; pass++) {  /* the second lets cascaded operators settle */",
        *init,
        "        bg_opin(t, x, u, du, th, mem, vin);",
        "    }",
        "}",
    ]
    return ModelC("\n".join(lines) + "\n", lay)


def operator_functions(k: int, title: str, src: CSource) -> list[str]:
    """C lines of ``op<k>_output``, ``op<k>_commit`` and ``op<k>_initial`` from ``src``.

    Parameters
    ----------
    k : int
        The operator's index.
    title : str
        What the comment above the functions calls it.
    src : CSource
        Its C source.

    Returns
    -------
    list of str
        The lines, without line ends.
    """
    sig = "int n_mem, const double *prm, int n_prm"
    unused = "    (void)mem; (void)n_mem; (void)prm; (void)n_prm;"
    return [
        "",
        comment(f"operator {title}"),
        f"static double op{k}_output(double v, const double *mem, {sig})",
        "{",
        "    (void)v;" + unused,
        _indent(src.output),
        "}",
        f"static void op{k}_commit(double v, double *mem, {sig})",
        "{",
        "    (void)v;" + unused,
        _indent(src.commit),
        "}",
        f"static void op{k}_initial(double v0, double *mem, {sig})",
        "{",
        "    (void)v0;" + unused,
        _indent(src.initial),
        "}",
    ]


def comment(text: str) -> str:
    """``text`` as a one-line C comment (a ``*/`` inside it is broken up).

    Parameters
    ----------
    text : str
        The comment's text (whitespace is collapsed).

    Returns
    -------
    str
        ``/* text */``.
    """
    return "/* " + " ".join(text.replace("*/", "* /").split()) + " */"


def _indent(body: str) -> str:
    return "\n".join("    " + ln if ln.strip() else "" for ln in body.strip("\n").splitlines())
