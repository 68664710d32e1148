"""The compiled implicit integrator for stiff models: Radau IIA of order 5 on a sparse LU.

Method: the three-stage Radau IIA collocation method with the simplified Newton iteration,
error estimate, step-size controller and dense output of Hairer & Wanner (E. Hairer, G.
Wanner, *Solving Ordinary Differential Equations II: Stiff and Differential-Algebraic
Problems*, 2nd ed., Springer 1996, Sec. IV.8), as scipy's ``Radau`` implements them (its
constants are used), compiled with numba.  The linear systems are those of the augmented
sparse Jacobian of :mod:`bondgraph.numerics.jacobian` (``c·D − J_aug``, states and hubs),
factorised by a compiled left-looking sparse LU with threshold partial pivoting (the
algorithm of T. A. Davis, *Direct Methods for Sparse Linear Systems*, SIAM 2006, ``cs_lu``)
in a fill-reducing column order computed once (COLAMD, by scipy's SuperLU) — in real and in
complex arithmetic.  A Jacobian that does not depend on the state (linear models: the
right-hand side is affine in the state) is evaluated once per run, and the collocation
system, linear then, is solved by one Newton step.

Memory operators follow the contract of :mod:`bondgraph.numerics.integrators`: within a step
the memory is frozen; an accepted step's operator inputs are checked at interior points of
its collocation polynomial and the step is retried up to a reversal; the memory is
committed only after that, once per accepted step.  Rejected steps (error test, Newton
failure, reversal) never touch it.

The sparse LU lives in this file with the integrator that calls it (numba's on-disk cache is
keyed by the source file); the input signals and the memory contract's reversal test come
from :mod:`~bondgraph.numerics.integrators` as compiled function values
(:func:`~bondgraph.numerics.integrators.compiled_input_values`,
:func:`~bondgraph.numerics.integrators.reversal_at`), so a change there reaches this file's
cached machine code.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit, types
from scipy.integrate._ivp import radau as _radau

from .integrators import _FLAGS, INPUTS_TYPE, REVERSAL_TYPE, SIGNAL_TYPES, store_sample
from .model_functions import FUNCTION_TYPE

_C = np.ascontiguousarray(_radau.C, float)
_E = np.ascontiguousarray(_radau.E, float)
_T = np.ascontiguousarray(_radau.T, float)
_TI = np.ascontiguousarray(_radau.TI, float)
_P = np.ascontiguousarray(_radau.P, float)
_MU_REAL = float(_radau.MU_REAL)
_MU_COMPLEX = complex(_radau.MU_COMPLEX)
_TI_COMPLEX = np.ascontiguousarray(_radau.TI[1] + 1j * _radau.TI[2])
_NEWTON_MAXITER = 6
_MIN_FACTOR, _MAX_FACTOR = 0.2, 10.0
_N_CHECK = 4  # interior points where operator inputs are checked for a reversal
_PIVOT_TOL = 0.1  # the diagonal is kept as pivot while it is at least this share of its column's largest

STATUS = {
    0: "ok",
    1: "step size underflow",
    2: "too many steps",
    3: "non-finite state",
}


class ImplicitStats(NamedTuple):
    """Outcome of :func:`radau5`: status code (see STATUS) and counts.

    Parameters
    ----------
    status : int
        0 when the run succeeded, else a code of ``STATUS``.
    steps : int
        Accepted steps.
    rejected : int
        Steps rejected by the error test.
    rhs_calls : int
        Right-hand-side evaluations.
    reversal_rejections : int
        Steps rejected because a memory operator's input reversed inside them.
    written : int
        Output samples written (the failure time when ``status`` is not 0).
    jacobians : int
        Jacobian evaluations.
    factorizations : int
        LU factorizations.
    newton_failures : int
        Steps retried at half the size because the Newton iteration diverged.
    """

    status: int
    steps: int
    rejected: int
    rhs_calls: int
    reversal_rejections: int
    written: int  # output samples written (the failure time when status != 0)
    jacobians: int
    factorizations: int
    newton_failures: int  # steps retried at half the size because the Newton iteration diverged


# ---- sparse LU (real or complex) ------------------------------------------------------------


@njit(cache=True)
def lu_factor(Ap, Ai, Ax, q, tol, rs, Lp, Li, Lx, Up, Ui, Ux, pinv, x, xi, stack, pstack, mark):
    """Left-looking LU with threshold partial pivoting of the CSC matrix (Ap, Ai, Ax), its rows
    equilibrated first (``rs[i]`` = 1/largest |entry| of row i) and its columns in the order
    ``q``: ``L·U = P·R·A·Q`` with L unit lower triangular (first entry of each column its
    diagonal), U upper triangular (last entry its diagonal), ``pinv`` the row permutation.
    The equilibration keeps a row in large units from winning every pivot (and filling the
    factors); the diagonal is the pivot while it is at least ``tol`` times its column's largest.

    Returns 0 on success, 1 if the matrix is singular, 2 if L or U needs more room than
    ``Li``/``Ui`` hold.  ``x`` (dtype of Ax), ``xi``, ``stack``, ``pstack``, ``mark`` are
    workspace of the matrix size."""
    n = Ap.shape[0] - 1
    for i in range(n):
        pinv[i] = -1
        mark[i] = -1
        x[i] = 0.0
        rs[i] = 0.0
    for p in range(Ap[n]):
        a = abs(Ax[p])
        if a > rs[Ai[p]]:
            rs[Ai[p]] = a
    for i in range(n):
        if not (rs[i] > 0.0) or not math.isfinite(rs[i]):
            return 1
        rs[i] = 1.0 / rs[i]
    lnz = 0
    unz = 0
    for k in range(n):
        Lp[k] = lnz
        Up[k] = unz
        if lnz + n > Li.shape[0] or unz + n > Ui.shape[0]:
            return 2
        col = q[k]
        # reach of A[:, col] in the graph of L (depth-first, iterative)
        top = n
        for p in range(Ap[col], Ap[col + 1]):
            j0 = Ai[p]
            if mark[j0] == k:
                continue
            head = 0
            stack[0] = j0
            while head >= 0:
                j = stack[head]
                jn = pinv[j]
                if mark[j] != k:
                    mark[j] = k
                    pstack[head] = Lp[jn] if jn >= 0 else 0
                done = True
                p2 = Lp[jn + 1] if jn >= 0 else 0
                for pp in range(pstack[head], p2):
                    i = Li[pp]
                    if mark[i] == k:
                        continue
                    pstack[head] = pp
                    head += 1
                    stack[head] = i
                    done = False
                    break
                if done:
                    head -= 1
                    top -= 1
                    xi[top] = j
        # x = L \ A[:, col] on the reach
        for p in range(top, n):
            x[xi[p]] = 0.0
        for p in range(Ap[col], Ap[col + 1]):
            x[Ai[p]] = Ax[p] * rs[Ai[p]]
        for px in range(top, n):
            j = xi[px]
            jn = pinv[j]
            if jn < 0:
                continue
            xj = x[j]
            for p in range(Lp[jn] + 1, Lp[jn + 1]):
                x[Li[p]] -= Lx[p] * xj
        # pivot
        ipiv = -1
        a = -1.0
        for p in range(top, n):
            i = xi[p]
            if pinv[i] < 0:
                t = abs(x[i])
                if t > a:
                    a = t
                    ipiv = i
            else:
                Ui[unz] = pinv[i]
                Ux[unz] = x[i]
                unz += 1
        if ipiv == -1 or a <= 0.0 or not math.isfinite(a):
            return 1
        if pinv[col] < 0 and abs(x[col]) >= a * tol:
            ipiv = col
        pivot = x[ipiv]
        Ui[unz] = k
        Ux[unz] = pivot
        unz += 1
        pinv[ipiv] = k
        Li[lnz] = ipiv
        Lx[lnz] = 1.0
        lnz += 1
        for p in range(top, n):
            i = xi[p]
            if pinv[i] < 0:
                Li[lnz] = i
                Lx[lnz] = x[i] / pivot
                lnz += 1
            x[i] = 0.0
    Lp[n] = lnz
    Up[n] = unz
    for p in range(lnz):
        Li[p] = pinv[Li[p]]
    return 0


@njit(cache=True)
def lu_solve(q, rs, Lp, Li, Lx, Up, Ui, Ux, pinv, b, x):
    """Overwrite ``b`` with the solution of A·y = b from :func:`lu_factor` (``x``: workspace)."""
    n = b.shape[0]
    for k in range(n):
        x[pinv[k]] = b[k] * rs[k]
    for j in range(n):
        xj = x[j]
        for p in range(Lp[j] + 1, Lp[j + 1]):
            x[Li[p]] -= Lx[p] * xj
    for j in range(n - 1, -1, -1):
        x[j] /= Ux[Up[j + 1] - 1]
        xj = x[j]
        for p in range(Up[j], Up[j + 1] - 1):
            x[Ui[p]] -= Ux[p] * xj
    for k in range(n):
        b[q[k]] = x[k]


@njit(cache=True)
def _factor(Ap, Ai, Ax, q, rs, Lp, Li, Lx, Up, Ui, Ux, pinv, x, xi, stack, pstack, mark):
    """:func:`lu_factor`, growing L and U until they fit; returns (status, Li, Lx, Ui, Ux)."""
    while True:
        st = lu_factor(Ap, Ai, Ax, q, _PIVOT_TOL, rs, Lp, Li, Lx, Up, Ui, Ux, pinv, x, xi, stack, pstack, mark)
        if st != 2:
            return st, Li, Lx, Ui, Ux
        Li = np.empty(2 * Li.shape[0], np.int64)
        Lx = np.empty(2 * Lx.shape[0], Lx.dtype)
        Ui = np.empty(2 * Ui.shape[0], np.int64)
        Ux = np.empty(2 * Ux.shape[0], Ux.dtype)


@njit(cache=True)
def _lu_storage(n, cap, like):
    """Empty L, U (room for ``cap`` entries each, values of ``like``'s dtype), pinv and row scales."""
    return (
        np.zeros(n + 1, np.int64),
        np.empty(cap, np.int64),
        np.empty(cap, like.dtype),
        np.zeros(n + 1, np.int64),
        np.empty(cap, np.int64),
        np.empty(cap, like.dtype),
        np.empty(n, np.int64),
        np.empty(n),
    )


# ---- the Jacobian program's numeric part ---------------------------------------------------


@njit(cache=True)
def run_plan(W, plan, first_accumulator):
    """The chain rule of a :class:`~bondgraph.numerics.jacobian.JacobianProgram`: zero the
    accumulators, then ``W[dst] += W[a]·W[b]`` for every plan row."""
    for k in range(first_accumulator, W.shape[0]):
        W[k] = 0.0
    for k in range(plan.shape[0]):
        W[plan[k, 0]] += W[plan[k, 1]] * W[plan[k, 2]]


@njit(cache=True)
def _jacobian_values(jac, t, x, u, du, th, mem, jaux, W, plan, first_accumulator, slots, J):
    """J = the CSC values of J_aug at (t, x): the partials, then the chain rule."""
    jac(t, x, u, du, th, mem, jaux, W[2:first_accumulator])
    run_plan(W, plan, first_accumulator)
    for k in range(slots.shape[0]):
        J[k] = W[slots[k]]


@njit(cache=True)
def _predict(have_sol, x_old, Q_old, t_old, h_old, t, h, x, Z, work):
    """Z[s] = the last step's collocation polynomial at t + C_s·h, minus x (0 without one)."""
    for s in range(3):
        if have_sol:
            _dense(x_old, Q_old, (t + _C[s] * h - t_old) / h_old, work)
            for i in range(x.shape[0]):
                Z[s, i] = work[i] - x[i]
        else:
            for i in range(x.shape[0]):
                Z[s, i] = 0.0


@njit(cache=True)
def _error(fx, Z, h, b):
    """b = f + Zᵀ·E/h on the state rows, 0 on the hub rows: the right side of the error estimate."""
    for i in range(b.shape[0]):
        b[i] = fx[i] + (Z[0, i] * _E[0] + Z[1, i] * _E[1] + Z[2, i] * _E[2]) / h if i < fx.shape[0] else 0.0


@njit(cache=True)
def _newton_matrix(J, diag, n, c, A):
    """A = c·D − J_aug (D: identity on the n state rows)."""
    for k in range(J.shape[0]):
        A[k] = -J[k]
    for i in range(n):
        A[diag[i]] += c


@njit(cache=True)
def _rms(v, w, n):
    acc = 0.0
    for i in range(n):
        e = v[i] / w[i]
        acc += e * e
    return math.sqrt(acc / max(n, 1))


@njit(cache=True)
def _predict_factor(h_abs, h_abs_old, error_norm, error_norm_old):
    """Gustafsson's predictive controller (Hairer & Wanner, Sec. IV.8), as in scipy."""
    if error_norm_old < 0.0 or h_abs_old < 0.0 or error_norm == 0.0:
        multiplier = 1.0
    else:
        multiplier = h_abs / h_abs_old * (error_norm_old / error_norm) ** 0.25
    if error_norm == 0.0:
        return math.inf
    return min(1.0, multiplier) * error_norm**-0.25


@njit(cache=True)
def _dense(x, Q, theta, out):
    """x(t_old + θh) = x_old + Σ_j Q[:, j]·θ^(j+1) (the collocation polynomial)."""
    for i in range(x.shape[0]):
        acc = 0.0
        for j in range(Q.shape[1] - 1, -1, -1):
            acc = (acc + Q[i, j]) * theta
        out[i] = x[i] + acc


_f1 = types.float64[::1]
_f2 = types.float64[:, ::1]
_i1 = types.int64[::1]
_i2 = types.int64[:, ::1]
_STATS = types.NamedUniTuple(types.int64, len(ImplicitStats._fields), ImplicitStats)


#: the numba signature of :func:`radau5` (first-class model functions: one build serves every model)
_RADAU5_SIGNATURE = _STATS(
    *((FUNCTION_TYPE,) * 5),
    INPUTS_TYPE,
    REVERSAL_TYPE,
    _f1,
    _f1,
    _f1,
    _f1,
    _f1,
    types.int64,
    *SIGNAL_TYPES,
    types.float64,
    _f1,
    _f1,
    types.float64,
    types.int64,
    _f2,
    _f2,
    _FLAGS,
    _i1,
    _i1,
    _i1,
    _i1,
    _i2,
    types.int64,
    types.int64,
    types.boolean,
    _i1,
)


@functools.cache
def compiled_radau5():
    """:func:`radau5` compiled by numba, built (or loaded from numba's disk cache) on first use.

    Compiling the implicit integrator takes several seconds of CPU the first time after an
    install; deferring it to the first stiff run keeps it off every run that never needs it
    (a non-stiff model on ``dopri5``).

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The compiled kernel, called with :func:`radau5`'s arguments.
    """
    return njit(_RADAU5_SIGNATURE, cache=True)(radau5)


def radau5(
    rhs,
    output,
    opin,
    commit,
    jac,
    inputs,
    reversal_at,
    x0,
    th,
    mem,
    aux,
    jaux,
    n_ops,
    skind,
    spar,
    soff,
    slen,
    stt,
    stv,
    scur,
    t_out,
    t_break,
    rtol,
    atol,
    h_io,
    h_max,
    max_steps,
    X,
    Y,
    flags,
    Ap,
    Ai,
    slots,
    diag,
    plan,
    n_work,
    first_accumulator,
    constant_jacobian,
    q,
):
    """Integrate from t_out[0] to t_out[-1]; write states X and outputs Y at t_out (run through
    :func:`compiled_radau5`, which compiles it on first use).

    ``rhs``, ``output``, ``opin``, ``commit`` are the model's functions, ``jac``  writes the
    local partials of its Jacobian program (``jaux`` its aux data; with memory operators, the
    direction of each one's slope, kept here), ``inputs`` and ``reversal_at`` are
    :func:`~bondgraph.numerics.integrators.input_values` and
    :func:`~bondgraph.numerics.integrators.reversal_at`; the signal arrays come from
    :meth:`~bondgraph.numerics.signal_bank.SignalBank.args`.  ``Ap``, ``Ai`` (CSC pattern of
    J_aug), ``slots``, ``diag``, ``plan``, ``n_work``, ``first_accumulator`` and
    ``constant_jacobian`` describe the Jacobian program, ``q`` the column order of the LU.
    ``h_io[0]``: the first step (0: chosen here), on return the next step proposed.
    Returns :class:`ImplicitStats`."""
    n = x0.shape[0]
    N = Ap.shape[0] - 1
    nnz = Ai.shape[0]
    nu = skind.shape[0]
    ny = Y.shape[1]
    nv = n_ops
    rates = flags.input_rates
    out_inputs = flags.outputs_use_inputs
    opin_inputs = flags.opins_use_inputs
    C, T, TI, P = _C, _T, _TI, _P
    u = np.zeros(max(nu, 1))
    du = np.zeros(max(nu, 1))
    x = x0.copy()
    xn = np.empty(n)
    xs = np.empty(n)
    xd = np.empty(n)
    f = np.empty(n)
    tmp = np.empty(n)
    Z = np.zeros((3, n))
    Wt = np.zeros((3, n))
    F = np.empty((3, n))
    dW = np.empty((3, n))
    Q = np.zeros((n, 3))
    Qold = np.zeros((n, 3))
    x_old = x0.copy()
    w = np.empty(n)
    peak = np.abs(x0)
    y = np.empty(max(ny, 1))
    v0 = np.zeros(max(nv, 1))
    v1 = np.zeros(max(nv, 1))
    vt = np.zeros(max(nv, 1))
    # the Jacobian program and the two factorisations
    Wk = np.zeros(n_work)
    Wk[0] = 1.0
    Wk[1] = -1.0
    Jv = np.zeros(nnz)
    Ar = np.empty(nnz)
    Ac = np.empty(nnz, np.complex128)
    cap = 4 * nnz + 8 * N
    Lp_r, Li_r, Lx_r, Up_r, Ui_r, Ux_r, pinv_r, rs_r = _lu_storage(N, cap, Ar)
    Lp_c, Li_c, Lx_c, Up_c, Ui_c, Ux_c, pinv_c, rs_c = _lu_storage(N, cap, Ac)
    br = np.zeros(N)
    bc = np.zeros(N, np.complex128)
    xr = np.zeros(N)
    xc = np.zeros(N, np.complex128)
    xi = np.empty(N, np.int64)
    stack = np.empty(N, np.int64)
    pstack = np.empty(N, np.int64)
    mark = np.empty(N, np.int64)

    t = t_out[0]
    t_end = t_out[-1]
    k_out = 0
    n_out = t_out.shape[0]
    ib = 0
    while ib < t_break.shape[0] and t_break[ib] <= t:
        ib += 1
    inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
    rhs(t, x, u, du, th, mem, aux, f)
    n_rhs = 1
    if nv:
        commit(t, x, u, du, th, mem, aux, v1)
    while k_out < n_out and t_out[k_out] <= t:
        output(t, x, u, du, th, mem, aux, y)
        store_sample(X, Y, k_out, x, y, ny)
        k_out += 1

    n_jac = 0
    n_lu = 0
    n_steps = 0
    n_rej = 0
    n_rev = 0
    n_fail = 0
    status = 0
    newton_tol = max(10.0 * np.finfo(np.float64).eps / rtol, min(0.03, rtol**0.5))
    h_abs = h_io[0]
    restart = True  # choose the step size (at the start and after a breakpoint)
    jac_stale = True
    lu_h = -1.0
    have_sol = False
    h_abs_old = -1.0
    err_old = -1.0
    t_old = t
    h_old = 1.0
    current_jac = False
    safety = 0.9
    while t < t_end:
        if n_steps >= max_steps:
            status = 2
            break
        t_stop = t_end
        if ib < t_break.shape[0] and t_break[ib] < t_stop:
            t_stop = t_break[ib]
        t_left = np.nextafter(t_stop, -np.inf)
        h_min = 10.0 * np.spacing(abs(t) + 1.0)
        if jac_stale:  # Jacobian at (t, x)
            inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            _jacobian_values(jac, t, x, u, du, th, mem, jaux, Wk, plan, first_accumulator, slots, Jv)
            n_jac += 1
            jac_stale = False
            current_jac = True
            lu_h = -1.0
        if restart:
            if not (h_abs > 0.0):  # Hairer & Wanner's initial step (order 3), as in scipy
                for i in range(n):
                    w[i] = atol[i] + rtol * max(abs(x[i]), peak[i])
                d0 = _rms(x, w, n)
                d1 = _rms(f, w, n)
                h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
                h0 = min(h0, t_stop - t)
                for i in range(n):
                    xs[i] = x[i] + h0 * f[i]
                inputs(t + h0, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                rhs(t + h0, xs, u, du, th, mem, aux, tmp)
                n_rhs += 1
                for i in range(n):
                    tmp[i] -= f[i]
                d2 = _rms(tmp, w, n) / h0
                if d1 <= 1e-15 and d2 <= 1e-15:
                    h1 = max(1e-6, h0 * 1e-3)
                else:
                    h1 = (0.01 / max(d1, d2)) ** 0.25
                h_abs = min(100.0 * h0, h1, h_max)
            restart = False
            have_sol = False
            h_abs_old = -1.0
            err_old = -1.0
        if h_abs > h_max:
            h_abs = h_max
            h_abs_old = -1.0
            err_old = -1.0
        elif h_abs < h_min:
            h_abs = h_min
            h_abs_old = -1.0
            err_old = -1.0
        rejected = False
        accepted = False
        n_iter = 0
        rate = -1.0
        err_norm = 0.0
        h = h_abs
        hit = False
        t_new = t
        h_full = h_abs
        while not accepted:
            if h_abs < h_min:
                status = 1
                break
            h_full = h_abs
            h = h_abs
            hit = False
            if t + h >= t_stop:
                h = t_stop - t
                hit = True
            t_new = t_stop if hit else t + h
            # predictor: the last step's collocation polynomial, extrapolated
            _predict(have_sol, x_old, Qold, t_old, h_old, t, h, x, Z, xd)
            for i in range(n):
                w[i] = atol[i] + rtol * max(abs(x[i]), peak[i])
            converged = False
            singular = False
            while True:
                if lu_h != h:
                    _newton_matrix(Jv, diag, n, _MU_REAL / h, Ar)
                    st, Li_r, Lx_r, Ui_r, Ux_r = _factor(
                        Ap, Ai, Ar, q, rs_r, Lp_r, Li_r, Lx_r, Up_r, Ui_r, Ux_r, pinv_r, xr, xi, stack, pstack, mark
                    )
                    if st == 0:
                        _newton_matrix(Jv, diag, n, _MU_COMPLEX / h, Ac)
                        st, Li_c, Lx_c, Ui_c, Ux_c = _factor(
                            Ap, Ai, Ac, q, rs_c, Lp_c, Li_c, Lx_c, Up_c, Ui_c, Ux_c, pinv_c, xc, xi, stack, pstack, mark
                        )
                    n_lu += 1
                    if st != 0:
                        singular = True
                        lu_h = -1.0
                        break
                    lu_h = h
                # simplified Newton iteration on the collocation system (transformed variables)
                mr = _MU_REAL / h
                mc = _MU_COMPLEX / h
                for s in range(3):
                    for i in range(n):
                        Wt[s, i] = TI[s, 0] * Z[0, i] + TI[s, 1] * Z[1, i] + TI[s, 2] * Z[2, i]
                dw_old = -1.0
                rate = -1.0
                converged = False
                for k in range(_NEWTON_MAXITER):
                    n_iter = k + 1
                    finite = True
                    for s in range(3):
                        ts = t + C[s] * h
                        if hit and ts >= t_stop:
                            ts = t_left  # inputs jump at a breakpoint: the step sees their left limit
                        for i in range(n):
                            xs[i] = x[i] + Z[s, i]
                        inputs(ts, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                        rhs(ts, xs, u, du, th, mem, aux, F[s])
                        for i in range(n):
                            if not math.isfinite(F[s, i]):
                                finite = False
                    n_rhs += 3
                    if not finite:
                        break
                    for i in range(n):
                        br[i] = TI[0, 0] * F[0, i] + TI[0, 1] * F[1, i] + TI[0, 2] * F[2, i] - mr * Wt[0, i]
                        bc[i] = (
                            _TI_COMPLEX[0] * F[0, i]
                            + _TI_COMPLEX[1] * F[1, i]
                            + _TI_COMPLEX[2] * F[2, i]
                            - mc * (Wt[1, i] + 1j * Wt[2, i])
                        )
                    for i in range(n, N):
                        br[i] = 0.0
                        bc[i] = 0.0
                    lu_solve(q, rs_r, Lp_r, Li_r, Lx_r, Up_r, Ui_r, Ux_r, pinv_r, br, xr)
                    lu_solve(q, rs_c, Lp_c, Li_c, Lx_c, Up_c, Ui_c, Ux_c, pinv_c, bc, xc)
                    acc = 0.0
                    for i in range(n):
                        dW[0, i] = br[i]
                        dW[1, i] = bc[i].real
                        dW[2, i] = bc[i].imag
                        acc += (br[i] / w[i]) ** 2 + (bc[i].real / w[i]) ** 2 + (bc[i].imag / w[i]) ** 2
                    dw_norm = math.sqrt(acc / max(3 * n, 1))
                    if dw_old >= 0.0:
                        rate = dw_norm / dw_old
                    if not math.isfinite(dw_norm):
                        break
                    if rate >= 0.0 and (
                        rate >= 1.0 or rate ** (_NEWTON_MAXITER - k) / (1.0 - rate) * dw_norm > newton_tol
                    ):
                        break
                    for s in range(3):
                        for i in range(n):
                            Wt[s, i] += dW[s, i]
                    for s in range(3):
                        for i in range(n):
                            Z[s, i] = T[s, 0] * Wt[0, i] + T[s, 1] * Wt[1, i] + T[s, 2] * Wt[2, i]
                    if (
                        constant_jacobian
                        or dw_norm == 0.0
                        or (rate >= 0.0 and rate / (1.0 - rate) * dw_norm < newton_tol)
                    ):
                        converged = True  # an affine right-hand side: one step with its exact Jacobian solves it
                        break
                    dw_old = dw_norm
                if converged or current_jac or constant_jacobian:
                    break
                # a Jacobian from an earlier step did not converge: a fresh one at (t, x)
                inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                _jacobian_values(jac, t, x, u, du, th, mem, jaux, Wk, plan, first_accumulator, slots, Jv)
                n_jac += 1
                current_jac = True
                lu_h = -1.0
                _predict(have_sol, x_old, Qold, t_old, h_old, t, h, x, Z, xd)
            if not converged or singular:
                h_abs *= 0.5
                lu_h = -1.0
                n_rej += 1
                n_fail += 1
                continue
            # error estimate (Hairer & Wanner's, with scipy's scaling)
            finite = True
            for i in range(n):
                xn[i] = x[i] + Z[2, i]
                if not math.isfinite(xn[i]):
                    finite = False
                w[i] = atol[i] + rtol * max(abs(x[i]), abs(xn[i]), peak[i])
            _error(f, Z, h, br)
            lu_solve(q, rs_r, Lp_r, Li_r, Lx_r, Up_r, Ui_r, Ux_r, pinv_r, br, xr)
            err_norm = _rms(br, w, n)
            safety = 0.9 * (2 * _NEWTON_MAXITER + 1) / (2 * _NEWTON_MAXITER + n_iter)
            if rejected and err_norm > 1.0:
                for i in range(n):
                    xs[i] = x[i] + br[i]
                inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                rhs(t, xs, u, du, th, mem, aux, tmp)
                n_rhs += 1
                _error(tmp, Z, h, br)
                lu_solve(q, rs_r, Lp_r, Li_r, Lx_r, Up_r, Ui_r, Ux_r, pinv_r, br, xr)
                err_norm = _rms(br, w, n)
            if not finite or not math.isfinite(err_norm):
                if h_abs < 2.0 * h_min:
                    status = 3
                    break
                h_abs *= 0.25
                lu_h = -1.0
                n_rej += 1
                rejected = True
                continue
            if err_norm > 1.0:
                factor = _predict_factor(h_abs, h_abs_old, err_norm, err_old)
                h_abs *= max(_MIN_FACTOR, safety * factor)
                n_rej += 1
                rejected = True
                continue
            # dense output of this step: x(t + θh) = x + Σ_j Q[:, j]·θ^(j+1)
            for i in range(n):
                for j in range(3):
                    Q[i, j] = Z[0, i] * P[0, j] + Z[1, i] * P[1, j] + Z[2, i] * P[2, j]
            t_eval = t_left if hit else t_new
            # memory operators: reject steps whose operator inputs reverse inside the step
            if nv:
                if opin_inputs:
                    inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                opin(t, x, u, du, th, mem, aux, v0)
                if opin_inputs:
                    inputs(t_eval, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                opin(t_eval, xn, u, du, th, mem, aux, v1)
                reversal = -1.0
                for c in range(1, _N_CHECK + 1):
                    theta = c / (_N_CHECK + 1.0)
                    _dense(x, Q, theta, xd)
                    if opin_inputs:
                        inputs(t + theta * h, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                    opin(t + theta * h, xd, u, du, th, mem, aux, vt)
                    reversal = reversal_at(v0, v1, vt, theta, reversal)
                if reversal > 0.0 and h > 64 * h_min:
                    h_abs = h * reversal
                    n_rev += 1
                    n_rej += 1
                    continue
            accepted = True
        if status != 0:
            break
        # accepted: dense outputs (memory still frozen), then commit
        while k_out < n_out and t_out[k_out] <= t_new:
            _dense(x, Q, (t_out[k_out] - t) / h, xd)
            if out_inputs:
                inputs(t_out[k_out], skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            output(t_out[k_out], xd, u, du, th, mem, aux, y)
            store_sample(X, Y, k_out, xd, y, ny)
            k_out += 1
        if nv:
            if hit:  # follow the input up to the jump, then across it
                inputs(t_left, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                commit(t_left, xn, u, du, th, mem, aux, v1)
            inputs(t_new, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            commit(t_new, xn, u, du, th, mem, aux, v1)
            for j in range(nv):  # operator slopes are taken in the direction their input moves
                d = 1.0 if v1[j] > v0[j] else (-1.0 if v1[j] < v0[j] else jaux[j])
                if d != jaux[j]:
                    jaux[j] = d
                    jac_stale = not constant_jacobian
        for i in range(n):
            x_old[i] = x[i]
            x[i] = xn[i]
            if abs(xn[i]) > peak[i]:
                peak[i] = abs(xn[i])
            for j in range(3):
                Qold[i, j] = Q[i, j]
        t_old = t
        h_old = h
        have_sol = True
        t = t_new
        n_steps += 1
        inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
        rhs(t, x, u, du, th, mem, aux, f)
        n_rhs += 1
        recompute = (not constant_jacobian) and n_iter > 2 and rate > 1e-3
        factor = _predict_factor(h, h_abs_old, err_norm, err_old)
        factor = min(_MAX_FACTOR, safety * factor)
        if not recompute and factor < 1.2:
            factor = 1.0
        h_abs_old = h
        err_old = err_norm
        h_abs = (h_full if hit else h) * factor
        current_jac = False
        if recompute:
            jac_stale = True
        if hit and ib < t_break.shape[0] and t >= t_break[ib]:
            ib += 1  # a discontinuity: start afresh (step size, predictor, Jacobian)
            restart = True
            h_abs = 0.0
            jac_stale = not constant_jacobian
    h_io[0] = h_abs
    return ImplicitStats(status, n_steps, n_rej, n_rhs, n_rev, k_out, n_jac, n_lu, n_fail)
