"""The compiled limit: a hand-written numba DOPRI5 with hand-written right-hand sides.

Same algorithm as ``bondgraph.numerics.integrators.dopri5`` (scipy's RK45 tableau, Hairer's initial
step, safety 0.9, factors 0.2..10, error weight atol_i + rtol·max(|x_i|, |x_new,i|, peak_i),
RMS norm, dense output at the requested times, memory frozen inside a step and committed
after each accepted step, FSAL refreshed after a commit, optional rejection of steps in which
an operator input reverses) but specialised at compile time: the model functions are plain
``@njit`` functions captured by a closure, so numba calls (and usually inlines) them directly
instead of through first-class function pointers, the inputs are computed inline, and there is
no generic signal bank, no break-point logic and no per-call array argument packing.

Models written by hand:

* ``chain``: the N-mass chain of bench_models (states p_1..p_N, q_1..q_N, as ours);
  input F = chirp (amplitude, f0, f1, t1) like ``bondgraph.Chirp``;
* ``apa_pi``: the APA-120ML with the modified-PI polarization (states q_K, q_CNL, p_M, as
  ours); input V = sine (amplitude, frequency, phase, offset) like ``bondgraph.Sine``, F = 0.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.integrate import RK45

_A = np.ascontiguousarray(RK45.A, float)
_B = np.ascontiguousarray(RK45.B, float)
_C = np.ascontiguousarray(RK45.C, float)
_E = np.ascontiguousarray(RK45.E, float)
_P = np.ascontiguousarray(RK45.P, float)
N_CHECK = 4


def make_dopri5(rhs, output, opin, commit):
    """A compiled DOPRI5 for one model: ``rhs(t, x, prm, mem, out)``, ``output(t, x, prm, mem,
    out)``, ``opin(t, x, prm, out)`` (operator inputs) and ``commit(t, x, prm, mem)``."""
    A, B, C, E, P = _A, _B, _C, _E, _P

    @njit(cache=False)
    def dense_coeffs(K, Q):
        """Q = K^T P: the interpolant's coefficients, once per step (as scipy's RK45)."""
        for i in range(Q.shape[0]):
            for j in range(P.shape[1]):
                q = 0.0
                for s in range(K.shape[0]):
                    q += K[s, i] * P[s, j]
                Q[i, j] = q

    @njit(cache=False)
    def dense(x, Q, h, theta, out):
        for i in range(x.shape[0]):
            acc = 0.0
            th = theta
            for j in range(Q.shape[1]):
                acc += Q[i, j] * th
                th *= theta
            out[i] = x[i] + h * acc

    @njit(cache=False)
    def run(x0, prm, mem, n_ops, check_reversals, t_out, rtol, atol, X, Y, stats):
        n = x0.shape[0]
        ns = B.shape[0]
        x = x0.copy()
        xn = np.empty(n)
        xs = np.empty(n)
        xd = np.empty(n)
        K = np.zeros((ns + 1, n))
        Q = np.zeros((n, P.shape[1]))
        w = np.empty(n)
        peak = np.abs(x0)
        tmp = np.empty(n)
        y = np.empty(Y.shape[1])
        v0 = np.zeros(max(n_ops, 1))
        v1 = np.zeros(max(n_ops, 1))
        vt = np.zeros(max(n_ops, 1))
        t = t_out[0]
        t_end = t_out[-1]
        k_out = 0
        n_out = t_out.shape[0]
        rhs(t, x, prm, mem, K[0])
        n_rhs = 1
        while k_out < n_out and t_out[k_out] <= t:
            X[k_out, :] = x
            output(t, x, prm, mem, y)
            Y[k_out, :] = y
            k_out += 1
        # initial step (as bondgraph.numerics.integrators / scipy)
        for i in range(n):
            w[i] = atol[i] + rtol * max(abs(x[i]), peak[i])
            if w[i] <= 0.0:
                w[i] = 1e-300
        d0 = 0.0
        d1 = 0.0
        for i in range(n):
            d0 += (x[i] / w[i]) ** 2
            d1 += (K[0, i] / w[i]) ** 2
        d0 = math.sqrt(d0 / n)
        d1 = math.sqrt(d1 / n)
        h = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
        h = min(h, t_end - t)
        for i in range(n):
            xn[i] = x[i] + h * K[0, i]
        rhs(t + h, xn, prm, mem, tmp)
        n_rhs += 1
        d2 = 0.0
        for i in range(n):
            d2 += ((tmp[i] - K[0, i]) / w[i]) ** 2
        d2 = math.sqrt(d2 / n) / h
        if d1 <= 1e-15 and d2 <= 1e-15:
            h1 = max(1e-6, h * 1e-3)
        else:
            h1 = (0.01 / max(d1, d2)) ** 0.2
        h = min(100 * h, h1)
        h = max(h, 1e-14 * max(abs(t), 1.0))
        n_steps = 0
        n_rej = 0
        n_rev = 0
        status = 0
        while t < t_end:
            h_min = 10.0 * np.spacing(abs(t) + 1.0)
            if h < h_min:
                status = 1
                break
            hit = False
            h_full = h
            if t + h >= t_end:
                h = t_end - t
                hit = True
            for s in range(1, ns):
                for i in range(n):
                    acc = 0.0
                    for j in range(s):
                        acc += A[s, j] * K[j, i]
                    xs[i] = x[i] + h * acc
                rhs(t + C[s] * h, xs, prm, mem, K[s])
            for i in range(n):
                acc = 0.0
                for j in range(ns):
                    acc += B[j] * K[j, i]
                xn[i] = x[i] + h * acc
            t_new = t_end if hit else t + h
            rhs(t_new, xn, prm, mem, K[ns])
            n_rhs += ns
            en = 0.0
            for i in range(n):
                m = max(abs(x[i]), abs(xn[i]), peak[i])
                wi = atol[i] + rtol * m
                if wi <= 0.0:
                    wi = 1e-300
                acc = 0.0
                for j in range(ns + 1):
                    acc += E[j] * K[j, i]
                e = h * acc / wi
                en += e * e
            en = math.sqrt(en / n)
            if not math.isfinite(en):
                h *= 0.25
                n_rej += 1
                continue
            if en > 1.0:
                h *= max(0.2, 0.9 * en**-0.2)
                n_rej += 1
                continue
            if n_ops > 0 and check_reversals:
                opin(t, x, prm, v0)
                opin(t_new, xn, prm, v1)
                reversal = -1.0
                dense_coeffs(K, Q)
                for c in range(1, N_CHECK + 1):
                    theta = c / (N_CHECK + 1.0)
                    dense(x, Q, h, theta, xd)
                    opin(t + theta * h, xd, prm, vt)
                    for j in range(n_ops):
                        tol = 1e-9 * (abs(v0[j]) + abs(v1[j])) + 1e-300
                        d_in = vt[j] - v0[j]
                        d_out = v1[j] - vt[j]
                        if (d_in > tol and d_out < -tol) or (d_in < -tol and d_out > tol):
                            if reversal < 0.0 or theta < reversal:
                                reversal = theta
                if reversal > 0.0 and h > 64 * h_min:
                    h = h * reversal
                    n_rev += 1
                    n_rej += 1
                    continue
            if k_out < n_out and t_out[k_out] <= t_new:
                dense_coeffs(K, Q)
            while k_out < n_out and t_out[k_out] <= t_new:
                theta = (t_out[k_out] - t) / h
                dense(x, Q, h, theta, xd)
                output(t_out[k_out], xd, prm, mem, y)
                X[k_out, :] = xd
                Y[k_out, :] = y
                k_out += 1
            if n_ops > 0:
                commit(t_new, xn, prm, mem)
            for i in range(n):
                x[i] = xn[i]
                if abs(xn[i]) > peak[i]:
                    peak[i] = abs(xn[i])
            t = t_new
            n_steps += 1
            if n_ops > 0:
                rhs(t, x, prm, mem, K[0])
                n_rhs += 1
            else:
                for i in range(n):
                    K[0, i] = K[ns, i]
            fac = 10.0 if en == 0.0 else min(10.0, 0.9 * en**-0.2)
            h = (h_full if hit else h) * fac
        stats[0] = n_steps
        stats[1] = n_rej
        stats[2] = n_rhs
        stats[3] = n_rev
        return status

    return run


# ---- the N-mass chain -----------------------------------------------------------------------
# prm = [n, F_amp, f0, f1, t1, m_1..m_n, k_1..k_n, c_1..c_n]
@njit
def chain_force(t, prm):
    a, f0, f1, t1 = prm[1], prm[2], prm[3], prm[4]
    beta = (f1 - f0) / t1
    return a * math.cos(2.0 * math.pi * (f0 * t + 0.5 * beta * t * t))


@njit
def chain_rhs(t, x, prm, mem, out):
    n = int(prm[0])
    m = prm[5 : 5 + n]
    k = prm[5 + n : 5 + 2 * n]
    c = prm[5 + 2 * n : 5 + 3 * n]
    F = chain_force(t, prm)
    prev = F  # force pushing mass i from the left
    for i in range(n):
        v = x[i] / m[i]
        s = v - x[i + 1] / m[i + 1] if i < n - 1 else v  # relative velocity of link i
        f = k[i] * x[n + i] + c[i] * s  # link force (compression)
        out[i] = prev - f
        out[n + i] = s
        prev = f


@njit
def chain_output(t, x, prm, mem, out):
    n = int(prm[0])
    out[0] = x[2 * n - 1]  # xN = q_N (wall spring)
    out[1] = x[0] / prm[5]  # v1 = p_1 / m_1


@njit
def no_opin(t, x, prm, out):
    pass


@njit
def no_commit(t, x, prm, mem):
    pass


def chain_prm(n, values, amp, f0, f1, t1):
    return np.array(
        [n, amp, f0, f1, t1]
        + [values[f"m{i}"] for i in range(1, n + 1)]
        + [values[f"k{i}"] for i in range(1, n + 1)]
        + [values[f"c{i}"] for i in range(1, n + 1)],
        float,
    )


# ---- APA-120ML with the modified PI (12 plays, 6 dead zones) -------------------------------
# prm = [Re, l, a, K, c, M, T, V_amp, V_freq, V_phase(rad), V_offset, n_play, n_dz,
#        r_1..r_n, w_1..w_n, d_1..d_m, ws_1..ws_m]
@njit
def _mpi(v, mem, prm):
    n = int(prm[11])
    m = int(prm[12])
    o = 13
    s = 0.0
    for i in range(n):
        r = prm[o + i]
        s += prm[o + n + i] * max(v - r, min(v + r, mem[i]))
    y = 0.0
    for j in range(m):
        d = prm[o + 2 * n + j]
        if d > 0.0:
            z = max(0.0, s - d)
        elif d < 0.0:
            z = min(0.0, s - d)
        else:
            z = s
        y += prm[o + 2 * n + m + j] * z
    return y


@njit
def apa_rhs(t, x, prm, mem, out):
    Re, l, a, K, c, M, T = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6]
    V = prm[10] + prm[7] * math.sin(2.0 * math.pi * prm[8] * t + prm[9])
    h = _mpi(x[1], mem, prm)  # field E2 = H[p]
    ratio = T * a / l
    i = (V - l * (ratio * K * x[0] + h)) / Re  # drive current
    out[0] = ratio * l * i - x[2] / M  # q_K' (layer spring compression)
    out[1] = l * i  # p'   (dipole)
    out[2] = K * x[0] - c * x[2] / M  # p_M' (F = 0)


@njit
def apa_output(t, x, prm, mem, out):
    Re, l, a, K, T = prm[0], prm[1], prm[2], prm[3], prm[6]
    V = prm[10] + prm[7] * math.sin(2.0 * math.pi * prm[8] * t + prm[9])
    h = _mpi(x[1], mem, prm)
    ratio = T * a / l
    out[0] = ratio * x[1] - x[0]  # x
    out[1] = (V - l * (ratio * K * x[0] + h)) / Re  # i
    out[2] = x[1]  # p
    out[3] = h  # E


@njit
def apa_opin(t, x, prm, out):
    out[0] = x[1]


@njit
def apa_commit(t, x, prm, mem):
    n = int(prm[11])
    v = x[1]
    for i in range(n):
        r = prm[13 + i]
        mem[i] = max(v - r, min(v + r, mem[i]))


def apa_prm(table: dict, op, amp, freq, phase_deg, offset):
    """Parameter vector from the model's parameter table (by name) and the V sine."""
    by = {str(k): v for k, v in table.items()}
    base = [by[k] for k in ("Re", "l", "a", "K", "c", "M", "T")]
    n, m = op.thresholds.size, op.deadzones.size
    opv = [by[f"stack.C_NL.H.{pn}"] for pn in op.parameter_names]
    return np.array(base + [amp, freq, math.radians(phase_deg), offset, n, m] + opv, float)


_CACHE: dict = {}


def integrator(name: str):
    """The compiled integrator for 'chain' or 'apa_pi' (compiled on first use)."""
    if name not in _CACHE:
        if name == "chain":
            _CACHE[name] = make_dopri5(chain_rhs, chain_output, no_opin, no_commit)
        else:
            _CACHE[name] = make_dopri5(apa_rhs, apa_output, apa_opin, apa_commit)
    return _CACHE[name]
