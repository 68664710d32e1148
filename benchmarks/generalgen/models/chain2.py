"""Two-mass chain: ground - spring1/damper1 - mass1 - spring2/damper2 - mass2.

The force acts on the outer mass (mass2); the sensor reads the displacement of the inner
mass (mass1), so the response is non-collocated (modes near 31 Hz and 62 Hz).
"""

from bondgraph import J0, J1, C, Experiment, I, Model, Parameter, R, Se, Step

PARAMETERS = [
    Parameter("m1", 0.4, "kg", "inner mass", bounds=(1e-4, 1e3)),
    Parameter("m2", 0.2, "kg", "outer mass", bounds=(1e-4, 1e3)),
    Parameter("k1", 3.0e4, "N/m", "stiffness from the ground to mass1", bounds=(1.0, 1e9)),
    Parameter("k2", 1.5e4, "N/m", "stiffness between mass1 and mass2", bounds=(1.0, 1e9)),
    Parameter("c1", 4.0, "N*s/m", "damping from the ground to mass1", bounds=(1e-4, 1e6)),
    Parameter("c2", 2.0, "N*s/m", "damping between mass1 and mass2", bounds=(1e-4, 1e6)),
]

EXPERIMENT = Experiment(t_end=0.5, dt=1e-4, inputs={"F": Step(10.0, t0=0.01)})

#: parameters that vary most between devices (the masses are weighed)
CALIBRATE = ["k*", "c*"]

#: plausible spread of a real device (×/÷)
TOLERANCE = {"m*": 1.2, "k*": 1.5, "c*": 4.0}


def build(p):
    g = Model("two-mass chain", __doc__.splitlines()[0])
    F = g.input("F", "N", "force on mass2, positive along x")
    g.add(Se("force", F), J1("v1"), J1("v2"), J0("n12"), J1("v12"))
    g.add(I("mass1", p.m1), I("mass2", p.m2))
    g.add(C("spring1", 1 / p.k1), R("damper1", p.c1), C("spring2", 1 / p.k2), R("damper2", p.c2))
    g.bond("force", "v2")
    g.bond("v2", "mass2")
    g.bond("v2", "n12")
    g.bond("n12", "v1")
    g.bond("n12", "v12")
    for e in ("spring2", "damper2"):
        g.bond("v12", e)
    for e in ("mass1", "spring1", "damper1"):
        g.bond("v1", e)
    for i in (1, 2):
        g.tag(f"mass{i}", "inertia")
        g.tag(f"spring{i}", "stiffness")
        g.tag(f"damper{i}", "damping")
    g.output("x1", g.displacement("spring1"), "m", "displacement of mass1")
    return g
