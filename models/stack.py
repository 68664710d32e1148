"""Piezoelectric stack actuator of N layers (Fig. 10 and eq. 13 of Rodriguez-Fortun, J.M., Orus, J.,
Buil, F., Castellanos, J.A. "General bond graph model for piezoelectric actuators and methodology
for experimental identification." Mechatronics 20 (2010) 303-314), or its lumped
equivalent (Fig. 11, eq. 14) with ``lumped=true``.

The stack-level parameters default to the APA-120ML values of Rodriguez-Fortun et al. 2010, Table 1 (K, a, l, Re)
and Table 2 (kx).  The APA's c = 3000 N·s/m damps its 160 g output; a bare stack of a few
grams gets c = 5 N·s/m (about 5 % of critical damping of its first mode, our choice).
Per layer (N layers in series mechanically, in parallel electrically):
K_w = N·K, kx_w = N·kx (C_NL = N·C·l², kx = 1/C_NL), c_w = N·c, mass M_layer, series
resistance Re_layer.  Lumped (eq. 14): K_NL = K_w/N, C_NL = N·C_w·l², M = (N+1)/2·M_layer.
M_layer = 1.95e-5 kg is a 5 × 5 mm² PZT layer (ρ = 7800 kg/m³) of thickness l, and
Re_layer = 1 Ω keeps the layer's electrical time constant near 1 µs: the paper gives neither,
so both are our choices (they do not affect the quasi-static response).
"""

from bondgraph import J0, J1, Experiment, I, Model, Parameter, R, Se, Step
from library.piezo import layer_extension, linear_polarization, piezo_layer

PARAMETERS = [
    Parameter("layers", 20, "", "number of layers N", bounds=(1, 10000)),
    Parameter("lumped", False, "", "lumped model of eq. 14 instead of the N-layer graph of Fig. 10"),
    Parameter("Re", 4.7, "ohm", "amplifier/lead resistance (Table 1)"),
    Parameter("Re_layer", 1.0, "ohm", "series resistance of each layer (R_e,j)"),
    Parameter("l", 1.0e-4, "m", "layer thickness (Table 1)"),
    Parameter("a", 0.0474, "m/C", "electromechanical transformation factor (Table 1)"),
    Parameter("K", 10.77e6, "N/m", "stack stiffness (Table 1)"),
    Parameter("kx", 5e12, "V/(C*m^2)", "lumped polarization stiffness 1/C_NL (Table 2)"),
    Parameter("c", 5.0, "N*s/m", "stack viscous term R_NL (bare stack, about 5 % of critical)"),
    Parameter("M_layer", 1.95e-5, "kg", "mass of one layer"),
]

EXPERIMENT = Experiment(t_end=0.02, dt=1e-5, inputs={"V": Step(100.0, t0=1e-3)})


#: linear parameters the diagnosis calibrates to data before looking for missing effects
CALIBRATE = ["a", "K", "c"]

#: plausible spread of a real device around these values (×/÷ factor; others: the setting
#: diagnosis.tolerance, 2 for material constants): damping is known to an order of magnitude
#: at best, the layer thickness (the capacitance goes with its square) to 30 %
TOLERANCE = {"c": 15.0, "l": 1.3}


def build(p):
    n = p.layers
    g = Model(f"stack of {n} layers" + (" (lumped)" if p.lumped else ""), __doc__.splitlines()[0])
    V = g.input("V", "V", "drive voltage")
    F = g.input("F", "N", "external force on the top, positive along x")
    g.add(Se("amp", V), J1("i"), R("Re", p.Re), Se("load", F))
    g.chain("amp", "i")
    g.bond("i", "Re")
    if p.lumped:
        g.add(
            piezo_layer(
                "stack", l=p.l, a=p.a, K=p.K, R_NL=p.c, polarization=lambda c, name: linear_polarization(c, name, p.kx)
            )
        )
        g.add(I("M", (n + 1) / 2 * p.M_layer))
        g.bond("i", "stack.elec")
        g.bond("stack.mech", "M")
        g.tag("M", "inertia")
        g.bond("load", "stack.mech")
        g.output("x", layer_extension("stack", p.a, p.l), "m", "top displacement")
        return g
    g.add(J0("V"))
    g.bond("i", "V")
    extension = 0
    for j in range(1, n + 1):
        g.add(
            piezo_layer(
                f"L{j}",
                l=p.l,
                a=p.a,
                K=n * p.K,
                R_NL=n * p.c,
                Re=p.Re_layer,
                polarization=lambda c, name: linear_polarization(c, name, n * p.kx),
            )
        )
        g.add(I(f"M{j}", p.M_layer), J1(f"v{j}"))
        g.bond("V", f"L{j}.elec")
        g.bond(f"v{j}", f"M{j}")
        if j == 1:
            g.bond("L1.mech", "v1")
        else:  # layer j pushes mass j up and mass j-1 down
            g.add(J0(f"F{j}"))
            g.bond(f"L{j}.mech", f"F{j}")
            g.bond(f"v{j - 1}", f"F{j}")
            g.bond(f"F{j}", f"v{j}")
        extension += layer_extension(f"L{j}", p.a, p.l)
    g.bond("load", f"v{n}")
    g.output("x", extension, "m", "top displacement")
    return g
