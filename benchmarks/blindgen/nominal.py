"""Nominal devices: the numbers of the project's model files (their PARAMETERS lists, read
through ``bondgraph.model.modelfile``) and, for the bimorph, our own clamped-free uniform-beam modes.

The bimorph is fully covered (one uniform segment), so its modes are the textbook cantilever
modes, mass-normalised (int_0^L rhoA phi^2 dx = 1, phi(L) > 0):

    phi_n(x) = s_n [cosh bx - cos bx - sigma_n (sinh bx - sin bx)] / sqrt(rhoA L),
    omega_n = (b_n L)^2 sqrt(EI / (rhoA L^4)),  m_p,n = M_p phi_n'(L),  M_p = b e31 (t_b + t_p),

EI and rhoA as in Ghafarirad et al. (2015), eq. 11 (units: phi in kg^-1/2, m_p in N kg^-1/2 V^-1,
modal coordinate q in kg^1/2 m; sensor reading w = sum phi_n(x_s) q_n in m).
"""

from __future__ import annotations

import functools
import os

import numpy as np
from scipy.optimize import brentq

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MODELS = {"apa": os.path.join(ROOT, "models", "apa120ml.py"), "t215": os.path.join(ROOT, "models", "bimorph_t215.py")}


@functools.lru_cache(maxsize=None)
def model_values(family: str) -> dict:
    """{name: default} of the model file's PARAMETERS (numbers only)."""
    from bondgraph.model.modelfile import load_model

    declared = load_model(MODELS[family]).declared
    return {p.name: float(p.default) for p in declared if isinstance(p.default, (int, float))}


@functools.lru_cache(maxsize=None)
def beam() -> dict:
    """Uniform-beam constants of the T215 model file: L (m), EI (N m^2), rhoA (kg/m), M_p (N m/V),
    alpha (1/s), beta (s), target (fraction of L), modes kept."""
    p = model_values("t215")
    h = p["t_b"] / 2
    EI = p["c_b"] * p["b"] * p["t_b"] ** 3 / 12 + p["c_p"] * 2 * p["b"] * ((h + p["t_p"]) ** 3 - h**3) / 3
    rhoA = p["rho_b"] * p["b"] * p["t_b"] + 2 * p["rho_p"] * p["b"] * p["t_p"]
    return {
        "L": p["L"],
        "EI": EI,
        "rhoA": rhoA,
        "M_p": p["b"] * p["e31"] * (p["t_b"] + p["t_p"]),
        "alpha": p["alpha"],
        "beta": p["beta"],
        "target": p["target"],
        "modes": int(p["modes"]),
        "b": p["b"],
        "t": p["t_b"] + 2 * p["t_p"],
        "rho": rhoA / (p["b"] * (p["t_b"] + 2 * p["t_p"])),
    }


def _beta_l(n: int) -> float:
    """n-th root of 1 + cos z cosh z = 0."""
    return brentq(lambda z: np.cos(z) + 1 / np.cosh(z), (n - 1) * np.pi + 1e-9, n * np.pi)


def cantilever_mode(n: int, x_frac: float) -> tuple[float, float, float, float]:
    """(omega_n rad/s, phi_n(x_frac L), phi_n(L), m_p,n) of the nominal T215 beam, mode n >= 1."""
    c = beam()
    z = _beta_l(n)
    b, L = z / c["L"], c["L"]
    sigma = (np.cosh(z) + np.cos(z)) / (np.sinh(z) + np.sin(z))
    norm = 1 / np.sqrt(c["rhoA"] * L)

    def shape(x):
        return norm * (np.cosh(b * x) - np.cos(b * x) - sigma * (np.sinh(b * x) - np.sin(b * x)))

    sign = np.sign(shape(L))
    slope_tip = sign * norm * b * (np.sinh(z) + np.sin(z) - sigma * (np.cosh(z) - np.cos(z)))
    omega = z**2 * np.sqrt(c["EI"] / (c["rhoA"] * L**4))
    return omega, sign * shape(x_frac * L), sign * shape(L), c["M_p"] * slope_tip


def rayleigh_zeta(omega: float) -> float:
    """Model-file damping ratio of a mode at omega: 2 zeta omega = alpha + beta omega^2."""
    c = beam()
    return (c["alpha"] + c["beta"] * omega**2) / (2 * omega)
