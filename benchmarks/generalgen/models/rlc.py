"""Series RLC circuit: a voltage source drives a resistor, an inductor and a capacitor in series.

The sensor reads the capacitor voltage (resonance near 156 Hz, 5 % of critical damping).
"""

from bondgraph import J1, C, Experiment, I, Model, Parameter, R, Se, Step

PARAMETERS = [
    Parameter("R", 4.7, "ohm", "series resistance (resistor and winding)", bounds=(1e-4, 1e6)),
    Parameter("L", 47e-3, "H", "inductance", bounds=(1e-9, 1e3)),
    Parameter("C", 22e-6, "F", "capacitance", bounds=(1e-12, 1.0)),
]

EXPERIMENT = Experiment(t_end=0.1, dt=1e-5, inputs={"V": Step(5.0, t0=1e-3)})

#: the drive and the capacitor voltage identify L*C and R*C only: the capacitance is held
CALIBRATE = ["R", "L"]

#: plausible spread of the parts (×/÷): resistance with the winding's and contacts' share,
#: inductor and capacitor to their 20 % ratings
TOLERANCE = {"R": 2.0, "L": 1.2, "C": 1.2}


def build(p):
    g = Model("series RLC circuit", __doc__.splitlines()[0])
    V = g.input("V", "V", "source voltage")
    g.add(Se("source", V), J1("i"), R("resistor", p.R), I("inductor", p.L), C("capacitor", p.C))
    g.bond("source", "i")
    for e in ("resistor", "inductor", "capacitor"):
        g.bond("i", e)
    g.tag("inductor", "inertia")
    g.tag("capacitor", "stiffness")
    g.tag("resistor", "damping")
    g.output("vC", g.effort("capacitor"), "V", "capacitor voltage")
    return g
