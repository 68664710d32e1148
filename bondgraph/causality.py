"""Sequential causality assignment procedure (SCAP, Karnopp).

Order: fixed causality of sources; preferred (integral) causality of storage elements; then
resistors (resistance form preferred: the R takes flow and gives effort); then any bond left
(junction-to-junction loops), each choice propagated through junctions, transformers and
gyrators.  A storage port that propagation forces into non-preferred causality is in
*derivative* causality; a conflict at a source, junction, TF or GY is an error naming them.

Result: for every bond, the element that sets its effort (the causal stroke is drawn at the
other end, where the effort arrives).
"""
from __future__ import annotations

from collections import defaultdict, deque
from dataclasses import dataclass, field

from .elements import C, CField, GY, I, J0, J1, R, Se, Sf, TF
from .errors import CausalityError
from .graph import Bond, Model


class _Conflict(Exception):
    pass


@dataclass
class Causality:
    """Causal assignment of a model's bonds.

    ``effort_from[k]`` is ``(element, port)`` of the end of bond ``k`` that sets its effort.
    ``derivative`` lists storage ports in derivative causality, ``arbitrary`` the bonds
    (and resistors) whose causality was a free choice.
    """

    model: Model
    effort_from: dict[int, tuple[str, str]]
    derivative: list[tuple[str, str]] = field(default_factory=list)
    arbitrary: list[str] = field(default_factory=list)

    def sets_effort(self, bond: Bond, end: tuple[str, str]) -> bool:
        return self.effort_from[bond.index] == end

    def stroke_end(self, bond: Bond) -> tuple[str, str]:
        """The end with the causal stroke (where the effort is an input)."""
        return bond.head if self.effort_from[bond.index] == bond.tail else bond.tail

    def table(self) -> list[dict]:
        rows = []
        for b in self.model.bonds:
            setter = self.effort_from[b.index]
            other = b.head if setter == b.tail else b.tail
            rows.append({"bond": b.index, "from": _ep(b.tail), "to": _ep(b.head),
                         "effort_by": _ep(setter), "flow_by": _ep(other), "stroke_at": _ep(other)})
        return rows


def _ep(end):
    """Readable endpoint: 'elem' for one-ports and junction ports, 'elem.port' otherwise."""
    return end[0] if end[1] == "p" or end[1].startswith("#") else f"{end[0]}.{end[1]}"


def preferred_sets_effort(elem) -> bool | None:
    """Whether an element prefers to set the effort on its ports (None: no preference)."""
    if isinstance(elem, (C, CField)):
        return True
    if isinstance(elem, I):
        return False
    if isinstance(elem, R):
        return elem.form == "resistance"
    return None


class _Assigner:
    def __init__(self, model: Model):
        self.m = model
        self.by_bond = {b.index: b for b in model.bonds}
        self.incident: dict[str, list[tuple[int, tuple[str, str]]]] = defaultdict(list)
        for b in model.bonds:
            self.incident[b.tail[0]].append((b.index, b.tail))
            self.incident[b.head[0]].append((b.index, b.head))
        self.setter: dict[int, tuple[str, str]] = {}
        self.trail: list[int] = []

    # E(end): does the element at `end` of bond k set the effort? None when unassigned
    def sets(self, k: int, end) -> bool | None:
        s = self.setter.get(k)
        return None if s is None else s == end

    def other(self, k: int, end):
        b = self.by_bond[k]
        return b.head if end == b.tail else b.tail

    def assign(self, k: int, end, sets_effort: bool, queue: deque):
        setter = end if sets_effort else self.other(k, end)
        cur = self.setter.get(k)
        if cur is not None:
            if cur != setter:
                raise _Conflict(k)
            return
        self.setter[k] = setter
        self.trail.append(k)
        b = self.by_bond[k]
        queue.append(b.tail[0])
        queue.append(b.head[0])

    def undo(self, mark: int):
        while len(self.trail) > mark:
            del self.setter[self.trail.pop()]

    def propagate(self, queue: deque):
        while queue:
            name = queue.popleft()
            self.constrain(name, queue)

    def constrain(self, name: str, queue: deque):
        elem = self.m.elements[name]
        inc = self.incident[name]
        if isinstance(elem, (Se, Sf)):
            k, end = inc[0]
            self.assign(k, end, isinstance(elem, Se), queue)
        elif isinstance(elem, (TF, GY)):
            (k1, e1), (k2, e2) = sorted(inc, key=lambda ke: ke[1][1])
            s1, s2 = self.sets(k1, e1), self.sets(k2, e2)
            same = isinstance(elem, GY)
            if s1 is not None:
                self.assign(k2, e2, s1 if same else not s1, queue)
            elif s2 is not None:
                self.assign(k1, e1, s2 if same else not s2, queue)
        elif isinstance(elem, (J0, J1)):
            # 0-junction: exactly one bond brings the effort in (junction does not set it);
            # 1-junction: exactly one bond brings the flow in (junction sets its effort).
            strong = isinstance(elem, J1)
            states = [(k, end, self.sets(k, end)) for k, end in inc]
            n_strong = sum(1 for _, _, s in states if s is strong)
            unassigned = [(k, end) for k, end, s in states if s is None]
            if n_strong > 1:
                raise _Conflict(name)
            if n_strong == 1:
                for k, end in unassigned:
                    self.assign(k, end, not strong, queue)
            elif len(unassigned) == 1:
                k, end = unassigned[0]
                self.assign(k, end, strong, queue)
            elif not unassigned:
                raise _Conflict(name)

    def attempt(self, choices) -> bool:
        mark = len(self.trail)
        queue: deque = deque()
        try:
            for k, end, sets in choices:
                self.assign(k, end, sets, queue)
            self.propagate(queue)
            return True
        except _Conflict:
            self.undo(mark)
            return False


def assign_causality(model: Model) -> Causality:
    """Run SCAP on ``model`` (after its structural check); see the module docstring."""
    model.check()
    a = _Assigner(model)
    names = list(model.elements)
    for name in names:
        elem = model.elements[name]
        if isinstance(elem, (Se, Sf)):
            k, end = a.incident[name][0]
            if not a.attempt([(k, end, isinstance(elem, Se))]):
                raise CausalityError(_source_conflict(model, a, name))
    derivative: list[tuple[str, str]] = []
    arbitrary: list[str] = []
    for kinds in ((C, I, CField), (R,)):
        for name in names:
            elem = model.elements[name]
            if not isinstance(elem, kinds):
                continue
            pref = preferred_sets_effort(elem)
            for k, end in a.incident[name]:
                if a.setter.get(k) is None:
                    if not (a.attempt([(k, end, pref)]) or a.attempt([(k, end, not pref)])):
                        raise CausalityError(f"{model.name}: no causal assignment fits '{name}' "
                                             f"(conflict at its neighbours)")
                    if isinstance(elem, R):
                        arbitrary.append(name)
                if elem.is_storage and a.sets(k, end) != pref:
                    derivative.append(end)
    for b in model.bonds:
        if a.setter.get(b.index) is None:
            if not (a.attempt([(b.index, b.tail, True)]) or a.attempt([(b.index, b.tail, False)])):
                raise CausalityError(f"{model.name}: bond {_ep(b.tail)} → {_ep(b.head)} admits no causality")
            arbitrary.append(f"bond {b.index}")
    return Causality(model, dict(a.setter), derivative, arbitrary)


def _source_conflict(model: Model, a: _Assigner, source: str) -> str:
    """Explain a source conflict: name the source, its junction and the rival sources there."""
    k, end = a.incident[source][0]
    other = a.other(k, end)[0]
    rivals = sorted({a.other(kk, e)[0] for kk, e in a.incident[other]} - {source, other})
    rivals = [r for r in rivals if isinstance(model.elements[r], (Se, Sf))]
    elem = model.elements[source]
    what = "effort" if isinstance(elem, Se) else "flow"
    also = f" (so does {', '.join(repr(r) for r in rivals)})" if rivals else ""
    return (f"{model.name}: causal conflict: {elem.kind} '{source}' imposes the {what} at '{other}'{also}; "
            f"two sources fix the same variable: remove one or put an R, C or I between them")
