"""APA family: an amplified piezo stack like the APA-120ML (Rodriguez-Fortun et al. 2010), with
the amplification folded into the coupling.  SI units throughout.

States: charge Q (C), output displacement x (m, positive = extension), velocity v (m/s), plus
cause states.  Linear device (the model file's structure):

    Re Q' = Vs - Vc,     Vc = l E2 + a F1,   E2 = kx p0,   p0 = l Q  (dipole, C m)
    F1 = K (a Q - x),    M v' = F1 - c v,    x' = v,       sensor: x.

Vs is the source voltage (the recorded V unless an amplifier pole sits between them).
Causes change one part: the polarization law E2(p0) (hysteresis E2 += Eh, saturation), a
polarization Kelvin-Voigt chain (creep: p0 = l Q - sum p_n, tau_n p_n' = r_n E2/kx - p_n), the
electrical source (series R, series L, amplifier bandwidth, amplifier current limit), an end
stop on x, or one more mechanical degree of freedom (shell, base, sensor bracket).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import drives, linear
from .nominal import model_values
from .spread import creep_knobs, factor, logu

FS = 10_000.0
DURATION = 18.0
V_RATED = 150.0
CAUSES = ("hysteresis", "creep", "saturation", "electrical", "higher-mode")
MECHANISMS = {
    "hysteresis": ("bouc-wen", "maxwell-slip", "duhem"),
    "creep": ("kelvin-voigt", "log", "fractional"),
    "saturation": ("tanh", "polynomial", "end-stop"),
    "electrical": ("series-resistance", "series-inductance", "amplifier-pole", "current-limit"),
    "higher-mode": ("shell", "base", "sensor-bracket"),
}
DRIVES = {
    "none": drives.QUASI_STATIC + ("chirp", "noise", "hi-chirp", "hi-noise", "bursts", "stepped-sine"),
    "hysteresis": ("sine", "triangle"),
    "creep": ("steps", "ramp-hold"),
    "saturation": ("sine", "triangle", "steps"),
    "electrical": ("chirp", "noise", "bursts", "steps"),
    "higher-mode": ("hi-chirp", "hi-noise", "bursts", "stepped-sine"),
}
LIN = ("Re", "iC", "a", "K", "c", "M")  # iC = l^2 kx = 1/C0 (V/C)
SPREAD = {
    "Re": (2.0, True),
    "iC": (0.25, False),
    "a": (0.25, False),
    "K": (0.30, False),
    "c": (8.0, True),
    "M": (0.30, False),
}
REFIT = {"Re": 3.0, "iC": 1.6, "a": 1.6, "K": 1.6, "c": 15.0, "M": 1.6}
HM_BAND = (1500.0, 0.4 * FS)


def nominal() -> dict:
    p = model_values("apa")
    return {
        "Re": p["Re"],
        "iC": p["l"] ** 2 * p["kx"],
        "a": p["a"] * p["T"],
        "K": p["K"],
        "c": p["c"],
        "M": p["M"],
        "l": p["l"],
    }


def limits() -> drives.Limits:
    n = nominal()
    return drives.Limits(
        vmax=V_RATED,
        vbip=V_RATED / 2,
        qs_f=(0.5, 20.0),
        dyn_f=(1.0, 0.45 * FS),
        f_res=math.sqrt(n["K"] / n["M"]) / (2 * math.pi),
        zeta_res=n["c"] / (2 * math.sqrt(n["K"] * n["M"])),
        holds=(1.0, 4.0),
        ramps=(0.05, 1.0),
        dyn_amp=(3.0, 20.0),
        p_unipolar=0.7,
        hi_band=(100.0, 500.0),
    )


def draw_linear(rng) -> dict:
    """Linear parameters around the model file's (capacitance 1/iC drawn +-25 %)."""
    n = nominal()
    lin = {k: n[k] * factor(rng, *SPREAD[k]) for k in LIN if k != "iC"}
    lin["iC"] = n["iC"] / factor(rng, *SPREAD["iC"])
    lin["l"] = n["l"]
    return lin


def linear_ss(lin, output="x"):
    """(A, B, C) of the linear device, states (Q, x, v), input Vs; output x or Q."""
    Re, iC, a, K, c, M = (lin[k] for k in LIN)
    A = np.array([[-(iC + a * a * K) / Re, a * K / Re, 0.0], [0.0, 0.0, 1.0], [K * a / M, -K / M, -c / M]])
    C = np.array([0.0, 1.0, 0.0]) if output == "x" else np.array([1.0, 0.0, 0.0])
    return A, np.array([1.0 / Re, 0.0, 0.0]), C


def refit_spec(lin, V, dt):
    """(predict, theta0, lower, upper, starts) of the visibility refit: the model file's linear
    parameters free within REFIT (x/÷) of their nominal values, in log; predict(theta) is the
    linear response to V."""
    n = nominal()
    centre = np.log([n[k] for k in LIN])
    half = np.log([REFIT[k] for k in LIN])

    def predict(theta):
        return linear.simulate(*linear_ss(dict(zip(LIN, np.exp(theta)))), V, dt)

    return predict, np.log([lin[k] for k in LIN]), centre - half, centre + half, (centre,)


def pilot(lin, V, dt) -> dict:
    """Peaks of the linear response: x_max, x_min (m), p_max = max |l Q| (C m)."""
    x = linear.simulate(*linear_ss(lin), V, dt)
    Q = linear.simulate(*linear_ss(lin, "Q"), V, dt)
    return {"x_max": float(x.max()), "x_min": float(x.min()), "p_max": float(lin["l"] * np.abs(Q).max())}


# ---- causes: knobs (drawn), strength (knob, step, limit) and realisation -----------------------
STRENGTH = {
    "bouc-wen": ("h", 1.3, 0.25),
    "maxwell-slip": ("h", 1.3, 0.25),
    "duhem": ("h", 1.3, 0.15),
    "kelvin-voigt": ("r_T", 1.3, 0.25),
    "log": ("r_T", 1.3, 0.25),
    "fractional": ("r_T", 1.3, 0.25),
    "tanh": ("r_max", 1.1, 0.8),
    "polynomial": ("e3", 1.3, 0.35),
    "end-stop": ("overshoot", 1.3, 0.45),
    "series-resistance": ("ratio", 1.5, 600.0),
    "series-inductance": ("f_lc", 1 / 1.3, 200.0),
    "amplifier-pole": ("f_a", 1 / 1.4, 60.0),
    "current-limit": ("i_max", 1 / 1.4, 0.01),
    "shell": ("mu", 1.3, 0.5),
    "base": ("mass_ratio", 1 / 1.4, 1.0),
    "sensor-bracket": ("eps", 1.5, 0.6),
}


def draw_knobs(mech, rng) -> dict:
    """The drawn size and shape of a mechanism (dimensionless or SI; Kernel turns them into
    model parameters)."""
    u = rng.uniform
    if mech == "bouc-wen":
        return {"h": u(0.06, 0.14), "w": u(0.1, 0.4), "beta": u(0.5, 0.9), "n": u(1.0, 2.0)}
    if mech == "maxwell-slip":
        m = int(rng.integers(8, 13))
        return {"h": u(0.06, 0.14), "rho": np.sort(u(0.05, 0.6, m)), "w": rng.dirichlet(np.full(m, 2.0))}
    if mech == "duhem":
        return {"h": u(0.03, 0.08), "alpha": u(3.0, 12.0), "beta": u(0.0, 0.5)}
    if mech in ("kelvin-voigt", "log", "fractional"):
        return creep_knobs(mech, rng, (0.04, 0.12), (0.05, 8.0), -2.0, -2.5, 3.0)
    if mech == "tanh":
        return {"r_max": u(0.45, 0.7)}
    if mech == "polynomial":
        return {"e3": u(0.06, 0.2), "e2": u(-0.08, 0.08)}
    if mech == "end-stop":
        return {"overshoot": u(0.08, 0.3), "kappa": u(1.0, 5.0)}
    if mech == "series-resistance":
        return {"ratio": logu(rng, 50.0, 250.0)}
    if mech == "series-inductance":
        return {"f_lc": logu(rng, 350.0, 1200.0)}
    if mech == "amplifier-pole":
        return {"f_a": logu(rng, 150.0, 700.0), "zeta": u(0.3, 0.7)}
    if mech == "current-limit":
        return {"i_max": logu(rng, 0.05, 0.5)}
    if mech == "shell":
        return {"mu": u(0.1, 0.3), "f": logu(rng, *HM_BAND), "zeta": logu(rng, 0.01, 0.05)}
    if mech == "base":
        return {"mass_ratio": u(2.0, 12.0), "f": logu(rng, *HM_BAND), "zeta": logu(rng, 0.01, 0.05)}
    if mech == "sensor-bracket":
        return {"eps": u(0.05, 0.25), "f": logu(rng, *HM_BAND), "zeta": logu(rng, 0.005, 0.03)}
    raise ValueError(mech)


class Kernel:
    """Arguments of the compiled simulation: lin (Re, iC, a, K, c, M, l, kx), flags (elec, hyst,
    sat, hm), ep (cause parameters), creep cells (r_n, tau_n), Maxwell-slip elements (k_i, f_i),
    and a stiffness factor bounding how much the cause speeds up the fastest dynamics beyond
    what the Jacobian at rest shows.

    flags[0] elec: 1 series L (ep[1] = L, H), 2 second-order amplifier (ep[2] = omega_a rad/s,
    ep[3] = zeta_a), 3 current limit (ep[1] = i_max, A); flags[1] hyst: 1 Bouc-Wen (ep[4] = h,
    ep[5] = w, ep[6] = beta, ep[7] = n), 2 Maxwell slip, 3 Duhem (ep[4] = h, ep[5] = alpha,
    ep[6] = beta); flags[2] sat: 1 tanh (ep[8] = p_s, C m), 2 polynomial (ep[8] = e2, ep[9] = e3,
    ep[10] = p_ref), 3 end stop (ep[8] = x_stop m, ep[9] = k_stop N/m, ep[10] = rounding m);
    flags[3] extra DOF: 1 shell (ep[11] = mass fraction, ep[12] = k N/m, ep[13] = c N s/m),
    2 base (ep[11] = mass kg, ep[12], ep[13] as shell), 3 sensor bracket (ep[11] = coupling,
    ep[12] = omega rad/s, ep[13] = zeta).  ep[0] = p_ref, the dipole at rated voltage (C m).
    Hysteresis fields are h kx p_ref at most (h: fraction of the rated field)."""

    def __init__(self, lin, mech=None, knobs=None, pil=None):
        self.lin = dict(lin)
        self.flags = np.zeros(4, np.int64)
        self.ep = np.zeros(16)
        self.cr_r = np.zeros(0)
        self.cr_tau = np.ones(0)
        self.ms_k = np.zeros(0)
        self.ms_f = np.zeros(0)
        self.stiff = 1.0
        self.info = {}
        kx = lin["iC"] / lin["l"] ** 2
        self.ep[0] = V_RATED / (lin["l"] * kx)  # p_ref: dipole at rated voltage
        if mech is not None:
            self._realise(mech, knobs, pil, kx)

    def _realise(self, mech, k, pil, kx):
        ep, lin, p_ref = self.ep, self.lin, self.ep[0]
        if mech in ("bouc-wen", "maxwell-slip", "duhem"):
            self.flags[1] = ("bouc-wen", "maxwell-slip", "duhem").index(mech) + 1
            ep[4] = k["h"]
            if mech == "bouc-wen":
                ep[5], ep[6], ep[7] = k["w"], k["beta"], k["n"]
            elif mech == "maxwell-slip":
                self.ms_f = k["h"] * kx * p_ref * k["w"]
                self.ms_k = self.ms_f / (k["rho"] * p_ref)
            else:
                ep[5], ep[6] = k["alpha"], k["beta"]
                self.stiff = 1 + 2 * k["h"] * k["alpha"]
        elif mech in ("kelvin-voigt", "log", "fractional"):
            tau, w = np.asarray(k["tau"]), np.asarray(k["w"])
            self.cr_tau = tau
            self.cr_r = k["r_T"] * w / np.sum(w * (1 - np.exp(-DURATION / tau)))
            self.info = {"r_n": self.cr_r.tolist(), "tau_n": tau.tolist()}
        elif mech == "tanh":
            self.flags[2] = 1
            ep[8] = pil["p_max"] / k["r_max"]
            self.stiff = 1 / (1 - k["r_max"] ** 2)
            self.info = {"p_s": ep[8]}
        elif mech == "polynomial":
            self.flags[2] = 2
            ep[8], ep[9], ep[10] = k["e2"], k["e3"], pil["p_max"]
            self.stiff = 1 + 2 * abs(k["e2"]) + 3 * k["e3"] * 1.5**2
        elif mech == "end-stop":
            self.flags[2] = 3
            ep[8] = pil["x_max"] * (1 - k["overshoot"])
            ep[9] = k["kappa"] * lin["K"]
            ep[10] = 0.01 * pil["x_max"]
            self.stiff = 1 + k["kappa"]
            self.info = {"x_stop": ep[8], "k_stop": ep[9]}
        elif mech == "series-resistance":
            self.lin["Re"] = lin["Re"] * k["ratio"]
        elif mech == "series-inductance":
            self.flags[0] = 1
            ep[1] = 1 / ((2 * np.pi * k["f_lc"]) ** 2 / (lin["iC"] + lin["a"] ** 2 * lin["K"]))
            self.info = {"L": ep[1]}
        elif mech == "amplifier-pole":  # second-order amplifier bandwidth
            self.flags[0] = 2
            ep[2] = 2 * np.pi * k["f_a"]
            ep[3] = k["zeta"]
        elif mech == "current-limit":  # amplifier output current saturating at i_max
            self.flags[0] = 3
            ep[1] = k["i_max"]
        else:
            self.flags[3] = ("shell", "base", "sensor-bracket").index(mech) + 1
            w2 = (2 * np.pi * k["f"]) ** 2
            if mech == "shell":  # output part mu*M on a frame flexure k_f
                mu = k["mu"]
                mred = mu * (1 - mu) * lin["M"]
                ep[11], ep[12], ep[13] = mu, w2 * mred, 2 * k["zeta"] * np.sqrt(w2) * mred
            elif mech == "base":  # base of mass m_b on a fixture spring k_b
                mb = k["mass_ratio"] * lin["M"]
                ep[11], ep[12], ep[13] = mb, w2 * mb, 2 * k["zeta"] * np.sqrt(w2) * mb
            else:  # sensor bracket, excited by the reaction force
                ep[11], ep[12], ep[13] = k["eps"], np.sqrt(w2), k["zeta"]

    def args(self):
        lin = self.lin
        la = np.array(
            [lin["Re"], lin["iC"], lin["a"], lin["K"], lin["c"], lin["M"], lin["l"], lin["iC"] / lin["l"] ** 2]
        )
        return la, self.flags, self.ep, self.cr_r, self.cr_tau, self.ms_k, self.ms_f

    def jacobian(self):
        """d(rhs)/d(state) at rest (central differences; exact for the linear terms)."""
        args = self.args()
        ns = 9 + self.cr_r.size
        J = np.zeros((ns, ns))
        ms_s = np.zeros(self.ms_k.size)
        for j in range(ns):
            for s in (1.0, -1.0):
                y = np.zeros(ns)
                y[j] = s * 1e-10
                d = np.zeros(ns)
                _rhs(y, 0.0, *args, ms_s, d)
                J[:, j] += s * d / 2e-10
        return J

    def n_sub(self, dt) -> int:
        """RK4 substeps per sample: |lambda| h <= 0.5 with the stiffness factor applied."""
        rho = np.abs(np.linalg.eigvals(self.jacobian())).max() * self.stiff
        return max(2, int(np.ceil(dt * rho / 0.5)))

    def new_modes(self):
        """Frequencies (Hz) and damping ratios of the lightly damped modes the cause adds."""
        lam = np.linalg.eigvals(self.jacobian())
        base = np.linalg.eigvals(linear_ss(self.lin)[0])
        extra = [z for z in lam if z.imag > 0 and np.min(np.abs(base - z)) > 1e-3 * abs(z)]
        return [(abs(z) / (2 * np.pi), -z.real / abs(z)) for z in extra if -z.real / abs(z) < 0.3]

    def simulate(self, V, dt) -> np.ndarray:
        """Noise-free sensor signal (m) at the samples of V (from rest)."""
        return _simulate(np.asarray(V, float), self.n_sub(dt), dt, *self.args())


@njit(cache=True)
def _softplus(z):
    return z + math.log1p(math.exp(-z)) if z > 0 else math.log1p(math.exp(z))


@njit(cache=True)
def _rhs(y, vc, lin, fl, ep, cr_r, cr_tau, ms_k, ms_f, ms_s, dy):
    Re, a, K, c, M, l, kx = lin[0], lin[2], lin[3], lin[4], lin[5], lin[6], lin[7]
    nc = cr_r.size
    Q, x, v = y[0], y[1], y[2]
    vs = y[4] if fl[0] == 2 else vc
    pc = 0.0
    for n in range(nc):
        pc += y[9 + n]
    p0 = l * Q - pc
    p_ref = ep[0]
    if fl[2] == 1:
        r = min(max(p0 / ep[8], -0.995), 0.995)
        E2 = kx * ep[8] * math.atanh(r)
    elif fl[2] == 2:
        u = p0 / ep[10]
        E2 = kx * p0 * (1.0 + ep[8] * u + ep[9] * u * u)
    else:
        E2 = kx * p0
    if fl[1] == 1:
        E2 += ep[4] * kx * p_ref * y[6]
    elif fl[1] == 2:
        for i in range(ms_k.size):
            E2 += min(max(ms_k[i] * (p0 - ms_s[i]), -ms_f[i]), ms_f[i])
    elif fl[1] == 3:
        E2 += ep[4] * kx * p_ref * ep[5] / (1.0 - ep[6]) * (p0 / p_ref - y[6])
    F1 = K * (a * Q - x)
    vC = l * E2 + a * F1
    if fl[0] == 1:
        dQ = y[3]
        dy[3] = (vs - Re * y[3] - vC) / ep[1]
    elif fl[0] == 3:
        dQ = ep[1] * math.tanh((vs - vC) / (Re * ep[1]))
    else:
        dQ = (vs - vC) / Re
    if fl[0] == 2:
        dy[4] = y[5]
        dy[5] = ep[2] * ep[2] * (vc - y[4]) - 2.0 * ep[3] * ep[2] * y[5]
    dpc = 0.0
    for n in range(nc):
        dy[9 + n] = (cr_r[n] * E2 / kx - y[9 + n]) / cr_tau[n]
        dpc += dy[9 + n]
    dp = (l * dQ - dpc) / p_ref
    if fl[1] == 1:
        z = y[6]
        sg = 1.0 if dp * z > 0 else -1.0
        dy[6] = dp / ep[5] * (1.0 - (ep[6] * sg + 1.0 - ep[6]) * abs(z) ** ep[7])
    elif fl[1] == 3:
        dy[6] = ep[5] * abs(dp) * (p0 / p_ref - y[6]) + ep[6] * dp
    else:
        dy[6] = 0.0
    dy[0] = dQ
    F = F1 - c * v
    if fl[2] == 3:
        F -= ep[9] * ep[10] * _softplus((x - ep[8]) / ep[10])
    dy[1] = v
    if fl[3] == 1:
        mu = ep[11]
        Fi = ep[12] * (x - y[7]) + ep[13] * (v - y[8])
        dy[2] = (F - Fi) / ((1.0 - mu) * M)
        dy[8] = Fi / (mu * M)
    elif fl[3] == 2:
        dvb = (-ep[12] * y[7] - ep[13] * y[8] - F) / ep[11]
        dy[2] = F / M - dvb
        dy[8] = dvb
    elif fl[3] == 3:
        dy[2] = F / M
        dy[8] = -ep[12] * ep[12] * y[7] - 2.0 * ep[13] * ep[12] * y[8] + ep[11] * F / M
    else:
        dy[2] = F / M
        dy[8] = 0.0
    dy[7] = y[8]


@njit(cache=True)
def _sensor(y, fl):
    if fl[3] == 1:
        return y[7]
    if fl[3] == 2:
        return y[1] + y[7]
    if fl[3] == 3:
        return y[1] - y[7]
    return y[1]


@njit(cache=True)
def _simulate(V, nsub, dt, lin, fl, ep, cr_r, cr_tau, ms_k, ms_f):
    ns = 9 + cr_r.size
    y = np.zeros(ns)
    tmp = np.zeros(ns)
    k1 = np.zeros(ns)
    k2 = np.zeros(ns)
    k3 = np.zeros(ns)
    k4 = np.zeros(ns)
    ms_s = np.zeros(ms_k.size)
    out = np.zeros(V.size)
    h = dt / nsub
    l = lin[6]
    for k in range(V.size - 1):
        v0 = V[k]
        dv = V[k + 1] - V[k]
        for j in range(nsub):
            va = v0 + dv * j / nsub
            vm = v0 + dv * (j + 0.5) / nsub
            vb = v0 + dv * (j + 1.0) / nsub
            _rhs(y, va, lin, fl, ep, cr_r, cr_tau, ms_k, ms_f, ms_s, k1)
            for i in range(ns):
                tmp[i] = y[i] + 0.5 * h * k1[i]
            _rhs(tmp, vm, lin, fl, ep, cr_r, cr_tau, ms_k, ms_f, ms_s, k2)
            for i in range(ns):
                tmp[i] = y[i] + 0.5 * h * k2[i]
            _rhs(tmp, vm, lin, fl, ep, cr_r, cr_tau, ms_k, ms_f, ms_s, k3)
            for i in range(ns):
                tmp[i] = y[i] + h * k3[i]
            _rhs(tmp, vb, lin, fl, ep, cr_r, cr_tau, ms_k, ms_f, ms_s, k4)
            for i in range(ns):
                y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            if ms_k.size:
                pc = 0.0
                for n in range(cr_r.size):
                    pc += y[9 + n]
                p0 = l * y[0] - pc
                for i in range(ms_k.size):
                    r = ms_f[i] / ms_k[i]
                    if p0 - ms_s[i] > r:
                        ms_s[i] = p0 - r
                    elif p0 - ms_s[i] < -r:
                        ms_s[i] = p0 + r
        out[k + 1] = _sensor(y, fl)
    return out
