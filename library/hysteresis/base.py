"""Parameter vectors, the initial-memory convention and Kuhnen's inverse formula shared by the
hysteresis operators of this package."""

from __future__ import annotations

import numpy as np

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


def _indexed(stem: str, n: int) -> tuple[str, ...]:
    return tuple(f"{stem}{i}" for i in range(1, n + 1))


class VectorOperator(MemoryOperator):
    """An operator whose parameters are equal-role vectors: prm is their concatenation in the
    order of ``vectors`` (attribute names); memory holds one value per entry of the first."""

    vectors: tuple[str, ...] = ()
    #: units of each vector's entries from the input's (v) and the output's (y): name -> (a, b)
    #: for [entry] = [v]^a·[y]^b (see MemoryOperator.parameter_dimensions)
    vector_units: dict[str, tuple[int, int]] = {}

    def parameter_dimensions(self) -> dict[str, tuple]:
        exps = [self.vector_units.get(name) for name in self.vectors for _ in range(getattr(self, name).size)]
        return {n: e for n, e in zip(self.parameter_names, exps) if e is not None}

    def __repr__(self) -> str:
        args = ", ".join(str(getattr(self, name).tolist()) for name in self.vectors)
        return f"{type(self).__name__}({args})"

    def parameter_values(self) -> np.ndarray:
        return np.concatenate([getattr(self, name) for name in self.vectors])

    @property
    def n_memory(self) -> int:
        return getattr(self, self.vectors[0]).size


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
            "(sorted by threshold); the loading curve is not strictly increasing"
        )
    w_inv = np.empty_like(w)
    w_inv[0] = 1.0 / w[0]
    w_inv[1:] = -w[1:] / (big_w[1:] * big_w[:-1])
    return big_w * r - np.cumsum(w * r), w_inv


def _merge_zero(d: np.ndarray, ws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One d = 0 term holding the summed weight of all d = 0 terms (first), the others after."""
    zero = d == 0.0
    return np.r_[0.0, d[~zero]], np.r_[np.sum(ws[zero]), ws[~zero]]
