"""``bondgraph check``: the model checked as a Modelica tool checks one: causality and units."""

from __future__ import annotations

from .registry import MODEL_ARGS, command, load


@command(
    "check",
    "check a model: its causal assignment (summary) and the units of every equation "
    "(each parameter's unit, the inferred ones marked); exit 2 with one line if they do not match",
    MODEL_ARGS,
)
def run(args):
    from ..equations.causality import assign_causality
    from ..equations.derivation import derive

    lm = load(args)
    caus = assign_causality(lm.model)
    eqs = derive(lm.model, caus, units=True)
    print("\n".join(summary(eqs) + eqs.units.lines()))


def summary(eqs) -> list[str]:
    """The causality summary: bonds, states, derivative causality, free choices, what the
    derivation had to solve."""
    m, caus = eqs.model, eqs.causality
    storage = sum(len(e.ports) for e in m.storage_elements())
    lines = [
        f"model: {m.name}",
        f"causality: {len(m.bonds)} bonds, {len(m.elements)} elements; {len(eqs.states)} states "
        f"({storage} storage ports, {len(caus.derivative)} in derivative causality); "
        f"{len(caus.arbitrary)} free choice(s)",
    ]
    lines += [f"  derivative causality: {e if p == 'p' else e + '.' + p}" for e, p in caus.derivative]
    lines += [f"  {_short(text)}" for text in eqs.eliminated + eqs.loops]
    return lines


def _short(text: str, keep: int = 6) -> str:
    """A loop or elimination note with its list of element names cut to the first few."""
    head, sep, rest = text.partition(" through ")
    names, paren, tail = rest.partition(" (")
    parts = names.split(", ")
    if not sep or not paren or len(parts) <= keep:
        return text
    return f"{head}{sep}{', '.join(parts[:keep])} and {len(parts) - keep} more{paren}{tail}"
