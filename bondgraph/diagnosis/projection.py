"""Variable projection: least squares over nonlinear parameters z with the coefficients of
a column matrix A(z) solved exactly (bounded) at every z, min_z min_c ||y − A(z)·c||.

Parameters live in a transformed space: a :class:`Param` maps a physical value to z (signed
logarithm for the linear parameters of a model, whose sign is fixed by the model).
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Callable, Iterator, Sequence

import numpy as np
from scipy.linalg import solve_triangular
from scipy.optimize import least_squares

from ..fit.identify import bounded_lstsq, bounded_lstsq_free
from ..numerics.simulate import SimulationTimeout

#: the time (time.monotonic) after which fits in this context stop at their best point so far
_DEADLINE: contextvars.ContextVar[float | None] = contextvars.ContextVar("deadline", default=None)
#: the time after which every simulation in this context stops (a SimulationTimeout)
_LIMIT: contextvars.ContextVar[float | None] = contextvars.ContextVar("limit", default=None)


@contextlib.contextmanager
def time_budget(seconds: float | None, limit: float | None = None) -> Iterator[None]:
    """Within the block, :func:`projected_fit` stops at the best point it has found once
    ``seconds`` have passed (reported as not converged), and every simulation that asks
    :func:`simulation_deadline` stops once ``limit`` seconds have passed (a
    :class:`~bondgraph.numerics.simulate.SimulationTimeout`: the first evaluation of a fit, which has no
    point to fall back on, and the final prediction included).

    Parameters
    ----------
    seconds : float or None
        The fits' budget, s (None: unbounded).
    limit : float, optional
        The simulations' hard limit, s (None: unbounded).

    Yields
    ------
    None
        Within the block, the budget holds (in this context and the copies it hands on).
    """
    now = time.monotonic()
    token = _DEADLINE.set(None if seconds is None else now + seconds)
    hard = _LIMIT.set(None if limit is None else now + limit)
    try:
        yield
    finally:
        _DEADLINE.reset(token)
        _LIMIT.reset(hard)


#: the deadline a simulation inside an optimiser's evaluation obeys once the optimiser has a
#: point to stop at (before that, its first evaluation obeys only the limit)
_STOP_AT: contextvars.ContextVar[float | None] = contextvars.ContextVar("stop_at", default=None)


def simulation_deadline() -> float | None:
    """The deadline (time.monotonic) for a simulation run in this context, or None: inside an
    optimiser's evaluation with a point to stop at, the fit's budget (the fit then stops at its
    best point so far: a single slow simulation must not outlast the budget); else the
    context's limit (see :func:`time_budget`).  :meth:`~bondgraph.numerics.simulate.Simulator.run`
    stops there.

    Returns
    -------
    float or None
        A ``time.monotonic()`` value, or None.
    """
    stop = _STOP_AT.get()
    return stop if stop is not None else _LIMIT.get()


class _OutOfTime(Exception):
    pass


@dataclass
class Projected:
    """Result of :func:`projected_fit`.

    Parameters
    ----------
    z : numpy.ndarray
        The nonlinear parameters found.
    coef : numpy.ndarray
        The coefficients c solved at z.
    columns : numpy.ndarray
        A(z) on every sample.
    cost : float
        Half the sum of squared residuals on the fit rows, scaled by the data's spread.
    nfev : int
        Evaluations the optimiser made.
    success : bool
        The optimiser's success flag (False when the time budget stopped it).
    message : str
        The optimiser's message.
    at_bounds : list of int
        Indices of the z within 1e-3 of the bounds' width from a bound.
    """

    z: np.ndarray
    coef: np.ndarray
    columns: np.ndarray
    cost: float
    nfev: int
    success: bool
    message: str
    at_bounds: list[int]


@contextlib.contextmanager
def jacobian_map(threads: int) -> Iterator[Callable | None]:
    """A map for ``least_squares(workers=...)``: the finite-difference Jacobian's columns in
    ``threads`` threads (each call in a copy of the caller's context, so its time budget holds
    there too), or None (serial) for one.  It gains where the evaluations spend their time in
    compiled kernels that release the GIL (the exact linear recursion, the Lur'e stepping);
    the columns, and so the fit, are the serial ones.

    Parameters
    ----------
    threads : int
        Threads (1 or fewer: serial).

    Yields
    ------
    callable or None
        The map, or None.
    """
    if threads < 2:
        yield None
        return
    caller = contextvars.copy_context()
    with ThreadPoolExecutor(threads) as ex:
        yield lambda f, xs: list(ex.map(lambda x: caller.copy().run(f, x), xs))


def projected_fit(
    columns: Callable[[np.ndarray, np.ndarray | None], np.ndarray],
    y: np.ndarray,
    idx: np.ndarray,
    z0: Sequence[float],
    lb: Sequence[float],
    ub: Sequence[float],
    lower: Sequence[float],
    upper: Sequence[float],
    max_nfev: int = 40,
    starts: Sequence[Sequence[float]] = (),
    threads: int = 1,
    derivatives: Callable[[np.ndarray, np.ndarray], np.ndarray | None] | None = None,
) -> Projected:
    """min over z in [lb, ub] of min over lower ≤ c ≤ upper of ||y[idx] − A(z)[idx]·c||.

    ``columns(z, rows)`` returns the rows ``rows`` of A(z) (every sample for None: the optimiser
    asks for the rows ``idx`` only, the result holds A on every sample); ``starts`` are extra
    start points (the best solution wins); ``threads``: see :func:`jacobian_map` (``columns``
    must then be safe to call from several threads).

    ``derivatives(z, rows)``, when given, returns ∂A/∂z on the rows ``rows`` (an array of shape
    (len(z), len(rows), columns)), or None where it has none: the optimiser then gets the
    exact Jacobian of the projected residual from them (:func:`projection_jacobian`) instead
    of finite differences of ``columns`` (forward differences of the residual, as
    ``least_squares`` takes them, where ``derivatives`` returns None).

    Parameters
    ----------
    columns : callable
        ``columns(z, rows)`` → A(z) on ``rows``.
    y : numpy.ndarray
        The data on every sample.
    idx : numpy.ndarray
        Sample indices of the fit part.
    z0 : sequence of float
        Start point (empty: linear least squares only).
    lb, ub : array_like
        Bounds of z.
    lower, upper : sequence of float
        Bounds of the coefficients c.
    max_nfev : int, optional
        The optimiser's evaluation budget per start.
    starts : sequence of sequence of float, optional
        Further start points.
    threads : int, optional
        Threads for the finite-difference Jacobian.
    derivatives : callable, optional
        ``derivatives(z, rows)`` → ∂A/∂z on ``rows``, or None.

    Returns
    -------
    Projected
        The best solution over the starts (or the best point when the time budget ran out).

    Raises
    ------
    FloatingPointError
        The columns at the solution are not finite.
    SimulationTimeout
        A simulation passed the context's limit (:func:`time_budget`).
    """
    scale = max(float(np.std(y[idx])), 1e-300)
    lb, ub = np.asarray(lb, float), np.asarray(ub, float)

    yi = y[idx]
    deadline = _DEADLINE.get()
    seen = {"cost": math.inf, "z": None}
    #: the last evaluation: z, the columns there (None when not finite), the solution, its free
    #: columns and the residual
    last: dict = {"z": None}

    def evaluate(fn, z):
        """fn(z, idx) within the fit's time limits (see :func:`simulation_deadline`)."""
        if deadline is not None and seen["z"] is not None and time.monotonic() > deadline:
            raise _OutOfTime
        token = _STOP_AT.set(deadline if seen["z"] is not None else None)
        try:
            return fn(z, idx)
        except SimulationTimeout:
            if seen["z"] is None:  # the limit, on the first evaluation: nothing to fall back on
                raise
            raise _OutOfTime from None
        finally:
            _STOP_AT.reset(token)

    def resid(z):
        Ai = evaluate(columns, z)
        last.update(z=np.array(z, float), A=None)
        if not np.all(np.isfinite(Ai)):  # never hand LAPACK a NaN (it prints to stdout)
            return np.full(idx.size, 1e3)
        c, free = bounded_lstsq_free(Ai, yi, lower, upper)
        r = (Ai @ c - yi) / scale
        if not np.all(np.isfinite(r)):
            return np.full(idx.size, 1e3)
        last.update(A=Ai, c=c, free=free, r=r)
        cost = 0.5 * float(r @ r)
        if cost < seen["cost"]:
            seen["cost"], seen["z"] = cost, np.array(z, float)
        return r

    def jac(z):
        if last["z"] is None or not np.array_equal(last["z"], z):
            resid(z)
        if last["A"] is None:  # the placeholder residual of a non-finite prediction: flat
            return np.zeros((idx.size, z.size))
        at = dict(last)
        dA = evaluate(derivatives, z)
        if dA is not None and np.all(np.isfinite(dA)):
            J = projection_jacobian(at["A"], at["c"], at["free"], at["r"] * scale, dA) / scale
            if np.all(np.isfinite(J)):
                return J
        return forward_differences(resid, z, at["r"], lb, ub)

    def final(z):
        A = columns(z, None)
        if not np.all(np.isfinite(A)):
            raise FloatingPointError("the fitted model's prediction is not finite")
        return bounded_lstsq(A[idx], yi, lower, upper), A

    z0 = np.asarray(z0, float)
    if z0.size == 0:
        c, A = final(z0)
        r = (A[idx] @ c - yi) / scale
        return Projected(z0, c, A, 0.5 * float(r @ r), 1, True, "linear least squares", [])
    best = None
    nfev, out_of_time = 0, False
    with jacobian_map(threads if derivatives is None else 1) as jmap:
        for start in [z0, *[np.asarray(s, float) for s in starts]]:
            try:
                sol = least_squares(
                    resid,
                    np.clip(start, lb, ub),
                    jac="2-point" if derivatives is None else jac,
                    bounds=(lb, ub),
                    max_nfev=max_nfev,
                    diff_step=1e-4,
                    x_scale=1.0,
                    workers=jmap if derivatives is None else None,
                )
            except _OutOfTime:
                out_of_time = True
                break
            nfev += int(sol.nfev)
            if best is None or sol.cost < best.cost:
                best = sol
    if out_of_time and (best is None or seen["cost"] < best.cost):
        x, cost, success, message = seen["z"], seen["cost"], False, "stopped at its best point: time budget spent"
    else:
        x, cost, success, message = best.x, float(best.cost), bool(best.success), str(best.message)
    c, A = final(x)
    width = np.where(np.isfinite(ub - lb), ub - lb, 1.0)
    at = [i for i in range(x.size) if x[i] - lb[i] < 1e-3 * width[i] or ub[i] - x[i] < 1e-3 * width[i]]
    return Projected(x, c, A, cost, nfev, success, message, at)


def forward_step(z: np.ndarray, i: int, lb: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """z moved along its coordinate i by ``least_squares``' forward-difference step (relative
    step 1e-4, at least 1e-4), away from the bound it would cross.

    Parameters
    ----------
    z : numpy.ndarray
        The point.
    i : int
        The coordinate.
    lb, ub : numpy.ndarray
        Bounds of z.

    Returns
    -------
    numpy.ndarray
        A copy of z with coordinate i moved.
    """
    h = 1e-4 * (1.0 if z[i] >= 0 else -1.0) * max(1.0, abs(z[i]))
    out = np.array(z, float)
    out[i] += -h if not lb[i] <= z[i] + h <= ub[i] else h
    return out


def forward_differences(fun: Callable, z: np.ndarray, f0: np.ndarray, lb, ub) -> np.ndarray:
    """The forward-difference Jacobian of ``fun`` at ``z`` (where it is ``f0``) that
    ``least_squares(diff_step=1e-4)`` takes (steps of :func:`forward_step`): the fallback of
    an analytic Jacobian that is not available at some point.

    Parameters
    ----------
    fun : callable
        ``fun(z)`` → residual vector.
    z : numpy.ndarray
        The point.
    f0 : numpy.ndarray
        ``fun(z)``.
    lb, ub : array_like
        Bounds of z.

    Returns
    -------
    numpy.ndarray
        (len(f0), len(z)) Jacobian.
    """
    lb, ub = np.asarray(lb, float), np.asarray(ub, float)
    J = np.empty((np.size(f0), z.size))
    for i in range(z.size):
        zi = forward_step(z, i, lb, ub)
        J[:, i] = (fun(zi) - f0) / (zi[i] - z[i])
    return J


def projection_jacobian(A: np.ndarray, c: np.ndarray, free: np.ndarray, r: np.ndarray, dA: np.ndarray) -> np.ndarray:
    """The Jacobian of the variable projection's residual r(z) = A(z)·c(z) − y, c(z) solving the
    bounded linear least squares at every z (the columns on a bound held there), from the
    derivatives dA[i] = ∂A/∂z_i at a point with solution ``c``, free columns ``free`` (mask)
    and residual ``r``:

        ∂r/∂z_i = P⊥·dA_i·c − A_F·(A_Fᵀ A_F)⁻¹·dA_{i,F}ᵀ·r,

    P⊥ projecting out the free columns A_F: the full Jacobian of Golub and Pereyra (G. H. Golub, V. Pereyra, 1973, "The differentiation
    of pseudo-inverses and nonlinear least squares problems whose variables separate", SIAM
    Journal on Numerical Analysis 10(2), 413-432), from one QR of the free columns (scaled to
    unit norm).  Returns an array (rows, len(z)).

    Parameters
    ----------
    A : numpy.ndarray
        (rows, columns) matrix at the point.
    c : numpy.ndarray
        The solution there.
    free : numpy.ndarray
        Boolean mask of the free columns.
    r : numpy.ndarray
        The residual there.
    dA : numpy.ndarray
        (len(z), rows, columns) derivatives of A.

    Returns
    -------
    numpy.ndarray
        ∂r/∂z, (rows, len(z)).
    """
    dAc = dA @ c  # (nz, rows)
    F = np.nonzero(free)[0]
    if F.size == 0:
        return dAc.T
    norms = np.linalg.norm(A[:, F], axis=0)
    Q, R = np.linalg.qr(A[:, F] / norms)
    proj = dAc - (dAc @ Q) @ Q.T
    w = np.einsum("irf,r->fi", dA[:, :, F], r) / norms[:, None]
    back = Q @ solve_triangular(R, w, trans="T")
    return (proj - back.T).T
