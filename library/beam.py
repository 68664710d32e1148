"""Bimorph piezoelectric cantilever: exact Euler–Bernoulli modes, after Ghafarirad, H., Rezaei, S.M.,
Sarhan, A.A.D., Zareinejad, M. "Continuous dynamic modelling of bimorph piezoelectric cantilevered
actuators considering hysteresis effect and dynamic behaviour analysis." Mathematical and Computer
Modelling of Dynamical Systems 21(2) (2015) 130-152; and the effective mass of tapered and
extended cantilevers after Wood, R.J., Steltz, E., Fearing, R.S. "Nonlinear performance limits for
high energy density piezoelectric bending actuators." Proc. IEEE ICRA, Barcelona, 2005.

SI units throughout. x runs from the clamp (x = 0) to the free tip (x = L); w is the transverse
deflection. Two piezo layers of equal thickness cover the substrate on [l1, l2], giving three
segments [0, l1] bare, [l1, l2] covered, [l2, L] bare (zero-length segments are dropped).

Modal model (Ghafarirad et al. eqs. 22-23), with mass-normalised modes phi_i:

    q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i = m_p,i V,     w(x, t) = sum_i phi_i(x) q_i(t)
    m_p,i = M_p (phi_i'(l2) - phi_i'(l1)),   M_p = b e31 (t_b + t_p)

Sign convention (decision, checked against the paper): the bending moment of the covered part is
M = EI w'' - M_p V (Ghafarirad et al. eq. 10, field E3 = V/t_p in each layer, poling opposite in the two
layers), so the distributed load is M_p V [delta'(x - l1) - delta'(x - l2)] (eq. 14) and, with
int delta'(x - l) phi dx = -phi'(l) (eq. 21), m_p,i = M_p (phi_i'(l2) - phi_i'(l1)). M_p keeps the
sign of e31: for PZT (e31 < 0) M_p < 0, so a positive V bends the tip towards negative w. Mode
signs are fixed by phi_i(L) > 0. A global sign of V cancels in the zeros of w(x_t)/V.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq


class Segment(NamedTuple):
    """A uniform piece of the beam: [start, end] (m), rhoA (kg/m), EI (N m^2)."""

    start: float
    end: float
    rhoA: float
    EI: float


@dataclass(frozen=True)
class Bimorph:
    """Symmetric bimorph cantilever (Ghafarirad et al. Fig. 1), clamped at x = 0, free at x = L.

    L, b: length and width (m); t_p: thickness of EACH piezo layer (m); t_b: substrate thickness (m);
    rho_p, rho_b: densities (kg/m^3); c_p, c_b: elastic moduli (Pa); e31: piezo constant (C/m^2);
    l1, l2: piezo coverage (m), default the whole length (l2 = None means L).
    """

    L: float
    b: float
    t_p: float
    t_b: float
    rho_p: float
    rho_b: float
    c_p: float
    c_b: float
    e31: float
    l1: float = 0.0
    l2: float | None = None

    def __post_init__(self):
        if self.l2 is None:
            object.__setattr__(self, "l2", self.L)
        if min(self.L, self.b, self.t_p, self.t_b, self.rho_p, self.rho_b, self.c_p, self.c_b) <= 0:
            raise ValueError("dimensions, densities and moduli must be positive")
        if not 0.0 <= self.l1 <= self.l2 <= self.L:
            raise ValueError(f"need 0 <= l1 <= l2 <= L, got l1={self.l1}, l2={self.l2}, L={self.L}")

    @property
    def rhoA_bare(self) -> float:
        """Mass per length of the bare substrate (kg/m)."""
        return self.rho_b * self.b * self.t_b

    @property
    def rhoA_covered(self) -> float:
        """Mass per length of substrate + two piezo layers (kg/m)."""
        return self.rhoA_bare + 2 * self.rho_p * self.b * self.t_p

    @property
    def EI_bare(self) -> float:
        """Bending stiffness c_b I_b of the bare substrate, I_b = b t_b^3 / 12 (N m^2)."""
        return self.c_b * self.b * self.t_b**3 / 12

    @property
    def EI_covered(self) -> float:
        """c_b I_b + c_p I_p, I_p = 2b[(t_b/2 + t_p)^3 - (t_b/2)^3]/3 (Ghafarirad et al. eq. 11) (N m^2)."""
        h = self.t_b / 2
        return self.EI_bare + self.c_p * 2 * self.b * ((h + self.t_p) ** 3 - h**3) / 3

    @property
    def M_p(self) -> float:
        """Piezoelectric moment per volt M_p = b e31 (t_b + t_p) (N m/V); sign of e31 kept."""
        return self.b * self.e31 * (self.t_b + self.t_p)

    @property
    def segments(self) -> tuple[Segment, ...]:
        """Non-empty uniform segments from clamp to tip."""
        parts = (
            (0.0, self.l1, self.rhoA_bare, self.EI_bare),
            (self.l1, self.l2, self.rhoA_covered, self.EI_covered),
            (self.l2, self.L, self.rhoA_bare, self.EI_bare),
        )
        return tuple(Segment(*p) for p in parts if p[1] > p[0])

    @property
    def mass(self) -> float:
        """Total beam mass (kg)."""
        return sum(s.rhoA * (s.end - s.start) for s in self.segments)

    def modes(self, n: int) -> Modes:
        """First n exact, mass-normalised clamped-free modes (see module docstring)."""
        return _modal_analysis(self, n)


# Ghafarirad et al. 2015, Table 1: Piezo Systems T215-A4-103X, PZT-5A on brass, fully covered.
T215_A4_103X = Bimorph(
    L=21.6e-3, b=3.2e-3, t_p=0.13e-3, t_b=0.12e-3, rho_p=7800.0, rho_b=9000.0, c_p=59e9, c_b=105e9, e31=-12.54
)
# Shahabi, Ghafarirad & Taghvaeipour 2019, Table 1: Piezo Systems T226-H4-203X, PZT-5H on brass, fully covered.
T226_H4_203X = Bimorph(
    L=24.53e-3, b=6.4e-3, t_p=0.265e-3, t_b=0.140e-3, rho_p=7500.0, rho_b=9000.0, c_p=51.51e9, c_b=105e9, e31=-13.11
)


def _basis(beta, xi, h, d):
    """d-th x-derivative / beta^d of [sin bx, cos bx, e^{b(x-h)}, e^{-bx}] at local coordinate xi.

    The two exponentials span the same space as sinh, cosh but stay within [0, 1] on [0, h], so
    high modes and long segments cannot overflow.
    """
    ph = beta * xi + d * np.pi / 2
    return np.stack([np.sin(ph), np.cos(ph), np.exp(beta * (xi - h)), (-1.0) ** d * np.exp(-beta * xi)], axis=-1)


def _matrix(segs, betas):
    """Boundary/continuity matrix (4m x 4m), each row scaled to O(1) entries."""
    m = len(segs)
    h = [s.end - s.start for s in segs]
    A = np.zeros((4 * m, 4 * m))
    A[0, :4] = _basis(betas[0], 0.0, h[0], 0)  # phi(0) = 0
    A[1, :4] = _basis(betas[0], 0.0, h[0], 1)  # phi'(0) = 0
    r = 2
    for k in range(m - 1):  # phi, phi', EI phi'', (EI phi'')' continuous
        for d in range(4):
            w = (segs[k + 1].EI / segs[k].EI if d >= 2 else 1.0) * (betas[k + 1] / betas[k]) ** d
            A[r, 4 * k : 4 * k + 4] = _basis(betas[k], h[k], h[k], d)
            A[r, 4 * k + 4 : 4 * k + 8] = -w * _basis(betas[k + 1], 0.0, h[k + 1], d)
            r += 1
    A[r, -4:] = _basis(betas[-1], h[-1], h[-1], 2)  # moment-free tip
    A[r + 1, -4:] = _basis(betas[-1], h[-1], h[-1], 3)  # shear-free tip
    return A


def _gauss(a, b, n):
    """Gauss–Legendre nodes and weights on [a, b]."""
    t, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * t + 0.5 * (a + b), 0.5 * (b - a) * w


def _modal_analysis(beam: Bimorph, n: int) -> Modes:
    if n < 1:
        raise ValueError("n must be >= 1")
    segs = beam.segments
    kappa = np.array([(s.rhoA / s.EI) ** 0.25 for s in segs])  # beta_k = kappa_k sqrt(omega)
    phase = float(np.sum(kappa * [s.end - s.start for s in segs]))

    def det(theta):  # theta = sum_k beta_k h_k; modes sit roughly pi apart in theta
        return np.linalg.det(_matrix(segs, kappa * theta / phase))

    # Eigenvalues of the clamped-free Euler–Bernoulli problem are simple (oscillation theory), so
    # each is a sign change of det. They lie about pi apart in theta (first one near 1.9 for
    # moderate EI, rhoA contrasts), so scanning from 0.05 in pi/32 steps brackets each exactly once
    # (checked against FEM for 8 modes in tests/test_beam.py).
    roots, step = [], np.pi / 32
    t0, f0 = 0.05, det(0.05)
    while len(roots) < n:
        t1 = t0 + step
        f1 = det(t1)
        if np.sign(f1) != np.sign(f0):
            roots.append(brentq(det, t0, t1, xtol=1e-14, rtol=4 * np.finfo(float).eps))
        t0, f0 = t1, f1
    theta = np.array(roots)
    omegas = (theta / phase) ** 2
    betas = kappa[None, :] * theta[:, None] / phase
    coefs = np.empty((n, len(segs), 4))
    for i in range(n):
        c = np.linalg.svd(_matrix(segs, betas[i]))[2][-1].reshape(len(segs), 4)
        norm = 0.0
        for k, s in enumerate(segs):
            x, w = _gauss(0.0, s.end - s.start, 40 + int(betas[i, k] * (s.end - s.start)))
            norm += s.rhoA * w @ (_basis(betas[i, k], x, s.end - s.start, 0) @ c[k]) ** 2
        tip = _basis(betas[i, -1], segs[-1].end - segs[-1].start, segs[-1].end - segs[-1].start, 0)
        coefs[i] = c * np.sign(tip @ c[-1]) / np.sqrt(norm)
    return Modes(beam, omegas, betas, coefs)


@dataclass(frozen=True, eq=False)
class Modes:
    """Exact mass-normalised modes: int_0^L rhoA phi_i phi_j dx = delta_ij, phi_i(L) > 0.

    omegas: natural frequencies (rad/s), ascending. betas[i, k], coefs[i, k]: wavenumber (1/m) and
    coefficients of mode i on segment k in the basis of _basis (local coordinate x - start_k).
    """

    beam: Bimorph
    omegas: np.ndarray
    betas: np.ndarray
    coefs: np.ndarray

    def derivative(self, i: int, x, d: int = 0) -> np.ndarray:
        """d-th x-derivative of phi_i at x in [0, L] (vectorised; at an interface the right limit)."""
        x = np.asarray(x, dtype=float)
        if np.any((x < 0) | (x > self.beam.L)):
            raise ValueError("x outside [0, L]")
        segs = self.beam.segments
        starts = np.array([s.start for s in segs])
        h = np.array([s.end - s.start for s in segs])
        k = np.searchsorted(starts, x, side="right") - 1
        beta = self.betas[i][k]
        return beta**d * np.sum(_basis(beta, x - starts[k], h[k], d) * self.coefs[i][k], axis=-1)

    def shape(self, i: int, x) -> np.ndarray:
        """Mode shape phi_i(x) (kg^-1/2)."""
        return self.derivative(i, x, 0)

    def slope(self, i: int, x) -> np.ndarray:
        """Mode slope phi_i'(x) (kg^-1/2 m^-1)."""
        return self.derivative(i, x, 1)

    @property
    def input_gains(self) -> np.ndarray:
        """m_p,i = M_p (phi_i'(l2) - phi_i'(l1)): modal force per volt (N kg^-1/2 V^-1)."""
        b = self.beam
        return np.array([b.M_p * (self.slope(i, b.l2) - self.slope(i, b.l1)) for i in range(len(self.omegas))])

    def damping_ratios(self, alpha: float, beta: float) -> np.ndarray:
        """Proportional damping: 2 zeta_i omega_i = alpha + beta omega_i^2 (alpha 1/s, beta s)."""
        return (alpha + beta * self.omegas**2) / (2 * self.omegas)

    def effective_mass(self, i: int = 0, x: float | None = None) -> float:
        """Modal mass of mode i referred to point x (default tip): 1 / phi_i(x)^2 (kg)."""
        return float(self.shape(i, self.beam.L if x is None else x) ** -2)

    def transfer_function(self, x: float, zetas) -> tuple[np.ndarray, np.ndarray]:
        """w(x)/V = sum_i phi_i(x) m_p,i / (s^2 + 2 zeta_i omega_i s + omega_i^2), all modes.

        Returns (num, den) polynomial coefficients in s, highest power first (m/V).
        """
        dens = [np.array([1.0, 2 * z * w, w**2]) for z, w in zip(zetas, self.omegas)]
        gains = self.input_gains
        num = np.zeros(1)
        for i in range(len(dens)):
            term = np.array([self.shape(i, x) * gains[i]])
            for j, dj in enumerate(dens):
                if j != i:
                    term = np.polymul(term, dj)
            num = np.polyadd(num, term)
        den = np.ones(1)
        for dj in dens:
            den = np.polymul(den, dj)
        return num, den


def effective_mass(beam: Bimorph) -> float:
    """Tip-referred effective mass from the static tip-load deflection delta(x) (Wood, Steltz &
    Fearing 2005, eq. 6):

    m_eff = int rhoA delta^2 dx / delta(L)^2  (kg); for a uniform beam this is 33/140 of its mass.
    """
    segs = beam.segments
    EI = np.array([s.EI for s in segs])
    a0 = np.array([s.start for s in segs])
    a1 = np.array([s.end for s in segs])

    def delta(x):  # EI(x) delta'' = L - x, delta(0) = delta'(0) = 0, per unit tip force (m/N)
        x = np.asarray(x, dtype=float)[..., None]
        P = lambda s: x * beam.L * s - (x + beam.L) * s**2 / 2 + s**3 / 3
        return np.sum((P(np.minimum(x, a1)) - P(np.minimum(x, a0))) / EI, axis=-1)

    energy = 0.0
    for s in segs:  # delta is cubic on each segment: 4-point Gauss is exact
        x, w = _gauss(s.start, s.end, 4)
        energy += s.rhoA * w @ delta(x) ** 2
    return float(energy / delta(beam.L) ** 2)


# ---- effective mass of tapered and extended cantilevers (Wood, Steltz & Fearing 2005, Sec. III-A) ----
def cantilever_mass_factor(w_r: float = 1.0, l_r: float = 0.0, d_r: float = 0.0) -> float:
    """M = m_eff / m_beam of a cantilever of length l with a tip load (Wood, Steltz & Fearing,
    "Nonlinear performance limits for high energy density piezoelectric bending actuators",
    ICRA 2005, eqs. 6-12), by quadrature of the static deflection.

    Width w(x) = w_nom (w_r + 2 (1 - w_r) x / l) (eq. 7: w_nom at mid-length, root w_r w_nom,
    tip (2 - w_r) w_nom, planform area fixed), bending stiffness proportional to the width;
    a rigid extension of length l_r l and the tip width, with mass per area d_r times the beam's
    (eq. 10). m_beam = rho t w_nom l (1 + d_r l_r (2 - w_r)) is the gross mass, so

        M = [int_0^l delta^2 w/w_nom dx + d_r (2 - w_r) int_l^{l(1+l_r)} delta^2 dx]
            / [l (1 + d_r l_r (2 - w_r)) delta(l (1 + l_r))^2]

    with delta from EI(x) delta'' = F (l (1 + l_r) - x), delta(0) = delta'(0) = 0 and the
    extension straight. M = 33/140 for the rectangular beam (eq. 6); see
    :func:`extension_mass_factor` for eq. 11. Dimensionless; 0 < w_r < 2."""
    if not 0.0 < w_r < 2.0 or l_r < 0.0 or d_r < 0.0:
        raise ValueError(f"need 0 < w_r < 2, l_r >= 0, d_r >= 0; got w_r={w_r}, l_r={l_r}, d_r={d_r}")
    tip = 1.0 + l_r  # lengths in units of l

    def width(x):
        return w_r + 2.0 * (1.0 - w_r) * x

    def slope(x):  # delta'(x) = int_0^x (tip - s)/w(s) ds
        return quad(lambda s: (tip - s) / width(s), 0.0, x, epsabs=0.0, epsrel=1e-13)[0]

    def deflection(x):  # delta(x) = int_0^x (x - s)(tip - s)/w(s) ds
        return quad(lambda s: (x - s) * (tip - s) / width(s), 0.0, x, epsabs=0.0, epsrel=1e-13)[0]

    d1, a1 = deflection(1.0), slope(1.0)
    beam = quad(lambda x: deflection(x) ** 2 * width(x), 0.0, 1.0, epsabs=0.0, epsrel=1e-12)[0]
    ext_w = d_r * (2.0 - w_r)
    # the straight extension: int_0^{l_r} (d1 + a1 s)^2 ds in closed form
    ext = ext_w * (d1**2 * l_r + d1 * a1 * l_r**2 + a1**2 * l_r**3 / 3.0)
    d_tip = d1 + a1 * l_r
    return float((beam + ext) / ((1.0 + ext_w * l_r) * d_tip**2))


def extension_mass_factor(l_r, d_r):
    """Eq. 11 of Wood, Steltz & Fearing 2005: M(l_r, d_r) of a rectangular cantilever with a rigid
    extension (extension ratio l_r = l_ext/l, mass-per-area ratio d_r, eq. 10),

        M = [33 + 7 l_r (13 + 9 l_r + 5 d_r (4 + 3 l_r (6 + l_r (11 + 2 l_r (5 + 2 l_r)))))]
            / [140 (1 + d_r l_r) (1 + 3 l_r + 3 l_r^2)^2].

    The numerator is as printed; the denominator, lost in the text, is derived from eq. 9
    (tests check both against :func:`cantilever_mass_factor`). Numbers or arrays."""
    num = 33 + 7 * l_r * (13 + 9 * l_r + 5 * d_r * (4 + 3 * l_r * (6 + l_r * (11 + 2 * l_r * (5 + 2 * l_r)))))
    return num / (140 * (1 + d_r * l_r) * (1 + 3 * l_r + 3 * l_r**2) ** 2)


def cantilever_tip_compliance(EI_nom: float, l: float, w_r: float = 1.0, l_r: float = 0.0) -> float:
    """Tip deflection per unit tip force (m/N) of the cantilever of :func:`cantilever_mass_factor`,
    bending stiffness EI_nom (N m^2) at mid-length, scaled with the width; at the end of the rigid
    extension: delta = l^3/EI_nom int_0^1 (1 + l_r - s)^2 / w(s) ds (Castigliano)."""
    tip = 1.0 + l_r
    integral = quad(lambda s: (tip - s) ** 2 / (w_r + 2.0 * (1.0 - w_r) * s), 0.0, 1.0, epsabs=0.0, epsrel=1e-13)[0]
    return float(l**3 / EI_nom * integral)


def cantilever_beta_L(n: int) -> np.ndarray:
    """First n roots of 1 + cos(bL) cosh(bL) = 0 (1.8751, 4.6941, 7.8548, ...)."""
    f = lambda z: np.cos(z) + 1 / np.cosh(z)  # same roots, no overflow
    return np.array([brentq(f, (k - 1) * np.pi, k * np.pi, xtol=1e-15) for k in range(1, n + 1)])


def uniform_cantilever_omegas(EI: float, rhoA: float, L: float, n: int) -> np.ndarray:
    """Natural frequencies (rad/s) of a uniform clamped-free beam: (bL)^2 sqrt(EI/(rhoA L^4))."""
    return cantilever_beta_L(n) ** 2 * np.sqrt(EI / (rhoA * L**4))
