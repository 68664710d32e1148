"""Random factors for drawing a device around its nominal values, and creep spectra."""

from __future__ import annotations

import numpy as np

MIN_DEV = 0.02  # a drawn linear parameter differs from the model file's by at least 2 %


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


def creep_knobs(mech: str, rng, size: tuple, cells_tau: tuple, log_from: float, frac_from: float, to: float) -> dict:
    """A creep mechanism's draw: the creep ratio over the record r_T uniform in ``size``, and
    its cells (time constants s, weights): ``kelvin-voigt`` 2-4 cells log-uniform in
    ``cells_tau``; ``log`` equal weights two a decade from 10^log_from to 10^to s;
    ``fractional`` weights tau^alpha (alpha 0.15-0.45) from 10^frac_from to 10^to s."""
    u = rng.uniform
    if mech == "kelvin-voigt":
        m = int(rng.integers(2, 5))
        return {"r_T": u(*size), "tau": np.sort(np.exp(u(*np.log(cells_tau), m))), "w": rng.dirichlet(np.full(m, 2.0))}
    if mech == "log":
        tau = 10.0 ** np.arange(log_from, to + 0.01, 0.5)
        return {"r_T": u(*size), "tau": tau, "w": np.ones_like(tau)}
    tau, alpha = 10.0 ** np.arange(frac_from, to + 0.01, 0.5), u(0.15, 0.45)
    return {"r_T": u(*size), "alpha": alpha, "tau": tau, "w": tau**alpha}
