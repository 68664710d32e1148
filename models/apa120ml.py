"""Cedrat APA-120ML amplified piezo actuator: the lumped stack model of seed 002 (eq. 14, Fig. 11)
with the amplification folded into the piezo-to-mechanical transformer (Section 5).

Numbers: seed 002 Table 1 (Re, l, a, K, c, M) and Table 2 (Bouc–Wen kx, kw, q, r, n).
Linear by default (hysteresis=none: E = kx·p with kx = 1/C_NL); ``hysteresis=bouc-wen`` uses
Table 2, ``hysteresis=pi`` the modified Prandtl–Ishlinskii operator read from Table 3
(illustrative: the extracted table is garbled, see library.hysteresis.apa120ml_modified_pi).
Table 1 gives K, M and a after amplification, so T = 1 reproduces the paper's numbers.
"""
from bondgraph import Experiment, I, J1, Model, Parameter, Se, Sine
from library.hysteresis import apa120ml_modified_pi
from library.identification import bouc_wen_seed
from library.piezo import (bouc_wen_polarization, layer_extension, linear_polarization,
                           operator_polarization, piezo_layer)

PARAMETERS = [
    Parameter("Re", 4.7, "ohm", "amplifier/lead resistance (Table 1)", bounds=(0.0, 1e6)),
    Parameter("l", 1.0e-4, "m", "layer thickness (Table 1)", bounds=(1e-7, 1e-1)),
    Parameter("a", 0.0474, "m/C", "electromechanical transformation factor (Table 1)"),
    Parameter("K", 10.77e6, "N/m", "actuator stiffness, 10.77 N/um (Table 1)", bounds=(0.0, 1e12)),
    Parameter("c", 3000.0, "N*s/m", "viscous rate-dependence term R_NL = c*dx/dt (Table 1)", bounds=(0.0, 1e8)),
    Parameter("M", 0.160, "kg", "moving mass (Table 1)", bounds=(1e-9, 1e3)),
    Parameter("T", 1.0, "", "mechanical amplification (Table 1 values already include it)"),
    Parameter("kx", 5e12, "V/(C*m^2)", "linear polarization stiffness 1/C_NL (Table 2)", bounds=(0.0, 1e20)),
    Parameter("hysteresis", "none", "", "polarization hysteresis model", choices=("none", "bouc-wen", "pi")),
    Parameter("kw", 1.98e5, "V/m", "Bouc-Wen hysteretic field weight (Table 2)"),
    Parameter("q_bw", 1.58e7, "1/(C*m)", "Bouc-Wen rate constant q (Table 2)"),
    Parameter("r_bw", 0.56, "", "Bouc-Wen shape parameter r (Table 2)"),
    Parameter("n_bw", 1.08, "", "Bouc-Wen exponent n (Table 2)"),
]

EXPERIMENT = Experiment(t_end=0.4, dt=1e-4, inputs={"V": Sine(amplitude=60.0, frequency=5.0, phase=-90.0, offset=60.0)})


#: linear parameters the diagnosis calibrates to data before looking for missing effects
CALIBRATE = ["a", "K", "c"]

def build(p):
    g = Model("APA-120ML", __doc__.splitlines()[0])
    V = g.input("V", "V", "drive voltage")
    F = g.input("F", "N", "external force on the output, positive along x")
    if p.hysteresis == "none":
        def pol(c, n): return linear_polarization(c, n, p.kx)
    elif p.hysteresis == "bouc-wen":
        def pol(c, n): return bouc_wen_polarization(c, n, p.kx, p.kw, p.q_bw, p.r_bw, p.n_bw)
    else:
        def pol(c, n): return operator_polarization(c, n, apa120ml_modified_pi())
    g.add(piezo_layer("stack", l=p.l, a=p.a, K=p.K, T=p.T, R_NL=p.c, polarization=pol))
    g.add(Se("amp", V), J1("i"), Se("load", F), I("M", p.M))
    from bondgraph import R
    g.add(R("Re", p.Re))
    g.chain("amp", "i", "stack.elec")
    g.bond("i", "Re")
    g.bond("stack.mech", "M")
    g.tag("M", "inertia")
    g.bond("load", "stack.mech")
    g.output("x", layer_extension("stack", p.a, p.l, p.T), "m", "output displacement")
    g.output("i", g.flow("Re"), "A", "drive current")
    g.output("p", g.displacement("stack.C_NL"), "C*m", "dipole (polarization domain)")
    g.output("E", g.effort("stack.C_NL"), "V/m", "field E2 on the polarization capacitor")
    return g


def seed(p, data):
    """Start values for `bondgraph fit`: with Bouc-Wen hysteresis, seed 002 §5.2 read off the
    quasi-static E-P curve of the data, P = x*l/(a*T) and E = V/l (Re drop and E3 neglected)."""
    if p.hysteresis != "bouc-wen":
        return {}
    l, a, T = p.value("l"), p.value("a"), p.value("T")
    s = bouc_wen_seed(data.column("x") * l / (a * T), data.column("V") / l, p.value("kx"))
    return {"kw": s["kw"], "q_bw": s["q"], "r_bw": s["r"], "n_bw": s["n"]}
