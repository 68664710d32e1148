"""Piezoelectric layers, stacks and amplified actuators, after Rodriguez-Fortun, J.M., Orus, J.,
Buil, F., Castellanos, J.A. "General bond graph model for piezoelectric actuators and methodology
for experimental identification." Mechatronics 20 (2010) 303-314 (cited below by equation).

Built only from the ``bondgraph`` public API.  Domains and variables (SI):

* electrical: voltage V (V), current i (A);
* polarization: field E (V/m), dipole rate ṗ (C·m/s), with the dipole p = Q·l (C·m);
* mechanical: force F (N), velocity ẋ (m/s).

One layer (Fig. 10), power flowing electrical → polarization → mechanical::

    elec ─▶ 1(i) ─▶ TF(l) ─▶ 1(ṗ) ─▶ C_NL          V = l·E,  ṗ = l·i,   E2 = C_NL(p)
             └▶ R_e            └──▶ TF(a·T/l) ─▶ 0(F1) ─▶ C(1/K)   E3 = (a·T/l)·F1,  ẋ_p = (a·T/l)·ṗ
                                                   └──▶ 1(ẋ) ─▶ mech    F1 = K·(x_p − x)
                                                          └▶ R_NL

so that V = (E2 + E3)·l, i.e. the paper's V = (E2 − E3)·l with its E3 = −(a/l)·K·(x − a·p/l)
(the paper writes the spring force as tension; here F1 is the compression the piezo strain
x_p = a·T·p/l puts into the layer spring).  The ``mech`` port delivers F = F1 − R_NL·ẋ with
ẋ the layer's extension rate.  T is the mechanical amplification of an APA (1 for a bare layer).
"""

from __future__ import annotations

import sympy as sp

from bondgraph import J0, J1, TF, C, CField, Component, Quantity, R


def model1_cfield(name: str, ports=("x", "Q"), *, K1, a1, C1) -> CField:
    """'Model 1' two-port C-field, U = ½·K1·(x − a1·Q)² + Q²/(2·C1)  (Rodriguez-Fortun et al. 2010, eqs. 4-5)."""
    px, pq = ports
    return CField(name, ports, energy=lambda q: K1 * (q[px] - a1 * q[pq]) ** 2 / 2 + q[pq] ** 2 / (2 * C1))


def model2_cfield(name: str, ports=("x", "Q"), *, K2, a2, C2) -> CField:
    """'Model 2' two-port C-field, U = ½·K2·x² + (Q − x/a2)²/(2·C2)  (Rodriguez-Fortun et al. 2010, eqs. 6-7)."""
    px, pq = ports
    return CField(name, ports, energy=lambda q: K2 * q[px] ** 2 / 2 + (q[pq] - q[px] / a2) ** 2 / (2 * C2))


def model2_from_model1(K1, a1, C1):
    """(K2, a2, C2) of the model-2 field storing the same energy as model 1 (equal stiffness matrices)."""
    C2 = 1 / (K1 * a1**2 + 1 / C1)
    a2 = 1 / (K1 * a1 * C2)
    K2 = K1 - 1 / (a2**2 * C2)
    return sp.simplify(K2) if isinstance(K2, sp.Basic) else K2, a2, C2


def linear_polarization(comp: Component, name: str, kx) -> C:
    """Linear polarization law E = kx·p (kx = 1/C_NL, V/(C·m²)); adds and returns the C element."""
    return comp.add(C(name, 1 / kx))


def bouc_wen_polarization(comp: Component, name: str, kx, kw, q, r, n) -> C:
    """Bouc–Wen polarization law (Rodriguez-Fortun et al. 2010, eq. 9): E = kx·p + kw·z with the internal state
    ż = q·(ṗ − r·|ṗ|·|z|^(n−1)·z + (r − 1)·ṗ·|z|^n).  Adds the C element and the state z."""
    z = comp.state(f"{name}.z", 0, unit="1", doc="Bouc–Wen hysteretic variable")
    cap = comp.add(C(name, law=lambda p: kx * p + kw * z))
    pdot = comp.flow(name)
    comp.set_rate(
        f"{name}.z", q * (pdot - r * sp.Abs(pdot) * sp.Abs(z) ** (n - 1) * z + (r - 1) * pdot * sp.Abs(z) ** n)
    )
    return cap


def operator_polarization(comp: Component, name: str, operator, kx=None) -> C:
    """Polarization law through a memory operator H (PI, modified PI, Maxwell slip):
    E = kx·p + H[p] (linear part plus hysteresis, option (a) of Rodriguez-Fortun et al. 2010) or, without
    ``kx``, E = H[p] (the operator replaces the capacitor, option (b))."""
    h = comp.operator(f"{name}.H", operator, Quantity("q", name))
    linear = 0 if kx is None else kx
    return comp.add(C(name, law=lambda q: linear * q + h))


def piezo_layer(name: str, *, l, a, K, polarization, T=1, R_NL=None, Re=None, doc: str = "") -> Component:
    """One three-domain piezo layer (see the module docstring) as a component with ports
    ``elec`` (power in) and ``mech`` (power out).

    ``polarization(comp, element_name)`` adds the polarization capacitor, e.g.
    ``lambda c, n: linear_polarization(c, n, kx)``.  ``R_NL`` is a viscous coefficient (N·s/m)
    or a callable ``R_NL(comp, junction)`` attaching a rate-dependent element (e.g. a
    Kelvin–Voigt chain); ``Re`` the layer's series resistance (Ω)."""
    c = Component(name, doc or "piezoelectric layer (electrical, polarization, mechanical domains)")
    c.add(TF("l", l), J1("pol"), TF("a", a * T / l), J0("F1"), C("K", 1 / K), J1("v"))
    polarization(c, "C_NL")
    if Re is not None:
        c.add(J1("i"), R("Re", Re))
        c.bond("i", "Re")
        c.bond("i", "l.p1")
        c.expose("elec", "i")
    else:
        c.expose("elec", "l.p1")
    c.bond("l.p2", "pol")
    c.bond("pol", "C_NL")
    c.bond("pol", "a.p1")
    c.bond("a.p2", "F1")
    c.bond("F1", "K")
    c.bond("F1", "v")
    if R_NL is not None:
        if callable(R_NL) and not isinstance(R_NL, sp.Basic):
            R_NL(c, "v")
        else:
            c.add(R("R_NL", R_NL))
            c.bond("v", "R_NL")
    c.expose("mech", "v")
    for name, role in (("C_NL", "polarization"), ("K", "stiffness"), ("R_NL", "damping")):
        if name in c.elements:
            c.tag(name, role)
    return c


def layer_extension(prefix: str, a, l, T=1) -> sp.Expr:
    """Algebraic extension x_p − q_K of a layer added under ``prefix`` (m): piezo strain
    a·T·p/l minus the compression of its spring; avoids an integrator state for x."""
    return a * T / l * Quantity("q", f"{prefix}.C_NL") - Quantity("q", f"{prefix}.K")
