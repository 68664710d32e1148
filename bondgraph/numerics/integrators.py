"""Compiled kernels: input-signal evaluation and the adaptive integrator (Dormand–Prince 5(4),
scipy's RK45 tableau) with memory.  They share this file so numba's on-disk cache, which is
keyed by the source file, never pairs a cached integrator with a changed signal kernel.

One numba function serves every model: the model's compiled functions are passed as
first-class function values, so the integrator is compiled once and cached on disk.

Contract with memory operators (see :mod:`bondgraph.model.memory`): inside a step the operator
memory is frozen; after a step passes the error test its operator inputs are sampled at
interior points of the dense output, and if one of them reverses direction inside the step
the step is rejected and retried up to the reversal, so a play/slip operator never misses a
turning point; only then is the memory committed at the step's end.  Rejected steps never
touch the memory.

Error weight per state: ``atol_i + rtol·max(|x_i|, peak_i)``, where ``peak_i`` is the largest
|x_i| seen so far (a tolerance relative to the signal's range, suited to SI magnitudes of
1e-9..1e3 in the same model).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit, types
from scipy.integrate import RK45

from ..model.signals import CHIRP, CONST, PWL, RAMP, SINE, STEP  # signal kinds (the last, TRIANGLE, is the else branch)
from .model_functions import FUNCTION_TYPE


@njit(cache=True)
def eval_inputs(t, kind, par, off, ln, tt, tv, cur, u, du, with_du):
    """Write every input's value and, when ``with_du``, its time derivative at time t into u and du.

    ``cur`` holds, per table input, the last table interval used: the integrator's times are
    nearly monotone, so the interval is usually found in O(1) instead of a binary search."""
    for i in range(kind.shape[0]):
        k = kind[i]
        if k == SINE:
            w = 2.0 * math.pi * par[i, 1]
            ph = w * t + par[i, 2]
            u[i] = par[i, 3] + par[i, 0] * math.sin(ph)
            du[i] = par[i, 0] * w * math.cos(ph) if with_du else 0.0
        elif k == PWL:
            o = off[i]
            last = o + ln[i] - 1
            if t < tt[o] or last == o:
                u[i] = tv[o]
                du[i] = 0.0
            elif t > tt[last]:
                u[i] = tv[last]
                du[i] = 0.0
            else:  # inside the table (ends included: the slope of the first/last interval)
                lo = cur[i]  # intervals are [t_k, t_k+1): at a knot, the slope that follows it
                if lo < o or lo >= last or not (tt[lo] <= t < tt[lo + 1] or (t == tt[last] and lo == last - 1)):
                    if o <= lo < last - 1 and tt[lo + 1] <= t < tt[lo + 2]:
                        lo += 1
                    else:
                        lo = o
                        hi = last
                        while hi - lo > 1:
                            mid = (lo + hi) >> 1
                            if tt[mid] <= t:
                                lo = mid
                            else:
                                hi = mid
                        if lo >= last:
                            lo = last - 1
                    cur[i] = lo
                s = (tv[lo + 1] - tv[lo]) / (tt[lo + 1] - tt[lo])
                u[i] = tv[lo] + s * (t - tt[lo])
                du[i] = s
        elif k == CONST:
            u[i] = par[i, 0]
            du[i] = 0.0
        elif k == STEP:
            u[i] = par[i, 2] + (par[i, 0] if t >= par[i, 1] else 0.0)
            du[i] = 0.0
        elif k == RAMP:
            if t > par[i, 1]:
                u[i] = par[i, 2] + par[i, 0] * (t - par[i, 1])
                du[i] = par[i, 0]
            else:
                u[i] = par[i, 2]
                du[i] = 0.0
        elif k == CHIRP:
            beta = (par[i, 2] - par[i, 1]) / par[i, 3]
            ph = 2.0 * math.pi * (par[i, 1] * t + 0.5 * beta * t * t) + par[i, 4]
            u[i] = par[i, 5] + par[i, 0] * math.cos(ph)
            du[i] = -par[i, 0] * math.sin(ph) * 2.0 * math.pi * (par[i, 1] + beta * t) if with_du else 0.0
        else:  # TRIANGLE, as scipy.signal.sawtooth(x, 0.5): rises over [0, π), falls over [π, 2π)
            y = 2.0 * math.pi * par[i, 1] * t + par[i, 2]
            x = y - 2.0 * math.pi * math.floor(y / (2.0 * math.pi))
            slope = 4.0 * par[i, 0] * par[i, 1]
            if x < math.pi:
                u[i] = par[i, 3] + par[i, 0] * (-1.0 + 2.0 * x / math.pi)
                du[i] = slope
            else:
                u[i] = par[i, 3] + par[i, 0] * (3.0 - 2.0 * x / math.pi)
                du[i] = -slope


_f1 = types.float64[::1]
_f2 = types.float64[:, ::1]
_i1 = types.int64[::1]
#: type of :func:`input_values` as a first-class function value
INPUTS_TYPE = types.FunctionType(types.void(types.float64, _i1, _f2, _i1, _i1, _f1, _f1, _i1, _f1, _f1, types.boolean))


def input_values(t, kind, par, off, ln, tt, tv, cur, u, du, with_du):
    """:func:`eval_inputs` as a function value for kernels in other files (numba's disk cache
    would not see a change to this file in a kernel that inlined it); compiled by
    :func:`compiled_input_values`."""
    eval_inputs(t, kind, par, off, ln, tt, tv, cur, u, du, with_du)


@functools.cache
def compiled_input_values():
    """:func:`input_values` compiled as a first-class function value, on first use (by the
    implicit integrator only: a non-stiff run never builds it).

    Returns
    -------
    numba.core.registry.CPUDispatcher
        The compiled function, of type :data:`INPUTS_TYPE`.
    """
    return njit(INPUTS_TYPE.signature, cache=True)(input_values)


#: type of :func:`reversal_at` as a first-class function value
REVERSAL_TYPE = types.FunctionType(types.float64(_f1, _f1, _f1, types.float64, types.float64))


@njit(REVERSAL_TYPE.signature, cache=True)
def reversal_at(v0, v1, vt, theta, reversal):
    """The memory contract's test: ``theta`` if an operator input reverses between the step's
    start (``v0``), its interior point θ (``vt``) and its end (``v1``), and θ is earlier than
    ``reversal`` (negative: none yet); ``reversal`` otherwise."""
    for j in range(v0.shape[0]):
        tol = 1e-9 * (abs(v0[j]) + abs(v1[j])) + 1e-300
        d_in = vt[j] - v0[j]
        d_out = v1[j] - vt[j]
        if (d_in > tol and d_out < -tol) or (d_in < -tol and d_out > tol):
            if reversal < 0.0 or theta < reversal:
                reversal = theta
    return reversal


@njit(cache=True)
def sample_inputs(t, kind, par, off, ln, tt, tv, cur, with_du, out):
    """Values of all inputs at the times ``t`` into ``out`` (len(t) × n_inputs); ``with_du``
    (False from the caller: a run-time flag, so the integrator's compiled :func:`eval_inputs`
    serves, where a literal would compile another specialisation of it)."""
    u = np.zeros(kind.shape[0])
    du = np.zeros(kind.shape[0])
    for k in range(t.shape[0]):
        eval_inputs(t[k], kind, par, off, ln, tt, tv, cur, u, du, with_du)
        for i in range(u.shape[0]):  # element by element: see store_sample
            out[k, i] = u[i]


_A = np.ascontiguousarray(RK45.A, float)
_B = np.ascontiguousarray(RK45.B, float)
_C = np.ascontiguousarray(RK45.C, float)
_E = np.ascontiguousarray(RK45.E, float)
_P = np.ascontiguousarray(RK45.P, float)
_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
_N_CHECK = 4  # interior points where operator inputs are checked for a reversal

STATUS = {0: "ok", 1: "step size underflow", 2: "too many steps", 3: "non-finite state"}


@njit(cache=True)
def _weights(x0, x1, peak, atol, rtol, w):
    for i in range(x0.shape[0]):
        a = abs(x0[i])
        b = abs(x1[i])
        m = a if a > b else b
        if peak[i] > m:
            m = peak[i]
        w[i] = atol[i] + rtol * m
        if w[i] <= 0.0:
            w[i] = 1e-300


@njit(cache=True)
def _coeffs(K, P, Q):
    """Q = Pᵀ·K: the dense-output polynomial of a step, computed once per step."""
    for j in range(P.shape[1]):
        for i in range(K.shape[1]):
            q = 0.0
            for s in range(K.shape[0]):
                q += K[s, i] * P[s, j]
            Q[j, i] = q


@njit(cache=True)
def _dense(x, Q, h, theta, out):
    """x(t + θh) = x + h·Σ_j Q_j·θ^(j+1)."""
    for i in range(x.shape[0]):
        acc = 0.0
        for j in range(Q.shape[0] - 1, -1, -1):
            acc = (acc + Q[j, i]) * theta
        out[i] = x[i] + h * acc


@njit(cache=True)
def store_sample(X, Y, k, x, y, ny):
    """Row k of the states X and outputs Y from x and y[:ny] (element by element: numba's
    slice assignment would compile its shape-mismatch error text, seconds of the first build).
    """
    for i in range(x.shape[0]):
        X[k, i] = x[i]
    for i in range(ny):
        Y[k, i] = y[i]


class Flags(NamedTuple):
    """What the model's functions read, so the integrator evaluates inputs only when needed.

    Parameters
    ----------
    input_rates : bool
        The laws use input rates (du is evaluated at every stage).
    outputs_use_inputs : bool
        The outputs read inputs or input rates.
    opins_use_inputs : bool
        The operator inputs read inputs or input rates.
    """

    input_rates: bool  # the laws use input rates (evaluate du at every stage)
    outputs_use_inputs: bool  # the outputs read inputs or input rates
    opins_use_inputs: bool  # the operator inputs read inputs or input rates


class Stats(NamedTuple):
    """Outcome of :func:`dopri5`: status code (0 ok, see STATUS) and counts.

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
    """

    status: int
    steps: int
    rejected: int
    rhs_calls: int
    reversal_rejections: int
    written: int  # output samples written (the failure time when status != 0)


_FLAGS = types.NamedUniTuple(types.boolean, len(Flags._fields), Flags)
_STATS = types.NamedUniTuple(types.int64, len(Stats._fields), Stats)
_FN4 = (FUNCTION_TYPE,) * 4
#: the types of SignalBank.args() (kind, par, off, len, tt, tv, cur), then t_out, t_break
SIGNAL_TYPES = (_i1, _f2, _i1, _i1, _f1, _f1, _i1, _f1, _f1)


@njit(
    _STATS(
        *_FN4,
        _f1,
        _f1,
        _f1,
        _f1,
        types.int64,
        *SIGNAL_TYPES,
        types.float64,
        _f1,
        types.float64,
        types.float64,
        types.int64,
        _f2,
        _f2,
        _FLAGS,
    ),
    cache=True,
)
def dopri5(
    rhs,
    output,
    opin,
    commit,
    x0,
    th,
    mem,
    aux,
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
    h_init,
    h_max,
    max_steps,
    X,
    Y,
    flags,
):
    """Integrate from t_out[0] to t_out[-1]; write states X and outputs Y at t_out.

    ``rhs``, ``output``, ``opin``, ``commit`` are the model's functions (calling convention of
    :mod:`bondgraph.numerics.model_functions`), ``mem`` the operator memory, ``aux`` the model's
    auxiliary data, ``n_ops`` the number of memory operators; the signal arrays come from
    :meth:`bondgraph.model.signals.SignalBank.args`.  Returns :class:`Stats`.
    """
    n = x0.shape[0]
    nu = skind.shape[0]
    ny = Y.shape[1]
    nv = n_ops
    rates = flags.input_rates
    out_inputs = flags.outputs_use_inputs
    opin_inputs = flags.opins_use_inputs
    A, B, C, E, P = _A, _B, _C, _E, _P
    ns = B.shape[0]
    u = np.zeros(max(nu, 1))
    du = np.zeros(max(nu, 1))
    x = x0.copy()
    xn = np.empty(n)
    xs = np.empty(n)
    xd = np.empty(n)
    K = np.zeros((ns + 1, n))
    Q = np.zeros((P.shape[1], n))
    w = np.empty(n)
    peak = np.abs(x0)
    err = np.empty(n)
    y = np.empty(max(ny, 1))
    v0 = np.zeros(max(nv, 1))
    v1 = np.zeros(max(nv, 1))
    vt = np.zeros(max(nv, 1))
    t = t_out[0]
    t_end = t_out[-1]
    k_out = 0
    n_out = t_out.shape[0]
    ib = 0
    while ib < t_break.shape[0] and t_break[ib] <= t:
        ib += 1
    eval_inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
    rhs(t, x, u, du, th, mem, aux, K[0])
    n_rhs = 1
    if nv:
        commit(t, x, u, du, th, mem, aux, v1)
    # outputs at the start
    while k_out < n_out and t_out[k_out] <= t:
        output(t, x, u, du, th, mem, aux, y)
        store_sample(X, Y, k_out, x, y, ny)
        k_out += 1
    # initial step (Hairer & Wanner), as in scipy
    _weights(x, x, peak, atol, rtol, w)
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        d0 += (x[i] / w[i]) ** 2
        d1 += (K[0, i] / w[i]) ** 2
    d0 = np.sqrt(d0 / max(n, 1))
    d1 = np.sqrt(d1 / max(n, 1))
    if h_init > 0.0:
        h = h_init
    else:
        h = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
        h = min(h, h_max, t_end - t)
        for i in range(n):
            xn[i] = x[i] + h * K[0, i]
        eval_inputs(t + h, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
        rhs(t + h, xn, u, du, th, mem, aux, err)
        n_rhs += 1
        d2 = 0.0
        for i in range(n):
            d2 += ((err[i] - K[0, i]) / w[i]) ** 2
        d2 = np.sqrt(d2 / max(n, 1)) / h
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** 0.2
        h = min(100 * h, h1, h_max)
    h = max(h, 1e-14 * max(abs(t), 1.0))
    n_steps = 0
    n_rej = 0
    n_rev = 0
    status = 0
    while t < t_end:
        if n_steps >= max_steps:
            status = 2
            break
        t_stop = t_end
        if ib < t_break.shape[0] and t_break[ib] < t_stop:
            t_stop = t_break[ib]
        h_min = 10.0 * np.spacing(abs(t) + 1.0)
        if h < h_min:
            status = 1
            break
        hit = False
        h_full = h
        if t + h >= t_stop:
            h = t_stop - t
            hit = True
        t_left = np.nextafter(t_stop, -np.inf)
        # stages
        for s in range(1, ns):
            for i in range(n):
                acc = 0.0
                for j in range(s):
                    acc += A[s, j] * K[j, i]
                xs[i] = x[i] + h * acc
            ts = t + C[s] * h
            if hit and ts >= t_stop:
                ts = t_left  # inputs jump at a breakpoint: the step sees their left limit
            eval_inputs(ts, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            rhs(ts, xs, u, du, th, mem, aux, K[s])
        for i in range(n):
            acc = 0.0
            for j in range(ns):
                acc += B[j] * K[j, i]
            xn[i] = x[i] + h * acc
        t_new = t_stop if hit else t + h
        t_eval = t_left if hit else t_new
        eval_inputs(t_eval, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
        rhs(t_eval, xn, u, du, th, mem, aux, K[ns])
        n_rhs += ns
        _weights(x, xn, peak, atol, rtol, w)
        en = 0.0
        finite = True
        for i in range(n):
            acc = 0.0
            for j in range(ns + 1):
                acc += E[j] * K[j, i]
            e = h * acc / w[i]
            en += e * e
            if not np.isfinite(xn[i]):
                finite = False
        en = np.sqrt(en / max(n, 1))
        if not finite or not np.isfinite(en):
            if h < h_min * 2:
                status = 3
                break
            h *= 0.25
            n_rej += 1
            continue
        if en > 1.0:
            h *= max(_MIN_FACTOR, _SAFETY * en**-0.2)
            n_rej += 1
            continue
        # memory operators: reject steps whose operator inputs reverse inside the step
        if nv:
            if opin_inputs:
                eval_inputs(t, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            opin(t, x, u, du, th, mem, aux, v0)
            reversal = -1.0
            if opin_inputs:
                eval_inputs(t_eval, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            opin(t_eval, xn, u, du, th, mem, aux, v1)
            _coeffs(K, P, Q)
            for c in range(1, _N_CHECK + 1):
                theta = c / (_N_CHECK + 1.0)
                _dense(x, Q, h, theta, xd)
                if opin_inputs:
                    eval_inputs(t + theta * h, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                opin(t + theta * h, xd, u, du, th, mem, aux, vt)
                reversal = reversal_at(v0, v1, vt, theta, reversal)
            if reversal > 0.0 and h > 64 * h_min:
                h = h * reversal
                n_rev += 1
                n_rej += 1
                continue
        # accepted: dense outputs (memory still frozen), then commit
        if k_out < n_out and t_out[k_out] <= t_new:
            _coeffs(K, P, Q)
        while k_out < n_out and t_out[k_out] <= t_new:
            theta = (t_out[k_out] - t) / h
            _dense(x, Q, h, theta, xd)
            if out_inputs:
                eval_inputs(t_out[k_out], skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            output(t_out[k_out], xd, u, du, th, mem, aux, y)
            store_sample(X, Y, k_out, xd, y, ny)
            k_out += 1
        if nv:
            if hit:  # follow the input up to the jump, then across it
                eval_inputs(t_eval, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
                commit(t_eval, xn, u, du, th, mem, aux, v1)
            eval_inputs(t_new, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
            commit(t_new, xn, u, du, th, mem, aux, v1)
        else:
            eval_inputs(t_new, skind, spar, soff, slen, stt, stv, scur, u, du, rates)
        for i in range(n):
            x[i] = xn[i]
            if abs(xn[i]) > peak[i]:
                peak[i] = abs(xn[i])
        t = t_new
        n_steps += 1
        if hit and ib < t_break.shape[0] and t >= t_break[ib]:
            ib += 1
            rhs(t, x, u, du, th, mem, aux, K[0])  # restart after a discontinuity
            n_rhs += 1
        else:
            if nv:
                rhs(t, x, u, du, th, mem, aux, K[0])  # memory changed: FSAL value is stale
                n_rhs += 1
            else:
                for i in range(n):
                    K[0, i] = K[ns, i]
        fac = _MAX_FACTOR if en == 0.0 else min(_MAX_FACTOR, _SAFETY * en**-0.2)
        # a step shortened to land on a breakpoint keeps the size the controller had proposed
        h = min(h_full, h_max) if hit else min(h * fac, h_max)
    return Stats(status, n_steps, n_rej, n_rhs, n_rev, k_out)
