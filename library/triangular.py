"""Triangular-based piezoelectric drive after Hassani, V., Tjahjowidodo, T. "Structural response
investigation of a triangular-based piezoelectric drive mechanism to hysteresis effect of the
piezoelectric actuator." Mechanical Systems and Signal Processing 36 (2013) (cited by equation):
two piezo stacks, 90° apart, under a compliant triangular body whose head (the tip) moves in
the x-y plane.  Built only from the ``bondgraph`` public API and :mod:`library.piezo`.

Geometry.  Stack 1 stands at −θ from the vertical (left, pushing up and to the right), stack 2
at +θ (right, pushing up and to the left); θ = 45° puts them 90° apart as in the paper.  Their
axes are n1 = (sin θ, cos θ) and n2 = (−sin θ, cos θ).  Each stack head is rigidly attached to
the body at the contact point, so with the tip displacement (x, y) (x horizontal, y vertical)
the stack elongations are

    δ1 = sin θ·x + cos θ·y,    δ2 = −sin θ·x + cos θ·y,

i.e. x = (δ1 − δ2)/(2 sin θ), y = (δ1 + δ2)/(2 cos θ); at θ = 45°: x = (δ1 − δ2)/√2,
y = (δ1 + δ2)/√2.  Driving the stacks in phase gives δ1 = δ2, hence x ≡ 0 (straight vertical
line); a phase difference gives an ellipse.

Body.  The compliant triangle is lumped at its tip: per direction a mass, a spring and a
viscous damper (m_x, k_x, c_x and m_y, k_y, c_y; the paper's FE frequency response gives one
equivalent set m_e, k_e, ζ_e and notes that y is stiffer than x).  The paper's dynamic
stiffness K_e(ω) = k_e·(1 − (ω/ω_n)² + 2iζω/ω_n) is what a stack sees of such a body.

Stacks.  Each stack is the lumped stack of Rodriguez-Fortun et al. 2010 (:func:`library.piezo.piezo_layer` with a
linear polarization law) with N = length/h layers, expressed in the paper's data sheet
quantities (Section 2, eqs. 3-5): stiffness K_i = A/(l·s33^E), field E = V/h, free stroke
U = d33·E·l.  :func:`stack_constants` gives the layer constants (l, a, K, kx) for which a
voltage-driven (short-circuited) stack has exactly stiffness K_i and free stroke U per volt,
and a free (stress-free) capacitance C^T = N·ε33^T·A/h.  The stack's effective moving mass
(ρ·A·l/3, Rayleigh, fixed-free rod) is added to the body masses through the projection:
½·m_s·(δ̇1² + δ̇2²) = ½·m_s·(2 sin²θ·ẋ² + 2 cos²θ·ẏ²), exact for the symmetric pair.

Bond graph, formulation ``layers`` (power in the direction of the arrows)::

    Se(V1) ─▶ 1(i1) ─▶ stack1.elec          stack1.mech ─▶ 0(head1) ─▶ TF(1/sinθ) ─▶ 1(ẋ) ─▶ I m_x, C k_x, R c_x
                └▶ R(Re)                                    └─────▶ TF(1/cosθ) ─▶ 1(ẏ) ─▶ I m_y, C k_y, R c_y
    Se(V2) ─▶ 1(i2) ─▶ stack2.elec          stack2.mech ─▶ 0(head2) ─▶ TF(−1/sinθ) ─▶ 1(ẋ)
                └▶ R(Re)                                    └─────▶ TF(1/cosθ)  ─▶ 1(ẏ)

The 0-junction at a head sums the flows δ̇_i = ±sinθ·ẋ + cosθ·ẏ and passes the stack force
F_i on; the transformers (TF convention e1 = n·e2, f2 = n·f1) project it onto x and y:
F_x = sinθ·(F1 − F2), F_y = cosθ·(F1 + F2).

Dependent states.  In the ``layers`` formulation each stack stores its elongation as
δ_i = a·Q_i − (spring compression) while the body springs store x and y, and δ_i = ±sinθ·x +
cosθ·y: the stack springs, the polarization capacitors and the grounded body springs form a
closed loop of storage elements (the structure is statically indeterminate), so two
combinations of the 8 states are conserved and the linearisation has two zero eigenvalues.
SCAP cannot see this (every storage element is in integral causality) and the framework keeps
all 8 states.  Formulation ``field`` stores the same energy in one 4-port C-field
(:func:`drive_field`: model 1 per stack plus the body springs written in δ1, δ2), with the
amplifiers on its charge ports and the heads on its elongation ports::

    Se(V1) ─▶ 1(i1) ─▶ drive.Q1      1(δ̇1) ─▶ drive.d1,  1(δ̇1) ─▶ R c_stack1,  1(δ̇1) ─▶ body.head1
                └▶ R(Re)              (and likewise for stack 2; the body keeps masses and dampers)

6 states, no conserved combinations; both give the same trajectories.

Quasi-static mapping (from this graph, and the γl → 0 limit of the paper's eq. 17 with its
stiffness ratio r): with free strokes U_i = d33·(l/h)·V_i,

    x = (U1 − U2) / (2 sinθ·(1 + r_x)),   r_x = k_x / (2 sin²θ·K_i)
    y = (U1 + U2) / (2 cosθ·(1 + r_y)),   r_y = k_y / (2 cos²θ·K_i)

(see :func:`static_tip_displacement`).  The lumped stack neglects the wave propagation of the
paper's eq. 17 (γ = ω·√(ρ·s33^E)); it is accurate while γ·l ≲ 0.5.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from bondgraph import J0, J1, TF, C, CField, Component, I, Model, ModelError, R, Se

from .piezo import layer_extension, linear_polarization, piezo_layer


def stack_constants(*, d33, s33E, eps33T, area, length, h) -> dict:
    """Layer constants (l, a, K, kx) of :func:`library.piezo.piezo_layer` for a lumped stack of
    N = length/h layers of thickness h and cross-section ``area`` (Hassani & Tjahjowidodo 2013, eqs. 3-5 in the
    three-domain form of Rodriguez-Fortun et al. 2010).  Values may be numbers or sympy expressions.

    * kx = 1/(C^T·h²) with the free capacitance C^T = N·ε33^T·area/h, i.e. kx = 1/(ε33^T·area·length);
    * a = N·d33/C^T = d33·h/(ε33^T·area): free stroke per charge, so the free stroke per volt
      a/(kx·h²) = d33·length/h = d33·N (U = d33·E·l with E = V/h);
    * K = K_i/(1 − k33²), K_i = area/(length·s33^E), k33² = d33²/(s33^E·ε33^T): the layer spring
      of piezo_layer is the open-circuit (constant-charge) stiffness; at constant voltage the
      stack is softened by the coupling to exactly K_i, the paper's internal stiffness.
    """
    k33sq = d33**2 / (s33E * eps33T)
    K_i = area / (length * s33E)
    return {"l": h, "a": d33 * h / (eps33T * area), "K": K_i / (1 - k33sq), "kx": 1 / (eps33T * area * length)}


def free_stroke(V, *, d33, length, h):
    """Free stroke U = d33·E·l with E = V/h (m), Hassani & Tjahjowidodo 2013, eqs. 4-5."""
    return d33 * (V / h) * length


def piezo_stack(name: str, *, d33, s33E, eps33T, area, length, h, c_stack=None, doc: str = "") -> Component:
    """A lumped linear piezo stack (ports ``elec`` power in, ``mech`` power out) from data
    sheet quantities; see :func:`stack_constants`.  ``c_stack`` is the stack's internal
    viscous term R_NL (N·s/m) on its elongation rate."""
    k = stack_constants(d33=d33, s33E=s33E, eps33T=eps33T, area=area, length=length, h=h)
    return piezo_layer(
        name,
        l=k["l"],
        a=k["a"],
        K=k["K"],
        R_NL=c_stack,
        polarization=lambda c, n: linear_polarization(c, n, k["kx"]),
        doc=doc or "lumped piezo stack of length/h layers (Hassani & Tjahjowidodo 2013, eqs. 3-5)",
    )


def _sin_cos(half_angle):
    """(sin θ, cos θ) for θ in degrees; numbers are made exact so that 45° prints as √2/2."""
    th = sp.pi * (half_angle if isinstance(half_angle, sp.Basic) else sp.nsimplify(half_angle)) / 180
    return sp.sin(th), sp.cos(th)


def triangular_body(
    name: str = "body",
    *,
    k_x,
    k_y,
    m_x,
    m_y,
    c_x,
    c_y,
    half_angle=45,
    stack_mass=0,
    springs: bool = True,
    doc: str = "",
) -> Component:
    """The compliant triangular body lumped at its tip, with ports ``head1``, ``head2`` (power
    in from the stack heads; flow δ̇_i = elongation rate of stack i along its axis, effort the
    stack force F_i).

    k_*, m_*, c_*: tip stiffness (N/m), mass (kg) and damping (N·s/m) per direction.  The springs
    are written as energies ½·k·q² so k = 0 (a body without stiffness) is allowed; with
    ``springs=False`` they are left out (the ``field`` formulation stores them in the drive's
    C-field instead, see :func:`drive_field`).
    half_angle: angle θ of each stack from the vertical (degrees; 45 → stacks 90° apart).
    stack_mass: effective moving mass of each stack (kg) along its axis, added to m_x as
    2·sin²θ·m_s and to m_y as 2·cos²θ·m_s (exact for the symmetric pair)."""
    s, c = _sin_cos(half_angle)
    b = Component(name, doc or "compliant triangular body lumped at its tip (x, y)")
    b.add(
        J0("F1"),
        J0("F2"),
        J1("vx"),
        J1("vy"),
        TF("x1", 1 / s),
        TF("y1", 1 / c),
        TF("x2", -1 / s),
        TF("y2", 1 / c),
        I("m_x", m_x + 2 * s**2 * stack_mass),
        I("m_y", m_y + 2 * c**2 * stack_mass),
        R("c_x", c_x),
        R("c_y", c_y),
    )
    if springs:
        b.add(C("k_x", energy=lambda q: k_x * q**2 / 2), C("k_y", energy=lambda q: k_y * q**2 / 2))
    for head, tx, ty in (("F1", "x1", "y1"), ("F2", "x2", "y2")):
        b.bond(head, f"{tx}.p1")
        b.bond(f"{tx}.p2", "vx")
        b.bond(head, f"{ty}.p1")
        b.bond(f"{ty}.p2", "vy")
    for v, d in (("vx", "x"), ("vy", "y")):
        for e in (f"m_{d}", f"k_{d}", f"c_{d}") if springs else (f"m_{d}", f"c_{d}"):
            b.bond(v, e)
    # the head junctions carry the stack forces F1, F2 (common effort) and sum the flows
    # δ̇_i = ±sinθ·ẋ + cosθ·ẏ; (a port named like its element would make resolve() recurse)
    b.expose("head1", "F1")
    b.expose("head2", "F2")
    return b


def drive_field(name: str, *, K, a, C1, k_x, k_y, half_angle=45) -> CField:
    """The elastic and dielectric energy of both stacks and the body as one 4-port C-field
    (ports ``Q1``, ``d1``, ``Q2``, ``d2``): 'model 1' of Rodriguez-Fortun et al. 2010 per stack plus the body springs,

        U = Σ_i [½·K·(δ_i − a·Q_i)² + Q_i²/(2·C1)] + ½·k_x·x² + ½·k_y·y²,
        x = (δ1 − δ2)/(2 sinθ),  y = (δ1 + δ2)/(2 cosθ).

    Both ports of a stack take power in (power-in convention of a C-field): ``Q_i`` from the
    amplifier, ``d_i`` from the stack's head junction, so the port displacements are the charge
    Q_i and the elongation δ_i; the effort at ``d_i`` is ∂U/∂δ_i, the negative of the force
    that stack i and its share of the body springs exert on the head.
    Same dynamics as the ``layers`` formulation, but the stacks' series springs and the
    grounded body springs no longer form a loop of separate storage elements, so there is no
    conserved combination of states (6 states instead of 8, no zero eigenvalues)."""
    s, c = _sin_cos(half_angle)

    def energy(q):
        d1, d2 = q["d1"], q["d2"]
        x, y = (d1 - d2) / (2 * s), (d1 + d2) / (2 * c)
        stacks = sum(K * (d - a * q[Q]) ** 2 / 2 + q[Q] ** 2 / (2 * C1) for d, Q in ((d1, "Q1"), (d2, "Q2")))
        return stacks + k_x * x**2 / 2 + k_y * y**2 / 2

    return CField(name, ("Q1", "d1", "Q2", "d2"), energy=energy)


@dataclass
class TriangularDrive:
    """What :func:`add_triangular_drive` added: output expressions (tip x, y and stack
    elongations, m), the stack constants it used and the formulation."""

    x: sp.Expr
    y: sp.Expr
    delta1: sp.Expr
    delta2: sp.Expr
    stack: dict
    formulation: str


FORMULATIONS = ("layers", "field")


def add_triangular_drive(
    m: Model,
    *,
    V1,
    V2,
    d33,
    s33E,
    eps33T,
    area,
    length,
    h,
    Re,
    k_x,
    k_y,
    m_x,
    m_y,
    c_x,
    c_y,
    c_stack=None,
    stack_mass=0,
    half_angle=45,
    formulation: str = "layers",
    outputs: bool = True,
) -> TriangularDrive:
    """Add the two-stack triangular drive to ``m``: amplifiers ``amp1``/``amp2`` (efforts
    ``V1``, ``V2``, expressions of the model's inputs) with series resistances ``Re1``/``Re2``
    (Ω), the stacks and the body ``body`` (:func:`triangular_body`).

    formulation:
      ``layers``: stacks ``stack1``/``stack2`` are three-domain lumped stacks (Rodriguez-Fortun et al. 2010)
        (:func:`piezo_stack`, i.e. :func:`library.piezo.piezo_layer`), the body has its own
        springs.  8 states, of which two combinations are conserved (δ_i computed from the
        stack and from the tip position agree for all time): the linearisation has two
        eigenvalues at zero.
      ``field``: the same energy as one 4-port C-field ``drive`` (:func:`drive_field`) with
        dampers ``c_stack1``/``c_stack2`` on the stack elongation rates; 6 states.
    With ``outputs`` it declares ``x``, ``y`` (tip, m), ``delta1``, ``delta2`` (stack
    elongations, m), ``V1``, ``V2`` (stack drive voltages, V) and ``i1``, ``i2`` (drive
    currents, A)."""
    if formulation not in FORMULATIONS:
        raise ModelError(f"triangular drive: formulation must be one of {', '.join(FORMULATIONS)}, got {formulation!r}")
    st = {"d33": d33, "s33E": s33E, "eps33T": eps33T, "area": area, "length": length, "h": h}
    consts = stack_constants(**st)
    layers = formulation == "layers"
    m.add(
        triangular_body(
            "body",
            k_x=k_x,
            k_y=k_y,
            m_x=m_x,
            m_y=m_y,
            c_x=c_x,
            c_y=c_y,
            half_angle=half_angle,
            stack_mass=stack_mass,
            springs=layers,
        )
    )
    if not layers:
        m.add(
            drive_field(
                "drive",
                K=consts["K"],
                a=consts["a"],
                C1=1 / (consts["kx"] * consts["l"] ** 2),
                k_x=k_x,
                k_y=k_y,
                half_angle=half_angle,
            )
        )
    deltas = []
    for j, V in ((1, V1), (2, V2)):
        m.add(Se(f"amp{j}", V), J1(f"i{j}"), R(f"Re{j}", Re))
        m.bond(f"amp{j}", f"i{j}")
        m.bond(f"i{j}", f"Re{j}")
        if layers:
            m.add(piezo_stack(f"stack{j}", c_stack=c_stack, **st))
            m.bond(f"i{j}", f"stack{j}.elec")
            m.bond(f"stack{j}.mech", f"body.head{j}")
            deltas.append(layer_extension(f"stack{j}", consts["a"], consts["l"]))
        else:
            m.bond(f"i{j}", f"drive.Q{j}")
            m.add(J1(f"v{j}"))  # common flow δ̇_j: the field, the body head and the stack damper
            m.bond(f"v{j}", f"drive.d{j}")
            m.bond(f"v{j}", f"body.head{j}")
            if c_stack is not None:
                m.add(R(f"c_stack{j}", c_stack))
                m.bond(f"v{j}", f"c_stack{j}")
            deltas.append(m.displacement(f"drive.d{j}"))
    if layers:
        x, y = m.displacement("body.k_x"), m.displacement("body.k_y")
    else:
        s, c = _sin_cos(half_angle)
        x, y = (deltas[0] - deltas[1]) / (2 * s), (deltas[0] + deltas[1]) / (2 * c)
    if outputs:
        m.output("x", x, "m", "tip displacement, horizontal (positive away from stack 1)")
        m.output("y", y, "m", "tip displacement, vertical (positive up)")
        m.output("delta1", deltas[0], "m", "elongation of stack 1")
        m.output("delta2", deltas[1], "m", "elongation of stack 2")
        m.output("V1", V1, "V", "drive voltage of stack 1")
        m.output("V2", V2, "V", "drive voltage of stack 2")
        m.output("i1", m.flow("Re1"), "A", "drive current of stack 1")
        m.output("i2", m.flow("Re2"), "A", "drive current of stack 2")
    return TriangularDrive(x, y, deltas[0], deltas[1], consts, formulation)


def wave_factor(omega, *, rho, s33E, length):
    """gamma*l*cot(gamma*l) with the wave number gamma = omega*sqrt(rho*s33E) (Hassani &
    Tjahjowidodo 2013, eqs. 10 and 17): 1 in the quasi-static limit, 1 - (gamma l)^2/3 + ... (the
    stack's moving mass rho*A*l/3) at low frequency. Numbers (numpy) only."""
    gl = np.asarray(omega, float) * np.sqrt(rho * s33E) * length
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(gl == 0.0, 1.0, gl / np.tan(np.where(gl == 0.0, 1.0, gl)))


def dynamic_stiffness(omega, *, k_e, m_e, zeta):
    """K_e(omega) = k_e*(1 - (omega/omega_n)^2 + 2i*zeta*omega/omega_n), omega_n = sqrt(k_e/m_e):
    the structure's dynamic stiffness at the stack head (eq. 13), N/m, complex."""
    wn = np.sqrt(k_e / m_e)
    w = np.asarray(omega, float)
    return k_e * (1.0 - (w / wn) ** 2 + 2j * zeta * w / wn)


def stiffness_ratio(omega, *, K_i, k_e, m_e, zeta):
    """r(omega) = K_e(omega)/K_i, the stiffness ratio of eq. 16 (complex)."""
    return dynamic_stiffness(omega, k_e=k_e, m_e=m_e, zeta=zeta) / K_i


def contact_displacement(omega, U, *, K_i, k_e, m_e, zeta, rho, s33E, length):
    """Displacement phasor of the stack head against the structure, eq. 17 (m):
    u(l, omega) = U / (gamma*l*cot(gamma*l) + r(omega)), with U the free stroke: d33*E*l in the
    constitutive route, the measured (hysteretic) stroke in eqs. 18-19."""
    r = stiffness_ratio(omega, K_i=K_i, k_e=k_e, m_e=m_e, zeta=zeta)
    return U / (wave_factor(omega, rho=rho, s33E=s33E, length=length) + r)


def tip_displacement(U1, U2, *, omega, K_i, k_x, k_y, m_x, m_y, c_x, c_y, rho, s33E, length, half_angle=45.0):
    """Tip phasors (X, Y) (m) of the two-stack drive for free-stroke phasors U1, U2, eq. 17 applied
    to the symmetric pair: in the antisymmetric motion (delta1 = -delta2) each stack sees the
    body's x dynamic stiffness K_x(omega) = k_x - omega^2 m_x + i omega c_x as
    K_x/(2 sin^2 theta), in the symmetric one K_y/(2 cos^2 theta), so

        X = (U1 - U2) / (2 sin theta (gamma l cot gamma l + r_x)),  r_x = K_x(omega)/(2 sin^2 theta K_i)
        Y = (U1 + U2) / (2 cos theta (gamma l cot gamma l + r_y)),  r_y = K_y(omega)/(2 cos^2 theta K_i)

    (m_x, m_y: body masses without the stacks, whose inertia is in the wave term)."""
    th = np.radians(half_angle)
    s, c = np.sin(th), np.cos(th)
    g = wave_factor(omega, rho=rho, s33E=s33E, length=length)
    Kx = k_x - omega**2 * m_x + 1j * omega * c_x
    Ky = k_y - omega**2 * m_y + 1j * omega * c_y
    return ((U1 - U2) / (2 * s * (g + Kx / (2 * s * s * K_i))), (U1 + U2) / (2 * c * (g + Ky / (2 * c * c * K_i))))


def ellipse_axes(X, Y) -> np.ndarray:
    """Semi-axes (major, minor) of the closed path (Re(X e^{i w t}), Re(Y e^{i w t})) traced by
    tip phasors X, Y: the singular values of [[Re X, Im X], [Re Y, Im Y]]."""
    return np.linalg.svd(np.array([[np.real(X), np.imag(X)], [np.real(Y), np.imag(Y)]], float), compute_uv=False)


@dataclass(frozen=True)
class MeasuredStroke:
    """Free-stroke amplitude of a stack measured at several drive frequencies (Hassani &
    Tjahjowidodo 2013, Table 1 and Sec. 4.2: the stroke falls as the frequency rises, so eqs.
    18-19 feed the measured stroke into eq. 17 instead of d33*E*l).

    frequencies: ascending drive frequencies (Hz); amplitudes: stroke amplitudes (m) measured at
    drive amplitude ``voltage`` (V). Between the table points the amplitude is interpolated
    linearly in log(frequency) and log(amplitude); outside it is an error."""

    frequencies: tuple
    amplitudes: tuple
    voltage: float

    def __post_init__(self):
        f, a = np.asarray(self.frequencies, float), np.asarray(self.amplitudes, float)
        if f.ndim != 1 or f.size < 2 or f.size != a.size or np.any(np.diff(f) <= 0) or f[0] <= 0:
            raise ModelError("measured stroke: give at least two ascending positive frequencies, one amplitude each")
        if np.any(a <= 0) or not self.voltage > 0:
            raise ModelError("measured stroke: amplitudes and the drive voltage must be positive")

    def amplitude(self, frequency: float) -> float:
        """Stroke amplitude (m) at ``frequency`` (Hz) and the table's drive voltage."""
        f = float(frequency)
        lo, hi = self.frequencies[0], self.frequencies[-1]
        if not lo <= f <= hi:
            raise ModelError(
                f"measured stroke: drive frequency {f:g} Hz is outside the measured "
                f"{lo:g}-{hi:g} Hz; use the constitutive stroke there"
            )
        return float(np.exp(np.interp(np.log(f), np.log(self.frequencies), np.log(self.amplitudes))))

    def per_volt(self, frequency: float) -> float:
        """Stroke per volt of drive amplitude (m/V) at ``frequency`` (Hz)."""
        return self.amplitude(frequency) / self.voltage


def static_tip_displacement(U1, U2, *, K_i, k_x, k_y, half_angle=45):
    """Quasi-static tip (x, y) for free strokes U1, U2 (m) of stacks of stiffness K_i against
    a body of tip stiffness k_x, k_y (see the module docstring); sympy or numbers."""
    s, c = _sin_cos(half_angle)
    r_x = k_x / (2 * s**2 * K_i)
    r_y = k_y / (2 * c**2 * K_i)
    return (U1 - U2) / (2 * s * (1 + r_x)), (U1 + U2) / (2 * c * (1 + r_y))
