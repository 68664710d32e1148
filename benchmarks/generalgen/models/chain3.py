"""Three-mass chain: ground - spring1/damper1 - mass1 - spring2/damper2 - mass2 - spring3/damper3 - mass3.

The force acts on the inner mass (mass1); the sensor reads the displacement of the outer
mass (mass3), the far end of the chain (modes near 30, 68 and 88 Hz).
"""

from bondgraph import J0, J1, C, Experiment, I, Model, Parameter, R, Se, Step

PARAMETERS = [
    Parameter("m1", 0.3, "kg", "inner mass", bounds=(1e-4, 1e3)),
    Parameter("m2", 0.2, "kg", "middle mass", bounds=(1e-4, 1e3)),
    Parameter("m3", 0.1, "kg", "outer mass", bounds=(1e-4, 1e3)),
    Parameter("k1", 4.0e4, "N/m", "stiffness from the ground to mass1", bounds=(1.0, 1e9)),
    Parameter("k2", 2.0e4, "N/m", "stiffness between mass1 and mass2", bounds=(1.0, 1e9)),
    Parameter("k3", 1.5e4, "N/m", "stiffness between mass2 and mass3", bounds=(1.0, 1e9)),
    Parameter("c1", 6.0, "N*s/m", "damping from the ground to mass1", bounds=(1e-4, 1e6)),
    Parameter("c2", 3.0, "N*s/m", "damping between mass1 and mass2", bounds=(1e-4, 1e6)),
    Parameter("c3", 1.5, "N*s/m", "damping between mass2 and mass3", bounds=(1e-4, 1e6)),
]

EXPERIMENT = Experiment(t_end=0.5, dt=1e-4, inputs={"F": Step(10.0, t0=0.01)})

#: parameters that vary most between devices (the masses are weighed)
CALIBRATE = ["k*", "c*"]

#: plausible spread of a real device (×/÷)
TOLERANCE = {"m*": 1.2, "k*": 1.5, "c*": 4.0}


def build(p):
    g = Model("three-mass chain", __doc__.splitlines()[0])
    F = g.input("F", "N", "force on mass1, positive along x")
    g.add(Se("force", F), J1("v1"), J1("v2"), J1("v3"), J0("n12"), J0("n23"), J1("v12"), J1("v23"))
    for i, (m, k, c) in enumerate(((p.m1, p.k1, p.c1), (p.m2, p.k2, p.c2), (p.m3, p.k3, p.c3)), start=1):
        g.add(I(f"mass{i}", m), C(f"spring{i}", 1 / k), R(f"damper{i}", c))
        g.tag(f"mass{i}", "inertia")
        g.tag(f"spring{i}", "stiffness")
        g.tag(f"damper{i}", "damping")
    g.bond("force", "v1")
    for e in ("mass1", "spring1", "damper1"):
        g.bond("v1", e)
    # a 0-junction between two 1-junctions: common force; the link's spring is stretched by
    # the outer mass moving out (its flow is v_b - v_a), so the displacements add up to x3
    for a, b in ((1, 2), (2, 3)):
        g.bond(f"v{b}", f"n{a}{b}")
        g.bond(f"n{a}{b}", f"v{a}")
        g.bond(f"n{a}{b}", f"v{a}{b}")
        g.bond(f"v{a}{b}", f"spring{b}")
        g.bond(f"v{a}{b}", f"damper{b}")
        g.bond(f"v{b}", f"mass{b}")
    x3 = g.displacement("spring1") + g.displacement("spring2") + g.displacement("spring3")
    g.output("x3", x3, "m", "displacement of mass3")
    return g
