"""The diagnosis' Welch estimates cover the whole record.  A logarithmic sweep spends its last
octave in the record's last seconds; Welch segments laid from the first sample stop up to half a
segment short of the end, so a single segmentation loses the sweep's top frequencies (measured:
coherence 0.035 at 3 kHz on a 10 kHz, 18 s amplified-actuator record whose output is the drive's
response there).  The estimates average a second segmentation that ends at the last sample: on
a known linear filter driven by such a sweep, the coherence at the top is ~1 and the empirical
response is the filter's analytic one; on a stationary drive both segmentations agree."""

from __future__ import annotations

import numpy as np
from scipy import signal

from bondgraph.diagnosis.calibration import empirical_frf, resolved_spectrum
from bondgraph.diagnosis.context import drive_band, welch, welch_length
from bondgraph.diagnosis.filters import lowpass

FS, N, TAU = 1000.0, 20000, 1e-3  # 20 s at 1 kHz; a lag with its corner at 159 Hz


def _sweep(f0=1.0, f1=400.0):
    t = np.arange(N) / FS
    k = np.log(f1 / f0) / t[-1]
    return 2.0 + np.sin(2 * np.pi * f0 * (np.exp(k * t) - 1) / k)


def _exact(w):
    """The lag's response at ``w`` (rad/s) as :func:`lowpass` computes it (the drive linear
    between samples): its steady state on e^(iωt)."""
    t = np.arange(4000) / FS
    out = []
    for wk in w:
        z = np.exp(1j * wk * t)
        out.append((lowpass(z.real, TAU, 1 / FS) + 1j * lowpass(z.imag, TAU, 1 / FS))[-1] / z[-1])
    return np.array(out)


def _record(u, noise=1e-3, seed=0):
    return lowpass(u, TAU, 1 / FS) + np.random.default_rng(seed).normal(0, noise, u.size)


def test_the_segments_leave_out_the_end_of_the_record_without_the_second_segmentation():
    nper = welch_length(N, 8, 15)
    assert (N - nper) % (nper - nper // 2) > 0.02 * N  # the first segmentation drops > 2 % of the record


def test_a_sweep_is_resolved_up_to_its_last_frequencies():
    u = _sweep()
    y = _record(u)
    f_top = 360.0  # passed 0.35 s before the end
    f, coh_single = signal.coherence(u, y, FS, nperseg=welch_length(N, 8, 15), detrend="linear")
    near = np.abs(f - f_top) <= 0.03 * f_top
    assert np.median(coh_single[near]) < 0.5  # one segmentation: noise there
    w, coh, _ = resolved_spectrum(u, y, FS, None)
    near = np.abs(w - 2 * np.pi * f_top) <= 0.03 * 2 * np.pi * f_top
    assert np.median(coh[near]) > 0.9
    w, H, _ = empirical_frf(u, y, FS)
    top = np.abs(w - 2 * np.pi * f_top) <= 0.03 * 2 * np.pi * f_top
    assert top.any()
    assert np.max(np.abs(H[top] / _exact(w[top]) - 1)) < 0.05
    assert drive_band(u, FS) > 330.0  # 219 Hz from one segmentation


def test_a_stationary_record_reads_alike_from_either_end():
    rng = np.random.default_rng(3)
    u = rng.normal(size=N)
    nper = welch_length(N, 8, 15)
    f, both = welch(u, FS, nper)
    _, first = signal.welch(u, FS, nperseg=nper, detrend="linear")
    band = (f > 10) & (f < 400)
    assert abs(np.mean(both[band]) / np.mean(first[band]) - 1) < 0.05
    y = _record(u, noise=1e-2)
    _, cross = welch(u, FS, nper, y)
    assert np.max(np.abs(cross[band] / both[band] / _exact(2 * np.pi * f[band]) - 1)) < 0.05
