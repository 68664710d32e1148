"""A small real stack driven through an amplifier: the PI PICMA P-885.91 of the shared real record
(tests/data/p885_bursts.csv; Aye & Ang, ICSTSD 2018, a handheld micromanipulator), for
``bondgraph fit`` and ``bondgraph compensate`` on measured data.

Chain, after Rodriguez-Fortun, J.M., Orus, J., Buil, F., Castellanos, J.A. "General bond graph
model for piezoelectric actuators and methodology for experimental identification."
Mechatronics 20 (2010) 303-314 (lumped stack, eq. 14, with the hysteresis at the input as
Ghafarirad et al. 2015 place their Prandtl-Ishlinskii operator):

    V (DAQ volts) --gain--> V_amp --H[.] (PI, hysteresis=pi)--> Se --R_amp--> stack --T--> x

* the amplifier: a voltage gain ``gain`` and an output resistance ``R_amp`` into the stack's
  capacitance (the record says neither: 36 V/V maps the DAQ's 0-3.6 V onto the stack's 0-130 V;
  300 ohm with the 1.5 uF stack is a 350 Hz bandwidth, as a current-limited amplifier gives such
  a load, far above the record's 1 Hz bursts, so the fit cannot see it);
* the hysteresis: a Prandtl-Ishlinskii operator on the amplifier voltage, six plays with
  thresholds spread over the drive's range (library.hysteresis.threshold_grid), its weights
  ``H.w1``..``H.w6`` identified on the record's first 25 s by non-negative least squares on the
  loop (WEIGHTS, :func:`identify_weights`); ``bondgraph fit --params T`` then calibrates the
  gain and the sensor's zero (fitting the six weights with ``bondgraph fit`` works too, but
  each is then fitted as nonlinear: some 200 simulations of the 70 s record);
* the stack: P-885.91 data-sheet numbers (5 x 5 x 18 mm, PICMA layers of 60 um, d33 = 400 pm/V,
  s33E = 20.7e-12 m^2/N, eps33T = 1750 eps0: 0.12 um/V free, 1.5 uF), lumped
  (library.triangular.piezo_stack), its head free (the manipulator's load is not known) with
  the viscous term R_NL = 3e4 N s/m of Rodriguez-Fortun et al. (0.45 ms with the 67 N/um
  stack: invisible at 200 Hz, and it keeps the model non-stiff); T, the micromanipulator's
  lever from the stack to the sensor.
  The weights carry the lever and the amplifier gain with the loop shape, so T stays 1 for
  ``hysteresis=pi``; with ``hysteresis=none`` (the linear model) fit T instead.

What the record cannot give and the model leaves out: creep (the holds drift; no rate-independent
operator removes it), the sensor's dynamics. See docs/papers.md for the fit, the compensation and
the predicted tracking errors on the held-out bursts.
"""

import numpy as np

from bondgraph import J1, Experiment, Model, Parameter, PiecewiseLinear, R, Se
from library.hysteresis import PrandtlIshlinskii, fit_pi_weights, threshold_grid
from library.piezo import layer_extension
from library.triangular import piezo_stack, stack_constants

EPS0 = 8.854e-12
#: the DAQ range the plays cover (V): the record's drive spans 0.17-3.51 V
DRIVE_RANGE = (0.17, 3.51)
N_PLAYS = 6

PARAMETERS = [
    Parameter(
        "hysteresis", "pi", "", "input hysteresis: pi (Prandtl-Ishlinskii, fitted) or none", choices=("pi", "none")
    ),
    Parameter("gain", 36.0, "V/V", "amplifier voltage gain (not stated with the record; ours)", bounds=(0.1, 1e3)),
    Parameter("R_amp", 300.0, "ohm", "amplifier output resistance (ours: a 350 Hz bandwidth)", bounds=(1e-3, 1e6)),
    Parameter("T", 1.0, "1", "lever from the stack to the sensor (fit it with hysteresis=none)", bounds=(1e-3, 1e3)),
    Parameter("d33", 400e-12, "m/V", "piezoelectric coefficient (PIC255-type data sheet)", bounds=(0.0, 1e-8)),
    Parameter("s33E", 20.7e-12, "m^2/N", "elastic compliance at constant field", bounds=(1e-13, 1e-9)),
    Parameter("eps33T", 1750 * EPS0, "F/m", "permittivity at constant stress, 1750 eps0", bounds=(1e-11, 1e-6)),
    Parameter("area", 25e-6, "m^2", "stack cross-section, 5 x 5 mm (P-885.91)", bounds=(1e-8, 1.0)),
    Parameter("length", 18e-3, "m", "stack length (P-885.91)", bounds=(1e-4, 1.0)),
    Parameter("h", 60e-6, "m", "layer thickness (PICMA)", bounds=(1e-6, 1e-2)),
    Parameter("c_stack", 1e4, "N*s/m", "stack internal viscous term R_NL (rate dependence; ours)", bounds=(0.0, 1e8)),
]

#: three seconds of the record's drive shape: 1 Hz sine about its 1.83 V rest
EXPERIMENT = Experiment(
    t_end=3.0,
    dt=5e-3,
    inputs={
        "V": PiecewiseLinear(
            list(np.linspace(0.0, 3.0, 301)), list(1.83 + 1.5 * np.sin(np.linspace(0.0, 6 * np.pi, 301)))
        )
    },
)


def thresholds(gain: float) -> np.ndarray:
    """Play thresholds (V at the amplifier output): N_PLAYS evenly over half the drive range
    (library.hysteresis.threshold_grid: a play opens a loop once the input swings by 2 r)."""
    return threshold_grid(gain * np.array(DRIVE_RANGE), N_PLAYS)


def free_stroke_per_volt(p) -> float:
    """x per volt of the PI output, quasi-statically (m/V): T d33 N, N = length/h."""
    return p.value("T") * p.value("d33") * p.value("length") / p.value("h")


def identify_weights(V, x, gain: float, stroke_per_volt: float) -> np.ndarray:
    """The PI weights of this file from a record (V in DAQ volts, x in m), read quasi-statically
    (the model's electrical and mechanical poles are hundreds of times faster than the record's
    1 Hz bursts): x = stroke_per_volt H[gain V] + c, non-negative least squares on the loop
    (Rodriguez-Fortun et al. 2010, Sec. 5.3)."""
    w, _ = fit_pi_weights(gain * np.asarray(V, float), x, thresholds(gain), offset=True)
    return w / stroke_per_volt


#: identify_weights on the record's first 25 s (burst 1 and a hold; tests/test_compensate.py
#: re-derives them); the loop shape the model keeps, ``bondgraph fit --params T`` calibrates its gain
WEIGHTS = (1.2075, 1.314, 0.0927, 0.6098, 0.2402, 0.0)


def build(p):
    g = Model("P-885.91", "PICMA P-885.91 stack behind an amplifier (the shared real record)")
    V = g.input("V", "V", "DAQ control voltage to the amplifier")
    v_amp = p.gain * V
    if p.hysteresis == "pi":
        v_amp = g.operator("H", PrandtlIshlinskii(thresholds(p.value("gain")), WEIGHTS), v_amp)
    g.add(
        Se("amp", v_amp),
        J1("i"),
        R("R_amp", p.R_amp),
        piezo_stack(
            "stack", d33=p.d33, s33E=p.s33E, eps33T=p.eps33T, area=p.area, length=p.length, h=p.h, c_stack=p.c_stack
        ),
        Se("load", 0),
    )
    g.chain("amp", "i", "stack.elec")
    g.bond("i", "R_amp")
    g.bond("load", "stack.mech")
    k = stack_constants(d33=p.d33, s33E=p.s33E, eps33T=p.eps33T, area=p.area, length=p.length, h=p.h)
    g.output("x", p.T * layer_extension("stack", k["a"], k["l"]), "m", "displacement at the sensor")
    g.output("i", g.flow("R_amp"), "A", "amplifier current")
    return g
