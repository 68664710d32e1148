"""Equation printouts as an engineer writes them: text, LaTeX or Markdown.

Sections: parameters, constitutive relations per element, the causal assignment (which end
of each bond sets the effort, where the stroke sits), eliminations (derivative causality) and
algebraic loops, memory operators, the state equations x' = f(x, u, θ) fully substituted,
and the outputs.

Fully substituted equations of big graphs repeat the same sub-expressions many times (every
layer of an N-layer stack sees the common electrode's voltage, a sum over all N layers), so
the printers remember the text of every sub-expression they have printed: the printout of
a 200-layer stack costs as much as its unique sub-expressions, not as its 4 MB of text.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.latex import LatexPrinter
from sympy.printing.str import StrPrinter

from ..model.graph import Model
from .system import Equations

FORMATS = ("text", "latex", "markdown")


class _Memo:
    """Printer mixin: each distinct sub-expression is printed once (keyed by the expression,
    so the text is exactly what the plain sympy printer gives)."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self._memo: dict = {}

    def _print(self, expr, **kw):
        if kw or not isinstance(expr, sp.Basic):
            return super()._print(expr, **kw)
        text = self._memo.get(expr)
        if text is None:
            text = self._memo[expr] = super()._print(expr)
        return text


class _Str(_Memo, StrPrinter):
    pass


class _Latex(_Memo, LatexPrinter):
    pass


def _fmt_value(v) -> str:
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _rows_parameters(model: Model):
    rows = []
    for name, decl in model.all_parameters().items():
        rows.append((name, _fmt_value(model.values.get(name, decl.default)), decl.unit, decl.doc))
    return rows


def _rows_elements(eqs: Equations):
    m = eqs.model
    bonds: dict[str, list[int]] = {name: [] for name in m.elements}
    for b in m.bonds:  # one pass (bonds_of per element is quadratic in big graphs)
        for end in {b.tail[0], b.head[0]}:
            bonds[end].append(b.index)
    return [(name, el.kind, el.describe(), ", ".join(map(str, sorted(bonds[name])))) for name, el in m.elements.items()]


def _rows_causality(eqs: Equations):
    rows = []
    for r in eqs.causality.table():
        e, f = eqs.bond_vars[r["bond"]]
        rows.append(
            (str(r["bond"]), f"{r['from']} → {r['to']}", r["effort_by"], r["flow_by"], r["stroke_at"], f"{e}, {f}")
        )
    return rows


def _derivative(sym: sp.Symbol, fmt: str) -> str:
    if fmt == "text":
        return f"d{sym}/dt"
    return r"\frac{d}{dt}" + sp.latex(sym)


def _substituted(eqs: Equations):
    """State equations, outputs and operator inputs, fully substituted in one pass over the
    program (the same as ``state_equations()``, ``output_equations()``, ``operator_inputs()``)."""
    ops = {st.var: st.expr for st in eqs.program if st.op is not None}
    both = eqs.substituted(
        {
            **{("x", k): v for k, v in eqs.rates.items()},
            **{("y", k): v for k, v in eqs.outputs.items()},
            **{("h", k): v for k, v in ops.items()},
        }
    )
    return (
        {k: both[("x", k)] for k in eqs.rates},
        {k: both[("y", k)] for k in eqs.outputs},
        {k: both[("h", k)] for k in ops},
    )


def render(eqs: Equations, fmt: str = "text") -> str:
    """The complete printout of ``eqs`` in ``fmt`` (text, latex or markdown)."""
    if fmt not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}")
    sstr, latex = _Str().doprint, _Latex().doprint
    m = eqs.model
    states, outputs, op_inputs = _substituted(eqs)
    if fmt == "latex":
        return _latex(eqs, states, outputs, op_inputs, latex)
    md = fmt == "markdown"
    out: list[str] = []

    def head(title):
        out.append("")
        out.append(f"## {title}" if md else f"{title}\n{'-' * len(title)}")

    def table(header, rows):
        if md:
            out.append("| " + " | ".join(header) + " |")
            out.append("|" + "---|" * len(header))
            for r in rows:
                out.append("| " + " | ".join(str(c).replace("|", "\\|") for c in r) + " |")
        else:
            widths = [
                max(len(str(h)), *(len(str(r[i])) for r in rows)) if rows else len(h) for i, h in enumerate(header)
            ]
            out.append("  ".join(str(h).ljust(w) for h, w in zip(header, widths)).rstrip())
            for r in rows:
                out.append("  ".join(str(c).ljust(w) for c, w in zip(r, widths)).rstrip())

    def eq(lhs, rhs):
        out.append(f"- ${lhs} = {latex(rhs)}$" if md else f"  {lhs} = {sstr(rhs)}")

    out.append(f"# {m.name}" if md else f"{m.name}\n{'=' * len(m.name)}")
    if m.doc:
        out.append(m.doc.strip())
    head("Parameters")
    table(("name", "value", "unit", "meaning"), _rows_parameters(m))
    head("Elements and constitutive relations")
    table(("element", "kind", "relation (power-in port variables)", "bonds"), _rows_elements(eqs))
    head("Causal assignment")
    table(("bond", "half-arrow", "effort set by", "flow set by", "stroke at", "variables"), _rows_causality(eqs))
    if eqs.causality.arbitrary:
        out.append(f"Free causal choices: {', '.join(eqs.causality.arbitrary)}")
    if eqs.eliminated or eqs.loops:
        head("Derivative causality and algebraic loops")
        for note in eqs.eliminated + eqs.loops:
            out.append(f"- {note}" if md else f"  * {note}")
    if eqs.operators:
        head("Memory operators")
        for ob in eqs.operators:
            lhs = f"{ob.symbol}" if not md else latex(ob.symbol)
            rhs = op_inputs[ob.symbol]
            if md:
                out.append(f"- ${lhs} = \\mathcal{{H}}_{{\\mathrm{{{ob.operator.kind}}}}}[{latex(rhs)}]$")
            else:
                out.append(f"  {lhs} = {ob.operator.kind}[{sstr(rhs)}]")
    head(f"State equations ({len(states)} states)")
    for s, rhs in states.items():
        eq(_derivative(s, "latex" if md else "text"), rhs)
    head("Outputs")
    for name, rhs in outputs.items():
        eq(latex(sp.Symbol(name)) if md else name, rhs)
    return "\n".join(out).strip() + "\n"


def _latex(eqs, states, outputs, op_inputs, latex) -> str:
    m = eqs.model
    lines = [f"% {m.name}: state equations generated by bondgraph", r"\begin{align}"]
    for s, rhs in states.items():
        lines.append(f"  {_derivative(s, 'latex')} &= {latex(rhs)} \\\\")
    for ob in eqs.operators:
        lines.append(
            f"  {latex(ob.symbol)} &= \\mathcal{{H}}_{{\\mathrm{{{ob.operator.kind}}}}}"
            f"[{latex(op_inputs[ob.symbol])}] \\\\"
        )
    for name, rhs in outputs.items():
        lines.append(f"  {latex(sp.Symbol(name))} &= {latex(rhs)} \\\\")
    if lines[-1].endswith(" \\\\"):
        lines[-1] = lines[-1][:-3]
    lines.append(r"\end{align}")
    return "\n".join(lines) + "\n"
