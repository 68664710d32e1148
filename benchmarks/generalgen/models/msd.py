"""Mass-spring-damper: a mass on a spring and a viscous damper to the ground, pushed by a force.

A generic single-degree-of-freedom oscillator (natural frequency about 32 Hz, 2.5 % of
critical damping), the simplest model a user writes for a mounted payload.
"""

from bondgraph import J1, C, Experiment, I, Model, Parameter, R, Se, Step

PARAMETERS = [
    Parameter("m1", 0.5, "kg", "moving mass", bounds=(1e-4, 1e3)),
    Parameter("k1", 2.0e4, "N/m", "suspension stiffness", bounds=(1.0, 1e9)),
    Parameter("c1", 5.0, "N*s/m", "viscous damping of the suspension", bounds=(1e-4, 1e6)),
]

EXPERIMENT = Experiment(t_end=0.5, dt=1e-4, inputs={"F": Step(10.0, t0=0.01)})

#: parameters that vary most between devices (the masses are weighed)
CALIBRATE = ["k*", "c*"]

#: plausible spread of a real device (×/÷): masses weighed to 20 %, stiffness from a
#: datasheet to 50 %, viscous damping known only roughly
TOLERANCE = {"m*": 1.2, "k*": 1.5, "c*": 4.0}


def build(p):
    g = Model("mass-spring-damper", __doc__.splitlines()[0])
    F = g.input("F", "N", "applied force, positive along x")
    g.add(Se("force", F), J1("v1"), I("mass1", p.m1), C("spring1", 1 / p.k1), R("damper1", p.c1))
    g.bond("force", "v1")
    for e in ("mass1", "spring1", "damper1"):
        g.bond("v1", e)
    g.tag("mass1", "inertia")
    g.tag("spring1", "stiffness")
    g.tag("damper1", "damping")
    g.output("x", g.displacement("spring1"), "m", "displacement of the mass")
    return g
