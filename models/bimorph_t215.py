"""Piezo Systems T215-A4-103X bimorph: PZT-5A on brass, fully covered cantilever, from

    Ghafarirad, H., Rezaei, S.M., Sarhan, A.A.D., Zareinejad, M. "Continuous dynamic modelling of
    bimorph piezoelectric cantilevered actuators considering hysteresis effect and dynamic
    behaviour analysis." Mathematical and Computer Modelling of Dynamical Systems 21(2) (2015)
    130-152, doi:10.1080/13873954.2014.906472.

Numbers: Table 1 (geometry, materials, alpha, beta); the model:

* exact Euler–Bernoulli modes of the three-segment beam (Sec. 2.2; here fully covered, l1 = 0,
  l2 = L), mass-normalised, one resonator per mode (eqs. 22-23):
  q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i = m_p,i u,  2 zeta_i omega_i = alpha + beta omega_i^2;
* sensor at the target point: x = w(l_t) = sum_i phi_i(l_t) q_i (eq. 36), l_t = target·L
  (the experiment of Sec. 4.1 uses l_t = 20.5 mm = 0.95 L);
* optional Prandtl–Ishlinskii hysteresis at the input, u = H[V] (eq. 25, Sec. 2.4).

Checks (tests/test_bimorph.py): Table 2 natural frequencies 2249, 14094.24, 39464.29 rad/s
(this model: 2247.4, 14084.2, 39436.2, 0.07 % low, as the uniform-beam formula); with two modes
w(l_t)/V has a right-half-plane zero for l_t < 0.737 L (Sec. 3.1, Fig. 8).
"""

from bondgraph import Chirp, Experiment, Model, Parameter
from library.beam import Bimorph
from library.bimorph import add_bimorph_modes, pi_operator

T1 = "Ghafarirad et al. 2015, Table 1"

PARAMETERS = [
    Parameter("modes", 2, "", "number of bending modes kept (the paper uses two)", bounds=(1, 12)),
    Parameter(
        "target", 0.95, "1", "sensor position as a fraction of L (Sec. 4.1: 0.95)", symbolic=False, bounds=(1e-3, 1.0)
    ),
    Parameter("L", 21.6e-3, "m", f"beam length ({T1})", symbolic=False),
    Parameter("b", 3.2e-3, "m", f"width of substrate and piezo layers ({T1})", symbolic=False),
    Parameter("t_p", 0.13e-3, "m", f"thickness of each PZT-5A layer ({T1})", symbolic=False),
    Parameter("t_b", 0.12e-3, "m", f"brass substrate thickness ({T1})", symbolic=False),
    Parameter("rho_p", 7800.0, "kg/m^3", f"PZT-5A density ({T1})", symbolic=False),
    Parameter("rho_b", 9000.0, "kg/m^3", f"brass density ({T1})", symbolic=False),
    Parameter("c_p", 59e9, "Pa", f"PZT-5A elastic modulus c11^E ({T1})", symbolic=False),
    Parameter("c_b", 105e9, "Pa", f"brass elastic modulus ({T1})", symbolic=False),
    Parameter("e31", -12.54, "C/m^2", f"PZT-5A piezoelectric constant ({T1})", symbolic=False),
    Parameter(
        "alpha", 1e-3, "1/s", f"mass-proportional damping, 2 zeta omega = alpha + beta omega^2 ({T1})", symbolic=False
    ),
    Parameter("beta", 1e-5, "s", f"stiffness-proportional damping ({T1})", symbolic=False),
    Parameter(
        "hysteresis",
        "none",
        "",
        "input hysteresis: none, or pi (Prandtl–Ishlinskii, Ghafarirad et al. 2015, eq. 25)",
        choices=("none", "pi"),
    ),
]

# Geometry, alpha and beta are numbers (symbolic=False): they feed the modal analysis at build time.
# What comes out of it is registered per mode as fittable, printable parameters: omega_i, zeta_i
# (from alpha + beta omega_i^2), mp_i and phi_i (at the target); e.g. --set zeta_1=0.02.

# The paper identifies its PI model on a quasi-static multi-amplitude input (Fig. 16-17) but does not
# tabulate the thresholds and weights. These illustrative values make H[V] an equivalent voltage
# (small-signal slope 1 from the virgin state, the play with r = 0) whose loading curve steepens by
# up to 30 % over a 0-60 V range, with a loop of a few volts; fit them to data for real use.
PI_THRESHOLDS = (0.0, 10.0, 20.0, 30.0, 40.0, 50.0)  # V
PI_WEIGHTS = (1.0, 0.08, 0.07, 0.06, 0.05, 0.04)  # 1

# The paper's linear identification (Sec. 4.1): a 0.3 V chirp over the first two modes
# (Fig. 12 spans 0-18000 rad/s), sampled at 20 kHz.
EXPERIMENT = Experiment(t_end=0.5, dt=5e-5, inputs={"V": Chirp(0.3, f0=10.0, f1=3000.0, t1=0.5)})


#: linear parameters the diagnosis calibrates to data before looking for missing effects
CALIBRATE = ["mp_*", "omega_*", "zeta_*"]

#: plausible spread of a real device around these values (×/÷ factor; others: the setting
#: diagnosis.tolerance, 2 for material constants): damping is known to an order of magnitude
#: at best, geometry (thickness, lengths, mode shapes) and capacitance (kx) far better
TOLERANCE = {"zeta_*": 15.0, "omega_*": 1.3, "phi_*": 1.1}


def build(p):
    beam = Bimorph(L=p.L, b=p.b, t_p=p.t_p, t_b=p.t_b, rho_p=p.rho_p, rho_b=p.rho_b, c_p=p.c_p, c_b=p.c_b, e31=p.e31)
    m = Model("bimorph_t215", "T215-A4-103X bimorph, modal model (Ghafarirad et al. 2015)")
    hyst = pi_operator(PI_THRESHOLDS, PI_WEIGHTS) if p.hysteresis == "pi" else None
    add_bimorph_modes(m, beam, p.modes, p.target, alpha=p.alpha, beta=p.beta, hysteresis=hyst, source=T1)
    return m


def bode_nmp(load):
    """Bode diagrams at 0.95, 0.9 and 0.7 L and the right-half-plane zero against the target."""
    import numpy as np
    from scipy.optimize import brentq

    from bondgraph import derive, linearize
    from bondgraph.plotting import Curve, Figure, Panel

    w = np.geomspace(500.0, 60000.0, 2000)
    mag, phase, numbers = [], [], {}
    for target in (0.95, 0.9, 0.7):
        lin = linearize(derive(load(target=target, hysteresis="none").model), "V", "x")
        H = lin.frequency_response(w)
        rhp = [z for z in lin.zeros if z.real > 0]
        label = f"{target:g} L" + (f" (RHP zero {rhp[0].real:.0f} rad/s)" if rhp else " (minimum phase)")
        mag.append(Curve(w, np.abs(H), label))
        phase.append(Curve(w, np.degrees(np.unwrap(np.angle(H))), label))
        numbers[f"RHP zeros at {target:g} L"] = len(rhp)
        if rhp:
            numbers[f"RHP zero at {target:g} L (rad/s)"] = rhp[0].real
    lm = load(hysteresis="none")
    p = lm.params
    beam = Bimorph(L=p.L, b=p.b, t_p=p.t_p, t_b=p.t_b, rho_p=p.rho_p, rho_b=p.rho_b, c_p=p.c_p, c_b=p.c_b, e31=p.e31)
    modes = beam.modes(2)
    g = modes.input_gains

    def a1(f):  # eq. 38: the numerator's coefficient whose sign change moves the zero across
        return 1 + g[1] * modes.shape(1, f * beam.L) / (g[0] * modes.shape(0, f * beam.L))

    boundary = brentq(a1, 0.5, 0.95, xtol=1e-12)
    numbers["minimum-phase boundary (fraction of L)"] = boundary
    targets = np.linspace(0.5, 1.0, 101)
    a = [a1(f) for f in targets]
    return Figure(
        "T215-A4-103X, two modes (Ghafarirad et al. 2015): Bode and the non-minimum-phase zero",
        [
            Panel(mag, "|w(l_t)/V|", "frequency (rad/s)", "m/V", "log", "log"),
            Panel(phase, "phase of w(l_t)/V", "frequency (rad/s)", "deg", "log"),
            Panel(
                [Curve(targets, a, "a1(l_t)"), Curve([boundary], [0.0], f"boundary {boundary:.4f} L", "ko")],
                "eq. 38: a1 < 0 puts a zero in the right half plane",
                "target l_t / L",
                "a1 = 1 + m_p2 phi2 / (m_p1 phi1)",
            ),
        ],
        numbers,
        columns=3,
    )


FIGURES = {"bode": bode_nmp}
