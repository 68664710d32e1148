"""High-energy-density piezoelectric bending actuators driven at high fields, after

    Wood, R.J., Steltz, E., Fearing, R.S. "Nonlinear performance limits for high energy density
    piezoelectric bending actuators." Proc. IEEE International Conference on Robotics and
    Automation (ICRA), Barcelona, 2005.

Built only from the ``bondgraph`` public API. Mechanical domain at the tip: force (N), tip
velocity (m/s); the tip deflection delta (m) is taken at the end of the rigid extension.

* creep: the generalized Kelvin-Voigt model (Fig. 2), a spring k0 in series with N parallel
  spring-damper cells, step response eq. 1 (:func:`kelvin_voigt_chain`, :func:`creep_step_response`);
* saturation and hysteresis: Maxwell slip (Fig. 4, eqs. 2-3; :class:`library.hysteresis.MaxwellSlip`)
  and the loss of a quasi-static loop as a loss factor (Sec. IV, Figs. 15-16; :func:`loss_factor`);
* stress: enhancement of the coupling under a tensile tip load (Sec. II-C, Fig. 6;
  :func:`load_enhancement`);
* conservative: effective mass (:mod:`library.beam`, eqs. 6-12) and the stiffness softening with
  the drive field k_a(E) (Sec. III-B, Figs. 12-13; :func:`field_stiffness`);
* nonconservative: b = 2 zeta sqrt(m k) (eq. 13; :func:`damping_coefficient`) and the
  thermoelastic loss factor of eqs. 14-15 (:func:`thermoelastic_relaxation`,
  :func:`thermoelastic_loss`), realised in the time domain as a Zener (standard linear solid)
  relaxation arm (:func:`thermoelastic_arm`), whose loss factor is eq. 14 to first order in the
  relaxation strength;
* eq. 16, m_eff delta'' + b_a(f, E) delta' + k_a(E) delta = F_a + F_ext (:func:`bending_actuator`;
  F_a counted positive along delta, the opposite of the paper's sign).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from bondgraph import J0, J1, C, Component, I, MemoryOperator, R, Se


def kelvin_voigt_chain(name: str, k0, cells: Sequence[tuple] = (), doc: str = "") -> Component:
    """Generalized Kelvin-Voigt element (Fig. 2): spring ``k0`` (N/m) in series with cells of a
    spring k_n (N/m) parallel to a damper b_n (N s/m), ``cells`` = [(k_n, b_n), ...].
    Port ``port``: the force through the chain (effort) and its elongation rate (flow, the sum of
    the parts' rates). Elements ``k0``, ``k<n>``, ``b<n>``; tagged stiffness / creep."""
    c = Component(name, doc or "generalized Kelvin-Voigt chain (creep)")
    c.add(J0("F"), C("k0", 1 / k0))
    c.bond("F", "k0")
    c.tag("k0", "stiffness")
    for n, (k, b) in enumerate(cells, 1):
        c.add(J1(f"cell{n}"), C(f"k{n}", 1 / k), R(f"b{n}", b))
        c.bond("F", f"cell{n}")
        c.bond(f"cell{n}", f"k{n}")
        c.bond(f"cell{n}", f"b{n}")
        c.tag(f"k{n}", "creep")
        c.tag(f"b{n}", "creep")
    c.expose("port", "F")
    return c


def creep_step_response(t, F0: float, k0: float, cells: Sequence[tuple] = ()) -> np.ndarray:
    """Eq. 1: delta(t) = F0 [1/k0 + sum_n (1/k_n)(1 - exp(-t/tau_n))], tau_n = b_n/k_n, for a
    force step F0 (N) at t = 0 on the chain of :func:`kelvin_voigt_chain` (m)."""
    t = np.asarray(t, float)
    out = np.full(t.shape, 1.0 / k0)
    for k, b in cells:
        out = out + (1.0 - np.exp(-t * k / b)) / k
    return F0 * np.where(t >= 0.0, out, 0.0)


def thermoelastic_relaxation(
    *, alpha: float, E_Y: float, T: float, c_v: float, kappa: float, thickness: float
) -> tuple[float, float]:
    """(Delta, f_r) of eqs. 14-15: relaxation strength Delta = alpha^2 E_Y T / c_v (alpha: thermal
    expansion, 1/K; E_Y: Young's modulus, Pa; T: temperature, K; c_v: volumetric heat capacity,
    J/(m^3 K)) and relaxation frequency f_r = pi kappa / (2 c_v t^2) (kappa: thermal conductivity,
    W/(m K); t: beam thickness, m), Hz. The extracted eq. 14 reads "2EYT" for the prefactor; we
    take Zener's alpha^2 E T / c_v, which the units require."""
    return alpha**2 * E_Y * T / c_v, math.pi * kappa / (2.0 * c_v * thickness**2)


def thermoelastic_loss(f, delta: float, f_r: float):
    """Eq. 14: loss factor eta(f) = Delta (f/f_r) / (1 + (f/f_r)^2) (peak Delta/2 at f = f_r)."""
    r = np.asarray(f, float) / f_r
    return delta * r / (1.0 + r**2)


def damping_coefficient(zeta, m, k):
    """Eq. 13: b = 2 zeta sqrt(m k) (N s/m); with a loss factor eta, zeta = eta / 2."""
    return 2 * zeta * (m * k) ** 0.5


def thermoelastic_arm(name: str, k, delta, f_r, doc: str = "") -> Component:
    """Zener relaxation arm for the thermoelastic loss of a spring k (N/m): a spring Delta k in
    series with a damper Delta k tau, tau = 1/(2 pi f_r), placed in parallel with k. Its complex
    stiffness Delta k i w tau / (1 + i w tau) gives k + that a loss factor
    Delta w tau / (1 + (1 + Delta) w^2 tau^2) + O(Delta^2): eq. 14 for Delta << 1. Port ``port``."""
    tau = 1 / (2 * math.pi * f_r) if isinstance(f_r, (int, float)) else 1 / (2 * np.pi * f_r)
    c = Component(name, doc or "thermoelastic relaxation arm (Zener)")
    c.add(J0("F"), C("k", 1 / (delta * k)), R("c", delta * k * tau))
    c.bond("F", "k")
    c.bond("F", "c")
    c.tag("c", "damping")
    c.expose("port", "F")
    return c


def field_stiffness(E, k0, E_soft):
    """k_a(E) = k0 (1 - E/E_soft): the actuator stiffness softening linearly with the peak drive
    field E (V/m) (Sec. III-B: the resonance falls with the field, Fig. 12, and so does the
    stiffness measured under static loads at increasing bias fields, Fig. 13, whose numbers are
    lost in the text; the linear law is our reading of that trend). Numbers or sympy."""
    return k0 * (1 - E / E_soft)


def load_enhancement(F, gain, F_peak):
    """Factor on the piezoelectric coupling under a static tip load F (N, tensile > 0) (Sec. II-C,
    Fig. 6: tension on the working plate enhances the coupling, compression degrades it; the
    displacement under 50 and 100 mN exceeds the unloaded one, with a peak at 50 mN):
    1 + gain (F/F_peak) exp(1 - F/F_peak), largest (1 + gain) at F_peak. The form is ours."""
    s = F / F_peak
    return 1 + gain * s * (math.e ** (1 - s) if isinstance(s, (int, float)) else np.exp(1 - s))


def loss_factor(op: MemoryOperator, amplitude: float, n: int = 400) -> float:
    """Loss factor eta = Delta W / (2 pi W) of the quasi-static loop of operator ``op`` driven by
    v = A sin over two cycles (the second is measured): Delta W the loop area, W = (half range
    of y)(A)/2 the peak energy of the secant spring (Sec. IV: loss per cycle from the area of the
    hysteresis loop, Figs. 15-16). Units-free; damping ratio zeta = eta/2."""
    if not amplitude > 0:
        raise ValueError("loss factor needs a positive amplitude")
    v = amplitude * np.sin(np.linspace(0.0, 4.0 * np.pi, 2 * n + 1))
    y = op.run(v)
    v2, y2 = v[n:], y[n:]
    area = abs(float(np.sum(0.5 * (y2[1:] + y2[:-1]) * np.diff(v2))))
    w = 0.5 * (0.5 * np.ptp(y2)) * amplitude
    return area / (2 * math.pi * w) if w > 0 else 0.0


def bending_actuator(
    name: str, *, m_eff, k_a, b_a, F_a, creep: Sequence[tuple] = (), thermoelastic: tuple | None = None, doc: str = ""
) -> Component:
    """Eq. 16 as a bond graph: a 1-junction ``tip`` (tip velocity) carrying the effective mass
    ``m_eff`` (kg), the damper ``b_a`` (N s/m), the piezoelectric force ``F_a`` (N, an expression
    of the model's inputs; positive along delta) and the actuator's elastic chain: stiffness ``k_a``
    (N/m) in series with the creep cells ``creep`` = [(k_n, b_n), ...] (:func:`kelvin_voigt_chain`),
    plus, with ``thermoelastic`` = (Delta, f_r), the relaxation arm of :func:`thermoelastic_arm`.
    Port ``tip`` takes external forces (power in). Tip deflection: :func:`tip_deflection`."""
    c = Component(name, doc or "high-field piezoelectric bending actuator (eq. 16)")
    c.add(J1("v"), I("m_eff", m_eff), R("b_a", b_a), Se("F_a", F_a), kelvin_voigt_chain("chain", k_a, creep))
    c.bond("F_a", "v")
    c.bond("v", "m_eff")
    c.bond("v", "b_a")
    c.bond("v", "chain.port")
    if thermoelastic is not None:
        c.add(thermoelastic_arm("ted", k_a, *thermoelastic))
        c.bond("v", "ted.port")
    c.tag("m_eff", "inertia")
    c.tag("b_a", "damping")
    c.expose("tip", "v")
    return c


def tip_deflection(m, prefix: str, n_creep: int):
    """The tip deflection delta (m) of a :func:`bending_actuator` added under ``prefix``: the sum
    of its chain's elongations (spring k0 and each creep cell)."""
    total = m.displacement(f"{prefix}.chain.k0")
    for k in range(1, n_creep + 1):
        total = total + m.displacement(f"{prefix}.chain.k{k}")
    return total
