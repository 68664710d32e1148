"""Truth models and synthetic measurements for the diagnosis tests.

Every truth device differs from the nominal model file in its linear parameters (10-30 %)
and in one hidden effect, built here *independently* of the extension the diagnosis uses for
it (Bouc–Wen polarization hysteresis vs. the diagnosis' Prandtl–Ishlinskii at the input; a
Kelvin–Voigt chain in the polarization domain vs. one on the drive; a saturating polarization
law vs. a drive polynomial; a second mass vs. a parallel resonator; quadratic velocity damping
vs. Stanton damping; a second beam mode vs. a parallel resonator ...), then simulated and
sampled with white sensor noise.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl
import sympy as sp
from conftest import MODELS

import bondgraph as bg
from bondgraph import J0, J1, C, I, Quantity, R, Se
from bondgraph.data import Dataset
from bondgraph.model.modelfile import load_model
from library.hysteresis import MaxwellSlip
from library.piezo import piezo_layer

APA_CHANGES = {"a": 1.2, "K": 0.8, "c": 1.25, "M": 1.15, "Re": 1.2}
T226_CHANGES = {"omega_1": 0.85, "zeta_1": 1.3, "mp_1": 1.2}


# ---- excitations ------------------------------------------------------------------------------
def apa_drive(t: np.ndarray) -> np.ndarray:
    """Quasi-static sines at two rates and amplitudes, step holds, and a chirp (volts)."""
    T = t[-1]
    v = np.zeros_like(t)
    seg = [0.3 * T, 0.45 * T, 0.75 * T]
    a = t < seg[0]
    v[a] = 60 - 55 * np.cos(2 * np.pi * 2.0 * t[a])
    b = (t >= seg[0]) & (t < seg[1])
    v[b] = 60 - 25 * np.cos(2 * np.pi * 12.0 * (t[b] - seg[0]))
    c = (t >= seg[1]) & (t < seg[2])
    tc = t[c] - seg[1]
    levels = np.array([90.0, 20.0, 110.0, 40.0])
    v[c] = levels[np.minimum((tc / ((seg[2] - seg[1]) / 4)).astype(int), 3)]
    d = t >= seg[2]
    td = t[d] - seg[2]
    span = T - seg[2]
    v[d] = 60 + 20 * np.sin(2 * np.pi * (2 * td + 0.5 * (1500 - 2) / span * td**2))
    return _smooth_edges(t, v)


def bimorph_drive(t: np.ndarray, omega_n: float) -> np.ndarray:
    """A broadband chirp through the first two modes, then sine dwells at and around resonance
    at three amplitudes (volts)."""
    T = t[-1]
    v = np.zeros_like(t)
    f_n = omega_n / (2 * np.pi)
    t1 = 0.4 * T
    a = t < t1
    v[a] = 1.0 * np.sin(2 * np.pi * (0.1 * f_n * t[a] + 0.5 * (8 * f_n - 0.1 * f_n) / t1 * t[a] ** 2))
    rest = ~a
    tr = t[rest] - t1
    n_dwell = 9
    dwell = (T - t1) / n_dwell
    k = np.minimum((tr / dwell).astype(int), n_dwell - 1)
    amps = np.array([0.2, 0.5, 1.0])[k // 3]
    freqs = f_n * np.array([0.95, 1.0, 1.03])[k % 3]
    ph = 2 * np.pi * np.cumsum(freqs) * (t[1] - t[0])
    v[rest] = amps * np.sin(ph)
    return _smooth_edges(t, v)


def _smooth_edges(t, v, width=2e-3):
    """Soften jumps to a few samples' ramp (a real amplifier's slew), keeping the signal shape."""
    n = max(1, int(width / (t[1] - t[0])))
    kern = np.ones(n) / n
    return np.convolve(np.pad(v, (n - 1, 0), mode="edge"), kern, mode="valid")


def measure(model: bg.Model, t: np.ndarray, V: np.ndarray, noise: float, seed: int = 0) -> Dataset:
    res = bg.simulate(model, t, {"V": bg.PiecewiseLinear(t, V)}, rtol=1e-8)
    x = res["x"] + np.random.default_rng(seed).normal(0.0, noise, t.size)
    return Dataset(t, {"V": V, "x": x}, {"truth": model.name})


# ---- APA-like truths ----------------------------------------------------------------------------
def apa_truth(effect: str, changes: dict = APA_CHANGES) -> bg.Model:
    """The APA-120ML with changed linear parameters (factors) and one hidden effect, built from elements."""
    lm = load_model(
        MODELS / "apa120ml.py", {k: f * load_model(MODELS / "apa120ml.py").params.value(k) for k, f in changes.items()}
    )
    p = lm.params
    if effect == "electrical-rc":
        p.set("Re", 400.0)
    g = bg.Model(f"APA truth ({effect})")
    V = g.input("V", "V")
    kx, l, a, K = p.value("kx"), p.value("l"), p.value("a"), p.value("K")

    def pol(c, n):
        if effect == "hysteresis":  # E = kx·p + Maxwell-slip field of the dipole (4 slip branches)
            ms = MaxwellSlip([1.2e12, 0.9e12, 0.6e12, 0.4e12], [0.9e4, 2.5e4, 5e4, 8e4])
            h = c.operator("H", ms, Quantity("q", n))
            return c.add(C(n, law=lambda q: kx * q + h))
        if effect == "saturation":  # polarization saturates: E = kx·p·(1 + (p/p_s)²)
            ps = 1.6e-7
            return c.add(C(n, law=lambda q: kx * q * (1 + (q / ps) ** 2)))
        if effect == "creep":  # Kelvin–Voigt cells in series with C_NL (same field, dipoles add)
            c.add(C(n, 1 / kx))
            return None
        return c.add(C(n, 1 / kx))

    layer = piezo_layer("stack", l=l, a=a, K=K, R_NL=p.value("c"), polarization=pol)
    if effect == "creep":
        # replace the bond pol → C_NL by pol → 0(creep) → {C_NL, cells}
        layer.unbond("pol", "C_NL")
        layer.add(J0("cr"))
        layer.bond("pol", "cr")
        layer.bond("cr", "C_NL")
        for k, (ratio, tau) in enumerate([(0.08, 0.25), (0.07, 2.0)]):
            Ck = ratio / kx
            layer.add(J1(f"cell{k}"), C(f"Cc{k}", Ck), R(f"Rc{k}", tau / Ck))
            layer.bond("cr", f"cell{k}")
            layer.bond(f"cell{k}", f"Cc{k}")
            layer.bond(f"cell{k}", f"Rc{k}")
    g.add(layer)
    g.add(Se("amp", V), J1("i"), R("Re", p.value("Re")), I("M", p.value("M")))
    g.chain("amp", "i", "stack.elec")
    g.bond("i", "Re")
    x = a / l * Quantity("q", "stack.C_NL") - Quantity("q", "stack.K")
    if effect == "creep":
        x += sum(a / l * Quantity("q", f"stack.Cc{k}") for k in range(2))
    if effect == "higher-mode":  # the output plate is a second mass on a spring (shell mode ~ 900 Hz)
        g.add(J0("shell"), C("ks", 1 / 2.5e6), J1("plate"), I("mp", 0.04), R("cs", 8.0))
        g.bond("stack.mech", "M")
        g.bond("stack.mech", "shell")
        g.bond("shell", "ks")
        g.bond("shell", "plate")
        g.bond("plate", "mp")
        g.bond("plate", "cs")
        x = g.displacement("plate")
    else:
        g.bond("stack.mech", "M")
    g.output("x", x, "m")
    return g


def apa_data(effect: str, duration: float = 6.0, rate: float = 5000.0, noise: float = 3e-8, seed: int = 0):
    t = np.arange(int(duration * rate) + 1) / rate
    return measure(apa_truth(effect), t, apa_drive(t), noise, seed)


# ---- bimorph-like truths -------------------------------------------------------------------------
def t226_truth(effect: str, changes: dict = T226_CHANGES) -> bg.Model:
    """The T226 bimorph's first mode with changed modal parameters (factors) and one hidden effect."""
    base = load_model(MODELS / "bimorph_t226.py").model
    table = {str(k): v for k, v in base.parameter_table().items()}
    w = table["omega_1"] * changes["omega_1"]
    z = table["zeta_1"] * changes["zeta_1"]
    mp = table["mp_1"] * changes["mp_1"]
    phi = table["phi_1"]
    g = bg.Model(f"bimorph truth ({effect})")
    V = g.input("V", "V")
    drive = V
    if effect == "hysteresis":  # Bouc–Wen on the drive (a DE-based operator, not the PI of the diagnosis)
        zb = g.state("bw.z", 0)
        Vdot = sp.Symbol("dV/dt", real=True)
        g.set_rate("bw.z", 0.35 * (Vdot - 0.5 * sp.Abs(Vdot) * zb - 0.5 * Vdot * sp.Abs(zb)))
        drive = 0.8 * V + 0.5 * zb
    g.add(Se("force", mp * drive), J1("mode"), I("mass", 1))
    if effect == "softening":  # Shahabi et al. (2019)'s cubic and quintic modal stiffness
        g.add(C("spring", energy=lambda q: w**2 * q**2 / 2 - 6.94e17 * q**4 / 4 + 1.443e28 * q**6 / 6))
    else:
        g.add(C("spring", 1 / w**2))
    if effect == "nonlinear-damping":  # damping growing with the amplitude |q| (loss per cycle ∝ q³)
        q = Quantity("q", "spring")
        g.add(R("damper", law=lambda f: (2 * z * w + 2.0e7 * sp.Abs(q)) * f))
    else:
        g.add(R("damper", 2 * z * w))
    g.bond("force", "mode")
    for e in ("mass", "spring", "damper"):
        g.bond("mode", e)
    x = phi * g.displacement("spring")
    if effect == "higher-mode":  # the second bending mode of the same beam, ratio 6.27 (uniform beam)
        w2, z2 = 6.27 * w, 0.012
        g.add(
            Se("force2", -1.5 * mp * drive),
            J1("mode2"),
            I("mass2", 1),
            C("spring2", 1 / w2**2),
            R("damper2", 2 * z2 * w2),
        )
        g.bond("force2", "mode2")
        for e in ("mass2", "spring2", "damper2"):
            g.bond("mode2", e)
        x = x + phi * g.displacement("spring2")
    g.output("x", x, "m")
    return g


def t226_data(effect: str, duration: float = 2.0, rate: float = 20000.0, noise: float = 1e-8, seed: int = 0):
    t = np.arange(int(duration * rate) + 1) / rate
    base = load_model(MODELS / "bimorph_t226.py").model
    w = {str(k): v for k, v in base.parameter_table().items()}["omega_1"] * T226_CHANGES["omega_1"]
    return measure(t226_truth(effect), t, bimorph_drive(t, w), noise, seed)


# ---- exact references ---------------------------------------------------------------------------
def exact_step_response(sim, t, inputs):
    """The first output of a linear model with one driven input (the first) whose drive is
    constant between samples (a step on the sample grid): x_{k+1} = Φ·x_k + Γ·V_k with Φ, Γ
    from one matrix exponential is exact, no integrator involved."""
    th = sim.theta()
    nu = len(sim.input_names)
    x = sim.initial_state(th)
    bank = sim.signal_bank(inputs)
    A = sim.jacobian_at(0.0, x, th, np.zeros(1), bank)
    aux = sim.compiled.aux.copy()

    def rates(V):
        out = np.zeros(x.size)
        sim.compiled.rhs(0.0, np.zeros(x.size), np.r_[V, np.zeros(nu - 1)], np.zeros(nu), th, np.zeros(1), aux, out)
        return out

    B = rates(1.0) - rates(0.0)
    dt = t[1] - t[0]
    M = np.zeros((x.size + 1, x.size + 1))
    M[:-1, :-1], M[:-1, -1] = A * dt, B * dt
    E = sl.expm(M)
    V = bank.sample(t)[:, 0]
    y = np.zeros(t.size)
    for k in range(t.size - 1):
        x = E[:-1, :-1] @ x + E[:-1, -1] * V[k]
        out = np.zeros(len(sim.output_names))
        sim.compiled.output(0.0, x, np.zeros(nu), np.zeros(nu), th, np.zeros(1), aux, out)
        y[k + 1] = out[0]
    return y
