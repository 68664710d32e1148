"""A mirror on a flexure as three modes seen at its drive point (modal superposition).

Each mode is a modal mass, stiffness and damping driven by the same force; the sensor reads
the displacement of the drive point, the sum of the modal displacements (modes near 60,
210 and 520 Hz, 2 % of critical damping).
"""

from bondgraph import J0, J1, C, Experiment, I, Model, Parameter, R, Se, Step

#: (modal mass kg, stiffness N/m, damping N*s/m) of the three modes
_MODES = ((0.05, 7.1e3, 0.75), (0.08, 1.4e5, 4.2), (0.15, 1.6e6, 19.6))

PARAMETERS = [
    q
    for i, (m, k, c) in enumerate(_MODES, start=1)
    for q in (
        Parameter(f"m{i}", m, "kg", f"modal mass of mode {i} at the drive point", bounds=(1e-5, 1e3)),
        Parameter(f"k{i}", k, "N/m", f"modal stiffness of mode {i}", bounds=(1.0, 1e10)),
        Parameter(f"c{i}", c, "N*s/m", f"modal damping of mode {i}", bounds=(1e-5, 1e6)),
    )
]

EXPERIMENT = Experiment(t_end=0.2, dt=2e-5, inputs={"F": Step(1.0, t0=1e-3)})

#: parameters that vary most between devices (modal masses follow from the drawings)
CALIBRATE = ["k*", "c*"]

#: plausible spread of a real device (×/÷)
TOLERANCE = {"m*": 1.2, "k*": 1.5, "c*": 4.0}


def build(p):
    g = Model("three-mode structure", __doc__.splitlines()[0])
    F = g.input("F", "N", "force at the drive point")
    g.add(Se("force", F), J0("drive"))
    g.bond("force", "drive")
    x = 0
    for i in (1, 2, 3):
        g.add(J1(f"mode{i}"), I(f"mass{i}", p[f"m{i}"]), C(f"spring{i}", 1 / p[f"k{i}"]), R(f"damper{i}", p[f"c{i}"]))
        g.bond("drive", f"mode{i}")
        for e in ("mass", "spring", "damper"):
            g.bond(f"mode{i}", f"{e}{i}")
        g.tag(f"mass{i}", "inertia")
        g.tag(f"spring{i}", "stiffness")
        g.tag(f"damper{i}", "damping")
        x = x + g.displacement(f"spring{i}")
    g.output("x", x, "m", "displacement of the drive point")
    return g
