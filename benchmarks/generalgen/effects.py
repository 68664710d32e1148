"""The effects a model file lacks: what is drawn, where it sits, and how it enters the truth.

:func:`draw_effect` picks the cause, its site and its form from the cause stream alone (no
simulation), so the mix of causes of any seed range can be counted without running anything.
:func:`apply_effect` then gives the effect its parameters, scaled to what the linear truth
does in this record (the elongation, velocity and force each link reaches, the drive's
excursion, the output's size), from the attempt stream; a ``boost`` above 1 makes it stronger
(the visibility rule's redraws, see ``PROTOCOL.md``).

Forms (each a physical law with drawn parameters; several are deliberately not polynomials):

==================  ====================================================================
hardening           cubic (Duffing), cubic + quintic, asymmetric (quadratic + cubic),
                    exponential (``k s sinh(e/s)``, contact/rubber stiffening)
softening           cubic - quintic (stabilised), tanh and arctan saturation, asymmetric
                    tanh (a saturating spring preloaded off its centre)
hysteresis          Bouc-Wen and Preisach (relay grid with a Gaussian density) on a
                    spring; Prandtl-Ishlinskii on a spring or on the drive
friction            Coulomb, Stribeck (exponential or Gaussian fall from static to Coulomb
                    level), in parallel with the site's viscous damper
nonlinear-damping   quadratic (drag), cubic, fractional power law, shear thinning
clearance           dead zone (a share of the spring engaged throughout), backlash with
                    impacts (contact damping, never pulling)
higher-mode         a mass split by a compliant part (one or two internal springs, the
                    attachments shared out among the pieces), modes above the model's
                    (modal truncation), an inductor's parasitic section
drift               linear, exponential (thermal), slow random walk
==================  ====================================================================
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.interpolate

from .network import Link, Network
from .systems import System

CAUSES = ("hardening", "softening", "hysteresis", "friction", "nonlinear-damping", "clearance", "higher-mode", "drift")
#: the vocabulary of the truth labels (and of the scoring)
VOCABULARY = CAUSES + ("none",)
#: share of effect-free records
P_NONE = 0.2

FORMS = {
    "hardening": ("cubic", "cubic-quintic", "asymmetric", "exponential"),
    "softening": ("cubic-quintic", "tanh", "arctan", "asymmetric-tanh"),
    "hysteresis": ("bouc-wen", "prandtl-ishlinskii", "preisach"),
    "friction": ("coulomb", "stribeck"),
    "nonlinear-damping": ("quadratic", "cubic", "power", "thinning"),
    "clearance": ("dead-zone", "impact"),
    "drift": ("linear", "thermal", "random-walk"),
}


@dataclass(frozen=True)
class EffectDraw:
    """What was drawn: ``cause`` (the vocabulary), ``site`` (a model-file element, ``drive``,
    or the output's name), ``form`` (the law), ``count`` (missing modes, for ``higher-mode``)."""

    cause: str
    site: str
    form: str
    count: int = 0


def draw_effect(rng: np.random.Generator, system: System) -> EffectDraw:
    """Draw the cause, site and form for one record of ``system``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The record's cause stream.
    system : System

    Returns
    -------
    EffectDraw
        ``cause`` is ``none`` with probability :data:`P_NONE`, otherwise uniform over the
        causes that make sense for the system.
    """
    if rng.random() < P_NONE:
        return EffectDraw("none", "", "")
    cause = system.causes[rng.integers(len(system.causes))]
    if cause == "higher-mode":
        count = 2 if rng.random() < 0.3 else 1
        if system.name == "rlc":
            return EffectDraw(cause, "inductor", "parasitic-section", count)
        if system.name == "modes3":
            return EffectDraw(cause, "mass3", "modal", count)
        form = "modal" if system.name == "msd" and rng.random() < 0.5 else "split-mass"
        return EffectDraw(cause, system.masses[rng.integers(len(system.masses))], form, count)
    if cause == "drift":
        return EffectDraw(cause, system.output, FORMS[cause][rng.integers(3)])
    form = FORMS[cause][rng.integers(len(FORMS[cause]))]
    if cause in ("friction", "nonlinear-damping"):
        site = system.dampers[rng.integers(len(system.dampers))]
    elif cause == "hysteresis" and system.hysteretic_drive and rng.random() < 0.25:
        return EffectDraw(cause, "drive", "prandtl-ishlinskii")
    else:
        site = system.springs[rng.integers(len(system.springs))]
    return EffectDraw(cause, site, form)


@dataclass
class Scales:
    """What the linear truth does in this record: per link the 99th percentile of the
    elongation's and the relative velocity's magnitude, the drive's, and the output's RMS."""

    elongation: np.ndarray
    velocity: np.ndarray
    drive: float
    output_rms: float
    duration: float


@dataclass
class Applied:
    """The truth with the effect: its ``network``, a ``drift`` added at the sensor (or None),
    the effect's parameters for the truth file, and the networks a recalibration is tried
    with for missing modes (``reduced``: the model file's structure; ``partial``: one
    missing mode put back, for two)."""

    network: Network
    drift: np.ndarray | None = None
    parameters: dict = field(default_factory=dict)
    reduced: list = field(default_factory=list)
    partial: list = field(default_factory=list)


def _u(rng, lo, hi):
    return float(rng.uniform(lo, hi))


def _spring_effect(link: Link, form: str, cause: str, s: float, rng, b: float) -> dict:
    """Give ``link`` a nonlinear elastic law scaled to its elongation ``s``."""
    if cause == "hardening":
        if form == "cubic":
            a3 = min(_u(rng, 0.1, 0.5) * b, 6.0)
            link.spring_law, link.spring_par = "poly", (s, 0.0, a3, 0.0)
        elif form == "cubic-quintic":
            a3, a5 = min(_u(rng, 0.05, 0.3) * b, 4.0), min(_u(rng, 0.05, 0.3) * b, 4.0)
            link.spring_law, link.spring_par = "poly", (s, 0.0, a3, a5)
        elif form == "asymmetric":
            a3 = min(_u(rng, 0.15, 0.5) * b, 6.0)
            a2 = rng.choice([-1.0, 1.0]) * _u(rng, 0.3, 0.85) * np.sqrt(3 * a3)  # stiffness stays positive
            link.spring_law, link.spring_par = "poly", (s, float(a2), a3, 0.0)
        else:
            x0 = min(_u(rng, 0.6, 1.4) * np.sqrt(b), 3.0)
            link.spring_law, link.spring_par = "sinh", (s / x0,)
        return {"law": link.spring_law, "par": list(link.spring_par), "scale_m": s}
    if form == "cubic-quintic":  # softening held up by a quintic: tangent >= 10 % of k everywhere
        a3 = min(_u(rng, 0.1, 0.35) * b, 1.5)
        a5 = a3 * a3 * _u(rng, 0.5, 1.0)
        link.spring_law, link.spring_par = "poly", (s, 0.0, -a3, a5)
    else:
        rho = min(_u(rng, 0.3, 0.7) * b**0.3, 0.9)
        st = s * _u(rng, 0.4, 1.2) / b
        eb = rng.choice([-1.0, 1.0]) * _u(rng, 0.2, 0.6) * st if form == "asymmetric-tanh" else 0.0
        link.spring_law, link.spring_par = "saturating", (st, rho, float(eb), 1.0 if form == "arctan" else 0.0)
    return {"law": link.spring_law, "par": list(link.spring_par), "scale_m": s}


def _plays(rng, scale, b):
    """Prandtl-Ishlinskii plays: thresholds spread over the excursion ``scale``, weights
    falling with the threshold, and the weight left on the elastic (play-free) part."""
    J = int(rng.integers(3, 9))
    r = scale * np.sort(rng.uniform(0.05, 0.9, J)) / b
    w = np.exp(-rng.uniform(0.5, 2.5) * r / scale)
    w0 = _u(rng, 0.3, 0.6) / b**0.3
    w *= (1.0 - w0) / w.sum()
    return w0, tuple(zip(r.tolist(), w.tolist()))


def _hysteresis(link: Link, form: str, s: float, rng, b: float) -> dict:
    if form == "bouc-wen":
        alpha = _u(rng, 0.2, 0.6)
        n = float(rng.choice([1.0, 2.0]))
        zsat = max(s * _u(rng, 0.15, 0.5) / b, 0.05 * s)
        frac = _u(rng, 0.55, 0.95)
        total = 1.0 / zsat**n
        link.spring_law, link.spring_par = "bouc-wen", (alpha, frac * total, (1 - frac) * total, n)
        return {
            "law": "bouc-wen",
            "alpha": alpha,
            "beta": frac * total,
            "gamma": (1 - frac) * total,
            "n": n,
            "z_sat_m": zsat,
        }
    if form == "prandtl-ishlinskii":
        w0, plays = _plays(rng, s, b)
        link.spring_law, link.spring_par, link.plays = "prandtl-ishlinskii", (w0,), plays
        return {"law": "prandtl-ishlinskii", "w0": w0, "plays": [list(p) for p in plays]}
    # Preisach: relays on a grid over +-a_max, a Gaussian density about a centre line and a
    # mean half-width (a coercive-like spread), normalised to sum 1
    levels = 12
    a_max = s * _u(rng, 0.5, 1.0)
    grid = np.linspace(-a_max, a_max, levels)
    half_mean = a_max * _u(rng, 0.1, 0.4)
    half_sd = half_mean * _u(rng, 0.3, 0.8)
    centre_sd = a_max * _u(rng, 0.2, 0.6)
    relays = []
    for i, al in enumerate(grid):
        for be in grid[: i + 1]:
            if al == be:
                continue
            half, centre = 0.5 * (al - be), 0.5 * (al + be)
            mu = np.exp(-0.5 * ((half - half_mean) / half_sd) ** 2 - 0.5 * (centre / centre_sd) ** 2)
            relays.append((float(al), float(be), float(mu)))
    total = sum(r[2] for r in relays)
    relays = tuple((al, be, mu / total) for al, be, mu in relays)
    w_lin = _u(rng, 0.6, 0.9)
    a_r = min(s * _u(rng, 0.1, 0.3) * b, 1.5 * s)
    link.spring_law, link.spring_par, link.relays = "preisach", (w_lin, a_r), relays
    return {"law": "preisach", "w_lin": w_lin, "relay_force_m": a_r, "relays": len(relays), "a_max_m": a_max}


def _damper_effect(net: Network, li: int, form: str, cause: str, sc: Scales, rng, b: float, h: float) -> dict:
    link = net.links[li]
    v = float(sc.velocity[li])
    if cause == "nonlinear-damping":
        if form == "thinning":
            rho = min(_u(rng, 0.4, 0.8) * b**0.3, 0.95)
            v0 = v * _u(rng, 0.1, 0.5) / b
            link.damper_law, link.damper_par = "thinning", (rho, v0)
            return {"law": "thinning", "rho": rho, "v0_m_s": v0}
        p = {"quadratic": 2.0, "cubic": 3.0}.get(form) or _u(rng, 1.4, 2.8)
        ratio = _u(rng, 0.5, 3.0) * b  # the added force at the link's speed, per viscous force there
        cp = ratio * link.c * v / v**p
        link.damper_law, link.damper_par = "power", (cp, p)
        return {"law": "power", "c_p": cp, "p": p, "ratio_at_v99": ratio}
    # dry friction scaled to the smaller of the spring force the link carries and the drive
    # (at resonance the spring force is Q times the drive: a level scaled to it would stick)
    f_ref = min(link.k * float(sc.elongation[li]), sc.drive)
    fc = min(_u(rng, 0.03, 0.12) * b, 0.5) * f_ref
    fs = fc * (_u(rng, 1.3, 2.0) if form == "stribeck" else 1.0)
    vs = v * _u(rng, 0.02, 0.2)
    delta = float(rng.choice([1.0, 2.0]))
    m_eff = net.masses[link.a] if link.b < 0 else 1.0 / (1.0 / net.masses[link.a] + 1.0 / net.masses[link.b])
    v_eps = max(1e-3 * v, 2.0 * h * fs / m_eff)  # stable under RK4 at step h
    link.damper_law, link.damper_par = "friction", (fc, fs, vs, delta, v_eps)
    return {"law": "friction", "Fc_N": fc, "Fs_N": fs, "vs_m_s": vs, "delta": delta, "v_eps_m_s": v_eps}


def _clearance(net: Network, li: int, form: str, sc: Scales, rng, b: float) -> dict:
    link = net.links[li]
    s = float(sc.elongation[li])
    gap = min(s * _u(rng, 0.05, 0.2) * b, 0.7 * s)
    if form == "dead-zone":
        rho, zc = _u(rng, 0.1, 0.4), 0.0
    else:
        rho, zc = _u(rng, 0.0, 0.15), _u(rng, 0.05, 0.3)
    m_eff = net.masses[link.a] if link.b < 0 else 1.0 / (1.0 / net.masses[link.a] + 1.0 / net.masses[link.b])
    cc = 2 * zc * np.sqrt(link.k * m_eff)
    link.spring_law, link.spring_par = "clearance", (gap, rho, cc)
    return {"law": "clearance", "gap_m": gap, "rho": rho, "contact_damping": cc}


def _attachments(net: Network, node: int) -> list:
    """What is attached to ``node``, in a fixed order: the drive, the sensor, link ends."""
    out = [("drive", None)] if net.drive[node] else []
    out += [("sensor", None)] if net.out_positions[node] else []
    for i, lk in enumerate(net.links):
        out += [("a", i)] if lk.a == node else []
        out += [("b", i)] if lk.b == node else []
    return out


def _split(net: Network, node: int, weights, omegas, zeta, pieces) -> tuple[Network, dict]:
    """``node`` split into pieces of mass shares ``weights`` joined in a row by springs
    tuned to ``omegas``; attachment ``j`` of :func:`_attachments` goes to piece ``pieces[j]``."""
    out = net.copy()
    more = len(weights) - 1
    idx = [node] + list(range(net.masses.size, net.masses.size + more))
    out.masses = np.concatenate([net.masses, np.zeros(more)])
    out.drive = np.concatenate([net.drive, np.zeros(more)])
    out.out_positions = np.concatenate([net.out_positions, np.zeros(more)])
    for i, w in zip(idx, weights):
        out.masses[i] = net.masses[node] * w
    where = {}
    for (what, li), piece in zip(_attachments(net, node), pieces):
        j = idx[piece]
        if what == "drive":
            out.drive[node], out.drive[j] = 0.0, net.drive[node]
        elif what == "sensor":
            out.out_positions[node], out.out_positions[j] = 0.0, net.out_positions[node]
        elif what == "a":
            out.links[li].a = j
        else:
            out.links[li].b = j
        name = what if li is None else (net.links[li].spring or "link") + ("" if what == "a" else " (far end)")
        where[name] = int(piece) + 1
    for j, om in enumerate(omegas):
        ma, mb = out.masses[idx[j]], out.masses[idx[j + 1]]
        m_eff = ma * mb / (ma + mb)
        k = om * om * m_eff
        out.links.append(Link(idx[j + 1], idx[j], k, 2 * zeta * np.sqrt(k * m_eff)))
    out.nodes = tuple(out.nodes) + tuple(f"{net.nodes[node]}.piece{j + 1}" for j in range(1, len(weights)))
    return out, where


def _modal(net: Network, extra) -> Network:
    """``net`` with modes (mass, omega, zeta) added at the drive point, each to the ground."""
    out = net.copy()
    for m, om, z in extra:
        i = out.masses.size
        out.masses = np.append(out.masses, m)
        out.drive = np.append(out.drive, 1.0)
        out.out_positions = np.append(out.out_positions, 1.0)
        out.links.append(Link(i, -1, m * om * om, 2 * z * m * om))
        out.nodes = tuple(out.nodes) + (f"mode{i + 1}",)
    return out


def _missing_modes(net: Network, eff: EffectDraw, fs: float, rng, b: float) -> Applied:
    """The truth with ``eff.count`` modes the model file lacks, and the structures a
    recalibration is tried with (the model file's; with one of two missing modes back)."""
    w_top = net.modes()[0][-1]
    w_cap = 2 * np.pi * fs / 12
    r1 = 1.0 + _u(rng, 0.4, 3.0) / b
    om = [min(w_top * r1, w_cap / 1.3 ** (eff.count - 1))]
    if eff.count == 2:
        om.append(min(om[0] * _u(rng, 1.3, 2.5), w_cap))
    zeta = _u(rng, 0.005, 0.04)
    par = {"target_hz": [o / (2 * np.pi) for o in om], "zeta": zeta}
    if eff.form == "modal":
        top = int(np.argmax([lk.k / net.masses[lk.a] for lk in net.links]))
        m_top = net.masses[net.links[top].a]
        # effective masses at the drive point from a fifth of the top mode's to two and a half times
        extra = [(m_top * float(np.exp(rng.uniform(np.log(0.2), np.log(2.5)))) / b, o, zeta) for o in om]
        truth = _modal(net, extra)
        par["modal_masses_kg"] = [e[0] for e in extra]
        partial = [_modal(net, [e]) for e in extra] if eff.count == 2 else []
        return Applied(truth, parameters=par, reduced=[net], partial=partial)
    node = net.nodes.index(eff.site)
    weights = np.maximum(rng.dirichlet(np.full(eff.count + 1, 3.0)), 0.12)
    weights /= weights.sum()
    pieces = rng.integers(eff.count + 1, size=len(_attachments(net, node)))
    truth, where = _split(net, node, weights, om, zeta, pieces)
    par.update(weights=weights.tolist(), pieces_of=where)
    partial = []
    if eff.count == 2:  # one mode more than the model: two of the three pieces merged
        for keep, merge in ((0, [0, 1, 1]), (1, [0, 0, 1])):
            w2 = np.bincount(merge, weights=weights)
            partial.append(_split(net, node, w2, [om[keep]], zeta, [merge[p] for p in pieces])[0])
    return Applied(truth, parameters=par, reduced=[net], partial=partial)


def drift_signal(form: str, t: np.ndarray, amplitude: float, rng) -> tuple[np.ndarray, dict]:
    """A sensor drift of ``form`` over times ``t``, starting at 0, of size ``amplitude``."""
    T = t[-1]
    sign = float(rng.choice([-1.0, 1.0]))
    if form == "linear":
        d = sign * amplitude * t / T
        par = {}
    elif form == "thermal":
        tau = T * _u(rng, 0.1, 1.0)
        d = sign * amplitude * -np.expm1(-t / tau) / -np.expm1(-T / tau)
        par = {"tau_s": tau}
    else:  # a slow random walk: Brownian knots, smoothly interpolated
        knots = int(rng.integers(8, 40))
        tk = np.linspace(0, T, knots + 1)
        wk = np.concatenate([[0.0], np.cumsum(rng.standard_normal(knots))])
        d = scipy.interpolate.CubicSpline(tk, wk)(t)
        d = amplitude * (d - d[0]) / max(np.ptp(d), 1e-300)
        par = {"knots": knots}
    par.update(form=form, size=amplitude)
    return d, par


def apply_effect(
    net: Network,
    eff: EffectDraw,
    sc: Scales,
    t: np.ndarray,
    fs: float,
    h: float,
    rng: np.random.Generator,
    boost: float,
) -> Applied:
    """The truth network (and drift) of effect ``eff`` on the linear truth ``net``.

    Parameters
    ----------
    net : Network
        The linear truth (not changed).
    eff : EffectDraw
        What to apply.
    sc : Scales
        The linear truth's excursions in this record.
    t : ndarray
        The sample times (s), for a drift.
    fs : float
        Sample rate (Hz): missing modes stay below ``fs / 12``.
    h : float
        The integration step (s): a friction's regularisation stays stable at it.
    rng : numpy.random.Generator
        The attempt's stream.
    boost : float
        Strength multiplier (1 on the first attempt).

    Returns
    -------
    Applied
    """
    if eff.cause == "none":
        return Applied(net)
    if eff.cause == "higher-mode":
        return _missing_modes(net, eff, fs, rng, boost)
    if eff.cause == "drift":
        size = sc.output_rms * float(np.exp(rng.uniform(np.log(0.01), np.log(0.3)))) * boost
        d, par = drift_signal(eff.form, t, size, rng)
        return Applied(net, drift=d, parameters=par)
    out = net.copy()
    if eff.site == "drive":
        w0, plays = _plays(rng, sc.drive, boost)
        out.drive_w0, out.drive_plays = w0, plays
        return Applied(out, parameters={"law": "prandtl-ishlinskii", "w0": w0, "plays": [list(p) for p in plays]})
    li = out.link_named(eff.site)
    s = float(sc.elongation[li])
    if eff.cause in ("hardening", "softening"):
        par = _spring_effect(out.links[li], eff.form, eff.cause, s, rng, boost)
    elif eff.cause == "hysteresis":
        par = _hysteresis(out.links[li], eff.form, s, rng, boost)
    elif eff.cause == "clearance":
        par = _clearance(out, li, eff.form, sc, rng, boost)
    else:
        par = _damper_effect(out, li, eff.form, eff.cause, sc, rng, boost, h)
    return Applied(out, parameters=par)
