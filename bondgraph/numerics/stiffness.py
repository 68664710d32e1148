"""The sparse analytic Jacobian at run time, and the stiffness test of method ``auto``.

:class:`SparseJacobian` evaluates a model's Jacobian program (:mod:`.jacobian`) — the
augmented matrix ``J_aug`` for the compiled implicit integrator (:mod:`.implicit`), the
Jacobian ``J`` itself (its Schur complement, sparse) for scipy's solvers — and fixes the
column order of the sparse LU.

Stiffness (:func:`stiffness`): the spectral radius ρ of ``J`` at the start (ARPACK on the
sparse operator, dense eigenvalues for small models) against the output's band.  An explicit
method is stable only for steps below about 3.3/ρ, whatever the accuracy asks; when ρ lies
far above the output's Nyquist frequency π/dt (more than ``simulate.stiff_ratio`` times),
the fast modes are not what the output resolves and an implicit method may step over them;
it pays when the explicit method would need more than ``simulate.stiff_min_steps`` steps.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import scipy.sparse as sps
import scipy.sparse.linalg as spla

from ..equations.system import Equations
from ..support import config
from .codegen import compile_jacobian
from .implicit import run_plan
from .jacobian import build_program

DENSE_EIGEN = 400  # states up to which the spectral radius comes from dense eigenvalues


class SparseJacobian:
    """A model's sparse Jacobian program, compiled (see the module docstring).

    Parameters
    ----------
    eqs : Equations
        The model's equations.

    Raises
    ------
    Exception
        Whatever building or compiling the program raised (sympy or numba); the caller decides
        whether the model can do without an analytic Jacobian.
    """

    def __init__(self, eqs: Equations):
        self.program = prog = build_program(eqs)
        self.compiled = compile_jacobian(eqs, prog)
        self.n = prog.n
        self.size = prog.size
        self.route = self.compiled.route
        self._q: np.ndarray | None = None

    def work(self) -> np.ndarray:
        """A fresh work array ``[1, −1, 0, ...]`` of the program.

        Returns
        -------
        numpy.ndarray
            ``n_work`` values.
        """
        W = np.zeros(self.program.n_work)
        W[0], W[1] = 1.0, -1.0
        return W

    def augmented(self, t, x, u, du, th, mem, aux=None) -> sps.csc_matrix:
        """``J_aug`` at (t, x) with inputs u, du, parameters θ and operator memory ``mem``.

        Parameters
        ----------
        t : float
            Time, s.
        x : numpy.ndarray
            State.
        u : numpy.ndarray
            Input values.
        du : numpy.ndarray
            Input rates (input units per s).
        th : numpy.ndarray
            θ, the parameter vector.
        mem : numpy.ndarray
            The memory operators' memory.
        aux : numpy.ndarray, optional
            Register array of the compiled program (default: a copy of the compiled one).

        Returns
        -------
        scipy.sparse.csc_matrix
            The augmented Jacobian over the states and the program's hub variables.
        """
        p = self.program
        aux = self.compiled.aux.copy() if aux is None else aux
        W = self.work()
        self.compiled.jac(float(t), np.ascontiguousarray(x, float), u, du, th, mem, aux, W[2 : p.first_accumulator])
        run_plan(W, p.plan, p.first_accumulator)
        return sps.csc_matrix((W[p.slots], p.indices, p.indptr), shape=(p.size, p.size))

    def reduced(self, J_aug: sps.csc_matrix) -> sps.csc_matrix:
        """``J = F_x + F_w·(I − G_w)⁻¹·G_x`` from ``J_aug`` (sparse, n × n).

        Parameters
        ----------
        J_aug : scipy.sparse.csc_matrix
            The augmented Jacobian (:meth:`augmented`).

        Returns
        -------
        scipy.sparse.csc_matrix
            ∂(dx/dt)/∂x, n × n.
        """
        n = self.n
        A = J_aug[:n, :n]
        if self.size == n:
            return A.tocsc()
        B, C, D = J_aug[:n, n:], J_aug[n:, :n], J_aug[n:, n:]
        X = spla.spsolve_triangular(D.tocsr(), C.toarray(), lower=True)  # D = G_w − I, lower triangular
        return (A - B @ sps.csc_matrix(X)).tocsc()

    def column_order(self) -> np.ndarray:
        """The LU's column order (computed once): COLAMD on the pattern of the state block of
        ``J_aug``, then the hubs (their dense rows and columns last, where they fill nothing).

        Returns
        -------
        numpy.ndarray
            A permutation of the augmented Jacobian's columns (int64).
        """
        if self._q is None:
            p = self.program
            rng = np.random.default_rng(0)
            values = rng.uniform(0.5, 1.0, p.indices.size)
            values[p.diagonal] += p.size  # nonsingular: only the pattern counts
            A = sps.csc_matrix((values, p.indices, p.indptr), shape=(p.size, p.size))[: p.n, : p.n].tocsc()
            core = spla.splu(A, permc_spec="COLAMD").perm_c.argsort() if p.n else np.zeros(0, int)
            self._q = np.ascontiguousarray(np.concatenate([core, np.arange(p.n, p.size)]), np.int64)
        return self._q


class Stiffness(NamedTuple):
    """What :func:`stiffness` found: the spectral radius ρ (1/s), the output's Nyquist
    frequency (rad/s), the explicit method's step count at its stability limit, and the verdict.

    Parameters
    ----------
    radius : float
        Spectral radius ρ of the Jacobian, 1/s.
    nyquist : float
        The output's Nyquist angular frequency, rad/s.
    explicit_steps : float
        Steps dopri5 would need at its stability limit over the run.
    stiff : bool
        The verdict.
    """

    radius: float
    nyquist: float
    explicit_steps: float
    stiff: bool

    def reason(self) -> str:
        """One phrase for the summary line, e.g. ``stiff: spectral radius 4.1e+08 1/s, 1300 × the
        output's Nyquist frequency; dopri5 would need ~1.2e+07 steps``.

        Returns
        -------
        str
            The phrase.
        """
        verdict = "stiff" if self.stiff else "not stiff"
        return (
            f"{verdict}: spectral radius {self.radius:.2g} 1/s, {self.radius / self.nyquist:.2g} × the output's "
            f"Nyquist frequency; dopri5 would need ~{self.explicit_steps:.2g} steps"
        )


def spectral_radius(J: sps.spmatrix) -> float:
    """|λ|max of the sparse matrix ``J`` (dense eigenvalues for small ones, ARPACK otherwise).

    Parameters
    ----------
    J : scipy.sparse.spmatrix
        A square Jacobian, 1/s.

    Returns
    -------
    float
        The spectral radius, 1/s (inf when ``J`` has a non-finite entry).
    """
    n = J.shape[0]
    if n == 0:
        return 0.0
    if not np.all(np.isfinite(J.data)):
        return math.inf
    if n <= DENSE_EIGEN:
        return float(np.max(np.abs(np.linalg.eigvals(J.toarray()))))
    try:
        lam = spla.eigs(J, k=1, which="LM", return_eigenvectors=False, tol=1e-3, maxiter=20 * n)
        return float(np.max(np.abs(lam)))
    except spla.ArpackNoConvergence as exc:
        if len(exc.eigenvalues):
            return float(np.max(np.abs(exc.eigenvalues)))
        return float(spla.norm(J, 1))  # a bound: the largest column sum


def stiffness(radius: float, t: np.ndarray) -> Stiffness:
    """The verdict of the module docstring for spectral radius ``radius`` and output times ``t``.

    Parameters
    ----------
    radius : float
        Spectral radius of the Jacobian, 1/s.
    t : numpy.ndarray
        Output times of the run, s.

    Returns
    -------
    Stiffness
        The numbers and the verdict (thresholds: settings ``simulate.stiff_ratio``,
        ``simulate.stiff_min_steps``, ``simulate.explicit_step_limit``).
    """
    span = float(t[-1] - t[0])
    dt = span / max(t.size - 1, 1)
    nyquist = math.pi / dt
    steps = span * radius / 3.3
    stiff = (
        radius > config.get("simulate.stiff_ratio") * nyquist and steps > config.get("simulate.stiff_min_steps")
    ) or steps > config.get("simulate.explicit_step_limit")
    return Stiffness(radius, nyquist, steps, stiff)
