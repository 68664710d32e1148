"""Rate-independent hysteresis operators: Prandtl–Ishlinskii (play and stop forms), the modified PI
(dead zones on the absolute PI sum, eq. 12, or measured from the last reversal, Sec. 5.3) of
Rodriguez-Fortun, J.M., Orus, J., Buil, F., Castellanos, J.A. "General bond graph model for
piezoelectric actuators and methodology for experimental identification." Mechatronics 20 (2010)
303-314, with exact inverses, and the Maxwell-slip model of Wood, R.J., Steltz, E., Fearing, R.S.
"Nonlinear performance limits for high energy density piezoelectric bending actuators." Proc. IEEE
ICRA, Barcelona, 2005. The initial-memory convention follows Ghafarirad, H., Rezaei, S.M., Sarhan,
A.A.D., Zareinejad, M. "Continuous dynamic modelling of bimorph piezoelectric cantilevered
actuators considering hysteresis effect and dynamic behaviour analysis." Mathematical and
Computer Modelling of Dynamical Systems 21(2) (2015) 130-152.

Physics-free: every operator maps a scalar input v to an output y. Play/stop thresholds r_i and
Maxwell-slip yield displacements carry the units of v, dead zones d_j the units of the PI sum,
weights w_i the units of y per unit of v. Each class is a :class:`MemoryOperator` (pure
``output``/in-place ``commit`` kernels, parameters in one flat float64 array).

Memory of a play-based operator is the vector of play outputs (for Maxwell slip: the slip
positions, which are the same thing). Initial memory convention, used throughout (Ghafarirad et al. 2015
eq. 32 with y_0 = 0): at rest at v0 each play holds the value reached by a monotone approach
from the demagnetised state v = 0, h_i = max(v0 - r_i, min(v0 + r_i, 0)). With this convention
the analytic inverse of :meth:`PrandtlIshlinskii.inverse` is exact from rest: the monotone
approach 0 -> v0 maps onto the monotone approach 0 -> H[v0] of the inverse operator.
"""
from __future__ import annotations

import numba
import numpy as np
from scipy.optimize import nnls

from bondgraph import MemoryOperator, ParameterError


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


# ---- kernel helpers (plain functions: compiled with the kernels that call them) -----------------
def _frozen_pi_sum(v, mem, prm, n):
    """sum_i w_i max(v - r_i, min(v + r_i, h_i)) with the plays h = mem[:n] frozen."""
    x = 0.0
    for i in range(n):
        x += prm[n + i] * max(v - prm[i], min(v + prm[i], mem[i]))
    return x


def _advance_plays(v, mem, prm, n):
    """Advance the plays mem[:n] to input v; returns their weighted sum (the PI sum)."""
    x = 0.0
    for i in range(n):
        mem[i] = max(v - prm[i], min(v + prm[i], mem[i]))
        x += prm[n + i] * mem[i]
    return x


def _dead_zone_sum(x, prm, n, m):
    """sum_j ws_j S_{d_j}(x): S_d(x) = max(0, x - d) for d > 0, min(0, x - d) for d < 0, x for d = 0."""
    y = 0.0
    for j in range(m):
        d = prm[2 * n + j]
        if d > 0.0:
            y += prm[2 * n + m + j] * max(0.0, x - d)
        elif d < 0.0:
            y += prm[2 * n + m + j] * min(0.0, x - d)
        else:
            y += prm[2 * n + m + j] * x
    return y


def _branch_gain(u, prm, n, m):
    """g(u) = sum_j ws_j max(0, u - d_j): the relative dead-zone stage along a branch."""
    g = 0.0
    for j in range(m):
        g += prm[2 * n + m + j] * max(0.0, u - prm[2 * n + j])
    return g


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
        """Advance every play to input ``v``: h_i = max(v - r_i, min(v + r_i, h_i)) (reads only
        the thresholds, so :func:`play_outputs` uses it with prm = r)."""
        for i in range(len(mem)):
            mem[i] = max(v - prm[i], min(v + prm[i], mem[i]))


class PrandtlIshlinskii(_PlayBank):
    """Play form y = sum_i w_i H_{r_i}[v] (Rodriguez-Fortun et al. 2010, eqs. 10-11, Ghafarirad et al. 2015, eq. 33).

    ``thresholds`` r_i >= 0 in units of v, ``weights`` w_i in units of y/v;
    prm = [r_1..r_n, w_1..w_n], memory = the n play outputs (units of v).
    """

    kind = "pi"

    @staticmethod
    def output(v, mem, prm):
        """y = sum_i w_i max(v - r_i, min(v + r_i, h_i)) with the plays h frozen."""
        return _frozen_pi_sum(v, mem, prm, len(mem))

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
        return PrandtlIshlinskii(*_kuhnen_inverse(self.thresholds, self.weights, "PI"))


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


def _kuhnen_inverse(r: np.ndarray, w: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Thresholds and weights of the inverse of a superposition y = sum_i w_i F_{r_i} of plays
    (F = H_r) or one-sided dead zones (F = max(0, . - r)), Kuhnen's formula: with the terms
    sorted by r (r_1 = 0) and partial sums W_i = w_1 + .. + w_i,
    r'_i = sum_{j<=i} w_j (r_i - r_j),  w'_1 = 1/w_1,  w'_i = -w_i / (W_i W_{i-1}).
    Requires r_1 = 0 and every W_i > 0 (a strictly increasing loading curve)."""
    order = np.argsort(r, kind="stable")
    r, w = r[order], w[order]
    big_w = np.cumsum(w)
    if r[0] != 0.0 or np.any(big_w <= 0.0):
        raise ParameterError(
            f"{what} inverse needs a term with threshold 0 and positive partial weight sums "
            "(sorted by threshold); the loading curve is not strictly increasing")
    w_inv = np.empty_like(w)
    w_inv[0] = 1.0 / w[0]
    w_inv[1:] = -w[1:] / (big_w[1:] * big_w[:-1])
    return big_w * r - np.cumsum(w * r), w_inv


def _merge_zero(d: np.ndarray, ws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One d = 0 term holding the summed weight of all d = 0 terms (first), the others after."""
    zero = d == 0.0
    return np.r_[0.0, d[~zero]], np.r_[np.sum(ws[zero]), ws[~zero]]


class _DeadZonePI(_PlayBank):
    """Shared parameters of a PI stage and a dead-zone stage: prm = [r_1..r_n, w_1..w_n,
    d_1..d_m, ws_1..ws_m]; S_d(x) = max(0, x - d) for d > 0, min(0, x - d) for d < 0, x for d = 0."""

    def __init__(self, thresholds, weights, deadzones, dz_weights):
        super().__init__(thresholds, weights)
        self.deadzones = _vector("deadzones", deadzones)
        self.dz_weights = _vector("dz_weights", dz_weights, self.deadzones.size)
        m = self.deadzones.size
        self.parameter_names += _indexed("d", m) + _indexed("ws", m)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.thresholds.tolist()}, {self.weights.tolist()}, "
                f"{self.deadzones.tolist()}, {self.dz_weights.tolist()})")

    def parameter_values(self) -> np.ndarray:
        return np.concatenate([self.thresholds, self.weights, self.deadzones, self.dz_weights])

    def _zero_gains(self, prm: np.ndarray) -> tuple[float, float]:
        """(sum of w over r = 0, sum of ws over d = 0): the slopes of both stages after a reversal."""
        n = self.thresholds.size
        m = self.deadzones.size
        d, ws = prm[2 * n:2 * n + m], prm[2 * n + m:2 * n + 2 * m]
        return float(np.sum(prm[n:2 * n][prm[:n] == 0.0])), float(np.sum(ws[d == 0.0]))

    def small_signal_gain(self, prm: np.ndarray) -> float:
        """Slope after a reversal at rest at v = 0: product of both stages' zero-threshold weights."""
        a, b = self._zero_gains(prm)
        return a * b


class ModifiedPI(_DeadZonePI):
    """Modified PI (Rodriguez-Fortun et al. 2010, eq. 12, after Kuhnen): y = sum_j ws_j S_{d_j}(x),
    x = sum_i w_i H_i[v], the dead zones acting on the absolute PI sum as eq. 12 is written.

    S_d(x) = max(0, x - d) for d > 0 (eq. 12), min(0, x - d) for d < 0 (Kuhnen's mirror image
    for the negative side, absent from the paper), S_0(x) = x. Dead zones d_j are in units of x
    (the PI sum), ws_j is dimensionless, so y has the units of x. The paper's fitting text
    (Sec. 5.3) measures the dead zones from the last reversal instead: that is
    :class:`RelativeModifiedPI`.

    prm = [r_1..r_n, w_1..w_n, d_1..d_m, ws_1..ws_m]; memory = the n play outputs.
    """

    kind = "modified_pi"

    @staticmethod
    def output(v, mem, prm):
        """Dead-zone superposition of the PI sum, with the plays h frozen."""
        n = len(mem)
        return _dead_zone_sum(_frozen_pi_sum(v, mem, prm, n), prm, n, (len(prm) - 2 * n) // 2)

    def inverse(self) -> "InverseModifiedPI":
        """The exact inverse: the inverse dead-zone map (static, both sides by Kuhnen's formula)
        followed by the inverse PI operator; H^{-1}[H[v]] = v from rest."""
        d, ws = self.deadzones, self.dz_weights
        pos_d, pos_w = _merge_zero(np.abs(d[d >= 0.0]), ws[d >= 0.0])
        neg_d, neg_w = _merge_zero(np.abs(d[d <= 0.0]), ws[d <= 0.0])
        pd, pw = _kuhnen_inverse(pos_d, pos_w, "dead-zone (x > 0)")
        nd, nw = _kuhnen_inverse(neg_d, neg_w, "dead-zone (x < 0)")
        pi = PrandtlIshlinskii(self.thresholds, self.weights).inverse()
        return InverseModifiedPI(pi.thresholds, pi.weights, np.r_[pd, -nd[1:]], np.r_[pw, nw[1:]])


class InverseModifiedPI(_DeadZonePI):
    """Inverse of :class:`ModifiedPI`: the static dead-zone map x = sum_j ws_j S_{d_j}(y) applied
    to the input first, then the PI sum v = sum_i w_i H_i[x] (parameters of the inverse stages,
    as returned by :meth:`ModifiedPI.inverse`). Memory: the n play outputs (units of x)."""

    kind = "modified_pi_inverse"

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """Plays at rest after a monotone approach from 0 to the mapped input x(v0)."""
        n = self.n_memory
        x0 = _dead_zone_sum(float(v0), prm, n, (len(prm) - 2 * n) // 2)
        return _virgin_plays(x0, np.asarray(prm[:n], dtype=np.float64))

    @staticmethod
    def output(v, mem, prm):
        """Static dead-zone map of the input, then the PI sum with the plays h frozen."""
        n = len(mem)
        return _frozen_pi_sum(_dead_zone_sum(v, prm, n, (len(prm) - 2 * n) // 2), mem, prm, n)

    @staticmethod
    def commit(v, mem, prm):
        """Advance the plays to the mapped input x(v)."""
        n = len(mem)
        _advance_plays(_dead_zone_sum(v, prm, n, (len(prm) - 2 * n) // 2), mem, prm, n)


class RelativeModifiedPI(_DeadZonePI):
    """Modified PI with the dead zones measured from the last reversal (Rodriguez-Fortun et al.
    2010, Sec. 5.3 and Fig. 20: "d_j are relative values with respect to the change of direction
    value ... so that the shape of the loop depends on the amplitude of the signal and not on its
    absolute value").

    x = sum_i w_i H_i[v] (PI sum); on a branch that started at the reversal (x_r, y_r) and runs in
    direction s = +1 (rising) or -1 (falling),

        y = y_r + s g(s (x - x_r)),    g(u) = sum_j ws_j max(0, u - d_j),  d_j >= 0 (units of x).

    A reversal of x starts a new branch at the current (x, y), so y is continuous. A d = 0 term
    with positive weight makes g strictly increasing and the operator invertible
    (:meth:`inverse`). Unlike the PI operator it has no return-point memory: a minor loop does
    not close. At rest at v0 the branch starts at the demagnetised state (x_r, y_r) = (0, 0).

    prm = [r_1..r_n, w_1..w_n, d_1..d_m, ws_1..ws_m];
    memory = [h_1..h_n, x_r, y_r, s, x_last] (x_last: the PI sum at the last accepted step).
    """

    kind = "modified_pi_relative"

    def __init__(self, thresholds, weights, deadzones, dz_weights):
        super().__init__(thresholds, weights, deadzones, dz_weights)
        if np.any(self.deadzones < 0.0):
            raise ParameterError("relative dead zones are distances from the last reversal: d_j >= 0")

    @property
    def n_memory(self) -> int:
        return self.thresholds.size + 4

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        n = self.thresholds.size
        h = _virgin_plays(v0, np.asarray(prm[:n], dtype=np.float64))
        x0 = _frozen_pi_sum(v0, h, prm, n)   # as the kernels sum it: a last-bit difference would be a reversal
        return np.r_[h, 0.0, 0.0, 1.0 if x0 >= 0.0 else -1.0, x0]

    @staticmethod
    def output(v, mem, prm):
        """y on the current branch (or on the new one if x turned back), plays frozen."""
        n = len(mem) - 4
        m = (len(prm) - 2 * n) // 2
        x = _frozen_pi_sum(v, mem, prm, n)
        x_r, y_r, s = mem[n], mem[n + 1], mem[n + 2]
        if s * (x - mem[n + 3]) < 0.0:   # turned back: a reversal at the last accepted point
            y_r += s * _branch_gain(s * (mem[n + 3] - x_r), prm, n, m)
            x_r = mem[n + 3]
            s = -s
        return y_r + s * _branch_gain(s * (x - x_r), prm, n, m)

    @staticmethod
    def commit(v, mem, prm):
        """Advance the plays; on a reversal of the PI sum start a new branch at the last point."""
        n = len(mem) - 4
        m = (len(prm) - 2 * n) // 2
        x = _advance_plays(v, mem, prm, n)
        s = mem[n + 2]
        if s * (x - mem[n + 3]) < 0.0:
            mem[n + 1] += s * _branch_gain(s * (mem[n + 3] - mem[n]), prm, n, m)
            mem[n] = mem[n + 3]
            mem[n + 2] = -s
        mem[n + 3] = x

    def inverse(self) -> "InverseRelativeModifiedPI":
        """The exact inverse: the inverse relative dead-zone stage (same reversal logic on the
        input, g^{-1} by Kuhnen's formula) followed by the inverse PI operator."""
        d, ws = _merge_zero(self.deadzones, self.dz_weights)
        d_inv, ws_inv = _kuhnen_inverse(d, ws, "relative dead-zone")
        pi = PrandtlIshlinskii(self.thresholds, self.weights).inverse()
        return InverseRelativeModifiedPI(pi.thresholds, pi.weights, d_inv, ws_inv)


class InverseRelativeModifiedPI(_DeadZonePI):
    """Inverse of :class:`RelativeModifiedPI`: the relative dead-zone stage acts on the input
    first, x = x_r + s g(s (v - v_r)) with reversals of v, then the PI sum sum_i w_i H_i[x].

    prm = [r_1..r_n, w_1..w_n, d_1..d_m, ws_1..ws_m] of the inverse stages (from
    :meth:`RelativeModifiedPI.inverse`); memory = [h_1..h_n, v_r, x_r, s, v_last]."""

    kind = "modified_pi_relative_inverse"

    def __init__(self, thresholds, weights, deadzones, dz_weights):
        super().__init__(thresholds, weights, deadzones, dz_weights)
        if np.any(self.deadzones < 0.0):
            raise ParameterError("relative dead zones are distances from the last reversal: d_j >= 0")

    @property
    def n_memory(self) -> int:
        return self.thresholds.size + 4

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        n = self.thresholds.size
        m = self.deadzones.size
        s = 1.0 if v0 >= 0.0 else -1.0
        x0 = s * _branch_gain(abs(v0), prm, n, m)
        return np.r_[_virgin_plays(x0, np.asarray(prm[:n], dtype=np.float64)), 0.0, 0.0, s, v0]

    @staticmethod
    def output(v, mem, prm):
        """The relative dead-zone stage on v (reversal detected on v), then the PI sum, frozen."""
        n = len(mem) - 4
        m = (len(prm) - 2 * n) // 2
        v_r, x_r, s = mem[n], mem[n + 1], mem[n + 2]
        if s * (v - mem[n + 3]) < 0.0:
            x_r += s * _branch_gain(s * (mem[n + 3] - v_r), prm, n, m)
            v_r = mem[n + 3]
            s = -s
        return _frozen_pi_sum(x_r + s * _branch_gain(s * (v - v_r), prm, n, m), mem, prm, n)

    @staticmethod
    def commit(v, mem, prm):
        """Advance the dead-zone stage's branch and the plays to the stage output x(v)."""
        n = len(mem) - 4
        m = (len(prm) - 2 * n) // 2
        s = mem[n + 2]
        if s * (v - mem[n + 3]) < 0.0:
            mem[n + 1] += s * _branch_gain(s * (mem[n + 3] - mem[n]), prm, n, m)
            mem[n] = mem[n + 3]
            s = -s
            mem[n + 2] = s
        _advance_plays(mem[n + 1] + s * _branch_gain(s * (v - mem[n]), prm, n, m), mem, prm, n)
        mem[n + 3] = v


class MaxwellSlip(MemoryOperator):
    """Maxwell slip (Wood, Steltz & Fearing 2005): n parallel branches, spring k_i in series with a Coulomb slip
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

_commit_plays = numba.njit(cache=True)(_PlayBank.commit)


@numba.njit(cache=True)
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
    threshold (Rodriguez-Fortun et al. 2010: r_i = P_i / 2 over the input range).
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
