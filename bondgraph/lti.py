"""Exact simulation of linear time-invariant models on a uniform time grid.

A model whose state equations are linear in its states and inputs is x' = A(θ)x + B(θ)u,
y = C(θ)x + D(θ)u.  The matrices come from the symbolic Jacobians of the straight-line
program (compiled to numeric functions of θ once); the response to an input that is linear
between samples (exactly what a sampled data column is) follows from the first-order-hold
discretisation (``scipy.signal.cont2discrete``, method ``foh``) and a compiled recursion, with
no integration error and a cost of a few n² flops per sample.  Identification uses it for the
nominal model and for every extension that acts on the input or adds a parallel branch.
"""
from __future__ import annotations

import numpy as np
import sympy as sp
from numba import njit
from scipy.linalg import expm

from .equations import Equations
from .errors import UsageError, did_you_mean


@njit(cache=True)
def recursion(Ad, Bd, Cd, Dd, x0, U, Y):
    """x[k+1] = Ad x[k] + Bd u[k], y[k] = Cd x[k] + Dd u[k] for every column of U (one input each)."""
    n = Ad.shape[0]
    N, m = U.shape
    x = np.empty(n)
    xn = np.empty(n)
    for j in range(m):
        for i in range(n):
            x[i] = x0[i]
        for k in range(N):
            u = U[k, j]
            acc = Dd[0, 0] * u
            for i in range(n):
                acc += Cd[0, i] * x[i]
            Y[k, j] = acc
            for i in range(n):
                s = Bd[i, 0] * u
                for l in range(n):
                    s += Ad[i, l] * x[l]
                xn[i] = s
            for i in range(n):
                x[i] = xn[i]


class LTI:
    """The (A, B, C, D) of one input → one output of a model, as numeric functions of θ."""

    def __init__(self, eqs: Equations, input: str = "V", output: str = "x"):
        names = [str(u) for u in eqs.inputs]
        if input not in names:
            raise UsageError(did_you_mean(input, names, "input"))
        if output not in eqs.outputs:
            raise UsageError(did_you_mean(output, list(eqs.outputs), "output"))
        self.eqs = eqs
        u = eqs.inputs[names.index(input)]
        xs = eqs.state_symbols
        rates = [eqs.rates[s] for s in xs]
        y = [eqs.outputs[output]]
        mats = [eqs.jacobian(rates, xs), eqs.jacobian(rates, [u]), eqs.jacobian(y, xs), eqs.jacobian(y, [u])]
        moving = set(xs) | set(eqs.inputs) | set(eqs.input_rates) | {ob.symbol for ob in eqs.operators}
        self.exact = not eqs.operators and all(
            not (e.free_symbols & moving) for M in mats for e in M) and self._affine(rates + y, xs, eqs.inputs)
        others = [s for s in eqs.inputs if s != u]
        zero = {s: 0 for s in list(moving - set(xs) - {u}) + others}
        mats = [M.xreplace(zero) for M in mats]
        self._fn = sp.lambdify([eqs.params], mats, modules="numpy", cse=True)
        self.n = len(xs)

    def _affine(self, exprs, xs, us) -> bool:
        """True when the rates and output are affine in states and inputs (so the Jacobians say everything)."""
        full = self.eqs.substituted({i: e for i, e in enumerate(exprs)})
        syms = list(xs) + list(us)
        for e in full.values():
            try:
                poly = sp.Poly(e, *syms) if syms else None
            except sp.PolynomialError:
                return False
            if poly is not None and poly.total_degree() > 1:
                return False
        return True

    def matrices(self, th: np.ndarray):
        A, B, C, D = (np.array(M, dtype=float).reshape(shape) for M, shape in
                      zip(self._fn(np.asarray(th, float)), [(self.n, self.n), (self.n, 1), (1, self.n), (1, 1)]))
        return A, B, C, D

    def response(self, th: np.ndarray, dt: float, U: np.ndarray, x0: np.ndarray | None = None) -> np.ndarray:
        """Output for each column of ``U`` (inputs sampled every ``dt`` s, linear in between),
        from the state ``x0`` (default rest)."""
        U = np.asarray(U, float)
        U = np.ascontiguousarray(U.reshape(-1, 1) if U.ndim == 1 else U)
        A, B, C, D = self.matrices(th)
        if self.n == 0:
            return D[0, 0] * U
        Phi, Gam, G1 = foh(A, B, dt)
        x0 = np.zeros(self.n) if x0 is None else np.asarray(x0, float)
        Y = np.empty_like(U)
        Cd = np.ascontiguousarray(C)
        Dd = D + C @ G1
        for j in range(U.shape[1]):
            col = np.ascontiguousarray(U[:, j:j + 1])
            out = np.empty_like(col)
            # the discrete state is ξ = x − Γ1·u (as in scipy.signal.cont2discrete, method 'foh')
            recursion(Phi, Gam, Cd, Dd, x0 - G1[:, 0] * col[0, 0], col, out)
            Y[:, j] = out[:, 0]
        return Y


def foh(A: np.ndarray, B: np.ndarray, dt: float):
    """First-order-hold discretisation: (Φ, Γ, Γ1) with ξ[k+1] = Φξ[k] + Γu[k], x = ξ + Γ1·u.

    The block-exponential construction of ``scipy.signal.cont2discrete(..., method='foh')``,
    returning Γ1 as well, which the initial state needs."""
    n, m = B.shape
    em = np.zeros((n + 2 * m, n + 2 * m))
    em[:n, :n] = A * dt
    em[:n, n:n + m] = B * dt
    em[n:n + m, n + m:] = np.eye(m)
    ms = expm(em)
    Phi, G, G1 = ms[:n, :n], ms[:n, n:n + m], ms[:n, n + m:]
    return np.ascontiguousarray(Phi), np.ascontiguousarray(G - G1 + Phi @ G1), G1
