"""The truth physics: lumped networks of masses and links, integrated by our own fixed-step RK4.

A :class:`Network` is a set of nodes (masses, or inductances in the electrical analogue) and
links between two nodes or a node and the ground.  A link is a spring and a damper in
parallel; each may follow a nonlinear or hysteretic law (:data:`SPRING_LAWS`,
:data:`DAMPER_LAWS`).  A force drive acts on the nodes through a distribution vector, and may
pass through a Prandtl-Ishlinskii operator first (a hysteretic drive); the sensor reads a
weighted sum of node positions or the spring force of one link (a capacitor's voltage).

The same description covers the mechanical chains, the modal structure (one node per mode,
each linked to the ground) and the series RLC circuit (charge for position, inductance for
mass, elastance 1/C for stiffness, resistance for damping, source voltage for force).

Two independent numerical routes, neither of them bondgraph's:

* :func:`integrate` - the truth: classical fourth-order Runge-Kutta at a fixed step on a grid
  finer than the sample rate, compiled with numba, rate-independent operators (play and relay
  hysterons) committed after each step;
* :func:`linear_response` - the linear part only, exactly in the frequency domain (modal
  residues of the state matrix times the drive's spectrum), used by the visibility rule's fits.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy.fft
from numba import njit

#: spring laws and their parameter rows (``e`` elongation in m, ``k`` the link stiffness)
SPRING_LAWS = {
    "linear": 0,  # k e
    "poly": 1,  # (s, a2, a3, a5): k (e + a2 e^2/s + a3 e^3/s^2 + a5 e^5/s^4)
    "sinh": 2,  # (s,): k s sinh(e/s)
    "saturating": 3,  # (s, rho, e_b, shape): k ((1-rho) e + rho s (g((e+e_b)/s) - g(e_b/s))), g tanh or arctan
    "bouc-wen": 4,  # (alpha, beta, gamma, n): k (alpha e + (1-alpha) z)
    "prandtl-ishlinskii": 5,  # (w0,) + plays: k (w0 e + sum w_j (e - play_rj(e))), stops: yield
    "preisach": 6,  # (w_lin, a_r) + relays: k (w_lin e + (1-w_lin) (e - a_r sum mu_i relay_i(e)))
    "clearance": 7,  # (g, rho, c_contact): k rho e + contact force beyond the gap g, never pulling
}

#: damper laws and their parameter rows (``v`` the link's relative velocity, ``c`` its damping)
DAMPER_LAWS = {
    "linear": 0,  # c v
    "power": 1,  # (c_p, p): c v + c_p sign(v) |v|^p
    "thinning": 2,  # (rho, v0): c ((1-rho) v + rho v / (1 + |v|/v0))
    "friction": 3,  # (Fc, Fs, vs, delta, v_eps): c v + (Fc + (Fs-Fc) exp(-|v/vs|^delta)) tanh(v/v_eps)
}

_NPAR = 6


@dataclass
class Link:
    """A spring and a damper in parallel between node ``a`` and node ``b`` (-1: the ground).

    The elongation is ``x[a] - x[b]``; the link pulls ``a`` back with its force and pushes
    ``b`` on.  ``spring`` and ``damper`` are the model file's element names ("" for a part
    the model file does not have)."""

    a: int
    b: int
    k: float
    c: float
    spring: str = ""
    damper: str = ""
    spring_law: str = "linear"
    spring_par: tuple = ()
    damper_law: str = "linear"
    damper_par: tuple = ()
    plays: tuple = ()  # ((r, w), ...) for the Prandtl-Ishlinskii law
    relays: tuple = ()  # ((alpha, beta, mu), ...) for the Preisach law


@dataclass
class Network:
    """Nodes, links, drive and sensor of a lumped system (SI units).

    ``masses[i]`` is node i's mass; ``drive[i]`` the share of the drive force on node i;
    ``out_positions`` the sensor's weights on the node positions, or ``out_link`` the index of
    the link whose spring force the sensor reads (then ``out_positions`` is ignored);
    ``drive_plays`` with ``drive_w0`` make the applied force a Prandtl-Ishlinskii operator of
    the commanded one.  ``nodes`` names each node after its model-file element."""

    masses: np.ndarray
    links: list[Link]
    drive: np.ndarray
    out_positions: np.ndarray
    out_link: int = -1
    nodes: tuple = ()
    drive_w0: float = 1.0
    drive_plays: tuple = ()
    extra: dict = field(default_factory=dict)

    def copy(self) -> Network:
        """A deep copy (links copied), to be changed without touching this one."""
        return dataclasses.replace(
            self,
            masses=self.masses.copy(),
            links=[dataclasses.replace(lk) for lk in self.links],
            drive=self.drive.copy(),
            out_positions=self.out_positions.copy(),
            extra=dict(self.extra),
        )

    def link_named(self, element: str) -> int:
        """Index of the link whose spring or damper is the model-file element ``element``."""
        for i, lk in enumerate(self.links):
            if element in (lk.spring, lk.damper):
                return i
        raise KeyError(element)

    # -- linear part -------------------------------------------------------------------
    def matrices(self):
        """Mass, damping and stiffness matrices ``M, Cd, K`` (n x n) of the linear part."""
        n = self.masses.size
        K = np.zeros((n, n))
        Cd = np.zeros((n, n))
        for lk in self.links:
            for mat, val in ((K, lk.k), (Cd, lk.c)):
                mat[lk.a, lk.a] += val
                if lk.b >= 0:
                    mat[lk.b, lk.b] += val
                    mat[lk.a, lk.b] -= val
                    mat[lk.b, lk.a] -= val
        return np.diag(self.masses), Cd, K

    def output_row(self) -> np.ndarray:
        """The sensor as a row on the node positions (linear part)."""
        if self.out_link < 0:
            return np.asarray(self.out_positions, float)
        lk = self.links[self.out_link]
        row = np.zeros(self.masses.size)
        row[lk.a] += lk.k
        if lk.b >= 0:
            row[lk.b] -= lk.k
        return row

    def state_space(self):
        """``A, B, C`` of the linear part with states ``[x, v]`` (positions, velocities)."""
        M, Cd, K = self.matrices()
        n = self.masses.size
        Minv = np.diag(1.0 / self.masses)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ Cd]])
        B = np.concatenate([np.zeros(n), Minv @ self.drive])
        C = np.concatenate([self.output_row(), np.zeros(n)])
        return A, B, C

    def modes(self):
        """Natural frequencies (rad/s, ascending) and damping ratios of the linear part."""
        lam = np.linalg.eigvals(self.state_space()[0])
        lam = lam[lam.imag > 0]
        order = np.argsort(np.abs(lam))
        lam = lam[order]
        return np.abs(lam), -lam.real / np.abs(lam)


# ------------------------------------------------------------------------------------------
# the compiled integrator
# ------------------------------------------------------------------------------------------


@njit(cache=True)
def _rk4(y, u_half, h, os, n, node, li, lf, hp, hr, w0, out_link, y_fine, rec_e, rec_v):  # noqa: C901
    """Fixed-step RK4 from state ``y``; every law written out in one loop body (calls between
    compiled functions that pass many arrays cost more than the physics)."""
    nsteps = y_fine.size - 1
    nl = li.shape[0]
    ny = y.size
    n2 = 2 * n
    kst = np.zeros((4, ny))
    tmp = np.empty(ny)
    dps = li[nl - 1, 5] if nl else 0  # the drive's plays follow the links' plays
    dpe = hp.shape[0]
    for i in range(nsteps + 1):
        for st in range(4):
            if st == 0:
                for j in range(ny):
                    tmp[j] = y[j]
                u = u_half[2 * i]
            elif st == 3:
                for j in range(ny):
                    tmp[j] = y[j] + h * kst[2, j]
                u = u_half[2 * i + 2]
            else:
                for j in range(ny):
                    tmp[j] = y[j] + 0.5 * h * kst[st - 1, j]
                u = u_half[2 * i + 1]
            out = kst[st]
            # the drive, through its hysteresis if any
            fin = w0 * u
            for j in range(dps, dpe):
                fin += hp[j, 1] * min(max(hp[j, 2], u - hp[j, 0]), u + hp[j, 0])
            for q in range(n):
                out[q] = tmp[n + q]
                out[n + q] = node[q, 1] * fin
            for l in range(nl):
                a = li[l, 0]
                b = li[l, 1]
                e = tmp[a]
                ed = tmp[n + a]
                if b >= 0:
                    e -= tmp[b]
                    ed -= tmp[n + b]
                kk = lf[l, 0]
                p0 = lf[l, 2]
                p1 = lf[l, 3]
                p2 = lf[l, 4]
                p3 = lf[l, 5]
                code = li[l, 2]
                if code == 0:
                    fs = kk * e
                elif code == 1:  # polynomial
                    x = e / p0
                    x2 = x * x
                    fs = kk * p0 * x * (1.0 + p1 * x + p2 * x2 + p3 * x2 * x2)
                elif code == 2:  # exponential stiffening
                    fs = kk * p0 * np.sinh(e / p0)
                elif code == 3:  # saturating, tanh or arctan shaped
                    if p3 == 0.0:
                        g = np.tanh((e + p2) / p0) - np.tanh(p2 / p0)
                    else:
                        g = (2.0 / np.pi) * (np.arctan(0.5 * np.pi * (e + p2) / p0) - np.arctan(0.5 * np.pi * p2 / p0))
                    fs = kk * ((1.0 - p1) * e + p1 * p0 * g)
                elif code == 4:  # Bouc-Wen: z' = e' - beta |e'| |z|^(n-1) z - gamma e' |z|^n
                    zi = n2 + li[l, 8]
                    z = tmp[zi]
                    fs = kk * (p0 * e + (1.0 - p0) * z)
                    az = abs(z) ** (p3 - 1.0)
                    out[zi] = ed - p1 * abs(ed) * az * z - p2 * ed * az * abs(z)
                elif code == 5:  # Prandtl-Ishlinskii
                    acc = p0 * e  # stops (e - play): elastic-plastic elements, so the loop dissipates
                    for j in range(li[l, 4], li[l, 5]):
                        acc += hp[j, 1] * (e - min(max(hp[j, 2], e - hp[j, 0]), e + hp[j, 0]))
                    fs = kk * acc
                elif code == 6:  # Preisach
                    acc = 0.0
                    for j in range(li[l, 6], li[l, 7]):
                        if e >= hr[j, 0]:
                            acc += hr[j, 2]
                        elif e <= hr[j, 1]:
                            acc -= hr[j, 2]
                        else:
                            acc += hr[j, 2] * hr[j, 3]
                    fs = kk * (e - (1.0 - p0) * p1 * acc)  # the relays slip: the loop dissipates
                else:  # clearance: a share rho stays engaged, the rest touches beyond the gap
                    fs = kk * p1 * e
                    over = abs(e) - p0
                    if over > 0.0:
                        sg = 1.0 if e > 0.0 else -1.0
                        contact = (1.0 - p1) * kk * over + p2 * ed * sg
                        if contact > 0.0:
                            fs += sg * contact
                if st == 0:
                    if l == out_link:
                        y_fine[i] = fs
                    if i % os == 0:
                        rec_e[l, i // os] = e
                        rec_v[l, i // os] = ed
                cc = lf[l, 1]
                d0 = lf[l, 8]
                d1 = lf[l, 9]
                dcode = li[l, 3]
                if dcode == 0:
                    fd = cc * ed
                elif dcode == 1:  # power law
                    fd = cc * ed + d0 * np.sign(ed) * abs(ed) ** d1
                elif dcode == 2:  # shear thinning
                    fd = cc * ((1.0 - d0) * ed + d0 * ed / (1.0 + abs(ed) / d1))
                else:  # Stribeck friction, regularised at v_eps
                    level = d0 + (d1 - d0) * np.exp(-(abs(ed / lf[l, 10]) ** lf[l, 11]))
                    fd = cc * ed + level * np.tanh(ed / lf[l, 12])
                f = fs + fd
                out[n + a] -= f
                if b >= 0:
                    out[n + b] += f
            for q in range(n):
                out[n + q] *= node[q, 0]
            if st == 0:
                if out_link < 0:
                    acc = 0.0
                    for q in range(n):
                        acc += node[q, 2] * tmp[q]
                    y_fine[i] = acc
                if i == nsteps:
                    break
        if i == nsteps:
            break
        for j in range(ny):
            y[j] += h / 6.0 * (kst[0, j] + 2.0 * kst[1, j] + 2.0 * kst[2, j] + kst[3, j])
        # commit the hysterons at the new state
        ue = u_half[2 * i + 2]
        for j in range(dps, dpe):
            hp[j, 2] = min(max(hp[j, 2], ue - hp[j, 0]), ue + hp[j, 0])
        for l in range(nl):
            e = y[li[l, 0]]
            if li[l, 1] >= 0:
                e -= y[li[l, 1]]
            for j in range(li[l, 4], li[l, 5]):
                hp[j, 2] = min(max(hp[j, 2], e - hp[j, 0]), e + hp[j, 0])
            for j in range(li[l, 6], li[l, 7]):
                if e >= hr[j, 0]:
                    hr[j, 3] = 1.0
                elif e <= hr[j, 1]:
                    hr[j, 3] = -1.0


@dataclass
class Trajectory:
    """What :func:`integrate` returns: the sensor's output on the fine grid (step ``h``) and
    every link's elongation and relative velocity at the sample instants (every ``os`` steps)."""

    y_fine: np.ndarray
    h: float
    os: int
    elongation: np.ndarray  # (links, samples)
    velocity: np.ndarray  # (links, samples)

    @property
    def y(self) -> np.ndarray:
        """The sensor's output at the sample instants."""
        return self.y_fine[:: self.os]

    def y_rate(self) -> np.ndarray:
        """The output's time derivative at the sample instants (central differences on the fine grid)."""
        d = np.gradient(self.y_fine, self.h)
        return d[:: self.os]


def _pack(net: Network):
    """The network as the integrator's arrays (see :func:`_rk4`)."""
    nl = len(net.links)
    li = np.zeros((nl, 9), np.int64)
    lf = np.zeros((nl, 2 + 2 * _NPAR))
    plays, relays = [], []
    nz = 0
    for i, lk in enumerate(net.links):
        li[i, :4] = lk.a, lk.b, SPRING_LAWS[lk.spring_law], DAMPER_LAWS[lk.damper_law]
        li[i, 4] = len(plays)
        plays += [(r, w, 0.0) for r, w in lk.plays]
        li[i, 5] = len(plays)
        li[i, 6] = len(relays)
        # the virgin (demagnetised) state at rest: up below the line alpha + beta = 0, down above it
        relays += [(al, be, mu, 1.0 if al + be < 0 else -1.0) for al, be, mu in lk.relays]
        li[i, 7] = len(relays)
        if lk.spring_law == "bouc-wen":
            li[i, 8] = nz
            nz += 1
        lf[i, :2] = lk.k, lk.c
        lf[i, 2 : 2 + len(lk.spring_par)] = lk.spring_par
        lf[i, 2 + _NPAR : 2 + _NPAR + len(lk.damper_par)] = lk.damper_par
    plays += [(r, w, 0.0) for r, w in net.drive_plays]
    hp = np.array(plays, float).reshape(-1, 3)
    hr = np.array(relays, float).reshape(-1, 4)
    node = np.column_stack([1.0 / np.asarray(net.masses, float), net.drive, net.out_positions]).astype(float)
    return li, lf, hp, hr, node, nz


def integrate(net: Network, u_half: np.ndarray, h: float, os: int) -> Trajectory:
    """Simulate ``net`` from rest under the drive ``u_half`` (values every ``h/2``).

    Parameters
    ----------
    net : Network
        The system, with its nonlinear laws.
    u_half : ndarray
        The commanded drive (N, or V) at ``t = j h / 2``, ``j = 0 .. 2 S`` for ``S`` steps.
    h : float
        The integration step (s).
    os : int
        Steps per sample: elongations and velocities are recorded every ``os`` steps.

    Returns
    -------
    Trajectory
        The sensor's output at every step and the links' state at every sample.

    Raises
    ------
    ValueError
        If ``u_half`` does not hold an odd number of points covering a whole number of samples.
    """
    u_half = np.ascontiguousarray(u_half, float)
    steps = (u_half.size - 1) // 2
    if u_half.size % 2 != 1 or steps % os:
        raise ValueError("the drive must be given at every half step over a whole number of samples")
    li, lf, hp, hr, node, nz = _pack(net)
    n = net.masses.size
    y = np.zeros(2 * n + nz)
    y_fine = np.empty(steps + 1)
    rec_e = np.empty((len(net.links), steps // os + 1))
    rec_v = np.empty_like(rec_e)
    _rk4(
        y,
        u_half,
        float(h),
        int(os),
        n,
        node,
        li,
        lf,
        hp,
        hr,
        float(net.drive_w0),
        int(net.out_link),
        y_fine,
        rec_e,
        rec_v,
    )
    return Trajectory(y_fine, float(h), int(os), rec_e, rec_v)


# ------------------------------------------------------------------------------------------
# the linear route: exact in the frequency domain
# ------------------------------------------------------------------------------------------


@dataclass
class Spectrum:
    """A drive's spectrum for :func:`linear_response`: ``U[k]`` at ``f_k = k / (M dt)``
    (``k = 0 .. M/2``), from the drive on a grid ``q`` times finer than the samples, zero
    padded to ``M`` samples so the circular convolution does not wrap onto the record."""

    U: np.ndarray
    freqs: np.ndarray
    M: int
    n: int
    dt: float
    scale: float = 1.0  # 1/D once decimated by D (the bins keep their spacing 1/(M dt))
    active: np.ndarray | None = None  # the bins where the drive has content (others are 0)

    def __post_init__(self):
        if self.active is None:
            mag = np.abs(self.U)
            self.active = np.flatnonzero(mag > 1e-9 * mag.max())

    def decimated(self, D: int) -> Spectrum:
        """The same drive seen every ``D`` samples: its spectrum cut at the new Nyquist
        frequency (``D`` must divide ``M``; :func:`drive_spectrum` makes ``M`` a multiple of 64)."""
        if self.M % D:
            raise ValueError(f"decimation {D} does not divide the padded length {self.M}")
        m = self.M // D
        return Spectrum(
            self.U[: m // 2 + 1],
            self.freqs[: m // 2 + 1],
            m,
            -(-self.n // D),
            self.dt * D,
            self.scale / D,
            self.active[self.active <= m // 2],
        )


def drive_spectrum(u_fine: np.ndarray, q: int, n: int, dt: float, decay_s: float) -> Spectrum:
    """The spectrum of a drive given every ``dt/q`` over ``n`` samples (``n q`` + 1 points or
    more), padded by ``decay_s`` seconds of silence (the slowest mode's ring-down; at most
    2**22 samples in all)."""
    M = 64 * scipy.fft.next_fast_len(-(-int(min(n + max(decay_s / dt, 0.2 * n), 2**22)) // 64), real=True)
    u = np.zeros(M * q)
    u[: n * q] = u_fine[: n * q]
    U = scipy.fft.rfft(u)[: M // 2 + 1] / q
    return Spectrum(U, np.arange(M // 2 + 1) / (M * dt), M, n, dt)


def transfer(net: Network, freqs: np.ndarray) -> np.ndarray:
    """The linear part's frequency response (sensor per unit drive) at ``freqs`` (Hz),
    from the modal residues of its state matrix."""
    A, B, C = net.state_space()
    lam, V = np.linalg.eig(A)
    left = C @ V
    right = np.linalg.solve(V, B)
    res = left * right
    s = 2j * np.pi * np.asarray(freqs)
    H = np.zeros(s.shape, complex)
    for r, lm in zip(res, lam):
        H += r / (s - lm)
    return H


def response(H: np.ndarray, spec: Spectrum) -> np.ndarray:
    """The output at the samples of a linear system of frequency response ``H`` (at
    ``spec.freqs``, or at ``spec.freqs[spec.active]`` only) driven by the drive of ``spec``, from rest."""
    Y = np.zeros(spec.U.shape, complex)
    if H.size == spec.U.size:
        H = H[spec.active]
    Y[spec.active] = H * spec.U[spec.active]
    return scipy.fft.irfft(Y, n=spec.M)[: spec.n] * spec.scale


def linear_response(net: Network, spec: Spectrum) -> np.ndarray:
    """The linear part of ``net`` driven by ``spec``, at the samples (the second route)."""
    return response(transfer(net, spec.freqs[spec.active]), spec)
