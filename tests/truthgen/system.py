"""Linear state equations written as physics, and their simulation (numpy/scipy only).

A truth device is a linear system ``dz/dt = A z + B V + E g`` with output ``y = C z``: ``V`` is
the drive (V), ``g`` a short vector of *pseudo-inputs* that carry the nonlinear or memory
effects (a hysteretic charge, a friction force, a cubic modal force, ...), computed from the
state once per step.  Equations are assembled from :class:`Lin` combinations, e.g.::

    eq = Equations()
    Q, x, v = eq.state("Q"), eq.state("x"), eq.state("v")
    F1 = K * (a * Q - x)
    eq.ddt(x, v)
    eq.ddt(v, (F1 - c * v) / M)

Simulation on a uniform grid of step ``h``: the drive is first-order-hold (linear between grid
points) and the linear part is integrated exactly (matrix exponential, Van Loan's block form);
the pseudo-inputs are held over a step (exponential Euler), or, for terms that ask for it,
extrapolated linearly from their last two values (exponential Adams–Bashforth of order 2: for
forces on lightly damped modes, where a held force would act as a spurious damping).  Holding
is right for laws on quickly relaxing states (the field of a voltage-driven stack): there the
state at the end of a step already carries the last value, and extrapolating would feed back.  Without pseudo-inputs the system is
diagonalised and run as first-order recursions by :func:`scipy.signal.lfilter` (fast and exact
for the same discretisation).  Memory operators are evaluated once per accepted step, so there
are no rejected steps to undo.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import expm
from scipy.signal import lfilter

DRIVE = "V"


class Lin:
    """A linear combination of named quantities (states, the drive ``V``, pseudo-inputs)."""

    __slots__ = ("terms",)

    def __init__(self, terms=None):
        self.terms = dict(terms or {})

    @staticmethod
    def of(value) -> "Lin":
        if isinstance(value, Lin):
            return value
        if value == 0:
            return Lin()
        raise TypeError(f"cannot combine a constant {value!r} with a linear combination")

    def __add__(self, other):
        other = Lin.of(other)
        out = dict(self.terms)
        for k, c in other.terms.items():
            out[k] = out.get(k, 0.0) + c
        return Lin(out)

    __radd__ = __add__

    def __neg__(self):
        return Lin({k: -c for k, c in self.terms.items()})

    def __sub__(self, other):
        return self + (-Lin.of(other))

    def __rsub__(self, other):
        return Lin.of(other) - self

    def __mul__(self, k):
        return Lin({n: c * float(k) for n, c in self.terms.items()})

    __rmul__ = __mul__

    def __truediv__(self, k):
        return self * (1.0 / float(k))


@dataclass
class Equations:
    """State equations ``d state/dt = Lin`` collected by name, in declaration order."""

    states: list = field(default_factory=list)
    rates: dict = field(default_factory=dict)

    def state(self, name: str) -> Lin:
        if name in self.states:
            raise ValueError(f"state {name!r} declared twice")
        self.states.append(name)
        self.rates[name] = Lin()
        return Lin({name: 1.0})

    def ddt(self, state: Lin, rate: Lin) -> None:
        (name,) = state.terms
        self.rates[name] = self.rates[name] + Lin.of(rate)

    def vector(self, combo: Lin) -> np.ndarray:
        """The coefficients of ``combo`` over the states (it must hold states only)."""
        out = np.zeros(len(self.states))
        for k, c in Lin.of(combo).terms.items():
            out[self.states.index(k)] = c
        return out

    def matrices(self, pseudo=()):
        """(A, B, E): rates over states, the drive and the pseudo-inputs ``pseudo``."""
        n = len(self.states)
        index = {s: i for i, s in enumerate(self.states)}
        cols = {DRIVE: 0, **{p: 1 + j for j, p in enumerate(pseudo)}}
        A = np.zeros((n, n))
        BE = np.zeros((n, 1 + len(pseudo)))
        for i, s in enumerate(self.states):
            for k, c in self.rates[s].terms.items():
                if k in index:
                    A[i, index[k]] += c
                elif k in cols:
                    BE[i, cols[k]] += c
                else:
                    raise KeyError(f"rate of {s!r} uses {k!r}: neither a state nor an input")
        return A, BE[:, 0], BE[:, 1:]


@dataclass
class System:
    """``dz/dt = A z + B V + E g(z, V)``, ``y = C z``; ``nonlinear`` computes ``g``."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    E: np.ndarray | None = None
    nonlinear: object | None = None  # callable (z, V) -> g, with reset(); evaluated once per step
    drive_map: object | None = None  # callable V(array) -> V(array): input-side memory effects

    @classmethod
    def build(cls, eq: Equations, output: Lin, terms=()):
        """From equations, an output combination and nonlinear terms (each with ``.pseudo``,
        the names of the pseudo-inputs it drives)."""
        pseudo = [p for term in terms for p in term.pseudo]
        A, B, E = eq.matrices(pseudo)
        nl = Nonlinear(list(terms), eq) if terms else None
        return cls(A, B, eq.vector(output), E if terms else None, nl)


class Nonlinear:
    """The pseudo-input vector g from a list of terms (each ``term(z, V) -> sequence``)."""

    def __init__(self, terms, eq: Equations):
        self.terms = terms
        for term in terms:
            term.bind(eq)
        self.extrapolated = np.array([float(term.extrapolate) for term in terms for _ in term.pseudo])

    def reset(self):
        for term in self.terms:
            term.reset()

    def __call__(self, z, v):
        if len(self.terms) == 1:
            return np.asarray(self.terms[0](z, v), dtype=float)
        return np.concatenate([np.asarray(term(z, v), dtype=float) for term in self.terms])


def discretize(A: np.ndarray, BE: np.ndarray, h: float):
    """Exact step ``h`` of ``dz/dt = A z + BE w`` with ``w`` linear over the step:
    ``z1 = Phi z0 + G0 w0 + G1 (w1 - w0)`` (Van Loan's block exponential)."""
    n, k = BE.shape
    M = np.zeros((n + 2 * k, n + 2 * k))
    M[:n, :n] = A * h
    M[:n, n : n + k] = BE * h
    M[n : n + k, n + k :] = np.eye(k)
    X = expm(M)
    return X[:n, :n], X[:n, n : n + k], X[:n, n + k :]


def static_state(A, B, v0: float) -> np.ndarray:
    """Equilibrium of ``A z + B v0 = 0`` (least squares if A is singular)."""
    if v0 == 0.0:
        return np.zeros(len(B))
    return np.linalg.lstsq(A, -B * v0, rcond=None)[0]


def simulate(system: System, V: np.ndarray, h: float, outputs=()) -> np.ndarray:
    """Output ``y`` (and the extra output rows ``outputs``, state-coefficient vectors) on the
    grid ``k*h`` for the drive samples ``V`` (first-order hold), from equilibrium at ``V[0]``.
    Returns an array of shape (1 + len(outputs), len(V))."""
    V = np.asarray(V, dtype=float)
    if system.drive_map is not None:
        V = system.drive_map(V)
    C = np.vstack([system.C, *outputs]) if outputs else system.C[None, :]
    if system.nonlinear is None:
        return _simulate_linear(system.A, system.B, C, V, h)
    return _simulate_etd(system, C, V, h)


def _simulate_linear(A, B, C, V, h):
    """Diagonalised: each mode is a first-order recursion with exact FOH gains (no matrix
    exponential: expm on a loaded machine costs more than the whole recursion)."""
    n = len(B)
    z0 = static_state(A, B, V[0])
    lam, W = np.linalg.eig(A)
    if np.linalg.cond(W) > 1e9:  # (near-)defective: step the state directly
        Phi, G0, G1 = discretize(A, B[:, None], h)
        return _loop_linear(Phi, G0[:, 0], G1[:, 0], C, z0, V)
    b = np.linalg.solve(W, B.astype(complex))
    x = lam * h
    small = np.abs(x) < 1e-6
    xs = np.where(small, 1.0, x)
    e = np.exp(x)
    g0 = b * h * np.where(small, 1 + x / 2, np.expm1(xs) / xs)
    g1 = b * h * np.where(small, 0.5 + x / 6, (np.expm1(xs) - xs) / xs**2)
    dV = V - V[0]
    CW = C @ W
    y = np.tile((C @ z0)[:, None], (1, len(V)))
    for i in range(n):
        # zeta[k] = e zeta[k-1] + g1 dV[k] + (g0 - g1) dV[k-1]; summed without BLAS, whose
        # threads stall on a loaded machine
        zeta = lfilter([g1[i], g0[i] - g1[i]], [1.0, -e[i]], dV)
        for j in range(C.shape[0]):
            y[j] += (CW[j, i] * zeta).real
    return y


def _loop_linear(Phi, g0, g1, C, z0, V):
    z = z0.copy()
    out = np.empty((C.shape[0], len(V)))
    out[:, 0] = C @ z
    for k in range(len(V) - 1):
        z = Phi @ z + g0 * V[k] + g1 * (V[k + 1] - V[k])
        out[:, k + 1] = C @ z
    return out


def _simulate_etd(system: System, C, V, h):
    A, B, E = system.A, system.B, system.E
    BE = np.column_stack([B, E])
    Phi, G0, G1 = discretize(A, BE, h)
    drive = np.outer(V[:-1], G0[:, 0]) + np.outer(np.diff(V), G1[:, 0])
    nl = system.nonlinear
    P0, P1 = G0[:, 1:], G1[:, 1:] * nl.extrapolated[None, :]
    nl.reset()
    z = static_state(A, B, V[0])
    g = nl(z, V[0])
    g_prev = g
    out = np.empty((C.shape[0], len(V)))
    out[:, 0] = C @ z
    for k in range(len(V) - 1):
        z = Phi @ z + drive[k] + P0 @ g + P1 @ (g - g_prev)
        g_prev = g
        g = nl(z, V[k + 1])
        out[:, k + 1] = C @ z
    return out
