"""How the recorded drive is read between its samples.

A sampled drive says nothing of what it did between samples.  An anti-aliased acquisition of a
smooth analog voltage is *band-limited*; a DAC that interpolates linearly, or a simulation with
a first-order hold, makes a drive that is *linear* between its samples.  Through a mode at
0.3 fs the two readings differ by 1/sinc²(0.3) = 1.38× in the response, and a linear structural
candidate (an RLC input stage, an added mode) can pass by absorbing the difference.  The
diagnosis reads the drive band-limited and, when the two readings change the calibrated
model's output by more than half the noise floor, diagnoses the record under both and keeps
the reading whose final model fits better (fewer causes when the two fit alike).

Truths here: the APA-120ML model file itself at off-nominal values (nothing hidden), driven by
noise up to 0.4 fs, simulated by the compiled integrator (an independent route) from a drive
that is linear between the recorded samples, or from a band-limited drive on a grid 8× finer
of which every 8th sample is recorded."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import bondgraph as bg
from bondgraph.data import Dataset
from bondgraph.data.sampling import interpolation_compensated
from bondgraph.diagnosis import diagnose
from bondgraph.diagnosis.context import Context, residual_floor
from bondgraph.diagnosis.engine import model_file_options
from bondgraph.model.modelfile import load_model

MODELS = Path(__file__).resolve().parent.parent / "models"
FS = 10_000.0
#: the device: off the model file's values, within its tolerance (nothing hidden)
DEVICE = {"Re": 4.7 * 1.25, "K": 10.77e6 * 1.15, "c": 3000.0 * 0.5, "M": 0.16 * 0.9}


def noise_drive(t, seed=1):
    """60 V ± 25 V RMS noise, band-limited to 0.4 of the sampling rate of ``t``."""
    rng = np.random.default_rng(seed)
    b, a = signal.butter(6, 0.8)
    return 60.0 + 25.0 * signal.filtfilt(b, a, rng.standard_normal(t.size)) / 0.63


def record(reading: str, T: float = 2.0, level: float = 1e-3, seed: int = 1) -> Dataset:
    """The device's record at FS, its drive ``linear`` between samples or ``band-limited``."""
    lm = load_model(MODELS / "apa120ml.py", DEVICE)
    up = 1 if reading == "linear" else 8
    t = np.arange(int(T * FS * up)) / (FS * up)
    V = noise_drive(t, seed) if up == 1 else signal.resample(noise_drive(t[::up], seed), t.size)
    x = bg.simulate(lm.model, t, {"V": bg.PiecewiseLinear(t, V)}, rtol=1e-9)["x"]
    t, V, x = t[::up], V[::up], x[::up]
    rng = np.random.default_rng(seed + 100)
    return Dataset(t, {"V": V, "x": x + level * np.ptp(x) * rng.standard_normal(t.size)})


def test_without_compensation_the_fir_only_delays():
    x = np.random.default_rng(0).standard_normal(500)
    assert np.allclose(interpolation_compensated(x, 0.0, edge=0.0), x, atol=1e-12)
    shifted = interpolation_compensated(np.sin(0.05 * np.arange(500)), 0.3, edge=0.0)
    assert np.allclose(shifted[50:450], np.sin(0.05 * (np.arange(500) - 0.3))[50:450], atol=1e-4)


@pytest.mark.parametrize("reading", ["linear", "band-limited"])
def test_each_reading_reproduces_the_integrated_truth_of_its_kind(reading):
    """Two routes: the exact linear route on the recorded samples, read as the truth's drive
    was, against the compiled integrator; the other reading is off by the sinc² factor."""
    data = record(reading, T=0.5, level=0.0)
    lm = load_model(MODELS / "apa120ml.py", DEVICE)
    errors = {}
    for r in ("linear", "band-limited"):
        ctx = Context(lm.model, data, reading=r)
        values = {**DEVICE, "sensor.gain": 1.0}
        pred = ctx.ident.predict(values)
        errors[r] = np.sqrt(np.mean((pred - data.column("x"))[1000:] ** 2)) / np.std(data.column("x"))
    other = "band-limited" if reading == "linear" else "linear"
    assert errors[reading] < 4e-3, errors  # 0.1 % (linear), 0.3 % (band-limited: the FIR)
    assert errors[other] > 10 * errors[reading], errors  # 4 %: the sinc² factor


def test_the_residual_floor_is_the_noise_under_a_misfit_in_a_few_bands():
    fs, n = 10_000.0, 100_000
    rng = np.random.default_rng(2)
    t = np.arange(n) / fs
    e = 1e-3 * rng.standard_normal(n) + 0.05 * np.sin(2 * np.pi * 730 * t) + 0.03 * np.sin(2 * np.pi * 2400 * t)
    assert 0.6e-3 < residual_floor(e, fs) < 1.05e-3


@pytest.mark.parametrize("reading", ["linear", "band-limited"])
def test_an_effect_free_record_is_none_under_either_reading(reading):
    """The device alone under a broadband drive: the readings differ by about 7× the noise
    floor, both are tried, the truth's is kept and the answer is `none`.  (Read band-limited,
    the record with the linear drive was named electrical-rc: an RLC stage absorbs the
    1/sinc² difference.)"""
    lm = load_model(MODELS / "apa120ml.py")
    rep = diagnose(lm.model, record(reading), **model_file_options(lm.module), workers=1)
    assert rep.data["reading_gap_rms"] > 3 * rep.data["reading_floor_rms"]
    assert any(n.startswith("drive read as") for n in rep.notes), rep.notes
    assert rep.data["drive_reading"] == reading, rep.notes
    assert rep.cause == "none", rep.steps[-1].why
