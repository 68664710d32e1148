"""Exact simulation of linear time-invariant models on a uniform time grid, their frequency
response, and time-scale separation (residualisation of modes the data cannot see).

A model whose state equations are linear in its states and inputs is x' = A(θ)x + B(θ)u,
y = C(θ)x + D(θ)u.  The matrices come from the symbolic Jacobians of the straight-line
program (compiled to numeric functions of θ once); the response to an input that is linear
between samples (exactly what a sampled data column is) follows from the first-order-hold
discretisation (the block-exponential construction of ``scipy.signal.cont2discrete``, method
``foh``) and a compiled recursion, with no integration error and a cost of a few n² flops per
sample.

**Residualisation** (:func:`residualise`): the modes faster than a cut-off frequency are
separated from the slow ones by an ordered real Schur form and a Sylvester equation (block
diagonalisation), and replaced by their quasi-static (DC) contribution, D_r = D − C_f·A_f⁻¹·B_f,
plus its first-order term in frequency, a feedthrough of the input's rate
D_1 = −C_f·A_f⁻²·B_f (C_f(sI − A_f)⁻¹B_f = −C_f A_f⁻¹B_f − s·C_f A_f⁻²B_f − ...): the
lag of the fast modes at the data's frequencies (ω/ω_f of a radian), which is far below what
those modes show of themselves yet, at a high signal-to-noise ratio, well above the noise.
The slow poles are kept exactly and the static gain is exact: the singular-perturbation
approximation of the fast subsystem, which is what data sampled far below those modes can
see of them.  With every mode fast the model reduces to its static gain and the rate term.
The input's rate at the samples is their central difference (one-sided at the ends).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
import sympy as sp
from numba import njit
from scipy.linalg import expm, matrix_balance, schur, solve_sylvester

from ..equations.system import Equations
from ..support.errors import ParameterError, UsageError, did_you_mean

#: a state whose magnitude is below this share of its column's largest so far is set to zero
#: (see :func:`recursion`), checked every :data:`GUARD_EVERY` samples
FLOOR = 1e-150
GUARD_EVERY = 64


@njit(cache=True, nogil=True)
def recursion(Ad, Bd, Cd, Dd, X0, U, rows, Y):
    """x_j[k+1] = Ad x_j[k] + Bd u_j[k], y_j[k] = Cd x_j[k] + Dd u_j[k] for every column j of U
    (one input each, states X0[:, j] at k = 0), all columns in one pass over the samples; the
    outputs are kept at the sample indices ``rows`` (ascending) only: Y[r, j] = y_j[rows[r]].

    The subnormal guard: every :data:`GUARD_EVERY` samples, a state whose magnitude is below
    :data:`FLOOR` times the largest state magnitude its column has had at these checks is set
    to zero.  A response that decays for long (a drive resting at zero) would otherwise reach
    subnormal numbers, on which arithmetic is slower (1.5x for this loop on the machine of
    benchmarks/README.md, far more on some processors) and which never reach zero.  What the guard
    drops is below 1e-150 of the states' own scale: the output changes by less than that
    share of its scale times the filter's gain; a mode would have to decay by 1e-158 within
    the samples between two checks to reach the subnormals first."""
    n = Ad.shape[0]
    N, m = U.shape
    if m == 1:
        _one_column(Ad, Bd[:, 0].copy(), Cd[0].copy(), Dd[0, 0], X0[:, 0].copy(), U[:, 0], rows, Y[:, 0])
        return
    x = X0.copy()
    xn = np.empty((n, m))
    peak = np.zeros(m)
    r = 0
    R = rows.shape[0]
    for k in range(N):
        if k % GUARD_EVERY == 0:
            for j in range(m):
                peak[j] = _guard(x[:, j], peak[j])
        keep = r < R and rows[r] == k
        for j in range(m):
            u = U[k, j]
            if keep:
                acc = Dd[0, 0] * u
                for i in range(n):
                    acc += Cd[0, i] * x[i, j]
                Y[r, j] = acc
            for i in range(n):
                s = Bd[i, 0] * u
                for l in range(n):
                    s += Ad[i, l] * x[l, j]
                xn[i, j] = s
        for i in range(n):
            for j in range(m):
                x[i, j] = xn[i, j]
        if keep:
            r += 1


@njit(cache=True, nogil=True)
def _guard(x, peak):
    """The subnormal guard of :func:`recursion` on one column's states ``x`` (in place);
    returns the column's new peak."""
    for i in range(x.shape[0]):
        peak = max(peak, abs(x[i]))
    floor = FLOOR * peak
    for i in range(x.shape[0]):
        if abs(x[i]) < floor:
            x[i] = 0.0
    return peak


@njit(cache=True, nogil=True)
def _one_column(Ad, b, c, d, x, u, rows, y):
    """:func:`recursion` for a single input column (vectors b, c, x, u, y; scalar d): the same
    arithmetic in the same order, in a loop about twice as fast; ``x`` is overwritten."""
    n = Ad.shape[0]
    xn = np.empty(n)
    peak = 0.0
    r = 0
    R = rows.shape[0]
    for k in range(u.shape[0]):
        if k % GUARD_EVERY == 0:
            peak = _guard(x, peak)
        if r < R and rows[r] == k:
            acc = d * u[k]
            for i in range(n):
                acc += c[i] * x[i]
            y[r] = acc
            r += 1
        for i in range(n):
            s = b[i] * u[k]
            for l in range(n):
                s += Ad[i, l] * x[l]
            xn[i] = s
        for i in range(n):
            x[i] = xn[i]


@dataclass(frozen=True)
class StateSpace:
    """Numeric single-input single-output (A, B, C, D); ``fast`` modes were residualised, and
    ``D1`` (output per unit input rate, s) is their first-order term (module docstring).

    Parameters
    ----------
    A : numpy.ndarray
        n × n state matrix.
    B : numpy.ndarray
        n × 1 input matrix.
    C : numpy.ndarray
        1 × n output matrix.
    D : numpy.ndarray
        1 × 1 feedthrough.
    fast : int, optional
        Number of modes residualised.
    D1 : float, optional
        Feedthrough of the input's rate, output units per (input unit / s).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    fast: int = 0
    D1: float = 0.0

    @property
    def n(self) -> int:
        """Number of states kept."""
        return self.A.shape[0]

    def poles(self) -> np.ndarray:
        """Eigenvalues of A, rad/s (unsorted).

        Returns
        -------
        numpy.ndarray
            Complex poles (empty without states).
        """
        return np.linalg.eigvals(self.A) if self.n else np.zeros(0, complex)

    def frequency_response(self, omega) -> np.ndarray:
        """H(jω) = C (jωI − A)⁻¹ B + D + jω·D1 at ``omega`` (rad/s).

        Parameters
        ----------
        omega : float or array_like
            Angular frequencies, rad/s.

        Returns
        -------
        numpy.ndarray
            Complex H(jω), output units per input unit.
        """
        H = frequency_response(self.A, self.B, self.C, self.D, omega)
        return H + 1j * np.atleast_1d(np.asarray(omega, float)) * self.D1 if self.D1 else H

    def dc_gain(self) -> float:
        """H(0) = D − C A⁻¹ B, the output per unit constant input at equilibrium.

        Returns
        -------
        float
            Output units per input unit; nan when A is singular (no equilibrium).
        """
        if self.n == 0:
            return float(self.D[0, 0])
        try:
            return float(self.D[0, 0] - (self.C @ np.linalg.solve(self.A, self.B))[0, 0])
        except np.linalg.LinAlgError:
            return float("nan")

    def response(
        self,
        dt: float,
        U: np.ndarray,
        x0: np.ndarray | None = None,
        rows: np.ndarray | None = None,
        steady: bool = False,
    ) -> np.ndarray:
        """Output for each column of ``U`` (inputs sampled every ``dt`` s, linear in between),
        from the state ``x0`` (default rest), or with ``steady`` from each column's steady
        state at its first sample (the response from rest to U − U[0] plus H(0)·U[0]: the same
        by superposition, and defined with fast modes residualised; from rest when A is
        singular); at the sample indices ``rows`` (ascending) only, if given.

        Parameters
        ----------
        dt : float
            Sample interval, s.
        U : numpy.ndarray
            Input samples, one column per input series (a 1-D array is one column).
        x0 : numpy.ndarray, optional
            Initial state (default: rest).
        rows : numpy.ndarray, optional
            Sample indices to return, ascending.
        steady : bool, optional
            Start at the steady state of each column's first sample instead (``x0`` unused).

        Returns
        -------
        numpy.ndarray
            (rows, columns) output, output units.
        """
        U = np.asarray(U, float)
        U = np.ascontiguousarray(U.reshape(-1, 1) if U.ndim == 1 else U)
        if steady and np.any(U[0]):
            h0 = self.dc_gain()
            if np.isfinite(h0):
                return self.response(dt, U - U[0], None, rows) + h0 * U[0]
        if self.n == 0:
            Y = self.D[0, 0] * (U if rows is None else U[rows])
        else:
            Phi, Gam, G1 = foh(self.A, self.B, dt)
            x0 = np.zeros(self.n) if x0 is None else np.asarray(x0, float)
            rows = np.arange(U.shape[0]) if rows is None else np.ascontiguousarray(rows, np.int64)
            Y = np.empty((rows.size, U.shape[1]))
            # the discrete state is ξ = x − Γ1·u (as in scipy.signal.cont2discrete, method 'foh')
            X0 = np.ascontiguousarray(x0[:, None] - G1[:, :1] * U[0][None, :])
            recursion(Phi, Gam, np.ascontiguousarray(self.C), self.D + self.C @ G1, X0, U, rows, Y)
        if self.D1 and U.shape[0] > 1:
            rate = np.gradient(U, dt, axis=0)
            Y = Y + self.D1 * (rate if rows is None else rate[rows])
        return Y


class LTI:
    """The (A, B, C, D) of one input → one output of a model, as numeric functions of θ.

    ``input``/``output`` default to the model's first declared input and output.

    Parameters
    ----------
    eqs : Equations
        The derived model.
    input : str, optional
        The input's name.
    output : str, optional
        The output's name.

    Raises
    ------
    UsageError
        An unknown input or output, or a model that declares none.
    """

    def __init__(self, eqs: Equations, input: str | None = None, output: str | None = None):
        names = [str(u) for u in eqs.inputs]
        input = input if input is not None else first_input(eqs)
        output = output if output is not None else first_output(eqs)
        if input not in names:
            raise UsageError(did_you_mean(input, names, "input"))
        if output not in eqs.outputs:
            raise UsageError(did_you_mean(output, list(eqs.outputs), "output"))
        self.eqs = eqs
        self.input, self.output = input, output
        mats, self.exact, used = linear_matrices(eqs, [input], [output])
        #: names of the parameters the linear dynamics depend on, in the order of ``eqs.params``
        self.parameters = [p.name for p in eqs.params if p in used]
        self._fn = sp.lambdify([eqs.params], mats, modules="numpy", cse=True)
        self._mats = mats
        self._dfn = self._analytic = None
        self.n = len(eqs.state_symbols)

    def matrices(self, th: np.ndarray):
        """The numeric (A, B, C, D) at θ.

        Parameters
        ----------
        th : numpy.ndarray
            θ, the model's parameter vector (order of ``eqs.params``).

        Returns
        -------
        tuple of numpy.ndarray
            A (n × n), B (n × 1), C (1 × n), D (1 × 1).
        """
        A, B, C, D = (
            np.array(M, dtype=float).reshape(shape)
            for M, shape in zip(self._fn(np.asarray(th, float)), [(self.n, self.n), (self.n, 1), (1, self.n), (1, 1)])
        )
        return A, B, C, D

    def derivatives(self, th: np.ndarray, names: Sequence[str]):
        """(∂A, ∂B, ∂C, ∂D) at θ with respect to the parameters ``names``, stacked along a first
        axis in that order (zero for a parameter the dynamics do not depend on).  By the
        complex step, ∂M/∂θ_j = Im M(θ + ih·e_j)/h with h = 1e-20·|θ_j| (exact to rounding, no
        difference taken), when the matrices are analytic in θ (arithmetic, powers and the
        functions of :data:`ANALYTIC`); else from their symbolic derivatives, compiled on first
        use.

        Parameters
        ----------
        th : numpy.ndarray
            θ, the model's parameter vector (order of ``eqs.params``).
        names : sequence of str
            The parameters.

        Returns
        -------
        tuple of numpy.ndarray
            (∂A, ∂B, ∂C, ∂D), each of shape (len(names), *matrix shape), per unit parameter.

        Raises
        ------
        ParameterError
            A name that is no parameter of the model."""
        known = [p.name for p in self.eqs.params]
        for n in names:
            if n not in known:
                raise ParameterError(did_you_mean(n, known, "parameter"))
        shapes = [(self.n, self.n), (self.n, 1), (1, self.n), (1, 1)]
        out = [np.zeros((len(names), *shape)) for shape in shapes]
        th = np.asarray(th, float)
        if self._analytic is None:
            self._analytic = all(
                type(f) in ANALYTIC for M in self._mats for e in M for f in e.atoms(sp.core.function.Application)
            )
        analytic = self._analytic
        for i, n in enumerate(names):
            if n not in self.parameters:
                continue
            if analytic:
                j = known.index(n)
                h = 1e-20 * max(abs(th[j]), 1e-280)
                tc = th.astype(complex)
                tc[j] += 1j * h
                parts = [np.array(M, dtype=complex).imag / h for M in self._fn(tc)]
            else:
                if self._dfn is None:
                    syms = [p for p in self.eqs.params if p.name in self.parameters]
                    diffs = [M.diff(p) for p in syms for M in self._mats]
                    self._dfn = sp.lambdify([self.eqs.params], diffs, "numpy", cse=True)
                at = 4 * self.parameters.index(n)
                parts = [np.array(dM, dtype=float) for dM in self._dfn(th)[at : at + 4]]
            for M, shape, dM in zip(out, shapes, parts):
                M[i] = dM.reshape(shape)
        return tuple(out)

    def state_space(self, th: np.ndarray, cut: float | None = None) -> StateSpace:
        """The numeric model at θ; modes faster than ``cut`` (rad/s) residualised.

        Parameters
        ----------
        th : numpy.ndarray
            θ, the model's parameter vector (order of ``eqs.params``).
        cut : float, optional
            Cut-off, rad/s (None: keep every mode).

        Returns
        -------
        StateSpace
            The numeric model.
        """
        A, B, C, D = self.matrices(th)
        return residualise(A, B, C, D, cut) if cut is not None else StateSpace(A, B, C, D)

    def response(self, th: np.ndarray, dt: float, U: np.ndarray, x0: np.ndarray | None = None) -> np.ndarray:
        """Output of the full model for each column of ``U`` (see :meth:`StateSpace.response`).

        Parameters
        ----------
        th : numpy.ndarray
            θ, the model's parameter vector (order of ``eqs.params``).
        dt : float
            Sample interval, s.
        U : numpy.ndarray
            Input samples, one column per series.
        x0 : numpy.ndarray, optional
            Initial state (default: rest).

        Returns
        -------
        numpy.ndarray
            (samples, columns) output, output units.
        """
        return self.state_space(th).response(dt, U, x0)


def linear_matrices(eqs: Equations, inputs: Sequence[str], outputs: Sequence[str]):
    """The symbolic (A, B, C, D) of the inputs ``inputs`` (names) → the outputs ``outputs``,
    whether they say everything (the model is affine in its states and every input: the slopes
    in the states and these inputs move with nothing, those in the other inputs with no state
    or input; the route is then exact) and the parameters they depend on.  The other inputs,
    the input rates and operator outputs are set to zero.  Returns (matrices, exact, symbols).

    Parameters
    ----------
    eqs : Equations
        The derived model.
    inputs : sequence of str
        Input names.
    outputs : sequence of str
        Output names.

    Returns
    -------
    matrices : list of sympy.Matrix
        A, B, C, D.
    exact : bool
        Whether the model is affine as described (the linear route is then exact).
    symbols : set
        The symbols the matrices depend on.
    """
    names = [str(u) for u in eqs.inputs]
    us = [eqs.inputs[names.index(i)] for i in inputs]
    xs = eqs.state_symbols
    rates = [eqs.rates[s] for s in xs]
    ys = [eqs.outputs[o] for o in outputs]
    mats = [eqs.jacobian(rates, xs), eqs.jacobian(rates, us), eqs.jacobian(ys, xs), eqs.jacobian(ys, us)]
    moving = set(xs) | set(eqs.inputs) | set(eqs.input_rates) | {ob.symbol for ob in eqs.operators}
    others = [s for s in eqs.inputs if s not in us]
    exact = (
        not eqs.operators
        and all(not (e.free_symbols & moving) for M in mats for e in M)
        and all(not (e.free_symbols & (set(xs) | set(eqs.inputs))) for e in eqs.jacobian(rates + ys, others))
    )
    zero = {s: 0 for s in list(moving - set(xs) - set(us)) + others}
    mats = [M.xreplace(zero) for M in mats]
    return mats, exact, set().union(*(e.free_symbols for M in mats for e in M))


def first_input(eqs: Equations) -> str:
    """The model's first declared input (what identification drives unless told otherwise).

    Parameters
    ----------
    eqs : Equations
        The derived model.

    Returns
    -------
    str
        The input's name.

    Raises
    ------
    UsageError
        The model declares no input.
    """
    declared = list(eqs.model.inputs)
    if not declared:
        raise UsageError(f"{eqs.model.name} declares no input")
    return declared[0]


def first_output(eqs: Equations) -> str:
    """The model's first declared output.

    Parameters
    ----------
    eqs : Equations
        The derived model.

    Returns
    -------
    str
        The output's name.

    Raises
    ------
    UsageError
        The model declares no output.
    """
    if not eqs.outputs:
        raise UsageError(f"{eqs.model.name} declares no output")
    return next(iter(eqs.outputs))


#: functions of the parameters through which :meth:`LTI.derivatives` takes the complex step
ANALYTIC = frozenset(
    {sp.exp, sp.log, sp.sin, sp.cos, sp.tan, sp.sinh, sp.cosh, sp.tanh, sp.asin, sp.acos, sp.atan, sp.asinh, sp.atanh}
)

#: eigenvector matrices worse conditioned than this are not used for the modal sum
MODAL_COND = 1e6


def frequency_response(A, B, C, D, omega) -> np.ndarray:
    """H(jω) = C (jωI − A)⁻¹ B + D of a single-input single-output model at ``omega`` (rad/s).

    As the modal sum Σ_k r_k/(jω − λ_k) (A = VΛV⁻¹ after balancing the states' scales,
    r_k = (CV)_k (V⁻¹B)_k): one eigendecomposition instead of a solve per frequency; by a
    solve per frequency when the eigenvectors are ill-conditioned (near-defective A, more
    than :data:`MODAL_COND`).

    Parameters
    ----------
    A : numpy.ndarray
        n × n state matrix.
    B : numpy.ndarray
        n × 1 input matrix.
    C : numpy.ndarray
        1 × n output matrix.
    D : numpy.ndarray
        1 × 1 feedthrough.
    omega : float or array_like
        Angular frequencies, rad/s.

    Returns
    -------
    numpy.ndarray
        Complex H(jω), output units per input unit.
    """
    omega = np.atleast_1d(np.asarray(omega, float))
    n = A.shape[0]
    if n == 0:
        return np.full(omega.size, complex(D[0, 0]))
    Ab, (scale, _) = matrix_balance(A, permute=False, separate=True)  # states in comparable units
    lam, V = np.linalg.eig(Ab)
    if np.all(np.isfinite(lam)) and np.linalg.cond(V) <= MODAL_COND:
        r = ((C[0] * scale) @ V) * np.linalg.solve(V, (B[:, 0] / scale).astype(complex))
        return np.reciprocal(1j * omega[:, None] - lam[None, :]) @ r + D[0, 0]
    M = 1j * omega[:, None, None] * np.eye(n)[None] - A[None]
    X = np.linalg.solve(M, np.broadcast_to(B.astype(complex), (omega.size, n, B.shape[1])))
    return (C[None] @ X)[:, 0, 0] + D[0, 0]


def residualise(A, B, C, D, cut: float) -> StateSpace:
    """Keep the modes with |λ| ≤ ``cut`` (rad/s) exactly; replace the others by their static
    contribution (see the module docstring).  The ordered real Schur form A = Z·T·Zᵀ puts the
    slow eigenvalues first; X solving T11·X − X·T22 = −T12 decouples the two blocks.

    Parameters
    ----------
    A : numpy.ndarray
        n × n state matrix.
    B : numpy.ndarray
        n × 1 input matrix.
    C : numpy.ndarray
        1 × n output matrix.
    D : numpy.ndarray
        1 × 1 feedthrough.
    cut : float
        Cut-off angular frequency, rad/s.

    Returns
    -------
    StateSpace
        The slow modes, with the fast ones' static gain in D and their rate term in D1.
    """
    n = A.shape[0]
    if n == 0:
        return StateSpace(A, B, C, D)
    lam = np.linalg.eigvals(A)
    if np.all(np.abs(lam) <= cut):
        return StateSpace(A, B, C, D)
    T, Z, k = schur(A, output="real", sort=lambda re, im: np.hypot(re, im) <= cut)
    Bt, Ct = Z.T @ B, C @ Z
    if k == 0:
        static = np.linalg.solve(T, Bt)
        return StateSpace(
            np.zeros((0, 0)),
            np.zeros((0, 1)),
            np.zeros((1, 0)),
            D - Ct @ static,
            fast=n,
            D1=float(-(Ct @ np.linalg.solve(T, static))[0, 0]),
        )
    T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
    X = solve_sylvester(T11, -T22, -T12)
    B1, B2 = Bt[:k] - X @ Bt[k:], Bt[k:]
    C1, C2 = Ct[:, :k], Ct[:, :k] @ X + Ct[:, k:]
    static = np.linalg.solve(T22, B2)
    return StateSpace(
        np.ascontiguousarray(T11),
        np.ascontiguousarray(B1),
        np.ascontiguousarray(C1),
        D - C2 @ static,
        fast=n - k,
        D1=float(-(C2 @ np.linalg.solve(T22, static))[0, 0]),
    )


def foh(A: np.ndarray, B: np.ndarray, dt: float):
    """First-order-hold discretisation: (Φ, Γ, Γ1) with ξ[k+1] = Φξ[k] + Γu[k], x = ξ + Γ1·u.

    The block-exponential construction of ``scipy.signal.cont2discrete(..., method='foh')``,
    returning Γ1 as well, which the initial state needs.

    Parameters
    ----------
    A : numpy.ndarray
        n × n state matrix.
    B : numpy.ndarray
        n × m input matrix.
    dt : float
        Sample interval, s.

    Returns
    -------
    Phi : numpy.ndarray
        Φ, n × n.
    Gamma : numpy.ndarray
        Γ, n × m.
    Gamma1 : numpy.ndarray
        Γ1, n × m.
    """
    n, m = B.shape
    em = np.zeros((n + 2 * m, n + 2 * m))
    em[:n, :n] = A * dt
    em[:n, n : n + m] = B * dt
    em[n : n + m, n + m :] = np.eye(m)
    ms = expm(em)
    Phi, G, G1 = ms[:n, :n], ms[:n, n : n + m], ms[:n, n + m :]
    return np.ascontiguousarray(Phi), np.ascontiguousarray(G - G1 + Phi @ G1), G1
