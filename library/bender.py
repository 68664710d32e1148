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
* the gain and loss of a saturating drive at a field amplitude (:func:`secant_gain`,
  :func:`loss_factor`), for a model linear at each field as the paper's Figs. 17-18;
* the plate fields of the alternating bias drive (Sec. I-A-1; :func:`bias_drive_fields`);
* the power delivered to a resonant load, eq. 17 (:func:`load_power`, :func:`best_load_damping`);
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


def bias_drive_fields(V_c, V_b, t_p):
    """The fields (V/m) in the two plates of a bimorph under the alternating bias drive of Sec.
    I-A-1: one outer electrode grounded, the other at the bias V_b, the centre electrode at V_c
    (0 <= V_c <= V_b); both plates poled along the bias field, so neither is reverse biased.
    Returns (E_1, E_2), the field in the plate between ground and centre and in the plate between
    centre and bias, each positive along its poling: E_1 = V_c / t_p, E_2 = (V_b - V_c) / t_p.
    Their mean V_b / (2 t_p) strains both plates alike (no bending in a symmetric laminate); the
    bending part is +-(E_1 - E_2)/2 = +-(V_c - V_b/2) / t_p, i.e. +-V/t_p with V the centre
    electrode's voltage from the neutral position V_b/2, at most V_b / (2 t_p): half the peak
    plate field V_b / t_p that the paper quotes as the drive field. Numbers or sympy."""
    return V_c / t_p, (V_b - V_c) / t_p


def _quasi_static_loop(op: MemoryOperator, amplitude: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The second of two cycles of ``op`` driven by v = A sin (input, output)."""
    if not amplitude > 0:
        raise ValueError("a quasi-static loop needs a positive amplitude")
    v = amplitude * np.sin(np.linspace(0.0, 4.0 * np.pi, 2 * n + 1))
    return v[n:], op.run(v)[n:]


def loss_factor(op: MemoryOperator, amplitude: float, n: int = 400) -> float:
    """Loss factor eta = Delta W / (2 pi W) of the quasi-static loop of operator ``op`` driven by
    v = A sin over two cycles (the second is measured): Delta W the loop area, W = (half range
    of y)(A)/2 the peak energy of the secant spring (Sec. IV: loss per cycle from the area of the
    hysteresis loop, Figs. 15-16). Units-free; damping ratio zeta = eta/2."""
    v, y = _quasi_static_loop(op, amplitude, n)
    area = abs(float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(v))))
    w = 0.5 * (0.5 * np.ptp(y)) * amplitude
    return area / (2 * math.pi * w) if w > 0 else 0.0


def secant_gain(op: MemoryOperator, amplitude: float, n: int = 400) -> float:
    """(half range of y) / A of the quasi-static loop of ``op`` at amplitude A (units of y/v):
    the slope of the loop's secant, the gain a linear model at that amplitude keeps (Sec. II-B:
    a saturating drive delivers less than its small-signal gain)."""
    v, y = _quasi_static_loop(op, amplitude, n)
    return 0.5 * float(np.ptp(y)) / amplitude


def load_power(F, b_a, b_l):
    """Eq. 17: the power (W) delivered at resonance to a load damper b_l (N s/m) by an actuator
    of damping b_a (N s/m) and peak blocked force F (N), P_l = F^2 b_l / (2 (b_l + b_a)^2): at
    resonance mass and stiffness cancel, the velocity amplitude is F / (b_a + b_l) and the load
    takes b_l v^2 / 2 on average. Numbers or arrays."""
    return 0.5 * F**2 * b_l / (b_l + b_a) ** 2


def best_load_damping(F: float, b_a: float, omega: float, deflection_limit: float | None = None) -> float:
    """The load damping (N s/m) that maximises eq. 17, with the resonant deflection amplitude
    F / (omega (b_a + b_l)) (m) kept within ``deflection_limit``: b_l = b_a (matched) when that
    keeps within the limit, else the smallest b_l that does, F / (omega delta_max) - b_a (Sec. VI:
    lowering the load damping to match the actuator raises the Q and may exceed the strain
    limit at resonance)."""
    if deflection_limit is None:
        return float(b_a)
    return float(max(b_a, F / (omega * deflection_limit) - b_a))


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
