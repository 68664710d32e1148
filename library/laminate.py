"""Laminate plate theory for piezoelectric bending actuators, the appendix A of

    Wood, R.J., Steltz, E., Fearing, R.S. "Nonlinear performance limits for high energy density
    piezoelectric bending actuators." Proc. IEEE International Conference on Robotics and
    Automation (ICRA), Barcelona, 2005.

Classical laminate plate theory: the force and moment resultants per unit width (N/m, N) of a
stack of orthotropic plies act on the mid-plane strains and curvatures through the ABD matrix,

    [N; M] = [[A, B], [B, D]] [eps0; kappa] - [N^P; M^P]                               (eq. 18)

with the vectors ordered (1, 2, 6): x along the beam, y across it, 6 the in-plane shear; N^P,
M^P the resultants of the plies' free piezoelectric strains (d31 E3, d32 E3, 0). The inverse
C = [[A, B], [B, D]]^-1 gives the free curvature along the beam
P(E3) = C41 N1^P + C42 N2^P + C44 M1^P + C45 M2^P (1-based indices, as in the paper) and, with
the beam's geometric factors G_S (free deflection) and G_F (tip force), the tip deflection

    delta = P(E3) l^2 G_S / 2 - C44 F_ext l^3 G_F / (3 w_nom)                          (eq. 19)
    k_a   = 3 w_nom / (C44 l^3 G_F)                                                      (eq. 20)

(the extracted eq. 20 prints a factor "G_s" in the denominator; with no field applied eq. 19
leaves only the force term, whose coefficient is 1/k_a, so we read it as G_F). G_S and G_F are
1 for the straight rectangular cantilever; :func:`geometry_factors` gives them for the tapered
beam with a rigid extension (Sec. III-A, eqs. 7 and 9): the piezoelectric moment per unit width
is uniform, so is the free curvature whatever the taper, and the extension carries the tip
slope (G_S = 1 + 2 l_r); G_F is the Castigliano compliance of :func:`library.beam.
cantilever_tip_compliance` in units of the straight beam's l^3/(3 EI).

Sign conventions: z runs from the bottom face of the laminate up; a positive curvature kappa_x
bends the beam towards +z at its tip (the tip deflection along +z is kappa l^2/2); a ply whose
free strain is positive above the mid-plane gives a negative curvature. SI units throughout.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .beam import cantilever_tip_compliance


@dataclass(frozen=True)
class Ply:
    """One ply of the laminate, principal axes along the beam (x) and across it (y).

    thickness (m); E1, E2 Young's moduli along x and y (Pa); nu12 the major Poisson ratio; G12
    the in-plane shear modulus (Pa); d31, d32 the piezoelectric strain coefficients (m/V) for a
    field E3 through the thickness, positive along the ply's poling direction (0 for a passive
    ply)."""

    thickness: float
    E1: float
    E2: float
    nu12: float
    G12: float
    d31: float = 0.0
    d32: float = 0.0

    @classmethod
    def isotropic(cls, thickness: float, E: float, nu: float, d31: float = 0.0) -> Ply:
        """An in-plane isotropic ply (a poled ceramic plate: d32 = d31, G = E / (2 (1 + nu)))."""
        return cls(thickness, E, E, nu, E / (2.0 * (1.0 + nu)), d31, d31)

    def stiffness(self) -> np.ndarray:
        """The reduced (plane-stress) stiffness Q (3 x 3, Pa) in the order (1, 2, 6)."""
        nu21 = self.nu12 * self.E2 / self.E1
        den = 1.0 - self.nu12 * nu21
        return np.array(
            [
                [self.E1 / den, self.nu12 * self.E2 / den, 0.0],
                [self.nu12 * self.E2 / den, self.E2 / den, 0.0],
                [0.0, 0.0, self.G12],
            ]
        )


def _faces(plies: Sequence[Ply]) -> np.ndarray:
    """z of the ply faces (m), measured from the laminate's geometric mid-plane, bottom to top."""
    z = np.concatenate([[0.0], np.cumsum([p.thickness for p in plies])])
    return z - z[-1] / 2.0


def abd_matrix(plies: Sequence[Ply]) -> np.ndarray:
    """The 6 x 6 matrix [[A, B], [B, D]] of eq. 18 for ``plies`` listed bottom to top:
    A = sum Q t, B = sum Q (z_top^2 - z_bot^2)/2, D = sum Q (z_top^3 - z_bot^3)/3
    (units N/m, N, N m)."""
    if not plies:
        raise ValueError("a laminate needs at least one ply")
    z = _faces(plies)
    A, B, D = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for p, z0, z1 in zip(plies, z[:-1], z[1:]):
        Q = p.stiffness()
        A += Q * (z1 - z0)
        B += Q * (z1**2 - z0**2) / 2.0
        D += Q * (z1**3 - z0**3) / 3.0
    return np.block([[A, B], [B, D]])


def piezo_resultants(plies: Sequence[Ply], fields: Sequence[float]) -> np.ndarray:
    """[N^P; M^P] of eq. 18 (N/m and N, per unit width): the resultants of the free strains
    (d31 E3, d32 E3, 0) of each ply, ``fields`` the field E3 (V/m) in each ply along its poling
    direction, bottom to top."""
    if len(fields) != len(plies):
        raise ValueError(f"give one field per ply: {len(plies)} plies, {len(fields)} fields")
    z = _faces(plies)
    out = np.zeros(6)
    for p, E3, z0, z1 in zip(plies, fields, z[:-1], z[1:]):
        sigma = p.stiffness() @ np.array([p.d31 * E3, p.d32 * E3, 0.0])
        out[:3] += sigma * (z1 - z0)
        out[3:] += sigma * (z1**2 - z0**2) / 2.0
    return out


def laminate_compliance(plies: Sequence[Ply]) -> np.ndarray:
    """C = [[A, B], [B, D]]^-1 (eq. 18's inverse, 6 x 6)."""
    return np.linalg.inv(abd_matrix(plies))


def free_curvature(plies: Sequence[Ply], fields: Sequence[float]) -> float:
    """P(E3) of eq. 19, C41 N1^P + C42 N2^P + C44 M1^P + C45 M2^P: the curvature along the beam
    (1/m) of the free laminate under the ply fields ``fields`` (V/m), no external load."""
    return float((laminate_compliance(plies) @ piezo_resultants(plies, fields))[3])


def geometry_factors(w_r: float = 1.0, l_r: float = 0.0) -> tuple[float, float]:
    """(G_S, G_F) of eq. 19 for the tapered beam (width ratio w_r, eq. 7) with a rigid
    extension (length ratio l_r, eq. 9), the deflection taken at the end of the extension:
    G_S = 1 + 2 l_r, G_F = (3/l^3) int_0^l (l (1 + l_r) - x)^2 w_nom/w(x) dx."""
    return 1.0 + 2.0 * l_r, 3.0 * cantilever_tip_compliance(1.0, 1.0, w_r, l_r)


def tip_deflection(P: float, F_ext: float, C44: float, w_nom: float, l: float, G_S: float, G_F: float) -> float:
    """Eq. 19: the tip deflection (m) for the free curvature ``P`` (1/m, :func:`free_curvature`)
    and a tip force ``F_ext`` (N, along the deflection it opposes: positive F_ext pushes the tip
    back), C44 (1/(N m)) from :func:`laminate_compliance`, nominal width ``w_nom`` and active
    length ``l`` (m)."""
    return P * l**2 * G_S / 2.0 - C44 * F_ext * l**3 * G_F / (3.0 * w_nom)


def actuator_stiffness(C44: float, w_nom: float, l: float, G_F: float) -> float:
    """Eq. 20: k_a = 3 w_nom / (C44 l^3 G_F), the tip stiffness (N/m) with no field applied."""
    return 3.0 * w_nom / (C44 * l**3 * G_F)
