"""Bimorph modal bond graphs (library.bimorph) and the model files of

* Ghafarirad, Rezaei, Sarhan, Zareinejad, "Continuous dynamic modelling of bimorph piezoelectric
  cantilevered actuators considering hysteresis effect and dynamic behaviour analysis", MCMDS
  21(2) (2015) 130-152 (T215 bimorph, models/bimorph_t215.py), and
* Shahabi, Ghafarirad, Taghvaeipour, "Nonlinear vibration analysis of piezoelectric bending
  actuators: theoretical and experimental studies", C. R. Mecanique 347(12) (2019) 953-966
  (T226 bimorph, models/bimorph_t226.py).

(a) Ghafarirad et al.: Table 2 natural frequencies and the 0.737 L minimum-phase boundary,
    through ``bondgraph linearize --json``;
(b) Shahabi et al.: time-domain steady state of the nonlinear single-mode model against the
    multiple-scales amplitude equation (eq. 54), the softening peak drift, and the reading of
    the identified coefficients' units;
(c) every CLI command on both model files.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from conftest import MODELS, ROOT
from scipy.optimize import brentq

import bondgraph as bg
from bondgraph.cli import main
from bondgraph.data import read_csv
from bondgraph.linear.linearize import linearize
from bondgraph.model.modelfile import load_model, read_model_module
from library.beam import T215_A4_103X, T226_H4_203X
from library.bimorph import (
    ModeNonlinearity,
    add_bimorph_modes,
    amplitude_equation_peak,
    amplitude_equation_phase,
    amplitude_equation_roots,
    effective_tip_mass,
    pi_operator,
)

T215 = str(MODELS / "bimorph_t215.py")
T226 = str(MODELS / "bimorph_t226.py")


def cli(capsys, *argv: str) -> str:
    """Run the CLI in-process; return stdout (exit status must be 0)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    assert code == 0, f"bondgraph {' '.join(argv)} exited {code}: {err}"
    return out


def cli_json(capsys, *argv: str) -> dict:
    return json.loads(cli(capsys, *argv))


# ---- (a) Ghafarirad et al. 2015: Table 2 and the non-minimum-phase boundary ------------------------------------
def test_table2_natural_frequencies_from_the_console_script():
    """`bondgraph linearize models/bimorph_t215.py --set modes=3 --json`: Table 2 within 0.5 %."""
    run = subprocess.run(
        [sys.executable, "-m", "bondgraph", "linearize", "models/bimorph_t215.py", "--set", "modes=3", "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    res = json.loads(run.stdout)
    np.testing.assert_allclose(res["natural_frequencies_rad_s"], [2249.0, 14094.24, 39464.29], rtol=5e-3)
    assert res["rhp_zeros"] == 0  # at 0.95 L the three-mode model is minimum phase too
    assert len(res["poles"]) == 6


@pytest.mark.parametrize("target, nmp", [(0.7, True), (0.9, False), (0.95, False)])
def test_rhp_zeros_depend_on_the_target_point(capsys, target, nmp):
    """Ghafarirad et al. 2015, Sec. 3.1 / 4.1: two modes, non-minimum phase at 0.7 L, minimum phase at 0.9 L, 0.95 L."""
    res = cli_json(capsys, "linearize", T215, "--set", f"target={target}", "--json")
    assert len(res["natural_frequencies_rad_s"]) == 2
    if nmp:
        assert res["rhp_zeros"] >= 1
    else:
        assert res["rhp_zeros"] == 0
        assert len(res["zeros"]) == 2  # the LHP pair that the paper's Fig. 13 shows


def test_minimum_phase_boundary_by_bisection(capsys):
    """The RHP zero disappears at l_t = 0.737 L (Ghafarirad et al. 2015, Fig. 8); 8 bisection steps on target."""

    def nmp(target):
        return cli_json(capsys, "linearize", T215, "--set", f"target={target!r}", "--json")["rhp_zeros"] > 0

    lo, hi = 0.70, 0.80
    assert nmp(lo) and not nmp(hi)
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if nmp(mid) else (lo, mid)
    assert abs(0.5 * (lo + hi) - 0.737) < 0.005
    # and the same boundary from the sign of a1 = 1 + mp2 phi2(lt) / (mp1 phi1(lt)) (Ghafarirad et al. 2015, eq. 38)
    modes = T215_A4_103X.modes(2)
    g = modes.input_gains
    a1 = lambda f: 1 + g[1] * modes.shape(1, f * T215_A4_103X.L) / (g[0] * modes.shape(0, f * T215_A4_103X.L))
    assert a1(lo) < 0 < a1(hi)


def test_modal_bond_graph_matches_the_beam_transfer_function():
    """The assembled graph (gains, signs, output) reproduces library.beam's w(l_t)/V exactly."""
    lm = load_model(T215, {"modes": 3, "target": 0.8})
    lin = linearize(bg.derive(lm.model))
    modes = T215_A4_103X.modes(3)
    num, den = modes.transfer_function(0.8 * T215_A4_103X.L, modes.damping_ratios(1e-3, 1e-5))
    w = np.array([100.0, 2247.4, 5000.0, 14084.2, 39436.2, 1e5])
    np.testing.assert_allclose(lin.frequency_response(w), np.polyval(num, 1j * w) / np.polyval(den, 1j * w), rtol=1e-9)


# ---- (b) Shahabi et al. 2019: multiple scales versus time-domain steady state ------------------------------------
LEVELS = (0.5, 2.0, 4.5)  # V, the paper's identification range 0.5-4.5 V
ABOVE = (0.0, 0.01, 0.02, 0.04)  # drive frequencies omega_peak (1 + d) on the resonant branch
CYCLES = 80  # from the multiple-scales state the transient is gone by ~40
PPC = 64  # samples per cycle for the Fourier projection


@pytest.fixture(scope="module")
def shahabi():
    """Simulated steady states of bimorph_t226 (nonlinear=true) near resonance at three drives."""
    lm = load_model(T226, {"nonlinear": True})
    sim = bg.Simulator(lm.model)
    tab = {str(k): v for k, v in lm.model.parameter_table().items()}
    wn, z, k1, k2, mu1, mp, phi = (tab[n] for n in ("omega_1", "zeta_1", "k1", "k2", "mu1", "mp_1", "phi_1"))
    s = read_model_module(T226)[0].modal_scale("charge", mp)  # the model's default reading
    k1, k2, mu1 = k1 * s**2, k2 * s**4, mu1 * s**2
    iq, ip = sim.state_names.index("q_spring_1"), sim.state_names.index("p_mass_1")

    def ms_state(V, w, a):
        """State of q = a cos(w t - gamma) at t = 0 (multiple scales, forcing mp V cos(w t))."""
        F = mp * V
        g = amplitude_equation_phase(a, w, wn, z, abs(F), k1, k2, mu1)
        x0 = np.zeros(2)
        x0[iq], x0[ip] = np.sign(F) * a * np.cos(g), np.sign(F) * a * w * np.sin(g)
        return x0

    def run(V, w, x0, cycles=CYCLES):
        """Simulate V cos(w t) from x0 for whole cycles; return the first-harmonic amplitude of x
        over the last 10 cycles (m) and the final state (at drive phase 0 again)."""
        t = np.linspace(0.0, cycles * 2 * np.pi / w, cycles * PPC + 1)
        res = sim.run(t, {"V": bg.Sine(V, w / (2 * np.pi), phase=90.0)}, x0=x0, rtol=1e-9)
        tt, x = t[-10 * PPC - 1 : -1], res["x"][-10 * PPC - 1 : -1]
        amp = float(np.hypot(2 * np.mean(x * np.cos(w * tt)), 2 * np.mean(x * np.sin(w * tt))))
        return amp, np.array([res.states[n][-1] for n in sim.state_names])

    out = {"wn": wn, "levels": {}}
    for V in LEVELS:
        F = abs(mp * V)
        w_pk, a_pk = amplitude_equation_peak(wn, z, F, k1, k2, mu1)
        rows = []
        for d in ABOVE:  # independent runs, each started on the multiple-scales resonant branch
            w = w_pk * (1 + d)
            a = amplitude_equation_roots(w, wn, z, F, k1, k2, mu1).max()
            rows.append((w, abs(phi) * a, run(V, w, ms_state(V, w, a))[0]))
        # slow downward sweep (each run starts from the previous end state) until the response
        # has fallen to half its maximum: the simulated peak frequency
        w = w_pk * 1.02
        x = ms_state(V, w, amplitude_equation_roots(w, wn, z, F, k1, k2, mu1).max())
        sweep = []
        for k in range(40):
            w = w_pk * (1.02 - 0.005 * k)
            amp, x = run(V, w, x, cycles=60)
            sweep.append((w, amp))
            if amp < 0.5 * max(a for _, a in sweep):
                break
        out["levels"][V] = {
            "w_peak": w_pk,
            "a_peak": a_pk,
            "rows": rows,
            "sweep": sweep,
            "w_sim": max(sweep, key=lambda r: r[1])[0],
        }
    return out


def test_shahabi_steady_state_agrees_with_multiple_scales(shahabi):
    """At and above the multiple-scales peak the simulated amplitude is within 3 % (measured <= 1.8 %).

    Below the peak first-order multiple scales is less accurate: it puts the jump too high in
    frequency and, on the lower branch, its detuning omega_n^2 - omega^2 ~ -2 sigma omega_n^2 is off by
    O(sigma) (2-5 % at these drives), so those frequencies are not compared."""
    for V, lev in shahabi["levels"].items():
        for w, x_ms, x_sim in lev["rows"]:
            assert abs(x_sim / x_ms - 1) < 0.03, f"V={V} V, omega={w:.1f} rad/s: sim {x_sim:.4e} m, MS {x_ms:.4e} m"


def test_shahabi_peak_drifts_down_with_drive(shahabi):
    """Softening: the simulated peak frequency (downward sweep) falls with the drive amplitude, as
    the multiple-scales peak does; at 0.5 V the two agree within the 0.5 % sweep step."""
    lev = shahabi["levels"]
    w_sim = [lev[V]["w_sim"] for V in LEVELS]
    w_ms = [lev[V]["w_peak"] for V in LEVELS]
    assert w_ms[0] < shahabi["wn"] and all(a > b for a, b in zip(w_ms, w_ms[1:]))
    assert w_sim[0] < shahabi["wn"] and all(a > b for a, b in zip(w_sim, w_sim[1:])), w_sim
    assert abs(w_sim[0] / w_ms[0] - 1) <= 0.0051
    for V in LEVELS:  # the sweep passed the peak: the response dropped (a jump above 0.5 V)
        amps = [a for _, a in lev[V]["sweep"]]
        assert amps[-1] < 0.5 * max(amps)


def test_amplitude_equation_linear_limit_and_peak():
    wn, z, F = 2637.0, 0.0085, 0.05
    for w in (2500.0, 2637.0, 2700.0):
        (a,) = amplitude_equation_roots(w, wn, z, F)
        sigma = w / wn - 1
        assert a == pytest.approx(F / (2 * wn * np.hypot(z * wn, sigma * wn)), rel=1e-9)
    k = dict(k1=-6.94e17, k2=1.443e28, mu1=6.28e13)
    w_pk, a_pk = amplitude_equation_peak(wn, z, F, **k)
    grid = np.linspace(0.95 * wn, 1.0 * wn, 501)
    best = max(amplitude_equation_roots(w, wn, z, F, **k).max() for w in grid)
    assert best == pytest.approx(a_pk, rel=1e-4) and w_pk < wn
    assert amplitude_equation_roots(w_pk, wn, z, F, **k).max() == pytest.approx(a_pk, rel=1e-3)


def _t226_peaks(reading, volts):
    """Multiple-scales peaks (rad/s) of the T226 model at the given drive amplitudes."""
    lm = load_model(T226, {"nonlinear": True, "coefficients": reading})
    tab = {str(k): v for k, v in lm.model.parameter_table().items()}
    s = lm.module.modal_scale(reading, tab["mp_1"])
    k = dict(k1=tab["k1"] * s**2, k2=tab["k2"] * s**4, mu1=tab["mu1"] * s**2)
    wn, z, mp = tab["omega_1"], tab["zeta_1"], abs(tab["mp_1"])
    peaks = [amplitude_equation_peak(wn, z, mp * V, **k)[0] for V in volts]

    def per_volt(w, V):
        return amplitude_equation_roots(w, wn, z, mp * V, **k).max() / V

    return np.array(peaks), per_volt, k


BAND = (2512.0, 2736.0)  # Sec. 4.3: the frequencies measured for identification and validation


def test_t226_coefficient_units_charge_reading_is_one_the_paper_allows():
    """Shahabi et al. 2019 never says on which coordinate its k1, k2, mu1 act. Read on the charge
    coordinate y = m_p q (models/bimorph_t226.py's default, one choice among those allowed: see
    the next test) every statement of the paper holds:
    Sec. 4.2, the 0.5 V chirp gives omega_n = 2637 rad/s (so the 0.5 V peak must sit there);
    Sec. 4.3, Figs. 5 and 10, identification (0.5-4.5 V) and validation (6, 8, 10 V) measured at
    2512-2736 rad/s; Fig. 9, at 2580 rad/s the amplitude grows faster than linear, at 2637 slower,
    the two frequencies lying 'below and above the first resonance'."""
    volts = [0.5, 1.5, 2.5, 3.5, 4.5, 6.0, 8.0, 10.0]
    peaks, per_volt, _ = _t226_peaks("charge", volts)
    print("\ncharge reading peaks:", dict(zip(volts, peaks.round(0))))
    assert peaks[0] == pytest.approx(2637.0, abs=2.0)
    assert np.all((peaks > BAND[0]) & (peaks < BAND[1]))
    assert peaks[volts.index(4.5)] == pytest.approx(2602.0, abs=1.0)
    assert peaks[volts.index(10.0)] == pytest.approx(2526.0, abs=1.0)
    ident = [0.5, 1.5, 2.5, 3.5, 4.5]
    below = [per_volt(2580.0, V) for V in ident]
    above = [per_volt(2637.0, V) for V in ident]
    assert all(a < b for a, b in zip(below, below[1:]))  # Fig. 9a: faster than linear
    assert all(a > b for a, b in zip(above, above[1:]))  # Fig. 9b: slower than linear
    assert np.all((peaks[:6] > 2580.0) & (peaks[:6] < 2637.0))  # Fig. 9 caption, 0.5-6 V


def test_t226_the_paper_bounds_the_coefficient_scale_but_does_not_fix_it():
    """With the coefficients on q written k1 s^2, k2 s^4, mu1 s^2, the paper's numbers (Sec. 4.2:
    the 0.5 V peak at 2637 rad/s; Sec. 4.3 / Figs. 5, 10: peaks at 0.5-10 V inside the measured
    2512-2736 rad/s; Fig. 9: at 2580 rad/s faster than linear, at 2637 slower) hold for every
    s up to 0.147, and to 0.136 if Fig. 9's caption keeps the 6 V peak above 2580 rad/s; they
    give no lower bound. The charge reading s = |m_p| = 0.133 is inside, not singled out."""
    lm = load_model(T226, {"nonlinear": True, "coefficients": "modal"})
    tab = {str(k): v for k, v in lm.model.parameter_table().items()}
    wn, z, mp = tab["omega_1"], tab["zeta_1"], abs(tab["mp_1"])
    K1, K2, MU1 = tab["k1"], tab["k2"], tab["mu1"]

    def peak(s, V):
        return amplitude_equation_peak(wn, z, mp * V, K1 * s**2, K2 * s**4, MU1 * s**2)[0]

    def statements_hold(s):
        volts = [0.5, 1.5, 2.5, 3.5, 4.5, 6.0, 8.0, 10.0]
        peaks = np.array([peak(s, V) for V in volts])
        k = dict(k1=K1 * s**2, k2=K2 * s**4, mu1=MU1 * s**2)
        ident = volts[:5]
        below = [amplitude_equation_roots(2580.0, wn, z, mp * V, **k).max() / V for V in ident]
        above = [amplitude_equation_roots(2637.0, wn, z, mp * V, **k).max() / V for V in ident]
        return (
            abs(peaks[0] - 2637.0) <= 2.0
            and np.all((peaks > BAND[0]) & (peaks < BAND[1]))
            and all(a < b for a, b in zip(below, below[1:]))
            and all(a > b for a, b in zip(above, above[1:]))
        )

    upper = brentq(lambda s: peak(s, 10.0) - BAND[0], 0.1, 0.2)
    caption = brentq(lambda s: peak(s, 6.0) - 2580.0, 0.1, 0.2)
    assert upper == pytest.approx(0.147, abs=5e-4) and caption == pytest.approx(0.136, abs=5e-4)
    assert mp == pytest.approx(0.133, abs=5e-4) and mp < caption < upper
    for s in (0.01, 0.05, 0.1, mp, 0.146):
        assert statements_hold(s), s
    assert not statements_hold(0.148)


def test_t226_coefficient_units_modal_reading_contradicts_the_paper():
    """The literal SI reading on the mass-normalised q puts the peaks at 2413 rad/s (2.5 V) and
    2253 rad/s (4.5 V), below the measured band, and the 0.5 V peak 1 % below the 2637 rad/s the
    paper identified at 0.5 V; every other unit reading (q as the tip displacement, x in [0, 1],
    the forcing scaled into V) scales the nonlinear terms up: the peaks leave the band even at
    0.5 V (down to 2308-2353 rad/s, or to 1309 rad/s and then far up once the quintic term
    dominates)."""
    peaks, per_volt, k = _t226_peaks("modal", [0.5, 2.5, 4.5, 10.0])
    assert peaks == pytest.approx([2611.0, 2413.0, 2253.0, 1936.0], abs=1.0)
    assert peaks[1] < BAND[0] and peaks[0] < 2637.0 - 20.0
    assert per_volt(2580.0, 4.5) < per_volt(2580.0, 0.5)  # contradicts Fig. 9a
    beam = T226_H4_203X
    modes = beam.modes(1)
    mp, phi_tip = abs(modes.input_gains[0]), modes.shape(0, beam.L)
    for s in (phi_tip, beam.L**-0.5, 1.0 / mp):  # tip metres, x in [0, 1], q / m_p
        assert s > 1.0
        for V in (0.5, 4.5):
            w, _ = amplitude_equation_peak(2637.0, 0.0085, mp * V, k["k1"] * s**2, k["k2"] * s**4, k["mu1"] * s**2)
            assert not BAND[0] < w < BAND[1]


# ---- (c) every CLI command on both model files --------------------------------------------------------
VARIANTS = [(T215, []), (T215, ["--set", "hysteresis=pi"]), (T226, []), (T226, ["--set", "nonlinear=true"])]
IDS = ["t215", "t215-pi", "t226", "t226-nonlinear"]


@pytest.mark.parametrize("model, sets", VARIANTS, ids=IDS)
def test_every_cli_command(capsys, tmp_path, model, sets):
    out = cli(capsys, "params", model, *sets)
    for name in ("omega_1", "zeta_1", "mp_1", "phi_1", "target"):
        assert name in out
    for fmt in ("text", "latex", "markdown"):
        text = cli(capsys, "equations", model, *sets, "--format", fmt)
        assert "omega" in text and "mp" in text and "phi" in text
    assert "bond" in cli(capsys, "causality", model, *sets)
    csv = tmp_path / "run.csv"
    cli(capsys, "simulate", model, *sets, "--out", str(csv), "--quiet")
    ds = read_csv(str(csv))
    assert {"V", "x"} <= set(ds.columns) and ds.t.size > 1000
    assert np.all(np.isfinite(ds.columns["x"])) and np.abs(ds.columns["x"]).max() > 1e-7
    res = cli_json(capsys, "linearize", model, *sets, "--json")
    assert res["input"] == "V" and res["output"] == "x" and res["natural_frequencies_rad_s"]
    assert {"poles", "zeros", "rhp_zeros"} <= set(res)


def test_model_parameters_and_options(capsys):
    assert "2637" in cli(capsys, "params", T226)
    comp = cli_json(capsys, "linearize", T226, "--set", "frequency=computed", "--json")
    assert comp["natural_frequencies_rad_s"][0] == pytest.approx(2915.5, rel=1e-4)  # Table 1, exact modes
    meas = cli_json(capsys, "linearize", T226, "--json")
    assert meas["natural_frequencies_rad_s"][0] == pytest.approx(2637.0, rel=1e-9)
    assert meas["damping_ratios"][0] == pytest.approx(0.0085, rel=1e-9)
    # nonlinear terms are parameters only when switched on; unknown names are usage errors
    assert "mu1" in cli(capsys, "params", T226, "--set", "nonlinear=true")
    assert main(["params", T226, "--set", "k1=1"]) == 2
    assert "unknown parameter 'k1'" in capsys.readouterr().err
    assert main(["params", T215, "--set", "hysteresis=bouc"]) == 2
    assert "none, pi" in capsys.readouterr().err


def test_pi_hysteresis_is_the_identity_at_small_drive(tmp_path, capsys):
    """H[V] has slope 1 below the first nonzero threshold (10 V): the 0.3 V chirp is unchanged."""
    paths = []
    for sets in ([], ["--set", "hysteresis=pi"]):
        paths.append(tmp_path / f"run{len(paths)}.csv")
        cli(capsys, "simulate", T215, *sets, "--t-end", "0.05", "--out", str(paths[-1]), "--quiet")
    x0, x1 = (read_csv(str(p)).columns["x"] for p in paths)
    assert np.max(np.abs(x1 - x0)) < 1e-4 * np.max(np.abs(x0))


def test_pi_operator_is_loaded_lazily(monkeypatch):
    monkeypatch.setitem(sys.modules, "library.hysteresis", None)
    with pytest.raises(bg.ModelError, match="hysteresis"):
        pi_operator([0.0, 1.0], [1.0, 0.1])


# ---- library details -------------------------------------------------------------------------------------
def test_per_mode_nonlinearity_and_parameters():
    m = bg.Model("two")
    info = add_bimorph_modes(
        m, T226_H4_203X, 2, 1.0, alpha=1e-3, beta=1e-5, nonlinear={2: ModeNonlinearity(k1=-1e17, mu1=1e13)}
    )
    assert {"k1_2", "k2_2", "mu1_2"} <= set(m.parameters) and "k1_1" not in m.parameters
    rates = bg.derive(m).state_equations()
    p2 = [s for s in rates if str(s) == "p_mass_2"][0]
    text = str(rates[p2])
    assert "k1_2" in text and "mu1_2" in text and "k1_1" not in str(rates)
    assert info.values["omega_1"] == pytest.approx(T226_H4_203X.modes(1).omegas[0])
    with pytest.raises(bg.ModelError):
        add_bimorph_modes(bg.Model("bad"), T226_H4_203X, 1, 1.5)


def test_effective_tip_mass():
    m = T226_H4_203X.mass
    assert effective_tip_mass(T226_H4_203X) == pytest.approx(33 / 140 * m, rel=1e-9)  # Wood et al. 2005, eq. 6
    assert effective_tip_mass(T226_H4_203X, mode=1) == pytest.approx(m / 4, rel=1e-6)  # 1/phi_1(L)^2


def test_t226_figure_resonance_curves_and_eq54_peaks(capsys, tmp_path):
    """The figure of docs/papers.md (one command): resonance curves at 0.5-10 V (Sec. 4.3's
    identification and validation levels) from eq. 54, their peaks drifting down with the drive
    (softening; Fig. 8), and simulated slow downward sweeps of the model at 4.5 and 10 V whose
    peaks fall within the 10 rad/s sweep step of eq. 54's."""
    png = tmp_path / "t226.png"
    out = cli_json(capsys, "figure", T226, "resonance", "--plot", str(png), "--json")
    n = out["numbers"]
    peaks = [n[f"eq. 54 peak at {V:g} V (rad/s)"] for V in (0.5, 2.5, 4.5, 6.0, 8.0, 10.0)]
    assert peaks == pytest.approx([2636.0, 2624.0, 2602.0, 2582.0, 2554.0, 2526.0], abs=1.0)
    assert all(BAND[0] < w < BAND[1] for w in peaks)
    for V in (4.5, 10.0):
        assert abs(n[f"simulated peak at {V:g} V (rad/s)"] - n[f"eq. 54 peak at {V:g} V (rad/s)"]) <= 10.0
    assert n["eq. 54 peak amplitude at 4.5 V (um)"] == pytest.approx(295.1, abs=0.5)
    assert png.stat().st_size > 10000


def test_t215_figure_bode_and_the_nmp_boundary(capsys, tmp_path):
    """The figure of docs/papers.md (one command): Bode diagrams at the paper's target points,
    minimum phase at 0.95 L and 0.9 L and a right-half-plane zero at 0.7 L (Ghafarirad et al.
    2015, Sec. 3.1, Fig. 8), and the boundary 0.737 L where eq. 38's a1 changes sign."""
    png = tmp_path / "t215.png"
    n = cli_json(capsys, "figure", T215, "bode", "--plot", str(png), "--json")["numbers"]
    assert n["RHP zeros at 0.95 L"] == 0 and n["RHP zeros at 0.9 L"] == 0 and n["RHP zeros at 0.7 L"] == 1
    assert n["minimum-phase boundary (fraction of L)"] == pytest.approx(0.7371, abs=2e-4)
    assert n["RHP zero at 0.7 L (rad/s)"] == pytest.approx(15926.0, rel=1e-3)
    assert png.stat().st_size > 10000
