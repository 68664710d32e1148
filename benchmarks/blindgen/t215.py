"""T215 family: a T215-geometry bimorph bender (Ghafarirad et al. 2015), modal, sensor near the
tip.  SI units; modal coordinates q_i in kg^1/2 m (mass-normalised modes).

Linear device (the model file's structure, two bending modes):

    q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i = m_p,i u + phi_i(L) F_tip,
    sensor w = sum_i phi_i(x_s) q_i (m),   u = V (V),  F_tip = 0.

Causes: an input operator u = H[V] (hysteresis, creep, static saturation), a tip force F_tip
(end stop, quadratic air drag, friction), nonlinear stiffness or damping of mode 1 (Shahabi et
al. 2019: k1 q^3 + k2 q^5, mu1 q^2 q'; or a modulus that softens with the vibration amplitude),
or a third resonator (bending mode 3, or a torsional or lateral mode seen through a small
sensor offset).  The sign convention is the model file's: m_p,i < 0, so V > 0 bends to w < 0.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import drives, linear, operators
from .nominal import beam, cantilever_mode, rayleigh_zeta
from .spread import creep_knobs, factor, logu

FS = 50_000.0
DURATION = 5.0
V_RATED = 90.0
CAUSES = ("hysteresis", "creep", "saturation", "softening", "nonlinear-damping", "higher-mode")
MECHANISMS = {
    "hysteresis": ("preisach", "bouc-wen"),
    "creep": ("kelvin-voigt", "log", "fractional"),
    "saturation": ("tanh", "polynomial", "end-stop"),
    "softening": ("cubic", "cubic-quintic", "amplitude-modulus"),
    "nonlinear-damping": ("amplitude-damping", "air-drag", "friction"),
    "higher-mode": ("bending-3", "torsion", "lateral"),
}
DRIVES = {
    "none": drives.QUASI_STATIC + drives.DYNAMIC,
    "hysteresis": ("sine", "triangle"),
    "creep": ("steps", "ramp-hold"),
    "saturation": ("sine", "triangle"),
    "softening": ("stepped-sine",),
    "nonlinear-damping": ("stepped-sine", "ringdown"),
    "higher-mode": ("hi-chirp", "hi-noise", "bursts", "steps"),
}
REFIT = {"omega": 1.3, "zeta": 15.0, "ratio": 2.0}
TIP_LIMIT = (5e-5, 4e-4)  # tip amplitude (m) the experimenter aims at in dynamic tests


def limits() -> drives.Limits:
    w1 = cantilever_mode(1, 1.0)[0]
    return drives.Limits(
        vmax=None,
        vbip=V_RATED,
        qs_f=(1.0, 40.0),
        dyn_f=(10.0, 0.4 * FS),
        f_res=w1 / (2 * math.pi),
        zeta_res=rayleigh_zeta(w1),
        holds=(0.3, 1.0),
        ramps=(0.01, 0.3),
        dyn_amp=(0.2, 3.0),
        p_unipolar=0.0,
        hi_band=(700.0, 3000.0),
    )


def _mode(n, target, coupling, rng, zeta=None):
    w, phi_s, phi_l, mp = cantilever_mode(n, target)
    return {
        "omega": w * factor(rng, 0.06, False),
        "zeta": zeta if zeta is not None else rayleigh_zeta(w) * factor(rng, 4.0, True),
        "mp": mp * coupling * factor(rng, 0.03, False),
        "phi_s": phi_s,
        "phi_l": phi_l,
    }


def draw_linear(rng) -> dict:
    """Two modes around the model file's: frequencies +-6 %, damping x/÷4, coupling +-25 %
    (common) and +-3 % (per mode), sensor at 0.92-0.98 L (model file: 0.95 L)."""
    target = rng.uniform(0.92, 0.98)
    coupling = factor(rng, 0.25, False)
    return {"target": target, "coupling": coupling, "modes": [_mode(n, target, coupling, rng) for n in (1, 2)]}


def _ss(omegas, zetas, gains, phis):
    n = len(omegas)
    A = np.zeros((2 * n, 2 * n))
    B = np.zeros(2 * n)
    C = np.zeros(2 * n)
    for i, (w, z, g, p) in enumerate(zip(omegas, zetas, gains, phis)):
        A[2 * i, 2 * i + 1] = 1.0
        A[2 * i + 1, 2 * i] = -w * w
        A[2 * i + 1, 2 * i + 1] = -2 * z * w
        B[2 * i + 1] = g
        C[2 * i] = p
    return A, B, C


def linear_ss(lin, output="x"):
    """(A, B, C) of the device's two modes, states (q_i, q_i'); output the sensor (x), the tip
    (tip) or mode 1's coordinate (q1)."""
    ms = lin["modes"]
    phis = {"x": [m["phi_s"] for m in ms], "tip": [m["phi_l"] for m in ms], "q1": [1.0] + [0.0] * (len(ms) - 1)}[output]
    return _ss([m["omega"] for m in ms], [m["zeta"] for m in ms], [m["mp"] for m in ms], phis)


def _nominal_modes():
    return [cantilever_mode(n, beam()["target"]) for n in (1, 2)]


def refit_spec(lin, V, dt):
    """Visibility refit: omega_i x/÷1.3, zeta_i x/÷15 and the static-gain ratio of mode 2 to mode 1
    x/÷2 around the model file's values (log), gain and offset free; predict(theta) is the
    two-mode response to V (each mode's response cached, so a derivative step re-simulates
    one mode)."""
    nm = _nominal_modes()
    rz = [rayleigh_zeta(m[0]) for m in nm]
    ratio = nm[1][1] * nm[1][3] / (nm[0][1] * nm[0][3])
    centre = np.log([nm[0][0], rz[0], nm[1][0], rz[1], ratio])
    half = np.log([REFIT["omega"], REFIT["zeta"], REFIT["omega"], REFIT["zeta"], REFIT["ratio"]])
    m1, m2 = lin["modes"]
    theta0 = np.log(
        [m1["omega"], m1["zeta"], m2["omega"], m2["zeta"], m2["phi_s"] * m2["mp"] / (m1["phi_s"] * m1["mp"])]
    )
    cache = {}

    def mode(w, z):
        if (w, z) not in cache:
            if len(cache) > 64:
                cache.clear()
            cache[(w, z)] = linear.simulate(*_ss([w], [z], [1.0], [1.0]), V, dt)
        return cache[(w, z)]

    def predict(theta):
        w1, z1, w2, z2, r = np.exp(theta)
        return mode(w1, z1) + r * mode(w2, z2)

    return predict, theta0, centre - half, centre + half, (centre,)


def pilot(lin, V, dt) -> dict:
    """Linear-response peaks: x_max, x_min (sensor), tip_max, tip_min, q1_max (|mode 1|)."""
    x = linear.simulate(*linear_ss(lin), V, dt)
    tip = linear.simulate(*linear_ss(lin, "tip"), V, dt)
    q1 = linear.simulate(*linear_ss(lin, "q1"), V, dt)
    return {
        "x_max": float(x.max()),
        "x_min": float(x.min()),
        "tip_max": float(tip.max()),
        "tip_min": float(tip.min()),
        "q1_max": float(np.abs(q1).max()),
        "v_peak": float(np.abs(V).max()),
    }


# ---- causes: knobs (drawn), strength (knob, step, limit) and realisation -----------------------
STRENGTH = {
    "preisach": ("h", 1.3, 0.7),
    "bouc-wen": ("H", 1.3, 0.2),
    "kelvin-voigt": ("r_T", 1.3, 0.3),
    "log": ("r_T", 1.3, 0.3),
    "fractional": ("r_T", 1.3, 0.3),
    "tanh": ("r_max", 1.1, 1.0),
    "polynomial": ("e3", 1.3, 0.3),
    "end-stop": ("overshoot", 1.3, 0.45),
    "cubic": ("drop", 1.4, 0.08),
    "cubic-quintic": ("drop", 1.4, 0.08),
    "amplitude-modulus": ("drop", 1.4, 0.08),
    "amplitude-damping": ("eta", 1.4, 3.0),
    "air-drag": ("eta", 1.4, 3.0),
    "friction": ("eta", 1.4, 1.0),
    "bending-3": ("zeta", 1 / 1.5, 0.004),
    "torsion": ("ratio", 1.5, 0.06),
    "lateral": ("ratio", 1.5, 0.06),
}


def draw_knobs(mech, rng) -> dict:
    """The drawn size and shape of a mechanism (dimensionless, most relative to the record's
    linear peaks; Kernel turns them into model parameters)."""
    u = rng.uniform
    if mech == "preisach":
        return {"h": u(0.2, 0.45), "table": operators.preisach_table(rng)}
    if mech == "bouc-wen":
        return {"H": u(0.05, 0.12), "w": u(0.15, 0.5), "beta": u(0.5, 0.9), "n": u(1.0, 2.0)}
    if mech in ("kelvin-voigt", "log", "fractional"):
        return creep_knobs(mech, rng, (0.05, 0.15), (0.02, 2.0), -2.5, -3.0, 2.5)
    if mech == "tanh":
        return {"r_max": u(0.5, 0.8)}
    if mech == "polynomial":
        return {"e3": u(0.05, 0.18), "e2": u(-0.06, 0.06)}
    if mech == "end-stop":
        return {"overshoot": u(0.08, 0.3), "kappa": u(2.0, 10.0), "side": float(rng.choice([-1.0, 1.0]))}
    if mech in ("cubic", "amplitude-modulus"):
        return {"drop": u(0.01, 0.04)}
    if mech == "cubic-quintic":
        return {"drop": u(0.01, 0.04), "chi": u(0.2, 0.6)}
    if mech in ("amplitude-damping", "air-drag"):
        return {"eta": u(0.3, 1.5)}
    if mech == "friction":
        return {"eta": u(0.1, 0.5)}
    if mech == "bending-3":
        return {"zeta": logu(rng, 0.01, 0.06), "omega_f": factor(rng, 0.06, False)}
    if mech in ("torsion", "lateral"):
        return {
            "ratio": logu(rng, 0.003, 0.02) * float(rng.choice([-1.0, 1.0])),
            "f_f": u(0.85, 1.15),
            "zeta": logu(rng, 0.005, 0.03),
        }
    raise ValueError(mech)


def _offaxis_frequency(mech) -> float:
    """Nominal torsional (thin strip, clamped-free: omega = pi/(2L) (2t/b) sqrt(G/rho), G = E/2.6)
    or lateral (in-plane bending: omega_1 b/t) frequency, rad/s."""
    c = beam()
    if mech == "lateral":
        return cantilever_mode(1, 1.0)[0] * c["b"] / c["t"]
    E = 12 * c["EI"] / (c["b"] * c["t"] ** 3)
    return math.pi / (2 * c["L"]) * 2 * c["t"] / c["b"] * math.sqrt(E / 2.6 / c["rho"])


class Kernel:
    """Compiled-simulation arguments: md (modes x [omega, zeta, mp, phi_s, phi_l]), flags
    (n_modes, off-axis resonator, soft, nld, stop), ep (cause parameters), the input operator
    (applied to V on the fine grid before integration) and a stiffness factor.

    Sizes are set at the record's drive level (pil: the linear response's peaks): q_ref, the
    largest |q_1|, and the tip amplitude phi_1(L) q_ref.  soft 1: k1 q^3 + k2 q^5 on mode 1
    (ep[0], ep[1]), the backbone drops by ``drop`` at q_ref; soft 2: omega_1^2 (1 - kappa A2/q_ref^2),
    A2 tracking q^2 + q'^2/omega^2 over tau_A (ep[2..4]); nld 1: mu1 q^2 q' (ep[5]); nld 2: tip
    force -c |v| v (ep[6]); nld 3: tip force -F_c tanh(v/v_eps) (ep[7], ep[8]); the added damping
    at q_ref is eta x the linear one.  stop: tip stop at side*w > ep[9] (ep[10] = side, ep[11] =
    k N/m, ep[12] = rounding m).  Off-axis resonator: omega ep[13], zeta ep[14], static gain
    ep[15] m/V."""

    def __init__(self, lin, mech=None, knobs=None, pil=None):
        self.lin = lin
        self.modes = [dict(m) for m in lin["modes"]]
        self.flags = np.zeros(5, np.int64)
        self.ep = np.zeros(16)
        self.op = None
        self.stiff = 1.0
        self.info = {}
        if mech is not None:
            self._realise(mech, knobs, pil)
        self.flags[0] = len(self.modes)

    def _realise(self, mech, k, pil):
        ep, m1 = self.ep, self.modes[0]
        w1, z1, q_ref = m1["omega"], m1["zeta"], pil["q1_max"]
        tip_ref = abs(m1["phi_l"]) * q_ref
        vr = max(pil["v_peak"], 1e-6)
        if mech == "preisach":
            self.op = lambda V, h: operators.preisach(V, V_RATED, k["h"], k["table"])
            self.info = {"density": k["table"][2]}
        elif mech == "bouc-wen":
            self.op = lambda V, h: operators.bouc_wen(V, V_RATED, k["H"], k["w"], k["beta"], k["n"])
        elif mech in ("kelvin-voigt", "log", "fractional"):
            tau, w = np.asarray(k["tau"]), np.asarray(k["w"])
            r = k["r_T"] * w / np.sum(w * (1 - np.exp(-DURATION / tau)))
            self.op = lambda V, h: operators.creep(V, h, r, tau)
            self.info = {"r_n": r.tolist(), "tau_n": tau.tolist()}
        elif mech == "tanh":
            vs = vr / k["r_max"]
            self.op = lambda V, h: vs * np.tanh(V / vs)
            self.info = {"V_s": vs}
        elif mech == "polynomial":
            self.op = lambda V, h: V * (1 + k["e2"] * V / vr - k["e3"] * (V / vr) ** 2)
            self.info = {"V_p": vr}
        elif mech == "end-stop":
            side = k["side"]
            peak = pil["tip_max"] if side > 0 else -pil["tip_min"]
            k_tip = 1 / sum(m["phi_l"] ** 2 / m["omega"] ** 2 for m in self.modes)
            self.flags[4] = 1
            ep[9], ep[10], ep[11], ep[12] = peak * (1 - k["overshoot"]), side, k["kappa"] * k_tip, 0.01 * peak
            self.stiff = 1 + k["kappa"]
            self.info = {"w_stop": side * ep[9], "k_stop": ep[11]}
        elif mech in ("cubic", "cubic-quintic"):
            self.flags[2] = 1
            d1 = k["drop"] / (1 - k.get("chi", 0.0))
            ep[0] = -8 / 3 * d1 * w1**2 / q_ref**2
            ep[1] = 32 / 10 * (d1 - k["drop"]) * w1**2 / q_ref**4
            self.info = {"k1": ep[0], "k2": ep[1]}
        elif mech == "amplitude-modulus":
            self.flags[2] = 2
            ep[2], ep[3], ep[4] = 2 * k["drop"], 10 * 2 * math.pi / w1, q_ref**2
            self.info = {"kappa": ep[2], "tau_A": ep[3]}
        elif mech == "amplitude-damping":
            self.flags[3] = 1
            ep[5] = 8 * k["eta"] * z1 * w1 / q_ref**2
            self.info = {"mu1": ep[5]}
        elif mech == "air-drag":
            self.flags[3] = 2
            ep[6] = k["eta"] * 2 * z1 * w1 * 3 * math.pi / (8 * w1 * tip_ref * m1["phi_l"] ** 2)
            self.info = {"c_drag": ep[6]}
        elif mech == "friction":
            self.flags[3] = 3
            ep[7] = k["eta"] * 2 * z1 * w1 * math.pi * w1 * tip_ref / (4 * m1["phi_l"] ** 2)
            ep[8] = 0.02 * w1 * tip_ref
            self.stiff = 1 + 50 * k["eta"] * 2 * z1
            self.info = {"F_c": ep[7], "v_eps": ep[8]}
        elif mech == "bending-3":
            w, phi_s, phi_l, mp = cantilever_mode(3, self.lin["target"])
            self.modes.append(
                {
                    "omega": w * k["omega_f"],
                    "zeta": k["zeta"],
                    "mp": mp * self.lin["coupling"],
                    "phi_s": phi_s,
                    "phi_l": phi_l,
                }
            )
        else:
            self.flags[1] = 1
            g1 = m1["phi_s"] * m1["mp"] / w1**2
            ep[13], ep[14], ep[15] = _offaxis_frequency(mech) * k["f_f"], k["zeta"], k["ratio"] * g1
            self.info = {"f": ep[13] / (2 * math.pi), "static_gain": ep[15]}

    def args(self):
        md = np.array([[m["omega"], m["zeta"], m["mp"], m["phi_s"], m["phi_l"]] for m in self.modes])
        return md, self.flags, self.ep

    def n_sub(self, dt) -> int:
        md, _, ep = self.args()
        rho = max(md[:, 0].max(), ep[13]) * self.stiff
        return max(2, int(np.ceil(dt * rho / 0.5)))

    def simulate(self, V, dt) -> np.ndarray:
        """Noise-free sensor signal (m) at the samples of V (from rest)."""
        V = np.asarray(V, float)
        nsub = self.n_sub(dt)
        h = dt / (2 * nsub)
        fine = np.interp(np.arange((V.size - 1) * 2 * nsub + 1) * h, np.arange(V.size) * dt, V)
        u = fine if self.op is None else self.op(fine, h)
        return _simulate(u, V.size, nsub, dt, *self.args())


@njit(cache=True)
def _softplus(z):
    return z + math.log1p(math.exp(-z)) if z > 0 else math.log1p(math.exp(z))


@njit(cache=True)
def _rhs(y, u, md, fl, ep, dy):
    nm = fl[0]
    wl = 0.0
    vl = 0.0
    for i in range(nm):
        wl += md[i, 4] * y[2 * i]
        vl += md[i, 4] * y[2 * i + 1]
    F = 0.0
    if fl[3] == 2:
        F -= ep[6] * abs(vl) * vl
    elif fl[3] == 3:
        F -= ep[7] * math.tanh(vl / ep[8])
    if fl[4] == 1:
        F -= ep[10] * ep[11] * ep[12] * _softplus((ep[10] * wl - ep[9]) / ep[12])
    for i in range(nm):
        w, z = md[i, 0], md[i, 1]
        q, v = y[2 * i], y[2 * i + 1]
        acc = md[i, 2] * u - 2.0 * z * w * v - w * w * q + md[i, 4] * F
        if i == 0:
            if fl[2] == 1:
                acc -= ep[0] * q**3 + ep[1] * q**5
            elif fl[2] == 2:
                acc += w * w * ep[2] * y[8] / ep[4] * q
            if fl[3] == 1:
                acc -= ep[5] * q * q * v
        dy[2 * i] = v
        dy[2 * i + 1] = acc
    if fl[1] == 1:
        dy[6] = y[7]
        dy[7] = -2.0 * ep[14] * ep[13] * y[7] - ep[13] * ep[13] * (y[6] - ep[15] * u)
    if fl[2] == 2:
        dy[8] = (y[0] * y[0] + y[1] * y[1] / (md[0, 0] * md[0, 0]) - y[8]) / ep[3]


@njit(cache=True)
def _simulate(u, n, nsub, dt, md, fl, ep):
    ns = 9
    y = np.zeros(ns)
    tmp = np.zeros(ns)
    k1 = np.zeros(ns)
    k2 = np.zeros(ns)
    k3 = np.zeros(ns)
    k4 = np.zeros(ns)
    out = np.zeros(n)
    h = dt / nsub
    for k in range(n - 1):
        for j in range(nsub):
            s = 2 * (k * nsub + j)
            _rhs(y, u[s], md, fl, ep, k1)
            for i in range(ns):
                tmp[i] = y[i] + 0.5 * h * k1[i]
            _rhs(tmp, u[s + 1], md, fl, ep, k2)
            for i in range(ns):
                tmp[i] = y[i] + 0.5 * h * k2[i]
            _rhs(tmp, u[s + 1], md, fl, ep, k3)
            for i in range(ns):
                tmp[i] = y[i] + h * k3[i]
            _rhs(tmp, u[s + 2], md, fl, ep, k4)
            for i in range(ns):
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        acc = 0.0
        for i in range(fl[0]):
            acc += md[i, 3] * y[2 * i]
        if fl[1] == 1:
            acc += y[6]
        out[k + 1] = acc
    return out
