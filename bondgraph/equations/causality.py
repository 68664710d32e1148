"""Sequential causality assignment procedure (SCAP, Karnopp) with backtracking.

Every element answers the causality questions of the element protocol
(:mod:`bondgraph.model.elements.base`): its causal class, preferred causality per port, whether it
allows a causality, and what the known causality of some of its ports forces on the others.

Order: the fixed causality of sources; then, one port at a time, the preferred causality of
storage ports (integral causality), then of resistors, then any bond left (junction-to-junction
loops), each choice propagated through the elements.  The order is canonical — by element name
(its last component first, so wrapping part of a graph in a component changes nothing) and
port — never the order in which elements were added.  A choice whose propagation hits a
conflict is replaced by the other causality, and if neither fits, earlier choices are revised
(depth-first search).  Storage ports whose causality is not the preferred one are in
*derivative* causality.  Choices in parts of the graph that no junction, transformer or
multiport joins cannot interact, so each such part is searched on its own.  A conflict is
reported only when no causal assignment exists, naming the elements where it arises.

Result: for every bond, the element that sets its effort (the causal stroke is drawn at the
other end, where the effort arrives).
"""

from __future__ import annotations

from collections import Counter, defaultdict, deque
from dataclasses import dataclass, field

from ..model.elements import DISSIPATION, FIXED, STORAGE, CausalConflict, Element
from ..model.graph import Bond, Model
from ..support import config
from ..support.errors import CausalityError


@dataclass
class Causality:
    """Causal assignment of a model's bonds, as :func:`assign_causality` returns it.

    Parameters
    ----------
    model : Model
        The model whose bonds are assigned.
    effort_from : dict of int to tuple of (str, str)
        ``effort_from[k]`` is ``(element, port)`` of the end of bond ``k`` that sets its
        effort; the causal stroke is at the other end.
    derivative : list of tuple of (str, str), optional
        The storage ports (``(element, port)``) in derivative causality.
    arbitrary : list of str, optional
        The bonds (``"bond k"``) and resistors whose causality was a free choice.
    """

    model: Model
    effort_from: dict[int, tuple[str, str]]
    derivative: list[tuple[str, str]] = field(default_factory=list)
    arbitrary: list[str] = field(default_factory=list)

    def sets_effort(self, bond: Bond, end: tuple[str, str]) -> bool:
        """Whether the element at ``end`` sets the effort of ``bond``.

        Parameters
        ----------
        bond : Bond
            A bond of the model.
        end : tuple of (str, str)
            ``(element, port)``, one end of ``bond``.

        Returns
        -------
        bool
            True if that end sets the effort (and so receives the flow).
        """
        return self.effort_from[bond.index] == end

    def stroke_end(self, bond: Bond) -> tuple[str, str]:
        """The end with the causal stroke (where the effort is an input).

        Parameters
        ----------
        bond : Bond
            A bond of the model.

        Returns
        -------
        tuple of (str, str)
            ``(element, port)`` of the end that receives the effort.
        """
        return bond.head if self.effort_from[bond.index] == bond.tail else bond.tail

    def _repr_svg_(self) -> str:
        """The bond graph with its half-arrows and causal strokes (notebook display)."""
        from ..model.drawing import svg

        return svg(self.model, self.stroke_end, {e for e, _ in self.derivative})

    def table(self) -> list[dict]:
        """The assignment as rows, one per bond, for printing.

        Returns
        -------
        list of dict
            Per bond: ``bond`` (its number), ``from`` and ``to`` (the half-arrow's tail and
            head: power flows from tail to head when positive), ``effort_by`` and
            ``flow_by`` (the ends that set effort and flow) and ``stroke_at``.
        """
        rows = []
        for b in self.model.bonds:
            setter = self.effort_from[b.index]
            other = b.head if setter == b.tail else b.tail
            rows.append(
                {
                    "bond": b.index,
                    "from": _ep(b.tail),
                    "to": _ep(b.head),
                    "effort_by": _ep(setter),
                    "flow_by": _ep(other),
                    "stroke_at": _ep(other),
                }
            )
        return rows


def _ep(end):
    """Readable endpoint: 'elem' for one-ports and junction ports, 'elem.port' otherwise."""
    return end[0] if end[1] == "p" or end[1].startswith("#") else f"{end[0]}.{end[1]}"


def name_key(name: str) -> tuple[str, str]:
    """Canonical order of element names: last component first (``sub.k1`` sorts as ``k1``)."""
    return name.rpartition(".")[2], name


class _Assigner:
    def __init__(self, model: Model):
        self.m = model
        self.elements = model.elements
        self.by_bond = {b.index: b for b in model.bonds}
        self.incident: dict[str, list[tuple[int, tuple[str, str]]]] = defaultdict(list)
        self.bond_of: dict[tuple[str, str], int] = {}
        for b in model.bonds:
            for end in (b.tail, b.head):
                self.incident[end[0]].append((b.index, end))
                self.bond_of[end] = b.index
        self.setter: dict[int, tuple[str, str]] = {}
        self.trail: list[int] = []
        self.conflicts: Counter = Counter()
        self.attempts = 0
        #: elements whose causality on one port constrains their others (junctions, TF, GY, ...)
        self.relays = {
            n for n, e in self.elements.items() if type(e).propagate_causality is not Element.propagate_causality
        }
        self.pending: set = set()

    def sets(self, k: int, end) -> bool | None:
        """Does the element at ``end`` of bond ``k`` set its effort? None when unassigned."""
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
                raise CausalConflict(end[0])
            return
        for e in (end, self.other(k, end)):
            if not self.elements[e[0]].allows_causality(e[1], setter == e):
                raise CausalConflict(e[0])
        self.setter[k] = setter
        self.trail.append(k)
        for name in (end[0], self.other(k, end)[0]):
            if name in self.relays and name not in self.pending:  # each relay queued once per wave
                self.pending.add(name)
                queue.append(name)

    def undo(self, mark: int):
        while len(self.trail) > mark:
            del self.setter[self.trail.pop()]

    def propagate(self, queue: deque):
        while queue:
            name = queue.popleft()
            self.pending.discard(name)
            known = {end[1]: self.sets(k, end) for k, end in self.incident[name]}
            for port, value in self.elements[name].propagate_causality(known).items():
                end = (name, port)
                self.assign(self.bond_of[end], end, bool(value), queue)

    def attempt(self, k: int, end, sets_effort: bool) -> bool:
        """Assign and propagate; on a conflict undo everything and return False."""
        self.attempts += 1
        mark = len(self.trail)
        queue: deque = deque()
        try:
            self.assign(k, end, sets_effort, queue)
            self.propagate(queue)
            return True
        except CausalConflict as exc:
            self.conflicts[exc.args[0] if exc.args else end[0]] += 1
            self.undo(mark)
            self.pending.clear()
            return False

    def search(self, decisions: list[tuple]) -> list[int]:
        """Depth-first search over ``decisions`` ``(bond, end, preferred, may_flip, label)`` in order:
        each gets its preferred value if the rest can still be assigned.  Returns the indices
        of the decisions that were choices (not forced by propagation)."""
        budget = self.attempts + config.get("causality.max_attempts") + 2 * len(decisions)
        stack: list[tuple[int, int, bool]] = []  # (decision index, trail mark, other value left)
        i = 0
        while i < len(decisions):
            if self.attempts > budget:
                raise CausalityError(self.conflict_message(decisions, gave_up=True))
            k, end, pref, may_flip, _ = decisions[i]
            if k in self.setter:
                i += 1
                continue
            mark = len(self.trail)
            if self.attempt(k, end, pref):
                stack.append((i, mark, may_flip))
                i += 1
                continue
            if may_flip and self.attempt(k, end, not pref):
                stack.append((i, mark, False))
                i += 1
                continue
            while stack:  # revise the latest choice that still has its other value
                j, m, left = stack.pop()
                self.undo(m)
                kj, endj, prefj = decisions[j][:3]
                if left and self.attempt(kj, endj, not prefj):
                    stack.append((j, m, False))
                    i = j + 1
                    break
            else:
                raise CausalityError(self.conflict_message(decisions))
        return [j for j, _, _ in stack]

    def conflict_message(self, decisions, gave_up: bool = False) -> str:
        names = [n for n, _ in self.conflicts.most_common(6)] or sorted({d[1][0] for d in decisions})[:6]
        where = ", ".join(repr(n) for n in names)
        if gave_up:
            return (
                f"{self.m.name}: no causal assignment found around {where} within "
                f"{config.get('causality.max_attempts')} attempts (setting causality.max_attempts); "
                f"add storage elements that decouple this part of the graph"
            )
        return (
            f"{self.m.name}: causal conflict around {where}: no causal assignment satisfies every junction, "
            f"transformer and gyrator there and the causality each element accepts (a law that cannot be "
            f"inverted refuses derivative causality); add a compliance or inertia between rigidly coupled "
            f"elements, or make their laws invertible"
        )

    def components(self) -> dict[int, int]:
        """Bond → part of the graph: bonds joined by an element with several bonds share a part."""
        parent = {k: k for k in self.by_bond}

        def root(k):
            while parent[k] != k:
                parent[k] = parent[parent[k]]
                k = parent[k]
            return k

        for inc in self.incident.values():
            for (k1, _), (k2, _) in zip(inc, inc[1:]):
                parent[root(k1)] = root(k2)
        return {k: root(k) for k in parent}


def assign_causality(model: Model) -> Causality:
    """Assign causality to every bond of ``model`` by SCAP (see the module docstring).

    Parameters
    ----------
    model : Model
        The acausal model; its structural check (:meth:`Model.check`) runs first.

    Returns
    -------
    Causality
        The element that sets each bond's effort, the storage ports in derivative causality
        and the free choices.

    Raises
    ------
    bondgraph.support.errors.ModelError
        If the model fails its structural check (an unbonded port, an unknown element).
    bondgraph.support.errors.CausalityError
        If no causal assignment exists (two sources imposing the same variable, a conflict
        no revision resolves); the message names the elements where it arises.
    """
    model.check()
    a = _Assigner(model)
    elements = model.elements
    by_class: dict[int, list] = defaultdict(list)  # causal class -> [(name, end, preferred)], canonical order
    for name in sorted(elements, key=name_key):
        elem = elements[name]
        for _, end in sorted(a.incident[name], key=lambda ke: ke[1][1]):
            pref = elem.preferred_causality(end[1])
            if pref is not None:
                by_class[elem.causal_class].append((name, end, bool(pref)))
    for name, end, pref in by_class[FIXED]:
        if not a.attempt(a.bond_of[end], end, pref):
            raise CausalityError(_source_conflict(model, a, name))
    decisions = [
        (a.bond_of[end], end, pref, True, name)  # (bond, end, preferred value, may flip, label)
        for cls in (STORAGE, DISSIPATION)
        for name, end, pref in by_class[cls]
    ]
    key = {end: _end_key(end) for b in model.bonds for end in (b.tail, b.head)}
    for b in sorted(model.bonds, key=lambda b: (*sorted((key[b.tail], key[b.head])), b.index)):
        decisions.append((b.index, min((b.tail, b.head), key=key.__getitem__), True, True, f"bond {b.index}"))
    part = a.components()
    by_part: dict[int, list] = defaultdict(list)
    for d in decisions:
        by_part[part[d[0]]].append(d)
    chosen = set()
    for group in by_part.values():
        chosen |= {group[j][4] for j in a.search(group)}
    arbitrary = [
        d[4]
        for d in decisions
        if d[4] in chosen and (d[4].startswith("bond ") or elements[d[4]].causal_class == DISSIPATION)
    ]
    derivative = [
        end
        for cls_ports in by_class.values()
        for name, end, pref in cls_ports
        if elements[name].is_storage and a.sets(a.bond_of[end], end) != pref
    ]
    derivative.sort(key=lambda end: (name_key(end[0]), end[1]))
    return Causality(model, dict(a.setter), derivative, arbitrary)


def _end_key(end) -> tuple:
    """Canonical key of a bond end (junction ports, named after bond numbers, count as one)."""
    return (*name_key(end[0]), "" if end[1].startswith("#") else end[1])


def _source_conflict(model: Model, a: _Assigner, source: str) -> str:
    """Explain a source conflict: name the source, its neighbour and the rival sources there."""
    k, end = a.incident[source][0]
    other = a.other(k, end)[0]
    rivals = sorted({a.other(kk, e)[0] for kk, e in a.incident[other]} - {source, other})
    rivals = [r for r in rivals if model.elements[r].causal_class == FIXED]
    elem = model.elements[source]
    what = "effort" if elem.preferred_causality(end[1]) else "flow"
    also = f" (so does {', '.join(repr(r) for r in rivals)})" if rivals else ""
    return (
        f"{model.name}: causal conflict: {elem.kind} '{source}' imposes the {what} at '{other}'{also}; "
        f"two sources fix the same variable: remove one or put an R, C or I between them"
    )
