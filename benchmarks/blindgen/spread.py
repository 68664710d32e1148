"""Random factors for drawing a device around its nominal values."""
from __future__ import annotations

import numpy as np

MIN_DEV = 0.02   # a drawn linear parameter differs from the model file's by at least 2 %


def factor(rng, spread: float, log: bool) -> float:
    """A factor away from 1 by at least MIN_DEV: log-uniform in [1/spread, spread] (log=True) or
    uniform in [1 - spread, 1 + spread]."""
    sign = 1.0 if rng.random() < 0.5 else -1.0
    if log:
        return float(np.exp(sign * rng.uniform(np.log1p(MIN_DEV), np.log(spread))))
    return float(1.0 + sign * rng.uniform(MIN_DEV, spread))


def logu(rng, lo: float, hi: float) -> float:
    """Log-uniform in [lo, hi]."""
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
