"""Rate-independent hysteresis operators: Prandtl–Ishlinskii (play and stop forms), the modified
PI of seed 002 eq. 12, and the Maxwell-slip model of seed 003.

Physics-free: every operator maps a scalar input v to an output y. Play/stop thresholds r_i and
Maxwell-slip yield displacements carry the units of v, dead zones d_j the units of the PI sum,
weights w_i the units of y per unit of v. Each class is a :class:`MemoryOperator` (pure
``output``/in-place ``commit`` kernels, parameters in one flat float64 array).

Memory of a play-based operator is the vector of play outputs (for Maxwell slip: the slip
positions, which are the same thing). Initial memory convention, used throughout (seed 000
eq. 32 with y_0 = 0): at rest at v0 each play holds the value reached by a monotone approach
from the demagnetised state v = 0, h_i = max(v0 - r_i, min(v0 + r_i, 0)). With this convention
the analytic inverse of :meth:`PrandtlIshlinskii.inverse` is exact from rest: the monotone
approach 0 -> v0 maps onto the monotone approach 0 -> H[v0] of the inverse operator.
"""
from __future__ import annotations

import numba
import numpy as np
from scipy.optimize import nnls

from bondgraph.errors import ParameterError
from bondgraph.memory import MemoryOperator


def _vector(name: str, values, n: int | None = None, nonneg: bool = False) -> np.ndarray:
    """A read-only 1-D finite float64 copy of ``values`` (optionally of length n, >= 0)."""
    a = np.array(values, dtype=np.float64).ravel()
    if a.size == 0 or not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be a non-empty sequence of finite numbers")
    if n is not None and a.size != n:
        raise ParameterError(f"{name} has {a.size} entries, expected {n}")
    if nonneg and np.any(a < 0):
        raise ParameterError(f"{name} must be >= 0")
    a.flags.writeable = False
    return a


def _virgin_plays(v0: float, r: np.ndarray) -> np.ndarray:
    """Play outputs after a monotone approach from 0 to v0 (the initial-memory convention)."""
    return np.ascontiguousarray(np.maximum(v0 - r, np.minimum(v0 + r, 0.0)), dtype=np.float64)


def _indexed(stem: str, n: int) -> tuple[str, ...]:
    return tuple(f"{stem}{i}" for i in range(1, n + 1))


class _PlayBank(MemoryOperator):
    """Shared part of the play-based operators: n plays, prm = [r_1..r_n, w_1..w_n, ...]."""

    def __init__(self, thresholds, weights):
        self.thresholds = _vector("thresholds", thresholds, nonneg=True)
        self.weights = _vector("weights", weights, self.thresholds.size)
        n = self.thresholds.size
        self.parameter_names = _indexed("r", n) + _indexed("w", n)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.thresholds.tolist()}, {self.weights.tolist()})"

    def parameter_values(self) -> np.ndarray:
        return np.concatenate([self.thresholds, self.weights])

    @property
    def n_memory(self) -> int:
        return self.thresholds.size

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """Play outputs at rest at ``v0`` (monotone approach from 0), units of v."""
        return _virgin_plays(v0, np.asarray(prm[: self.n_memory], dtype=np.float64))

    @staticmethod
    def commit(v, mem, prm):
        """Advance every play to input ``v``: h_i = max(v - r_i, min(v + r_i, h_i))."""
        for i in range(len(mem)):
            mem[i] = max(v - prm[i], min(v + prm[i], mem[i]))


class PrandtlIshlinskii(_PlayBank):
    """Play form y = sum_i w_i H_{r_i}[v] (seed 002 eqs. 10-11, seed 000 eq. 33).

    ``thresholds`` r_i >= 0 in units of v, ``weights`` w_i in units of y/v;
    prm = [r_1..r_n, w_1..w_n], memory = the n play outputs (units of v).
    """

    kind = "pi"

    @staticmethod
    def output(v, mem, prm):
        """y = sum_i w_i max(v - r_i, min(v + r_i, h_i)) with the plays h frozen."""
        n = len(mem)
        y = 0.0
        for i in range(n):
            y += prm[n + i] * max(v - prm[i], min(v + prm[i], mem[i]))
        return y

    def small_signal_gain(self, prm: np.ndarray) -> float:
        """Slope right after a reversal: the sum of the weights of the r = 0 plays."""
        n = self.n_memory
        return float(np.sum(prm[n:2 * n][prm[:n] == 0.0]))

    def inverse(self) -> "PrandtlIshlinskii":
        """The exact inverse PI operator (Krejci/Kuhnen), output units of v, input units of y.

        With the plays sorted by threshold (r_1 = 0) and partial weight sums W_i = w_1+..+w_i:
        r'_i = sum_{j<=i} w_j (r_i - r_j), w'_1 = 1/w_1, w'_i = -w_i / (W_i W_{i-1}).
        Requires r_1 = 0 and every W_i > 0 (a strictly increasing loading curve).
        With the common initial-memory convention H^{-1}[H[v]] = v from rest.
        """
        order = np.argsort(self.thresholds, kind="stable")
        r, w = self.thresholds[order], self.weights[order]
        big_w = np.cumsum(w)
        if r[0] != 0.0 or np.any(big_w <= 0.0):
            raise ParameterError(
                "PI inverse needs a play with threshold 0 and positive partial weight sums "
                "(sorted by threshold); the loading curve is not strictly increasing")
        r_inv = big_w * r - np.cumsum(w * r)
        w_inv = np.empty_like(w)
        w_inv[0] = 1.0 / w[0]
        w_inv[1:] = -w[1:] / (big_w[1:] * big_w[:-1])
        return PrandtlIshlinskii(r_inv, w_inv)


class PIStop(_PlayBank):
    """Stop form y = sum_i w_i E_{r_i}[v], E_r[v] = v - H_r[v] (saturates at +-r, units of v).

    Same parameters (prm = [r, w]) and memory (the play outputs) as :class:`PrandtlIshlinskii`,
    so sum_i w_i E_i[v] = (sum_i w_i) v - sum_i w_i H_i[v].
    """

    kind = "pi_stop"

    @staticmethod
    def output(v, mem, prm):
        """y = sum_i w_i (v - max(v - r_i, min(v + r_i, h_i))) with the plays h frozen."""
        n = len(mem)
        y = 0.0
        for i in range(n):
            y += prm[n + i] * (v - max(v - prm[i], min(v + prm[i], mem[i])))
        return y

    def small_signal_gain(self, prm: np.ndarray) -> float:
        """Slope right after a reversal: every stop with r > 0 is unsaturated (slope 1)."""
        n = self.n_memory
        return float(np.sum(prm[n:2 * n][prm[:n] > 0.0]))


class ModifiedPI(_PlayBank):
    """Modified PI (seed 002 eq. 12, after Kuhnen): y = sum_j ws_j S_{d_j}(x), x = sum_i w_i H_i[v].

    Dead zones (decision): S_d(x) = max(0, x - d) for d > 0 (the paper's eq. 12),
    S_d(x) = min(0, x - d) for d < 0 (Kuhnen's mirror image for the negative side, absent from
    the paper), S_0(x) = x. Dead zones d_j are in units of x (the PI sum), ws_j is dimensionless,
    so y has the units of x. The dead zones act on the absolute PI output, as eq. 12 is written;
    seed 002's fitting text measures them from the last reversal, which eq. 12 does not express
    and this operator does not do.

    prm = [r_1..r_n, w_1..w_n, d_1..d_m, ws_1..ws_m]; memory = the n play outputs.
    """

    kind = "modified_pi"

    def __init__(self, thresholds, weights, deadzones, dz_weights):
        super().__init__(thresholds, weights)
        self.deadzones = _vector("deadzones", deadzones)
        self.dz_weights = _vector("dz_weights", dz_weights, self.deadzones.size)
        m = self.deadzones.size
        self.parameter_names += _indexed("d", m) + _indexed("ws", m)

    def __repr__(self) -> str:
        return (f"ModifiedPI({self.thresholds.tolist()}, {self.weights.tolist()}, "
                f"{self.deadzones.tolist()}, {self.dz_weights.tolist()})")

    def parameter_values(self) -> np.ndarray:
        return np.concatenate([self.thresholds, self.weights, self.deadzones, self.dz_weights])

    @staticmethod
    def output(v, mem, prm):
        """Dead-zone superposition of the PI sum, with the plays h frozen."""
        n = len(mem)
        m = (len(prm) - 2 * n) // 2
        x = 0.0
        for i in range(n):
            x += prm[n + i] * max(v - prm[i], min(v + prm[i], mem[i]))
        y = 0.0
        for j in range(m):
            d = prm[2 * n + j]
            if d > 0.0:
                s = max(0.0, x - d)
            elif d < 0.0:
                s = min(0.0, x - d)
            else:
                s = x
            y += prm[2 * n + m + j] * s
        return y

    def small_signal_gain(self, prm: np.ndarray) -> float:
        """Slope after a reversal at rest at v = 0 (x = 0: only the d = 0 terms are active)."""
        n = self.n_memory
        m = (prm.size - 2 * n) // 2
        d, ws = prm[2 * n:2 * n + m], prm[2 * n + m:2 * n + 2 * m]
        return float(np.sum(prm[n:2 * n][prm[:n] == 0.0]) * np.sum(ws[d == 0.0]))


def apa120ml_modified_pi() -> ModifiedPI:
    """ILLUSTRATIVE modified-PI parameters for the APA-120ML, read from seed 002 Table 3.

    Input: dipole p = Q l (C m); output: field E (V/m). The extracted table cannot be read
    consistently, so this is a plausible reading, not the paper's fitted model:

    * r_i: printed 0, 2.2e9, 5.5e9, 1.1e8, 1.7e8, 2.5e8, 1.0e7, 1.4e7, 1.6e7, 1.8e7, 2.0e7, 2.0e7.
      Taken as lost minus signs in the exponents (2.2e-9 ... 2.0e-7 C m): this makes them
      ascending, and of the size of the dipole at full drive (p = E/kx ~ 1.5e6/5e12 = 3e-7 C m
      with Table 2's kx and 150 V over l = 0.1 mm), as the paper's r_i = P_i/2 rule requires.
    * w_i (V/m per C m) as printed, 6.64e12 ... 2.74e12, 0: comparable with kx = 5e12.
    * d_j (V/m) and ws_j as printed, row by row; the inert row (d = 1.30e6, ws = 0) is dropped.
      Every printed row with d = 0 has ws = 0, which would make E = 0 below 0.94e6 V/m, so an
      identity term (d = 0, ws = 1) is added.
    * The paper says fifteen parameters; the table holds about thirty nonzero entries.
    * Check: the virgin curve reaches 1.5e6 V/m (150 V) at p = 1.43e-7 C m, and a loop to
      -0.2e6 V/m (-20 V) stays within |p| <= 1.43e-7, so the plays with r >= 1.0e-7 never open at
      rated drive (they need swings above 2e-7 C m). The set is plausible, not recovered.
    """
    thresholds = [0.0, 2.2e-9, 5.5e-9, 1.1e-8, 1.7e-8, 2.5e-8,
                  1.0e-7, 1.4e-7, 1.6e-7, 1.8e-7, 2.0e-7, 2.0e-7]
    weights = [6.64e12, 1.46e12, 0.0, 0.25e12, 0.0, 0.75e12,
               0.80e12, 0.61e12, 0.43e12, 0.42e12, 2.74e12, 0.0]
    deadzones = [0.0, 0.94e6, 1.10e6, 1.22e6, 1.28e6, 1.30e6]
    dz_weights = [1.0, 0.09, 0.15, 0.33, 1.71, 1.33]
    return ModifiedPI(thresholds, weights, deadzones, dz_weights)


class MaxwellSlip(MemoryOperator):
    """Maxwell slip (seed 003): n parallel branches, spring k_i in series with a Coulomb slip
    element of break-away force f_i. Input displacement delta, output force
    F = sum_i k_i (delta - delta_i); branch i sticks while |k_i (delta - delta_i)| < f_i.

    ``stiffnesses`` k_i > 0 (units of y/v), ``breakaway_forces`` f_i >= 0 (units of y);
    prm = [k_1..k_n, f_1..f_n]; memory = slip positions delta_i (units of v), which are the play
    outputs of thresholds f_i/k_i (see :meth:`to_pi_stop`).
    """

    kind = "maxwell_slip"

    def __init__(self, stiffnesses, breakaway_forces):
        self.stiffnesses = _vector("stiffnesses", stiffnesses)
        if np.any(self.stiffnesses <= 0):
            raise ParameterError("stiffnesses must be > 0")
        self.breakaway_forces = _vector("breakaway_forces", breakaway_forces,
                                        self.stiffnesses.size, nonneg=True)
        n = self.stiffnesses.size
        self.parameter_names = _indexed("k", n) + _indexed("f", n)

    def __repr__(self) -> str:
        return f"MaxwellSlip({self.stiffnesses.tolist()}, {self.breakaway_forces.tolist()})"

    def parameter_values(self) -> np.ndarray:
        return np.concatenate([self.stiffnesses, self.breakaway_forces])

    @property
    def n_memory(self) -> int:
        return self.stiffnesses.size

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """Slip positions at rest at ``v0`` after a monotone approach from 0, units of v."""
        n = self.n_memory
        return _virgin_plays(v0, prm[n:2 * n] / prm[:n])

    @staticmethod
    def output(v, mem, prm):
        """F = sum_i clip(k_i (v - delta_i), -f_i, f_i) with the slip positions frozen."""
        n = len(mem)
        y = 0.0
        for i in range(n):
            y += max(-prm[n + i], min(prm[n + i], prm[i] * (v - mem[i])))
        return y

    @staticmethod
    def commit(v, mem, prm):
        """Slip every branch whose spring force would exceed its break-away force."""
        n = len(mem)
        for i in range(n):
            r = prm[n + i] / prm[i]
            mem[i] = max(v - r, min(v + r, mem[i]))

    def small_signal_gain(self, prm: np.ndarray) -> float:
        """Slope right after a reversal: the sum of k_i over branches with f_i > 0."""
        n = self.n_memory
        return float(np.sum(prm[:n][prm[n:2 * n] > 0.0]))

    def to_pi_stop(self) -> PIStop:
        """The equal stop-form PI operator: r_i = f_i / k_i, w_i = k_i."""
        return PIStop(self.breakaway_forces / self.stiffnesses, self.stiffnesses)


# --- identification -----------------------------------------------------------------------

_commit_plays = numba.njit(_PlayBank.commit)


@numba.njit
def _play_matrix(v, r, h):
    out = np.empty((v.size, r.size))
    for k in range(v.size):
        _commit_plays(v[k], h, r)
        out[k, :] = h
    return out


def play_outputs(v, thresholds) -> np.ndarray:
    """Outputs of plays with the given thresholds for a sampled input, from rest at v[0].

    Returns an (n_samples, n_plays) array in units of v (initial-memory convention of the module).
    """
    v = np.ascontiguousarray(v, dtype=np.float64).ravel()
    r = np.ascontiguousarray(_vector("thresholds", thresholds, nonneg=True))
    if v.size == 0:
        raise ParameterError("input sequence is empty")
    return _play_matrix(v, r, _virgin_plays(v[0], r))


def threshold_grid(v, n: int) -> np.ndarray:
    """n equally spaced thresholds 0, R/n, ..., (n-1)R/n with R = (max v - min v)/2, units of v.

    A play only opens a loop when the input swings by more than 2r, so R is the largest useful
    threshold (seed 002: r_i = P_i / 2 over the input range).
    """
    v = np.asarray(v, dtype=np.float64)
    return np.linspace(0.0, 0.5 * float(np.ptp(v)), int(n), endpoint=False)


def fit_pi_weights(v, y, thresholds, offset: bool = False):
    """Non-negative least-squares PI weights w (units of y/v) for y ~ sum_i w_i H_{r_i}[v].

    The r = 0 play is v itself, so a threshold 0 gives the linear term. With ``offset`` an
    additive constant c (units of y, either sign) is fitted too and ``(w, c)`` is returned.
    Columns are scaled internally so NNLS is insensitive to the units of v and y.
    """
    a = play_outputs(v, thresholds)
    y = np.asarray(y, dtype=np.float64).ravel()
    if y.size != a.shape[0]:
        raise ParameterError(f"y has {y.size} samples, v has {a.shape[0]}")
    n = a.shape[1]
    if offset:
        a = np.hstack([a, np.ones((a.shape[0], 1)), -np.ones((a.shape[0], 1))])
    scale = np.max(np.abs(a), axis=0)
    scale[scale == 0.0] = 1.0
    y_scale = max(float(np.max(np.abs(y))), np.finfo(float).tiny)
    sol = nnls(a / scale, y / y_scale, maxiter=50 * a.shape[1])[0] / scale * y_scale
    if offset:
        return sol[:n], float(sol[n] - sol[n + 1])
    return sol[:n]


@numba.njit(cache=True)
def _bouc_wen_path(v, beta, gamma, n, z0, out):
    z = z0
    out[0] = z
    for k in range(1, v.shape[0]):
        dv = v[k] - v[k - 1]
        # sub-steps keep each explicit update small against the loop's curvature
        m = 1 + int(abs(dv) * (abs(beta) + abs(gamma) + 1.0) * 8.0)
        h = dv / m
        for _ in range(m):
            az = abs(z)
            z += h - beta * abs(h) * az ** (n - 1.0) * z - gamma * h * az ** n
        out[k] = z


def bouc_wen_response(v, beta: float, gamma: float, n: float, z0: float = 0.0) -> np.ndarray:
    """Bouc–Wen variable z along a sampled input path (rate independent):
    dz = dv − β·|dv|·|z|^(n−1)·z − γ·dv·|z|^n, from z0 (units of v; z saturates near
    (β + γ)^(−1/n)).  For identification: z depends on the path only, not on time."""
    v = np.ascontiguousarray(v, dtype=np.float64)
    out = np.empty_like(v)
    _bouc_wen_path(v, float(beta), float(gamma), float(n), float(z0), out)
    return out
