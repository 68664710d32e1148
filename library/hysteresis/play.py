"""Play-based operators: Prandtl–Ishlinskii (play and stop forms) and the modified PI with dead
zones on the absolute PI sum or measured from the last reversal, with their exact inverses.
Kernels and the helpers they call live in this one file (numba caches a kernel only when all
its helpers share its file)."""

from __future__ import annotations

import numpy as np

from bondgraph import ParameterError

from . import c_kernels
from .base import VectorOperator, _indexed, _kuhnen_inverse, _merge_zero, _vector, _virgin_plays


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


class _PlayBank(VectorOperator):
    """Shared part of the play-based operators: n plays, prm = [r_1..r_n, w_1..w_n, ...]."""

    vectors = ("thresholds", "weights")
    vector_units = {"thresholds": (1, 0), "weights": (-1, 1), "prior": (1, 0)}

    def __init__(self, thresholds, weights):
        self.thresholds = _vector("thresholds", thresholds, nonneg=True)
        self.weights = _vector("weights", weights, self.thresholds.size)
        n = self.thresholds.size
        self.parameter_names = _indexed("r", n) + _indexed("w", n)

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

    ``prior`` (units of v, optional): the input level the device was last driven to before
    the first input; the plays start as after a monotone approach from it,
    h_i = clip(prior, v0 − r_i, v0 + r_i) (a device last driven to its maximum starts on the
    descending branch).  It is then a parameter too (prm = [r, w, prior]); without it the
    plays start as after an approach from 0.
    """

    kind = "pi"

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.PI

    def __init__(self, thresholds, weights, prior: float | None = None):
        super().__init__(thresholds, weights)
        if prior is not None:
            self.prior = np.asarray(prior, dtype=np.float64).reshape(1)
            self.vectors = ("thresholds", "weights", "prior")
            self.parameter_names = self.parameter_names + ("prior",)

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """Play outputs after a monotone approach from ``prior`` (or 0) to ``v0``, units of v."""
        n = self.n_memory
        prior = float(prm[2 * n]) if len(prm) > 2 * n else 0.0
        r = np.asarray(prm[:n], dtype=np.float64)
        return np.ascontiguousarray(np.clip(prior, v0 - r, v0 + r), dtype=np.float64)

    @staticmethod
    def output(v, mem, prm):
        """y = sum_i w_i max(v - r_i, min(v + r_i, h_i)) with the plays h frozen."""
        return _frozen_pi_sum(v, mem, prm, len(mem))

    def small_signal_gain(self, prm: np.ndarray) -> float:
        """Slope right after a reversal: the sum of the weights of the r = 0 plays."""
        n = self.n_memory
        return float(np.sum(prm[n : 2 * n][prm[:n] == 0.0]))

    def monotone_problem(self, prm: np.ndarray) -> str:
        """A branch's slope at a distance s from its last reversal is the sum of the weights of
        the plays with 2 r_i < s: the output rises with the input exactly when every partial sum
        (plays sorted by threshold) is positive; negative weights are named either way."""
        n = self.n_memory
        r, w = np.asarray(prm[:n], float), np.asarray(prm[n : 2 * n], float)
        order = np.argsort(r, kind="stable")
        sums = np.cumsum(w[order])
        negative = [f"w{i + 1} = {w[i]:.3g}" for i in range(n) if w[i] < 0]
        if np.all(sums > 0):
            return ""
        k = int(np.argmax(sums <= 0))
        return (
            f"not monotone, so it has no inverse for compensation: its weights summed up to the play of "
            f"threshold {r[order][k]:.3g} give a slope of {sums[k]:.3g} (the output falls while the input "
            f"rises there)" + (f"; negative weights {', '.join(negative)}" if negative else "")
        )

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

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.PI_STOP

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
        return float(np.sum(prm[n : 2 * n][prm[:n] > 0.0]))


class _DeadZonePI(_PlayBank):
    """Shared parameters of a PI stage and a dead-zone stage: prm = [r_1..r_n, w_1..w_n,
    d_1..d_m, ws_1..ws_m]; S_d(x) = max(0, x - d) for d > 0, min(0, x - d) for d < 0, x for d = 0."""

    vectors = ("thresholds", "weights", "deadzones", "dz_weights")
    vector_units = {**_PlayBank.vector_units, "deadzones": (0, 1), "dz_weights": (0, 0)}

    def __init__(self, thresholds, weights, deadzones, dz_weights):
        super().__init__(thresholds, weights)
        self.deadzones = _vector("deadzones", deadzones)
        self.dz_weights = _vector("dz_weights", dz_weights, self.deadzones.size)
        m = self.deadzones.size
        self.parameter_names += _indexed("d", m) + _indexed("ws", m)

    def _zero_gains(self, prm: np.ndarray) -> tuple[float, float]:
        """(sum of w over r = 0, sum of ws over d = 0): the slopes of both stages after a reversal."""
        n = self.thresholds.size
        m = self.deadzones.size
        d, ws = prm[2 * n : 2 * n + m], prm[2 * n + m : 2 * n + 2 * m]
        return float(np.sum(prm[n : 2 * n][prm[:n] == 0.0])), float(np.sum(ws[d == 0.0]))

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

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.MODIFIED_PI

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
    vector_units = {**_DeadZonePI.vector_units, "deadzones": (1, 0)}  # the dead zones act on the input

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.INVERSE_MODIFIED_PI

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


class _RelativeDeadZones(_DeadZonePI):
    """Dead zones measured from the last reversal (d_j >= 0); memory = the n plays and the
    branch state [start of the stage's input, start of its output, direction, last input]."""

    def __init__(self, thresholds, weights, deadzones, dz_weights):
        super().__init__(thresholds, weights, deadzones, dz_weights)
        if np.any(self.deadzones < 0.0):
            raise ParameterError("relative dead zones are distances from the last reversal: d_j >= 0")

    @property
    def n_memory(self) -> int:
        return self.thresholds.size + 4


class RelativeModifiedPI(_RelativeDeadZones):
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

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.RELATIVE_MODIFIED_PI

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        n = self.thresholds.size
        h = _virgin_plays(v0, np.asarray(prm[:n], dtype=np.float64))
        x0 = _frozen_pi_sum(v0, h, prm, n)  # as the kernels sum it: a last-bit difference would be a reversal
        return np.r_[h, 0.0, 0.0, 1.0 if x0 >= 0.0 else -1.0, x0]

    @staticmethod
    def output(v, mem, prm):
        """y on the current branch (or on the new one if x turned back), plays frozen."""
        n = len(mem) - 4
        m = (len(prm) - 2 * n) // 2
        x = _frozen_pi_sum(v, mem, prm, n)
        x_r, y_r, s = mem[n], mem[n + 1], mem[n + 2]
        if s * (x - mem[n + 3]) < 0.0:  # turned back: a reversal at the last accepted point
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


class InverseRelativeModifiedPI(_RelativeDeadZones):
    """Inverse of :class:`RelativeModifiedPI`: the relative dead-zone stage acts on the input
    first, x = x_r + s g(s (v - v_r)) with reversals of v, then the PI sum sum_i w_i H_i[x].

    prm = [r_1..r_n, w_1..w_n, d_1..d_m, ws_1..ws_m] of the inverse stages (from
    :meth:`RelativeModifiedPI.inverse`); memory = [h_1..h_n, v_r, x_r, s, v_last]."""

    kind = "modified_pi_relative_inverse"
    vector_units = {**_DeadZonePI.vector_units, "deadzones": (1, 0)}  # the dead zones act on the input

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.INVERSE_RELATIVE_MODIFIED_PI

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
