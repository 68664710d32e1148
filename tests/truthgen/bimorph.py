"""Truth physics of a cantilevered bimorph in modal form, written by hand.

Mass-normalised modes (Ghafarirad et al., MCMDS 21 (2015), eqs. 22-23 and 36)::

    q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i = mp_i u + F_i,    x = sum_i phi_i q_i

with ``u`` the equivalent drive voltage.  The hidden effects enter as

* input side (the field in the piezo layers): ``u = map(V)`` — hysteresis (Preisach,
  Bouc–Wen, Duhem), saturation (tanh, polynomial, piecewise); creep cells
  ``u = V + sum c_j``, ``tau_j dc_j/dt = w_j V - c_j``;
* modal forces ``F_i`` (:class:`.terms.ModalForces`): softening (cubic, cubic+quintic on
  mode 1, a cubic spring at the sensor point coupling the modes, a drive-dependent stiffness),
  nonlinear damping (quadratic in the sensor-point velocity, amplitude-dependent viscous
  damping of mode 1, smooth Coulomb friction), Maxwell-slip friction on mode 1 (hysteresis);
* extra modes (a next beam mode, an off-beam mode), or a sensor-bracket mode excited by the
  acceleration of the sensed point.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .system import DRIVE, Equations, Lin, System
from .terms import ModalForces


@dataclass
class Effects:
    creep: list = field(default_factory=list)  # (tau_j, w_j)
    drive_map: object | None = None  # V array -> u array
    modal: list = field(default_factory=list)  # laws (q, qd, V) -> forces on the modes
    extra_modes: list = field(default_factory=list)  # (omega, zeta, mp, phi)
    sensor_mode: dict | None = None  # {gamma, omega, zeta}


def system(p: dict, fx: Effects | None = None, probes: bool = False):
    """The bimorph as a :class:`System` (``p``: lists ``omega``, ``zeta``, ``mp``, ``phi``);
    with ``probes``, also the rows of q_1, q_1' and the sensed velocity."""
    fx = fx or Effects()
    eq = Equations()
    u = Lin({DRIVE: 1.0})
    cells = [eq.state(f"c{j}") for j in range(len(fx.creep))]
    for cell, (tau, w) in zip(cells, fx.creep):
        eq.ddt(cell, (w * Lin({DRIVE: 1.0}) - cell) / tau)
    u = u + sum(cells, Lin())
    modes = list(zip(p["omega"], p["zeta"], p["mp"], p["phi"])) + list(fx.extra_modes)
    n_model = len(p["omega"])
    qs, qds, accel = [], [], Lin()
    out, vel = Lin(), Lin()
    for i, (w, z, mp, phi) in enumerate(modes):
        q, qd = eq.state(f"q{i + 1}"), eq.state(f"qd{i + 1}")
        force = Lin({f"F{i + 1}": 1.0}) if (fx.modal and i < n_model) else Lin()
        rate = mp * u - 2 * z * w * qd - w * w * q + force
        eq.ddt(q, qd)
        eq.ddt(qd, rate)
        qs.append(q)
        qds.append(qd)
        out = out + phi * q
        vel = vel + phi * qd
        accel = accel + phi * (mp * u - 2 * z * w * qd - w * w * q)
    if fx.sensor_mode:
        m = fx.sensor_mode
        s, sd = eq.state("s"), eq.state("sd")
        eq.ddt(s, sd)
        eq.ddt(sd, -m["gamma"] * accel - 2 * m["zeta"] * m["omega"] * sd - m["omega"] ** 2 * s)
        out = out + s
    terms = []
    if fx.modal:
        laws = list(fx.modal)

        def law(q, qd, v):
            return sum(f(q, qd, v) for f in laws)

        law.reset = lambda: [f.reset() for f in laws if hasattr(f, "reset")]
        terms.append(ModalForces(qs[:n_model], qds[:n_model], law))
    sys_ = System.build(eq, out, terms)
    sys_.drive_map = fx.drive_map
    if probes:
        return sys_, [eq.vector(qs[0]), eq.vector(qds[0]), eq.vector(vel)]
    return sys_


def static_gain(p: dict) -> float:
    """Quasi-static x/V (m/V) of the linear device."""
    return float(sum(mp * phi / w**2 for w, mp, phi in zip(p["omega"], p["mp"], p["phi"])))


# Uniform clamped-free Euler–Bernoulli beam: roots of 1 + cos(bL) cosh(bL) = 0.
BETA_L = (1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349, 14.1371683910)


def cantilever_ratios(mode: int, target: float):
    """(omega_k/omega_1, slope_k(L)/slope_1(L), shape_k(t)/shape_1(t)) of a uniform
    cantilever for mode ``k`` (1-based) at the sensor position ``target`` (fraction of L):
    how a further beam mode scales against the first (mass-normalised shapes)."""

    def shape(k, xi):
        b = BETA_L[k - 1]
        sig = (np.sinh(b) - np.sin(b)) / (np.cosh(b) + np.cos(b))
        return np.cosh(b * xi) - np.cos(b * xi) - sig * (np.sinh(b * xi) - np.sin(b * xi))

    def slope_tip(k):
        b = BETA_L[k - 1]
        sig = (np.sinh(b) - np.sin(b)) / (np.cosh(b) + np.cos(b))
        return b * (np.sinh(b) + np.sin(b) - sig * (np.cosh(b) - np.cos(b)))

    return ((BETA_L[mode - 1] / BETA_L[0]) ** 2, slope_tip(mode) / slope_tip(1), shape(mode, target) / shape(1, target))
