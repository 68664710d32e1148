"""Piezo Systems T226-H4-203X bimorph near its first resonance: PZT-5H on brass (seed 001).

"Nonlinear vibration analysis of piezoelectric bending actuators: theoretical and experimental
studies" (seed 001). Single-mode Galerkin model, eq. 34:

    q'' + (mu + mu1 q^2) q' + omega_n^2 q + k1 q^3 + k2 q^5 = m_p V(t),   mu = 2 xi omega_n

with the multiple-scales steady state of eq. 54 (library.bimorph.amplitude_equation_roots).

Decisions (see also library/bimorph.py):

* q is the MASS-NORMALISED modal coordinate (kg^1/2 m): seed 001 normalises the mode with
  eq. 24, eta_1 = (int rhoA phi^2 dx)^-1/2, i.e. int rhoA phi^2 dx = 1 (eq. 25), and
  m_p = -M_p phi'(l) (eq. 32) uses that phi. From Table 1, m_p = 0.1330 N/(kg^1/2 V) in magnitude
  (here with library.beam's sign, mp_1 = -0.1330: only |m_p| enters eq. 54), phi(L) = 69.76
  kg^-1/2, phi(23.46 mm) = 65.58 kg^-1/2. The identified k1, k2, mu1 then make physical sense:
  at 0.5 V on resonance the sensor amplitude is about 32 µm (linear theory 35 µm) and the cubic
  term is 2.6 % of the linear stiffness, consistent with the paper's use of 0.5 V as the "linear"
  drive; softening turns into hardening (3/8 k1 a^2 + 10/32 k2 a^4 = 0) only at a = 7.6e-6,
  a tip amplitude of about 530 µm, beyond the tested range. Read with q as the tip displacement
  in metres instead, k1 q^2 / omega_n^2 would be about 150 at 0.5 V, which is absurd.
  Note that with these numbers the resonance peak drifts fast (about 2611 rad/s at 0.5 V, 2460 at
  2 V, below 2400 rad/s from 3 V on) and nonlinear damping dominates above 1 V.
* V enters as m_p V: eq. 54 is written with the forcing scaled into V (V(t) = eps V_a,
  V_a = V/2 e^{i omega T0} + cc, i.e. V(t) = V cos(omega t)); with m_p explicit its right-hand
  side is (m_p V)^2 / 4, V the amplitude of the sine in volts.
* omega_n: the paper's measured 2637 rad/s (Sec. 4.2, 0.5 V chirp) by default. The exact
  Euler–Bernoulli first mode of Table 1's dimensions is 2915.5 rad/s, 10.5 % higher: a real
  model-versus-measurement gap; ``frequency=computed`` uses it instead. The mass-normalised
  shape and m_p do not depend on the stiffness (uniform beam), so they are the same either way.
* Sensor at x_t = 23.46 mm ("close to the tip", Sec. 4.2), target = 0.9564.
"""
from bondgraph import Experiment, Model, Parameter, Sine

from library.beam import Bimorph
from library.bimorph import UNITS, ModeNonlinearity, add_bimorph_modes

T1 = "seed 001 Table 1"

PARAMETERS = [
    Parameter("nonlinear", False, "", "add the identified k1, k2, mu1 of seed 001 (eq. 34, Sec. 4.3)"),
    Parameter("frequency", "measured", "", "omega_n: measured 2637 rad/s (seed 001 Sec. 4.2) or computed "
              "from Table 1 (exact modes, 2915.5 rad/s)", choices=("measured", "computed")),
    Parameter("target", 23.46 / 24.53, "1", "sensor position as a fraction of L (x_t = 23.46 mm, Sec. 4.2)",
              symbolic=False, bounds=(1e-3, 1.0)),
    Parameter("L", 24.53e-3, "m", f"beam length ({T1})", symbolic=False),
    Parameter("b", 6.4e-3, "m", f"width Y ({T1})", symbolic=False),
    Parameter("t_p", 0.265e-3, "m", f"thickness of each PZT-5H layer ({T1})", symbolic=False),
    Parameter("t_b", 0.140e-3, "m", f"brass substrate thickness ({T1})", symbolic=False),
    Parameter("rho_p", 7500.0, "kg/m^3", f"PZT-5H density ({T1})", symbolic=False),
    Parameter("rho_b", 9000.0, "kg/m^3", f"brass density ({T1})", symbolic=False),
    Parameter("c_p", 51.51e9, "Pa", f"PZT-5H elastic modulus c_E ({T1})", symbolic=False),
    Parameter("c_b", 105e9, "Pa", f"brass elastic modulus ({T1})", symbolic=False),
    Parameter("e31", -13.11, "C/m^2", f"PZT-5H piezoelectric constant ({T1})", symbolic=False),
]

OMEGA_MEASURED = 2637.0   # rad/s, seed 001 Sec. 4.2 (FFT of a 0.5 V chirp response)
XI_MEASURED = 0.0085      # seed 001 Sec. 4.2
K1, K2, MU1 = -6.94e17, 1.443e28, 6.28e13   # seed 001 Sec. 4.3, identified on 0.5-4.5 V

# Sine drive near resonance, as in the paper's nonlinear identification (Sec. 4.3: 2512-2736
# rad/s, nine voltages); 0.2 s is about 4.5 decay times 1/(xi omega_n).
EXPERIMENT = Experiment(t_end=0.2, dt=2e-5, inputs={"V": Sine(2.5, 2600.0 / (2 * 3.141592653589793))})


#: linear parameters the diagnosis calibrates to data before looking for missing effects
CALIBRATE = ["mp_*", "omega_*", "zeta_*"]


def build(p):
    beam = Bimorph(L=p.L, b=p.b, t_p=p.t_p, t_b=p.t_b, rho_p=p.rho_p, rho_b=p.rho_b, c_p=p.c_p, c_b=p.c_b,
                   e31=p.e31)
    m = Model("bimorph_t226", "T226-H4-203X bimorph, first mode near resonance (seed 001)")
    nonlin = None
    if p.nonlinear:
        nonlin = {1: ModeNonlinearity(
            k1=m.parameter("k1", K1, UNITS["k1"], "cubic modal stiffness (seed 001 Sec. 4.3)"),
            k2=m.parameter("k2", K2, UNITS["k2"], "quintic modal stiffness (seed 001 Sec. 4.3)"),
            mu1=m.parameter("mu1", MU1, UNITS["mu1"], "nonlinear damping, (mu + mu1 q^2) q' (seed 001 Sec. 4.3)"))}
    if p.frequency == "measured":
        omega = m.parameter("omega_1", OMEGA_MEASURED, UNITS["omega"],
                            "natural frequency, measured (seed 001 Sec. 4.2); Table 1 gives 2915.5 rad/s")
    else:
        omega = None   # exact Euler-Bernoulli first mode of Table 1's beam
    xi = m.parameter("zeta_1", XI_MEASURED, UNITS["zeta"], "damping ratio, measured (seed 001 Sec. 4.2)")
    add_bimorph_modes(m, beam, 1, p.target, omegas=[omega], zetas=[xi], nonlinear=nonlin, source=T1)
    return m
