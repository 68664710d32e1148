"""Bimorph cantilever as a bond graph: one mass-normalised modal resonator per bending mode.

Ghafarirad, H., Rezaei, S.M., Sarhan, A.A.D., Zareinejad, M. "Continuous dynamic modelling of
bimorph piezoelectric cantilevered actuators considering hysteresis effect and dynamic behaviour
analysis." Mathematical and Computer Modelling of Dynamical Systems 21(2) (2015) 130-152, eqs.
22-25 and 36; Shahabi, P., Ghafarirad, H., Taghvaeipour, A. "Nonlinear vibration analysis of
piezoelectric bending actuators: theoretical and experimental studies." Comptes Rendus Mecanique
347(12) (2019) 953-966, eqs. 31-34 (cited below as Ghafarirad et al. 2015 and Shahabi et al.
2019). For each mode i the
modal coordinate q_i (kg^1/2 m, mass-normalised: int rhoA phi_i^2 dx = 1) obeys

    q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i [+ k1_i q_i^3 + k2_i q_i^5]
        [+ mu1_i q_i^2 q_i'] = m_p,i u(t)

and the sensor reads w(l_t) = sum_i phi_i(l_t) q_i (m). The drive u is the voltage V (V) or the
output of a hysteresis operator applied to it, u = H[V] (Ghafarirad et al. 2015, eq. 25; H in volts).

Bond graph per mode: a 1-junction ``mode_i`` (common flow q_i') with

    Se ``force_i``   e = mp_i u               (modulated effort source, modal force)
    I  ``mass_i``    f = p / 1                (unit modal mass: the modes are mass-normalised)
    C  ``spring_i``  e = omega_i^2 q [+ k1_i q^3 + k2_i q^5]     (energy form, conservative)
    R  ``damper_i``  e = 2 zeta_i omega_i f [+ mu1_i q_i^2 f]    (q_i: displacement of spring_i)

The numbers that come out of the beam geometry (omega_i, zeta_i, mp_i, phi_i at the target) are
computed at build time from :mod:`library.beam` and registered as model parameters (printed by
name, settable with ``--set``, fittable); the geometry itself stays numeric.

Sign convention: :attr:`library.beam.Modes.input_gains`, m_p,i = M_p (phi_i'(l2) - phi_i'(l1)) with
M_p = b e31 (t_b + t_p) < 0 for PZT, so mp_1 < 0 and a positive V moves the tip towards negative w.
Shahabi et al. 2019 write m_p = -M_p phi'(l) (eq. 32), the opposite sign; only |m_p| enters its amplitude
equation (and the zeros of w/V do not depend on a global sign), so one convention serves both.

Units of the per-mode nonlinear coefficients (q in kg^1/2 m, modal force in kg^1/2 m s^-2):
k1 [kg^-1 m^-2 s^-2], k2 [kg^-2 m^-4 s^-2], mu1 [kg^-1 m^-2 s^-1].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
import sympy as sp

from bondgraph import J1, I, Model, ModelError, R, Se
from bondgraph import C as Cap

from .beam import Bimorph, Modes
from .beam import effective_mass as _static_effective_mass

#: units of the per-mode quantities (mass-normalised modal coordinate q in kg^1/2 m)
UNITS = {
    "omega": "rad/s",
    "zeta": "1",
    "mp": "N/(kg^1/2 V)",
    "phi": "kg^-1/2",
    "k1": "1/(kg m^2 s^2)",
    "k2": "1/(kg^2 m^4 s^2)",
    "mu1": "1/(kg m^2 s)",
}


@dataclass(frozen=True)
class ModeNonlinearity:
    """Nonlinear terms of one mode (Shahabi et al. 2019, eq. 34): stiffness k1 q^3 + k2 q^5 added to
    omega^2 q, damping mu1 q^2 q' added to 2 zeta omega q'. Units in :data:`UNITS`.
    A value may be a number (registered as a parameter ``k1_<i>`` etc.) or a sympy expression
    (used as given, e.g. a model-file parameter)."""

    k1: float | sp.Expr = 0.0
    k2: float | sp.Expr = 0.0
    mu1: float | sp.Expr = 0.0


@dataclass
class BimorphModes:
    """What :func:`add_bimorph_modes` added: the modal analysis and the symbols it used.

    ``omega``, ``zeta``, ``mp``, ``phi`` (phi_i at the target) and ``q`` (the modal
    displacements, as port quantities) are lists over the modes; ``drive`` is u (V or H[V]);
    ``x`` is the sensor expression sum phi_i q_i; ``values`` maps each registered parameter
    name to its number.
    """

    modes: Modes
    target: float
    drive: sp.Expr
    omega: list = field(default_factory=list)
    zeta: list = field(default_factory=list)
    mp: list = field(default_factory=list)
    phi: list = field(default_factory=list)
    q: list = field(default_factory=list)
    x: sp.Expr = sp.Integer(0)
    values: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(self.omega)


def add_bimorph_modes(
    m: Model,
    beam: Bimorph,
    n_modes: int = 2,
    target: float = 1.0,
    *,
    alpha: float = 0.0,
    beta: float = 0.0,
    zetas: Sequence[float] | None = None,
    omegas: Sequence[float] | None = None,
    drive=None,
    hysteresis=None,
    nonlinear: Mapping[int, ModeNonlinearity] | Sequence | None = None,
    output: str | None = "x",
    prefix: str = "",
    source: str = "",
) -> BimorphModes:
    """Add ``n_modes`` modal resonators of ``beam`` to ``m`` and (unless ``output`` is None) the
    sensor output ``x = w(target·L) = sum_i phi_i(target·L) q_i`` (m).

    target: sensor position as a fraction of L (0 < target <= 1).
    alpha, beta: proportional damping 2 zeta_i omega_i = alpha + beta omega_i^2 (1/s, s), used
        for every mode whose zeta is not given in ``zetas``.
    zetas, omegas: override the damping ratios / natural frequencies (e.g. measured values);
        entries may be None to keep the computed value, numbers (registered as ``zeta_<i>``,
        ``omega_<i>``) or sympy expressions (e.g. parameters the caller declared with its own
        docs), used as given. Mode shapes, gains and phi are always the
        beam's (for a uniform beam they do not depend on the stiffness).
    drive: the drive expression u (default: the model input ``V``, created if needed).
    hysteresis: a :class:`bondgraph.MemoryOperator` applied to the drive, u = H[drive]
        (Ghafarirad et al. 2015, eq. 25); its parameters become ``<prefix>H.<name>``.
    nonlinear: {mode number (1-based): ModeNonlinearity} or a sequence aligned with the modes
        (None entries for linear modes).
    prefix: prepended to every element and parameter name (to put two beams in one model).
    source: a citation appended to the parameter docs (e.g. "Ghafarirad et al. 2015, Table 1").
    """
    if not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ModelError(f"number of modes must be a positive integer, got {n_modes!r}")
    if not 0.0 < float(target) <= 1.0:
        raise ModelError(f"target must be a fraction of the length in (0, 1], got {target!r}")
    modes = beam.modes(int(n_modes))
    x_t = float(target) * beam.L
    cite = f" ({source})" if source else ""
    nl = _per_mode(nonlinear, n_modes)
    w_given = _per_mode(omegas, n_modes)
    z_given = _per_mode(zetas, n_modes)

    if drive is None:
        drive = m.input("V", "V", "drive voltage")
    if hysteresis is not None:
        drive = m.operator(f"{prefix}H", hysteresis, drive)
    out = BimorphModes(modes=modes, target=float(target), drive=drive)

    def param(name, value, unit, doc):
        if isinstance(value, sp.Basic):
            return value
        full = f"{prefix}{name}"
        out.values[full] = float(value)
        return m.parameter(full, float(value), unit, doc + cite)

    gains = modes.input_gains
    omega_beam = modes.omegas
    x_expr = sp.Integer(0)
    for i in range(int(n_modes)):
        k = i + 1
        w_val = omega_beam[i] if w_given[i] is None else w_given[i]
        if z_given[i] is None:
            if isinstance(w_val, sp.Basic):
                raise ModelError(f"mode {k}: give zetas[{i}] too when omega is an expression")
            z_val = (alpha + beta * float(w_val) ** 2) / (2 * float(w_val))
            z_doc = f"damping ratio of mode {k}, 2 zeta omega = alpha + beta omega^2"
        else:
            z_val = z_given[i]
            z_doc = f"damping ratio of mode {k}"
        w_doc = f"natural frequency of mode {k}" + (" (exact Euler-Bernoulli modes)" if w_given[i] is None else "")
        omega = param(f"omega_{k}", w_val, UNITS["omega"], w_doc)
        zeta = param(f"zeta_{k}", z_val, UNITS["zeta"], z_doc)
        mp = param(f"mp_{k}", gains[i], UNITS["mp"], f"modal input gain of mode {k}, M_p (phi_{k}'(l2) - phi_{k}'(l1))")
        phi = param(
            f"phi_{k}",
            float(modes.shape(i, x_t)),
            UNITS["phi"],
            f"mass-normalised mode shape {k} at the target x = {x_t * 1e3:.4g} mm",
        )

        j, se, ms, sp_, dm = (f"{prefix}{s}_{k}" for s in ("mode", "force", "mass", "spring", "damper"))
        m.add(J1(j), Se(se, mp * drive), I(ms, 1))
        nli = nl[i]
        if nli is None or nli == ModeNonlinearity():
            m.add(Cap(sp_, 1 / omega**2), R(dm, 2 * zeta * omega))
        else:
            k1 = param(f"k1_{k}", nli.k1, UNITS["k1"], f"cubic modal stiffness of mode {k}")
            k2 = param(f"k2_{k}", nli.k2, UNITS["k2"], f"quintic modal stiffness of mode {k}")
            mu1 = param(
                f"mu1_{k}", nli.mu1, UNITS["mu1"], f"nonlinear damping of mode {k}: (2 zeta omega + mu1 q^2) q'"
            )
            m.add(Cap(sp_, energy=lambda qq, w=omega, a=k1, b=k2: w**2 * qq**2 / 2 + a * qq**4 / 4 + b * qq**6 / 6))
            q = m.displacement(sp_)
            m.add(R(dm, law=lambda f, z=zeta, w=omega, c=mu1, qq=q: (2 * z * w + c * qq**2) * f))
        m.bond(se, j)
        for e in (ms, sp_, dm):
            m.bond(j, e)
        for e, role in ((ms, "inertia"), (sp_, "stiffness"), (dm, "damping")):
            m.tag(e, role)
        q = m.displacement(sp_)
        out.omega.append(omega)
        out.zeta.append(zeta)
        out.mp.append(mp)
        out.phi.append(phi)
        out.q.append(q)
        x_expr += phi * q
    out.x = x_expr
    if output:
        m.output(output, x_expr, "m", f"deflection at the target x = {x_t * 1e3:.4g} mm ({target:g} L)")
    return out


def _per_mode(spec, n: int) -> list:
    """A per-mode list of length n from None, a sequence, or a {mode number: value} mapping."""
    if spec is None:
        return [None] * n
    if isinstance(spec, Mapping):
        bad = [k for k in spec if not (isinstance(k, int) and 1 <= k <= n)]
        if bad:
            raise ModelError(f"per-mode settings name modes {bad}; modes are numbered 1..{n}")
        return [spec.get(k + 1) for k in range(n)]
    seq = list(spec)
    if len(seq) > n:
        raise ModelError(f"{len(seq)} per-mode values given for {n} modes")
    return seq + [None] * (n - len(seq))


# ---- hysteresis at the input (Ghafarirad et al. 2015, Sec. 2.3-2.4) ---------------------------------------------
def pi_operator(thresholds: Sequence[float], weights: Sequence[float]):
    """A Prandtl–Ishlinskii operator H[V] = sum_j w_j play_{r_j}[V] (Ghafarirad et al. 2015, eqs. 30-33) from
    :mod:`library.hysteresis` (imported only when asked for)."""
    try:
        from library.hysteresis import PrandtlIshlinskii
    except ImportError as exc:  # the hysteresis library is optional for the linear models
        raise ModelError(
            f"PI hysteresis needs library/hysteresis/ (PrandtlIshlinskii), which is not available: {exc}"
        ) from None
    return PrandtlIshlinskii(np.asarray(thresholds, float), np.asarray(weights, float))


# ---- effective mass -----------------------------------------------------------------------------
def effective_tip_mass(beam: Bimorph, mode: int | None = None, x: float | None = None) -> float:
    """Effective mass referred to the point x (default the tip), kg.

    mode None: from the static tip-load deflection shape (Wood, Steltz & Fearing 2005: 33/140 of the beam mass for a
    uniform beam), the mass of a lumped model that matches the static stiffness.
    mode i (1-based): modal mass 1/phi_i(x)^2 of the mass-normalised mode, the mass of a 1-DOF
    model that matches mode i's resonance and static contribution at x.
    """
    if mode is None:
        if x is not None and x != beam.L:
            raise ValueError("the static effective mass is referred to the tip; give mode= for another point")
        return _static_effective_mass(beam)
    return beam.modes(int(mode)).effective_mass(int(mode) - 1, x)


# ---- Shahabi et al. 2019: multiple-scales steady state ---------------------------------------------------------
def amplitude_equation_roots(
    omega_drive: float, omega_n: float, zeta: float, force: float, k1: float = 0.0, k2: float = 0.0, mu1: float = 0.0
) -> np.ndarray:
    """Steady-state amplitudes a > 0 of q'' + (mu + mu1 q^2) q' + omega_n^2 q + k1 q^3 + k2 q^5
    = force cos(omega_drive t), mu = 2 zeta omega_n, by first-order multiple scales (Shahabi et al. 2019
    eq. 54 with the modal force m_p V written out as ``force``):

        (mu omega_n a/2 + mu1 omega_n a^3/8)^2 + (sigma omega_n^2 a - 3/8 k1 a^3 - 10/32 k2 a^5)^2
            = force^2 / 4,          omega_drive = omega_n (1 + sigma).

    Returns all real positive roots, ascending (one or three near a softening peak).
    """
    sigma = omega_drive / omega_n - 1.0
    mu = 2 * zeta * omega_n
    wn = omega_n
    c1, c3 = mu * wn / 2, mu1 * wn / 8
    d1, d3, d5 = sigma * wn**2, -3 / 8 * k1, -10 / 32 * k2
    # in s = a^2: s [(c1 + c3 s)^2 + (d1 + d3 s + d5 s^2)^2] - force^2/4 = 0
    poly = np.polyadd(np.polymul([c3, c1], [c3, c1]), np.polymul([d5, d3, d1], [d5, d3, d1]))
    poly = np.polymul(poly, [1.0, 0.0])
    poly = np.polyadd(poly, [-(force**2) / 4])
    poly = np.trim_zeros(poly, "f")
    roots = np.roots(poly)
    s = roots[(np.abs(roots.imag) <= 1e-9 * np.abs(roots)) & (roots.real > 0)].real
    return np.sort(np.sqrt(s))


def amplitude_equation_phase(
    a: float,
    omega_drive: float,
    omega_n: float,
    zeta: float,
    force: float,
    k1: float = 0.0,
    k2: float = 0.0,
    mu1: float = 0.0,
) -> float:
    """Phase lag gamma (rad) of the multiple-scales steady state q ≈ a cos(omega t - gamma)
    for the forcing ``force cos(omega t)`` (Shahabi et al. 2019, eqs. 52-53)."""
    sigma = omega_drive / omega_n - 1.0
    mu = 2 * zeta * omega_n
    sin_g = (mu * omega_n * a / 2 + mu1 * omega_n * a**3 / 8) / (force / 2)
    cos_g = (-sigma * omega_n**2 * a + 3 / 8 * k1 * a**3 + 10 / 32 * k2 * a**5) / (force / 2)
    # Shahabi et al. 2019, eqs. 44-53: q0 = a cos(omega t - gamma) for the forcing force cos(omega t)
    return float(np.arctan2(sin_g, cos_g))


def amplitude_equation_peak(
    omega_n: float, zeta: float, force: float, k1: float = 0.0, k2: float = 0.0, mu1: float = 0.0
) -> tuple[float, float]:
    """(omega_peak, a_peak): the largest steady-state amplitude of the multiple-scales equation
    (see :func:`amplitude_equation_roots`) and the drive frequency where it occurs.

    The maximum over sigma has the stiffness bracket zero (the backbone), so a_peak solves the
    damping balance mu omega_n a/2 + mu1 omega_n a^3/8 = force/2 and
    omega_peak = omega_n + (3/8 k1 a^2 + 10/32 k2 a^4)/omega_n (below omega_n when softening).
    """
    if mu1 < 0:
        raise ValueError("mu1 must be >= 0 (nonlinear damping)")
    mu = 2 * zeta * omega_n
    roots = (
        np.roots([mu1 * omega_n / 8, 0.0, mu * omega_n / 2, -abs(force) / 2])
        if mu1 > 0
        else np.array([abs(force) / (mu * omega_n)])
    )
    a = float(np.max(roots[np.abs(roots.imag) <= 1e-9 * np.abs(roots)].real))
    sigma = (3 / 8 * k1 * a**2 + 10 / 32 * k2 * a**4) / omega_n**2
    return omega_n * (1 + sigma), a
