"""Truth physics of a (lumped) piezo stack, bare or amplified, written by hand.

Lumped stack (Rodriguez-Fortun et al., Mechatronics 20 (2010), eq. 14; amplification folded
into the parameters, T = 1), state: charge Q (C), output displacement x (m), velocity v (m/s)::

    Re dQ/dt = V - V_dev,           V_dev = S e + a F1,     e = Q - sum(c_j) - Q_x
    M dv/dt  = F1 - c v + F_m,      F1 = K (a Q - x),       dx/dt = v

``S = kx l^2`` is the elastance of the polarization capacitor (V/C), ``e`` the charge the
field sets on it.  The hidden effects enter as

* field-domain laws: an extra charge ``Q_x = law(e)`` (hysteresis: Preisach, Bouc–Wen,
  Duhem; saturation: tanh, polynomial, piecewise) — :class:`.terms.FieldCharge`;
* creep cells in the field domain: ``tau_j dc_j/dt = w_j e - c_j`` (a spectrum: log-time,
  fractional power law, or a few Kelvin–Voigt-like cells);
* a force ``F_m`` on the output mass: Maxwell-slip friction of the flexure hinges
  (hysteresis), an end stop (saturation);
* electrical: a larger series resistance, a series inductance (state: the current), an
  amplifier pole (the recorded V is the amplifier's command; state: the output voltage);
* a second mechanical mode: ``shell`` (the output mass split by a spring: amplification shell),
  ``frame`` (the stack sits on a compliant base), ``sensor`` (the sensor target on a compliant
  bracket, excited by the output acceleration; the sensor reads x plus its deflection).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .system import DRIVE, Equations, Lin, System
from .terms import FieldCharge, OutputForce

LINEAR = ("Re", "S", "a", "K", "c", "M")


@dataclass
class Effects:
    """What the hidden mechanisms add to the linear stack (all empty: the linear device)."""

    series_R: float = 0.0
    L: float = 0.0
    amp_tau: float = 0.0
    creep: list = field(default_factory=list)  # (tau_j, w_j)
    laws: list = field(default_factory=list)  # FieldLaw on the field e
    force: object | None = None  # callable x -> force on the output mass
    mode: tuple | None = None  # (kind, {numbers})


def system(p: dict, fx: Effects | None = None, probes: bool = False):
    """The stack as a :class:`System`; with ``probes``, also the state rows of the field ``e``
    and the displacement ``x`` (to scale the effects)."""
    fx = fx or Effects()
    eq = Equations()
    Q = eq.state("Q")
    terms = []
    cells = [eq.state(f"c{j}") for j in range(len(fx.creep))]
    Qx = Lin({"Qx": 1.0}) if fx.laws else Lin()
    e = Q - sum(cells, Lin()) - Qx
    for cell, (tau, w) in zip(cells, fx.creep):
        eq.ddt(cell, (w * e - cell) / tau)

    # mechanics: the stack end x1 (mass m1) and the sensed output
    kind, mode = fx.mode if fx.mode else (None, {})
    x1, v1 = eq.state("x"), eq.state("v")
    Fm = Lin({"Fm": 1.0}) if fx.force is not None else Lin()
    M = p["M"]
    if kind == "frame":
        xb, vb = eq.state("xb"), eq.state("vb")
        F1 = p["K"] * (p["a"] * Q - (x1 - xb))
        damp = p["c"] * (v1 - vb)
        eq.ddt(xb, vb)
        eq.ddt(vb, (-F1 + damp - mode["kb"] * xb - mode["cb"] * vb) / mode["mb"])
    else:
        F1 = p["K"] * (p["a"] * Q - x1)
        damp = p["c"] * v1
    eq.ddt(x1, v1)
    if kind == "shell":
        x2, v2 = eq.state("x2"), eq.state("v2")
        m1, m2 = mode["mu"] * M, (1 - mode["mu"]) * M
        link = mode["k2"] * (x1 - x2) + mode["c2"] * (v1 - v2)
        eq.ddt(v1, (F1 - damp - link) / m1)
        eq.ddt(x2, v2)
        eq.ddt(v2, (link + Fm) / m2)
        mass = x2
    else:
        accel = (F1 - damp + Fm) / M
        eq.ddt(v1, accel)
        mass = x1
    out = mass
    if kind == "sensor":
        s, sd = eq.state("s"), eq.state("sd")
        w = mode["omega"]
        eq.ddt(s, sd)
        eq.ddt(sd, -mode["gamma"] * accel - 2 * mode["zeta"] * w * sd - w * w * s)
        out = out + s

    # electrical side: source (amplifier), series R (and L), the stack
    source = Lin({DRIVE: 1.0})
    if fx.amp_tau > 0:
        va = eq.state("va")
        eq.ddt(va, (source - va) / fx.amp_tau)
        source = va
    R = p["Re"] + fx.series_R
    v_dev = p["S"] * e + p["a"] * F1
    if fx.L > 0:
        i = eq.state("i")
        eq.ddt(i, (source - R * i - v_dev) / fx.L)
        eq.ddt(Q, i)
    else:
        eq.ddt(Q, (source - v_dev) / R)

    if fx.laws:
        terms.append(FieldCharge(Q - sum(cells, Lin()), fx.laws))
    if fx.force is not None:
        terms.append(OutputForce(mass, fx.force))
    sys_ = System.build(eq, out, terms)
    if probes:
        return sys_, [eq.vector(Q - sum(cells, Lin())), eq.vector(out)]
    return sys_


def static_gain(p: dict) -> float:
    """Quasi-static x/V of the linear device (m/V): x = a Q, V = S Q."""
    return p["a"] / p["S"]
