"""The Maxwell-slip operator (Wood, Steltz & Fearing 2005)."""

from __future__ import annotations

import numpy as np

from bondgraph import ParameterError

from . import c_kernels
from .base import VectorOperator, _indexed, _vector, _virgin_plays
from .play import PIStop


class MaxwellSlip(VectorOperator):
    """Maxwell slip (Wood, Steltz & Fearing 2005): n parallel branches, spring k_i in series with a Coulomb slip
    element of break-away force f_i. Input displacement delta, output force
    F = sum_i k_i (delta - delta_i); branch i sticks while |k_i (delta - delta_i)| < f_i.

    ``stiffnesses`` k_i > 0 (units of y/v), ``breakaway_forces`` f_i >= 0 (units of y);
    prm = [k_1..k_n, f_1..f_n]; memory = slip positions delta_i (units of v), which are the play
    outputs of thresholds f_i/k_i (see :meth:`to_pi_stop`).
    """

    kind = "maxwell_slip"
    vectors = ("stiffnesses", "breakaway_forces")
    vector_units = {"stiffnesses": (-1, 1), "breakaway_forces": (0, 1)}

    def c_source(self):
        """The kernels in C, for exported models."""
        return c_kernels.MAXWELL_SLIP

    def __init__(self, stiffnesses, breakaway_forces):
        self.stiffnesses = _vector("stiffnesses", stiffnesses)
        if np.any(self.stiffnesses <= 0):
            raise ParameterError("stiffnesses must be > 0")
        self.breakaway_forces = _vector("breakaway_forces", breakaway_forces, self.stiffnesses.size, nonneg=True)
        n = self.stiffnesses.size
        self.parameter_names = _indexed("k", n) + _indexed("f", n)

    def initial_memory(self, v0: float, prm: np.ndarray) -> np.ndarray:
        """Slip positions at rest at ``v0`` after a monotone approach from 0, units of v."""
        n = self.n_memory
        return _virgin_plays(v0, prm[n : 2 * n] / prm[:n])

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
        return float(np.sum(prm[:n][prm[n : 2 * n] > 0.0]))

    def to_pi_stop(self) -> PIStop:
        """The equal stop-form PI operator: r_i = f_i / k_i, w_i = k_i."""
        return PIStop(self.breakaway_forces / self.stiffnesses, self.stiffnesses)
