"""The analytic Jacobian ∂(dx/dt)/∂x as a sparse straight-line program.

A model's equations are a straight-line program (``v_k = e_k(states, v_<k, ...)``, then the
rates).  The Jacobian is built from it in three parts, never as a dense symbolic matrix:

1. **Local partials.**  For every statement and every rate, the symbolic derivative with
   respect to each state or program variable it reads (one small derivative per
   dependency, sympy only at build time).
2. **Accumulation plan.**  The chain rule through the program, done numerically as a list of
   multiply-adds ``W[dst] += W[a]·W[b]`` over the partials' values (:func:`run_plan`, compiled).
   A program variable whose gradient would reach more than ``jacobian.hub_support`` states
   (the voltage node shared by every layer of a stack) is not substituted: it becomes an extra
   unknown, a *hub*, so the matrix keeps its sparsity.  The result is the augmented matrix

       J_aug = [[F_x, F_w], [G_x, G_w − I]]

   (rates F and hubs G, differentiated by states x and hubs w; G_w is strictly lower
   triangular, hubs being in program order), whose Schur complement is the Jacobian
   ``J = F_x + F_w·(I − G_w)⁻¹·G_x``.  Newton matrices ``c·I − J`` become ``c·D − J_aug``
   with ``D`` the identity on the state rows and zero on the hub rows: the same solution,
   the sparsity of the equations instead of the dense fill a shared node causes.
3. **Compilation.**  The partials are compiled like the model's other functions (numba
   source, or the tape interpreter for long programs) into ``jac(t, x, u, du, th, mem, aux,
   out)``, ``out`` receiving the partials' values.

Kinks.  Every Jacobian entry is the derivative *from the right* where the equations have a
kink: ``d|u|/du = +1`` at ``u = 0`` (the right subgradient; :class:`RightSign`), and the
derivatives of ``sign`` and ``Heaviside`` are 0.  Products such as ``u·|u|^(n−2)·sign(u)``
(the derivative of Bouc–Wen's ``|z|^(n−1)·z``) are merged into ``|u|^(n−1)`` before code is
generated, so a derivative that exists at 0 is evaluated there by its limit instead of
``0·∞``.  A memory operator's output ``h = H[v]`` has the slope of its output function at
frozen memory, the one-sided difference quotient ``(H(v + δ) − H(v))/δ`` with ``|δ| = 2⁻²⁶·
max(|v|, |memory|)`` (``1e-12`` at complete rest), taken in the direction the operator's
input last moved — from the right at rest: the one-sided slope of the branch the input
follows (a play operator's slope differs on the two sides of a turning point).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from ..equations.system import Equations
from ..support import config

ONE, MINUS_ONE, FIRST_PARTIAL = 0, 1, 2  # fixed slots of the work array


class RightSign(sp.Function):
    """``sign(u)`` with the value +1 at ``u = 0``: the right derivative of ``|u|``.

    It is never 0, so ``RightSign(u)**2`` is 1 everywhere.

    Parameters
    ----------
    arg : sympy.Expr
        u.
    """

    @classmethod
    def eval(cls, arg):
        """±1 for a number (+1 at 0); None (stay unevaluated) otherwise.

        Parameters
        ----------
        arg : sympy.Expr
            u.

        Returns
        -------
        sympy.Integer or None
            The value, or None for a symbolic argument.
        """
        if arg.is_Number:
            return sp.Integer(1) if arg >= 0 else sp.Integer(-1)
        return None

    def _eval_power(self, exponent):
        if exponent.is_Integer:
            return self if exponent % 2 else sp.Integer(1)
        return None


def _gradient(e: sp.Expr, wrt) -> dict:
    """{s: ∂e/∂s} for the symbols of ``wrt`` that ``e`` reads, each node of ``e`` visited once
    (a sum over many layers is not rescanned per symbol), with the kink conventions of the
    module docstring."""
    if e.is_Symbol:
        return {e: sp.Integer(1)} if e in wrt else {}
    if e.is_Atom:
        return {}
    if e.is_Add or e.is_Mul:
        parts = [(i, _gradient(a, wrt)) for i, a in enumerate(e.args)]
        terms: dict = {}
        for i, g in parts:
            for s, d in g.items():
                if e.is_Mul:
                    d = sp.Mul(*e.args[:i], d, *e.args[i + 1 :])
                terms.setdefault(s, []).append(d)
        return {s: sp.Add(*ds) for s, ds in terms.items()}
    if isinstance(e, (sp.sign, sp.Heaviside)):
        return {}
    if e.is_Pow and not (e.exp.free_symbols & wrt):
        b, p = e.args
        outer = p * b ** (p - 1)
    elif isinstance(e, sp.Abs):
        b, outer = e.args[0], RightSign(e.args[0])
    elif isinstance(e, sp.Function) and len(e.args) == 1:
        b, outer = e.args[0], e.fdiff(1)
    else:
        return {s: sp.diff(e, s).replace(sp.DiracDelta, lambda *a: sp.Integer(0)) for s in e.free_symbols & set(wrt)}
    return {s: outer * d for s, d in _gradient(b, wrt).items()}


def _merge_kinks(e: sp.Expr) -> sp.Expr:
    """``u^k·|u|^p·RightSign(u)^m`` → ``|u|^(p+k)·RightSign(u)^(m+k)`` in every product (equal
    for u ≠ 0, and the limit at u = 0 where the left side is 0·∞)."""
    if e.is_Atom:
        return e
    args = tuple(_merge_kinks(a) for a in e.args)
    if args != e.args:
        e = e.func(*args)
    if not e.is_Mul:
        return e
    groups: dict = {}
    for f in e.args:
        b, k = f.as_base_exp()
        if isinstance(b, sp.Abs):
            groups.setdefault(b.args[0], {}).setdefault("abs", []).append(f)
        elif k.is_Integer and not b.is_Number and not isinstance(b, RightSign):
            groups.setdefault(b, {}).setdefault("pow", []).append(f)
    rest = list(e.args)
    changed = False
    for u, g in groups.items():
        if "abs" in g and "pow" in g:
            k = sum(f.as_base_exp()[1] for f in g["pow"])
            p = sum(f.as_base_exp()[1] for f in g["abs"])
            for f in g["pow"] + g["abs"]:
                rest.remove(f)
            rest += [sp.Abs(u) ** (p + k), RightSign(u) ** k]
            changed = True
    return sp.Mul(*rest) if changed else e


def local_partials(expr: sp.Expr, wrt) -> dict:
    """{s: ∂expr/∂s} for the symbols ``wrt`` (a set) that ``expr`` reads, zero derivatives left out.

    Parameters
    ----------
    expr : sympy.Expr
        The expression.
    wrt : set of sympy.Symbol
        The symbols to differentiate by.

    Returns
    -------
    dict
        Symbol → derivative (with the kink conventions of the module docstring).
    """
    parts = {s: _merge_kinks(d) for s, d in _gradient(expr, wrt).items()}
    return {s: d for s, d in parts.items() if d != 0}


def slope_symbol(k: int) -> sp.Symbol:
    """The slope of operator ``k``'s output at frozen memory (computed by the generated code).

    Parameters
    ----------
    k : int
        The operator's index in ``eqs.operators``.

    Returns
    -------
    sympy.Symbol
        ``_slopeK``.
    """
    return sp.Symbol(f"_slope{k}", real=True)


@dataclass
class JacobianProgram:
    """The sparse Jacobian of a model (see the module docstring).

    ``partials`` are the symbolic local partials; ``jac`` writes their values.  The work array
    ``W`` holds ``[1, −1, partials..., accumulators...]``; ``plan`` rows ``(dst, a, b)`` mean
    ``W[dst] += W[a]·W[b]`` after the accumulators are zeroed; ``indptr``/``indices`` are the
    CSC pattern of ``J_aug`` (size ``n + n_hubs``, every diagonal entry present), its values
    ``W[slots]``; ``diagonal[i]`` the position of entry (i, i) in the CSC data.

    Parameters
    ----------
    n : int
        Number of states.
    hubs : list of str
        The program variables kept as extra unknowns.
    partials : list of sympy.Expr
        The symbolic local partials.
    slopes : list of int
        The memory operators whose slopes the partials read.
    plan : numpy.ndarray
        Rows (dst, a, b) of the accumulation ``W[dst] += W[a]·W[b]``.
    n_work : int
        Length of the work array.
    first_accumulator : int
        Index of the first accumulator in the work array.
    indptr : numpy.ndarray
        CSC column pointers of ``J_aug``.
    indices : numpy.ndarray
        CSC row indices of ``J_aug``.
    slots : numpy.ndarray
        Work-array slot of each CSC entry.
    diagonal : numpy.ndarray
        Position of each diagonal entry in the CSC data.
    constant : bool
        The Jacobian depends on no state, input or operator (computed once).
    """

    n: int
    hubs: list[str]
    partials: list[sp.Expr]
    slopes: list[int]
    plan: np.ndarray
    n_work: int
    first_accumulator: int
    indptr: np.ndarray
    indices: np.ndarray
    slots: np.ndarray
    diagonal: np.ndarray
    constant: bool

    @property
    def size(self) -> int:
        """Rows of ``J_aug``: states and hubs."""
        return self.n + len(self.hubs)


def build_program(eqs: Equations, hub_support: int | None = None) -> JacobianProgram:
    """The sparse Jacobian program of ``eqs`` (see the module docstring).

    Parameters
    ----------
    eqs : Equations
        The derived model.
    hub_support : int, optional
        A program variable whose gradient reaches more states becomes a hub (default: the
        setting ``jacobian.hub_support``).

    Returns
    -------
    JacobianProgram
        The program.
    """
    hub_support = config.get("jacobian.hub_support") if hub_support is None else hub_support
    xs = eqs.state_symbols
    n = len(xs)
    rates = [eqs.rates[s] for s in xs]
    program = eqs.needed(rates)[0]
    op_index = {ob.symbol: k for k, ob in enumerate(eqs.operators)}
    partials: list[sp.Expr] = []
    partial_slot: dict = {}
    slopes: list[int] = []

    def slot_of(d: sp.Expr) -> int:
        if d == 1:
            return ONE
        if d == -1:
            return MINUS_ONE
        if d not in partial_slot:
            partial_slot[d] = FIRST_PARTIAL + len(partials)
            partials.append(d)
        return partial_slot[d]

    grad: dict = {x: {i: ONE} for i, x in enumerate(xs)}  # symbol -> {basis column: slot}
    plan: list[tuple[int, int, int]] = []
    entries: dict = {}  # (row, column) -> slot of J_aug
    accumulators: list[int] = []  # accumulator slots, numbered after the partials at the end
    hubs: list[str] = []

    def terms_of(expr: sp.Expr, op_k: int | None) -> list[tuple[int, dict]]:
        out = []
        for s, d in local_partials(expr, grad.keys()).items():
            if op_k is not None:
                d = slope_symbol(op_k) * d
            out.append((slot_of(d), grad[s]))
        return out

    def accumulate(target: dict, key, terms_slot: int, g_slot: int) -> None:
        if key not in target:
            target[key] = -(len(accumulators) + 1)  # provisional (negative) slot
            accumulators.append(0)
        plan.append((target[key], terms_slot, g_slot))

    for st in program:
        op_k = op_index.get(st.var) if st.op is not None else None
        terms = terms_of(st.expr, op_k)
        if not terms:
            continue
        if op_k is not None:
            slopes.append(op_k)
        support = set().union(*(g.keys() for _, g in terms))
        if len(support) > hub_support:
            row = n + len(hubs)
            hubs.append(str(st.var))
            for p, g in terms:
                for col, gs in g.items():
                    accumulate(entries, (row, col), p, gs)
            accumulate(entries, (row, row), ONE, MINUS_ONE)
            grad[st.var] = {row: ONE}
        elif len(terms) == 1 and terms[0][0] == ONE:
            grad[st.var] = terms[0][1]  # a copy: the same gradient
        else:
            g_new: dict = {}
            for p, g in terms:
                for col, gs in g.items():
                    accumulate(g_new, col, p, gs)
            grad[st.var] = g_new
    for i, r in enumerate(rates):
        for p, g in terms_of(r, None):
            for col, gs in g.items():
                accumulate(entries, (i, col), p, gs)
    size = n + len(hubs)
    first = FIRST_PARTIAL + len(partials)
    n_work = first + len(accumulators) + 1  # the last slot stays 0: diagonal entries nobody writes
    zero = n_work - 1

    def final(slot: int) -> int:
        return first + (-slot - 1) if slot < 0 else slot

    plan_arr = np.array([(final(d), final(a), final(b)) for d, a, b in plan], np.int64).reshape(-1, 3)
    for i in range(size):
        entries.setdefault((i, i), zero)
    keys = sorted(entries, key=lambda rc: (rc[1], rc[0]))
    rows = np.array([r for r, _ in keys], np.int64)
    cols = np.array([c for _, c in keys], np.int64)
    indptr = np.zeros(size + 1, np.int64)
    np.add.at(indptr, cols + 1, 1)
    indptr = np.cumsum(indptr)
    slots = np.array([final(entries[k]) for k in keys], np.int64)
    diagonal = np.array([indptr[i] + int(np.flatnonzero(rows[indptr[i] : indptr[i + 1]] == i)[0]) for i in range(size)])
    varying = set(xs) | set(eqs.inputs) | set(eqs.input_rates) | {ob.symbol for ob in eqs.operators}
    depends = eqs.needed(partials)[1] if partials else set()
    constant = not (depends & varying) and not slopes
    return JacobianProgram(
        n, hubs, partials, slopes, plan_arr, n_work, first, indptr, rows, slots, diagonal.astype(np.int64), constant
    )
