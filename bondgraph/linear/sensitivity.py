"""Output sensitivities of a linear model: ∂y/∂θ of y = LTI(θ)·u as filtered signals.

A single-input single-output model x' = A x + B u, y = C x + D u whose A = VΛV⁻¹ has distinct
eigenvalues λ_k answers an input u with y = Σ_k r_k w_k + D u, where w_k is u filtered by
1/(s − λ_k) and r_k = (CV)_k (V⁻¹B)_k the mode's residue.  Its derivative with respect to a
parameter θ_i is again a sum of filtered signals:

    ∂y/∂θ_i = Σ_k α_ik w_k + κ_ik v_k + ∂D/∂θ_i u,

v_k being u filtered by 1/(s − λ_k)²; κ_ik = r_k ∂λ_k and α_ik = ∂r_k, from the modal
coordinates of the perturbation E = V⁻¹ (∂A/∂θ_i) V, β = V⁻¹ ∂B/∂θ_i, γ = (∂C/∂θ_i) V:
∂λ_k = E_kk and

    α_ik = (CV)_k β_k + γ_k (V⁻¹B)_k + Σ_{j≠k} [(CV)_k E_kj (V⁻¹B)_j + (CV)_j E_jk (V⁻¹B)_k] / (λ_k − λ_j)

(the forward sensitivity equation s' = A s + ∂A x + ∂B u in modal coordinates, its products of
two first-order filters split into partial fractions).  The output and all its derivatives
are combinations of two filtered signals per mode, whatever the number of parameters: one
pass over the samples per input column, at a cost of a few complex operations per mode and
sample, instead of one simulation per parameter for a finite difference.  The filters are
those of the Jordan pair v' = λv + w, w' = λw + u, discretised exactly for an input linear
between samples (the first-order hold of :func:`bondgraph.linear.lti.foh`), so the result is
the exact derivative of what :meth:`bondgraph.linear.lti.StateSpace.response` computes.

Modes faster than a cut-off are residualised as in :func:`bondgraph.linear.lti.residualise`:
a fast mode contributes its quasi-static expansion, 1/(s − λ) ≈ −1/λ − s/λ² and
1/(s − λ)² ≈ 1/λ² + 2s/λ³, to the feedthrough of the input and of its rate.  A model whose
eigenvectors are ill-conditioned (a near-defective A, more than
:data:`bondgraph.linear.lti.MODAL_COND` after balancing) or whose eigenvalues nearly coincide
has no modal form to speak of: :func:`modal_sensitivity` returns None, and the caller falls
back to finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numba import njit
from scipy.linalg import expm, matrix_balance

from .lti import FLOOR, GUARD_EVERY, LTI, MODAL_COND

#: eigenvalues closer than this share of the largest magnitude count as coincident
SEPARATION = 1e-8


@dataclass(frozen=True)
class ModalSensitivity:
    """The output of a single-input single-output model and its derivatives with respect to
    P parameters as combinations of filtered inputs (module docstring).

    ``lam``: the kept (slow) eigenvalues (rad/s); ``res`` (n) their residues; ``alpha``,
    ``kappa`` (P, n) the derivative weights of 1/(s − λ) and 1/(s − λ)²; ``d``, ``d1``: the
    feedthrough of the input and of its rate (s) after the fast modes are residualised, and
    ``dd``, ``dd1`` (P) their derivatives.

    Parameters
    ----------
    lam : numpy.ndarray
        The kept eigenvalues, rad/s (complex).
    res : numpy.ndarray
        Their residues (complex).
    alpha : numpy.ndarray
        (P, n) weights of 1/(s − λ) in the derivatives.
    kappa : numpy.ndarray
        (P, n) weights of 1/(s − λ)² in the derivatives.
    d : float
        Feedthrough of the input, output units per input unit.
    d1 : float
        Feedthrough of the input's rate, s times ``d``'s unit.
    dd : numpy.ndarray
        (P) derivatives of ``d``.
    dd1 : numpy.ndarray
        (P) derivatives of ``d1``.
    """

    lam: np.ndarray
    res: np.ndarray
    alpha: np.ndarray
    kappa: np.ndarray
    d: float
    d1: float
    dd: np.ndarray
    dd1: np.ndarray

    def frequency(self, omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(H, dH): the frequency response at ``omega`` (rad/s), as
        :meth:`bondgraph.linear.lti.StateSpace.frequency_response` gives it, and its
        derivatives dH[i] with respect to each parameter.

        Parameters
        ----------
        omega : numpy.ndarray
            Angular frequencies, rad/s.

        Returns
        -------
        H : numpy.ndarray
            Complex frequency response, one per frequency.
        dH : numpy.ndarray
            (P, frequencies) derivatives, per unit parameter.
        """
        jw = 1j * np.atleast_1d(np.asarray(omega, float))
        g = 1.0 / (jw[:, None] - self.lam[None, :])
        H = g @ self.res + self.d + jw * self.d1
        dH = self.alpha @ g.T + self.kappa @ (g * g).T + self.dd[:, None] + jw[None, :] * self.dd1[:, None]
        return H, dH

    def time(
        self, dt: float, U: np.ndarray, rows: np.ndarray | None = None, steady: bool = False
    ) -> tuple[np.ndarray, np.ndarray]:
        """(Y, dY) from rest (with ``steady``: from each column's steady state at its first
        sample, as :meth:`bondgraph.linear.lti.StateSpace.response` starts it) for each column
        of ``U`` (inputs sampled every ``dt`` s, linear in between), at the sample indices
        ``rows`` (ascending; every sample for None): Y[r, j] as
        :meth:`bondgraph.linear.lti.StateSpace.response` gives it, dY[i, r, j] its derivative
        with respect to parameter i.

        Parameters
        ----------
        dt : float
            Sample interval, s.
        U : numpy.ndarray
            Input samples, one column per series (a 1-D array is one column).
        rows : numpy.ndarray, optional
            Sample indices to return, ascending.
        steady : bool, optional
            Start at the steady state of each column's first sample (from rest when a kept
            eigenvalue is zero).

        Returns
        -------
        Y : numpy.ndarray
            (rows, columns) output.
        dY : numpy.ndarray
            (P, rows, columns) derivatives, per unit parameter.
        """
        U = np.asarray(U, float)
        U = np.ascontiguousarray(U.reshape(-1, 1) if U.ndim == 1 else U)
        if steady and np.any(U[0]) and not np.any(self.lam == 0):
            H0, dH0 = self.frequency(np.zeros(1))
            Y, dY = self.time(dt, U - U[0], rows)
            return Y + H0[0].real * U[0], dY + dH0[:, 0].real[:, None, None] * U[0][None, None, :]
        N, m = U.shape
        rows = np.arange(N) if rows is None else np.ascontiguousarray(rows, np.int64)
        P = self.alpha.shape[0]
        # one filter per real mode and per complex pair (its partner's signal is the conjugate)
        up = self.lam.imag > 0
        keep = np.nonzero(self.lam.imag >= 0)[0]
        partner = {k: int(np.argmin(np.abs(self.lam - np.conj(self.lam[k])))) for k in np.nonzero(up)[0]}
        weights = np.concatenate([self.res[None, :], self.alpha], axis=0)  # (P+1, n)
        kappas = np.concatenate([np.zeros((1, self.lam.size), complex), self.kappa], axis=0)
        cw = weights[:, keep].astype(complex)
        cv = kappas[:, keep].astype(complex)
        for i, k in enumerate(keep):
            if k in partner:  # Re(c w) + Re(c' conj(w)) = Re((c + conj(c')) w)
                cw[:, i] += np.conj(weights[:, partner[k]])
                cv[:, i] += np.conj(kappas[:, partner[k]])
        out = np.zeros((P + 1, m, rows.size))
        if keep.size:
            Phi, Gam, G1 = jordan_foh(self.lam[keep], dt)
            F = np.empty((2, 2 * keep.size, m, rows.size))
            _jordan_filters(Phi, Gam, G1, U, rows, F)
            coef = np.concatenate([cw, cv], axis=1)  # Re(coef · (F[0] + iF[1]))
            out += (coef.real @ F[0].reshape(2 * keep.size, -1) - coef.imag @ F[1].reshape(2 * keep.size, -1)).reshape(
                out.shape
            )
        direct = np.concatenate([[self.d], self.dd])
        out += direct[:, None, None] * U[rows].T[None]
        if (self.d1 or np.any(self.dd1)) and N > 1:
            rate = np.gradient(U, dt, axis=0)[rows]
            out += np.concatenate([[self.d1], self.dd1])[:, None, None] * rate.T[None]
        out = out.transpose(0, 2, 1)  # (P+1, R, m)
        return out[0], out[1:]


def sensitivity(lti: LTI, th: np.ndarray, names: Sequence[str], cut: float | None = None) -> ModalSensitivity | None:
    """The output of ``lti`` at θ and its derivatives with respect to the parameters ``names``
    (:meth:`~bondgraph.linear.lti.LTI.derivatives`), modes faster than ``cut`` (rad/s)
    residualised: a :class:`ModalSensitivity`, or None (see :func:`modal_sensitivity`).

    Parameters
    ----------
    lti : LTI
        The model's linear form.
    th : numpy.ndarray
        θ, the model's parameter vector.
    names : sequence of str
        The parameters.
    cut : float, optional
        Cut-off angular frequency, rad/s (None: keep every mode).

    Returns
    -------
    ModalSensitivity or None
        The modal form, or None without a well-conditioned one.

    Raises
    ------
    ParameterError
        A name that is no parameter of the model.
    """
    return modal_sensitivity(*lti.matrices(th), *lti.derivatives(th, names), cut)


def modal_sensitivity(A, B, C, D, dA, dB, dC, dD, cut: float | None = None) -> ModalSensitivity | None:
    """The :class:`ModalSensitivity` of (A, B, C, D) (single input and output) with respect to
    P parameters whose derivatives are dA (P, n, n), dB (P, n, 1), dC (P, 1, n), dD (P, 1, 1);
    modes with |λ| > ``cut`` (rad/s) residualised.  None when the model has no well-conditioned
    modal form (module docstring).

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
    dA, dB, dC, dD : numpy.ndarray
        Their derivatives, stacked along a first axis of P parameters.
    cut : float, optional
        Cut-off angular frequency, rad/s (None: keep every mode).

    Returns
    -------
    ModalSensitivity or None
        The modal form, or None for ill-conditioned eigenvectors or nearly coincident
        eigenvalues.
    """
    n = A.shape[0]
    P = dA.shape[0]
    if n == 0:
        return ModalSensitivity(
            np.zeros(0, complex),
            np.zeros(0, complex),
            np.zeros((P, 0), complex),
            np.zeros((P, 0), complex),
            float(D[0, 0]),
            0.0,
            dD[:, 0, 0].astype(float),
            np.zeros(P),
        )
    Ab, (scale, _) = matrix_balance(A, permute=False, separate=True)  # states in comparable units
    lam, V = np.linalg.eig(Ab)
    if not (np.all(np.isfinite(lam)) and np.all(np.isfinite(V))) or np.linalg.cond(V) > MODAL_COND:
        return None
    delta = lam[:, None] - lam[None, :]
    np.fill_diagonal(delta, np.inf)
    if n > 1 and np.min(np.abs(delta)) < SEPARATION * max(float(np.max(np.abs(lam))), 1e-300):
        return None
    Vi = np.linalg.inv(V)
    b = Vi @ (B[:, 0] / scale)  # V⁻¹B in balanced coordinates
    c = (C[0] * scale) @ V  # CV
    E = Vi[None] @ (dA / scale[None, :, None] * scale[None, None, :]) @ V[None]  # (P, n, n)
    beta = (dB[:, :, 0] / scale[None, :]) @ Vi.T  # (P, n)
    gam = (dC[:, 0, :] * scale[None, :]) @ V  # (P, n)
    res = c * b
    dlam = np.diagonal(E, axis1=1, axis2=2)
    kappa = res[None, :] * dlam
    M = c[None, :, None] * E * b[None, None, :]  # M[i, k, j] = (CV)_k E_kj (V⁻¹B)_j
    cross = np.sum((M + M.transpose(0, 2, 1)) / delta[None], axis=2)
    alpha = c[None, :] * beta + gam * b[None, :] + cross
    slow = np.abs(lam) <= cut if cut is not None else np.ones(n, bool)
    if np.all(slow):
        d1, dd1 = 0.0, np.zeros(P)
        d, dd = float(D[0, 0]), dD[:, 0, 0].astype(float)
    else:
        f = ~slow
        lf = lam[f]
        d = float((D[0, 0] - np.sum(res[f] / lf)).real)
        d1 = float((-np.sum(res[f] / lf**2)).real)
        dd = (dD[:, 0, 0] + np.sum(-alpha[:, f] / lf + kappa[:, f] / lf**2, axis=1)).real
        dd1 = np.sum(-alpha[:, f] / lf**2 + 2 * kappa[:, f] / lf**3, axis=1).real
    return ModalSensitivity(lam[slow], res[slow], alpha[:, slow], kappa[:, slow], d, d1, dd, dd1)


def jordan_foh(lam: np.ndarray, dt: float):
    """First-order-hold discretisation (as :func:`bondgraph.linear.lti.foh`) of the Jordan pairs
    v' = λv + w, w' = λw + u, one per eigenvalue in ``lam``: (Φ (K, 2, 2), Γ (K, 2), Γ1 (K, 2))
    with ξ[k+1] = Φξ[k] + Γu[k] and (v, w) = ξ + Γ1·u.

    Parameters
    ----------
    lam : numpy.ndarray
        Eigenvalues, rad/s (complex).
    dt : float
        Sample interval, s.

    Returns
    -------
    Phi : numpy.ndarray
        Φ, (K, 2, 2), complex.
    Gamma : numpy.ndarray
        Γ, (K, 2), complex.
    Gamma1 : numpy.ndarray
        Γ1, (K, 2), complex.
    """
    K = lam.size
    em = np.zeros((K, 4, 4), complex)
    em[:, 0, 0] = em[:, 1, 1] = lam * dt
    em[:, 0, 1] = em[:, 1, 2] = dt
    em[:, 2, 3] = 1.0
    ms = expm(em)
    Phi, G, G1 = ms[:, :2, :2], ms[:, :2, 2], ms[:, :2, 3]
    return np.ascontiguousarray(Phi), np.ascontiguousarray(G - G1 + (Phi @ G1[:, :, None])[:, :, 0]), G1.copy()


@njit(cache=True, nogil=True)
def _jordan_filters(Phi, Gam, G1, U, rows, F):
    """F[0, k, j, r] + i·F[1, k, j, r]: the input column j filtered by 1/(s − λ_k) from rest, at
    the sample index rows[r]; F[:, K + k, j, r] the same by 1/(s − λ_k)² (the Jordan pairs of
    :func:`jordan_foh`, K of them), with the subnormal guard of
    :func:`bondgraph.linear.lti.recursion`.  Every filter advances at each sample (independent
    recurrences side by side, not one long chain after another)."""
    N, m = U.shape
    K = Phi.shape[0]
    R = rows.shape[0]
    a = np.empty((m, K), np.complex128)
    b = np.empty((m, K), np.complex128)
    peak = np.zeros((m, K))
    for j in range(m):
        for k in range(K):
            a[j, k] = -G1[k, 0] * U[0, j]
            b[j, k] = -G1[k, 1] * U[0, j]
    r = 0
    for i in range(N):
        if r == R:
            break
        if i % GUARD_EVERY == 0:
            for j in range(m):
                for k in range(K):
                    size = abs(a[j, k].real) + abs(a[j, k].imag) + abs(b[j, k].real) + abs(b[j, k].imag)
                    if size > peak[j, k]:
                        peak[j, k] = size
                    elif size < FLOOR * peak[j, k]:
                        a[j, k] = 0j
                        b[j, k] = 0j
        out = rows[r] == i
        for j in range(m):
            u = U[i, j]
            for k in range(K):
                aa = a[j, k]
                bb = b[j, k]
                if out:
                    v = aa + G1[k, 0] * u
                    w = bb + G1[k, 1] * u
                    F[0, k, j, r] = w.real
                    F[1, k, j, r] = w.imag
                    F[0, K + k, j, r] = v.real
                    F[1, K + k, j, r] = v.imag
                a[j, k] = Phi[k, 0, 0] * aa + Phi[k, 0, 1] * bb + Gam[k, 0] * u
                b[j, k] = Phi[k, 1, 0] * aa + Phi[k, 1, 1] * bb + Gam[k, 1] * u
        if out:
            r += 1
