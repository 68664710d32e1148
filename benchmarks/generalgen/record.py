"""One seed, one record: the draw (no simulation), the truth's simulation, the visibility
rule, the sensor, and the files.

Streams (``numpy.random.default_rng`` on a ``SeedSequence`` of ``[seed, k]``, PCG64, the same
numbers on every machine): ``k = 0`` the system, its detuning, the sample rate and length;
``1`` the drive; ``2`` the cause, site and form; ``3`` the sensor and noise levels; ``4, a``
the effect's parameters on attempt ``a``; ``5`` the noise itself.  The cause of a seed is
therefore known from :func:`draw` alone, and a redraw for visibility changes only the
effect's strength, never its cause, site or form.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.fft

from .drives import Drive, draw_drive
from .effects import EffectDraw, Scales, apply_effect, draw_effect
from .network import Network, drive_spectrum, integrate
from .systems import SYSTEMS, System
from .visibility import RATIO, flexible_linear_residual, recalibrated_residual

FS_CHOICES = (1000.0, 2000.0, 5000.0, 10000.0, 20000.0, 50000.0)
N_MIN, N_MAX = 10_000, 150_000
#: attempts at a visible effect; attempt a draws its parameters anew at strength 1.6**a
ATTEMPTS = 6
BOOST = 1.6
DEVELOPMENT = range(0, 100)
HELD_OUT = range(1000, 1200)


def seed_set(seed: int) -> str:
    """``development``, ``held-out`` or ``other`` (see ``PROTOCOL.md``)."""
    return "development" if seed in DEVELOPMENT else "held-out" if seed in HELD_OUT else "other"


def _rng(seed: int, *stream: int) -> np.random.Generator:
    return np.random.default_rng([seed, *stream])


@dataclass
class Draw:
    """Everything a seed decides before any simulation."""

    seed: int
    system: System
    params: dict  # the truth's linear parameters (model-file names)
    model_params: dict  # the model file's values
    fs: float
    n: int
    drive: Drive
    effect: EffectDraw
    noise: dict

    @property
    def name(self) -> str:
        return f"gen3_{self.seed}"


def draw(seed: int) -> Draw:
    """The seed's system, detuning, sampling, drive, effect and noise levels (no simulation).

    Parameters
    ----------
    seed : int
        A non-negative integer.

    Returns
    -------
    Draw

    Raises
    ------
    ValueError
        If ``seed`` is negative or not an integer.
    """
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"a seed is a non-negative integer, not {seed!r}")
    seed = int(seed)
    rs = _rng(seed, 0)
    names = sorted(SYSTEMS)
    system = SYSTEMS[names[rs.integers(len(names))]]
    model = system.defaults()
    # the device: each linear parameter off the model file's by a factor within its tolerance
    params = {k: v * system.tolerance(k) ** rs.uniform(-0.85, 0.85) for k, v in model.items()}
    w, _ = system.network(model).modes()
    f1, f_top = w[0] / (2 * np.pi), w[-1] / (2 * np.pi)
    allowed = [fs for fs in FS_CHOICES if fs >= 30 * f_top and 30 * fs / f1 <= N_MAX]
    fs = allowed[rs.integers(len(allowed))]
    lo, hi = max(N_MIN, 30 * fs / f1), min(N_MAX, 1500 * fs / f1)
    n = int(np.exp(rs.uniform(np.log(lo), np.log(hi)))) // 8 * 8
    drive = draw_drive(_rng(seed, 1), system.drive_level, f1, f_top, fs, n)
    effect = draw_effect(_rng(seed, 2), system)
    rn = _rng(seed, 3)
    noise = dict(
        relative=float(np.exp(rn.uniform(np.log(3e-4), np.log(1e-2)))),
        white_share=float(rn.uniform(0.4, 1.0)),
        colour=("pink", "low-pass")[rn.integers(2)],
        corner_hz=float(fs * np.exp(rn.uniform(np.log(0.005), np.log(0.1)))),
        jitter_s=float(rn.uniform(0.0, 0.003) / fs),
        gain=float(np.exp(rn.uniform(-0.03, 0.03))),
        offset_share=float(rn.uniform(-0.2, 0.2)),
    )
    return Draw(seed, system, params, model, fs, n, drive, effect, noise)


def _oversampling(net: Network, fs: float) -> int:
    """Integration steps per sample: at least 16, and h·ω_max at most 0.06."""
    return int(max(16, np.ceil(net.modes()[0][-1] / (0.06 * fs))))


def _coloured(rng, n: int, fs: float, colour: str, corner: float) -> np.ndarray:
    """Unit-RMS coloured Gaussian noise: 1/f (pink) or white through a first-order low-pass."""
    X = scipy.fft.rfft(rng.standard_normal(n))
    f = np.arange(X.size) * fs / n
    if colour == "pink":
        shape = 1 / np.sqrt(np.maximum(f, fs / n))
    else:
        shape = 1 / np.sqrt(1 + (f / corner) ** 2)
    shape[0] = 0.0
    x = scipy.fft.irfft(X * shape, n=n)
    return x / np.sqrt(np.mean(x**2))


@dataclass
class Record:
    """A realised record: sample times, drive and measured output, and the truth label."""

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    truth: dict


def realize(d: Draw) -> Record:
    """Simulate the seed's truth, apply the visibility rule and the sensor.

    Parameters
    ----------
    d : Draw

    Returns
    -------
    Record
    """
    sysm, n, fs = d.system, d.n, d.fs
    dt = 1.0 / fs
    t = np.arange(n) * dt
    net0 = sysm.network(d.params)
    omegas, zetas = net0.modes()
    os0 = _oversampling(net0, fs)
    drives = {os0: d.drive.evaluate(dt, n, 2 * os0)}
    lin = integrate(net0, drives[os0], dt / os0, os0)
    y_lin = lin.y[:n]
    u = drives[os0][:: 2 * os0][:n]
    sc = Scales(
        elongation=np.percentile(np.abs(lin.elongation[:, :n]), 99, axis=1),
        velocity=np.percentile(np.abs(lin.velocity[:, :n]), 99, axis=1),
        drive=float(np.percentile(np.abs(u), 99)),
        output_rms=float(np.std(y_lin)),
        duration=n * dt,
    )
    # the slowest ring-down to 1e-11 (25 time constants), including added modes' (zeta >= 0.005)
    decay = 25.0 / min(np.min(zetas * omegas), 0.005 * omegas[-1])
    spec = drive_spectrum(d.drive.evaluate(dt, n, 4), 4, n, dt, decay)

    nz = d.noise
    gain = nz["gain"]
    offset = nz["offset_share"] * sc.output_rms
    rz = _rng(d.seed, 5)
    sigma = nz["relative"] * sc.output_rms * gain
    white = rz.standard_normal(n)
    coloured = _coloured(rz, n, fs, nz["colour"], nz["corner_hz"])
    base_noise = sigma * (np.sqrt(nz["white_share"]) * white + np.sqrt(1 - nz["white_share"]) * coloured)
    delta = nz["jitter_s"] * rz.standard_normal(n)

    eff = d.effect
    vis: dict = {"rule": f"unexplained RMS >= {RATIO:g} x noise RMS", "attempts": 0, "diverged": 0}
    kept = None  # the last attempt whose simulation stayed finite
    for attempt in range(ATTEMPTS if eff.cause != "none" else 1):
        boost = BOOST**attempt
        app = apply_effect(net0, eff, sc, t, fs, dt / os0, _rng(d.seed, 4, attempt), boost)
        os1 = _oversampling(app.network, fs)
        if os1 not in drives:
            drives[os1] = d.drive.evaluate(dt, n, 2 * os1)
        tr = lin if eff.cause in ("none", "drift") else integrate(app.network, drives[os1], dt / os1, os1)
        clean = gain * tr.y[:n] + offset + (app.drift if app.drift is not None else 0.0)
        noise = base_noise + gain * delta * tr.y_rate()[:n]
        vis.update(attempts=attempt + 1, boost=boost)
        if not (np.all(np.isfinite(clean)) and np.all(np.isfinite(noise))):
            vis["diverged"] += 1  # a redraw, like an invisible one
            continue
        noise_rms = float(np.sqrt(np.mean(noise**2)))
        kept = (clean, noise, noise_rms, app)
        vis["noise_rms"] = noise_rms
        if eff.cause == "none":
            break
        if eff.cause == "higher-mode":
            f_top = max(d.drive.top_frequency(), app.network.modes()[0][-1] / (2 * np.pi))
            res = min((recalibrated_residual(clean, spec, s, f_top) for s in app.reduced), key=lambda r: np.mean(r**2))
            ratio = float(np.sqrt(np.mean(res**2))) / noise_rms
            vis["residual_rms_model_structure"] = float(np.sqrt(np.mean(res**2)))
            if app.partial:
                res2 = min(
                    (recalibrated_residual(clean, spec, s, f_top) for s in app.partial), key=lambda r: np.mean(r**2)
                )
                vis["residual_rms_one_mode_back"] = float(np.sqrt(np.mean(res2**2)))
                ratio = min(ratio, vis["residual_rms_one_mode_back"] / noise_rms)
            vis["basis"] = "recalibrated model-file structure (and with one missing mode back)"
        else:
            res = flexible_linear_residual(clean, gain * y_lin, spec, net0, omegas[0] / (2 * np.pi))
            vis["residual_rms_flexible_linear"] = float(np.sqrt(np.mean(res**2)))
            ratio = vis["residual_rms_flexible_linear"] / noise_rms
            vis["basis"] = "flexible linear model from the drive"
        vis["ratio"] = ratio
        if ratio >= RATIO:
            break
    if kept is None:
        raise RuntimeError(f"seed {d.seed}: the truth's simulation diverged on every attempt")
    clean, noise, noise_rms, app = kept
    vis["visible"] = bool(eff.cause == "none" or vis.get("ratio", 0.0) >= RATIO)
    y = clean + noise
    truth = _truth(d, eff, app.parameters, app.network, vis, noise_rms, delta)
    return Record(t, u, y, truth)


def _hz(w) -> list:
    return [float(x) / (2 * np.pi) for x in w]


def _truth(d: Draw, eff: EffectDraw, parameters, network, vis, noise_rms, delta) -> dict:
    sysm = d.system
    truth = {
        "record": d.name,
        "seed": d.seed,
        "set": seed_set(d.seed),
        "system": sysm.name,
        "model": f"{sysm.name}.py",
        "model_source": f"benchmarks/generalgen/models/{sysm.name}.py",
        "input": sysm.input,
        "output": sysm.output,
        "cause": eff.cause,
        "site": eff.site or None,
        "site_aliases": _aliases(sysm, eff),
        "effect": None if eff.cause == "none" else {"form": eff.form, "parameters": _plain(parameters)},
        "visible": vis["visible"],
        "visibility": vis,
        "fs": d.fs,
        "samples": d.n,
        "duration_s": d.n / d.fs,
        "drive": _plain(d.drive.summary()),
        "drive_label": d.drive.describe(),
        "noise": {**d.noise, "total_rms": noise_rms, "jitter_rms": float(np.sqrt(np.mean(delta**2)))},
        "true_params": d.params,
        "model_params": d.model_params,
        "detune": {k: d.params[k] / d.model_params[k] for k in d.params},
        "model_modes_hz": _hz(sysm.network(d.model_params).modes()[0]),
        "truth_linear_modes_hz": _hz(network.modes()[0]),
    }
    if eff.cause == "higher-mode":
        truth["count"] = eff.count
    return truth


def _aliases(sysm: System, eff: EffectDraw) -> list:
    """Other names the diagnosis may give the same site."""
    if eff.site == "drive":
        return ["drive", sysm.drive_element, sysm.input]
    if eff.cause == "drift":
        return [sysm.output, "sensor"]
    return [eff.site] if eff.site else []


def _plain(obj):
    """``obj`` with numpy scalars and arrays made JSON-serialisable."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _short(x: np.ndarray) -> np.ndarray:
    """``x`` rounded to 10 significant digits (short in the CSV, far below the noise)."""
    return np.array([float(s) for s in np.char.mod("%.10g", x)])


def write(record: Record, d: Draw, out_dir: str | os.PathLike) -> tuple[Path, Path, Path]:
    """Write ``<out>/gen3_<seed>.csv``, ``<out>/gen3_<seed>.truth.json`` and a copy of the
    model file ``<out>/<system>.py``; return their paths.  The CSV holds only the time, the
    drive and the measured output (and the record's name): nothing of the truth."""
    from bondgraph.data import write_csv
    from bondgraph.support.atomic import atomic_write

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv = out / f"{d.name}.csv"
    sysm = d.system
    write_csv(
        csv,
        record.t,
        {sysm.input: _short(record.u), sysm.output: _short(record.y)},
        {"record": d.name, "source": "benchmarks/generalgen"},
    )
    truth = out / f"{d.name}.truth.json"
    with atomic_write(truth) as f:
        json.dump(_plain(record.truth), f, indent=1)
    model = out / sysm.model_file.name
    if not model.exists() or model.read_bytes() != sysm.model_file.read_bytes():
        with atomic_write(model) as f:
            f.write(sysm.model_file.read_text(encoding="utf-8"))
    return csv, truth, model


def generate(seed: int, out_dir: str | os.PathLike) -> tuple[Path, Path, Path]:
    """Draw, simulate and write one seed's record (see :func:`write`)."""
    d = draw(seed)
    return write(realize(d), d, out_dir)


__all__ = ["Draw", "Record", "draw", "realize", "write", "generate", "seed_set"]
