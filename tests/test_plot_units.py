"""Plots a user can read at a glance: every axis says its quantity and unit, SI-prefixed to
suit the data (µm, not ticks of 0.0001 m), and a start-up transient does not set the scale
of a residual panel (the data stay drawn).  Checked on the matplotlib objects of generated
figures (each plot function's figure is caught as it is saved)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from conftest import MODELS

from bondgraph.model.modelfile import load_model
from bondgraph.plotting import figures

pytest.importorskip("matplotlib")


@pytest.fixture
def caught(monkeypatch):
    """The figures the plot functions save, kept open for the test to read."""
    figs = []
    monkeypatch.setattr(figures, "save", lambda fig, path: figs.append(fig))
    yield figs
    plt = figures.pyplot()
    for f in figs:
        plt.close(f)


def test_si_scale_picks_the_prefix_of_the_datas_magnitude():
    assert figures.si_scale("m", [0.0, 1.05e-4]) == (1e6, "µm")
    assert figures.si_scale("m", [-3e-9, 2e-9]) == (1e9, "nm")
    assert figures.si_scale("m", [0.0, 0.02]) == (1e3, "mm")
    assert figures.si_scale("V", [0.0, 120.0]) == (1.0, "V")
    assert figures.si_scale("V", [0.004, -0.05]) == (1e3, "mV")
    assert figures.si_scale("m/s", [1e-4]) == (1.0, "m/s")  # a compound unit keeps its own scale
    assert figures.si_scale("m", [0.0, 0.0]) == (1.0, "m")
    assert figures.scaled_label("x residual", "m", [2e-7]) == ("x residual (nm)", 1e9)


def record_with_transient(n=20_000):
    """A 100 µm, 1 Hz stroke whose record starts 75 µm away from the models' rest (decaying in
    about 10 ms), and a 0.3 µm hysteresis loop the models miss."""
    t = np.linspace(0.0, 2.0, n)
    u = 60.0 + 60.0 * np.sin(2 * np.pi * t)
    x = 100e-6 * u / 120.0
    loop = 0.3e-6 * np.cos(2 * np.pi * t)
    transient = 75e-6 * np.exp(-t / 2e-3)
    return t, u, x, loop, transient


def test_diagnosis_plot_labels_units_and_scales_residuals_after_the_transient(caught):
    from bondgraph.plotting import plot_diagnosis

    t, u, x, loop, transient = record_with_transient()
    y = x + loop + transient
    report = SimpleNamespace(
        predictions={"t": t, "u": u, "y": y, "baseline": x, "extended": x + loop},
        causes=["bouc-wen"],
        data={"input": "V", "output": "x"},
        extended_model=None,
        baseline="calibrated",
        baseline_rms=float(np.sqrt(np.mean((y - x) ** 2))),
        extended_rms=float(np.sqrt(np.mean(transient**2))),
        noise=1e-8,
        gain=10.0,
    )
    plot_diagnosis(report, "d.png", load_model(MODELS / "apa120ml.py").model)
    (fig,) = caught
    top, res, loops = fig.axes
    assert top.get_ylabel() == "x (µm)" and top.get_xlabel() == "t (s)"
    assert res.get_ylabel() == "x residual (µm)" and loops.get_ylabel() == "x residual (µm)"
    assert loops.get_xlabel() == "V (V)"
    assert np.max(top.lines[0].get_ydata()) == pytest.approx(1e6 * np.max(y))  # drawn in µm
    for ax in (res, loops):
        lo, hi = ax.get_ylim()
        # the loop (±0.3 µm) fills the panel; the 75 µm transient is off scale but still drawn
        assert -0.45 < lo < -0.3 and 0.3 < hi < 0.45
        assert np.max(ax.lines[0].get_ydata()) == pytest.approx(75.0, rel=0.01)
        (note,) = [t for t in ax.texts if "scale from" in t.get_text()]
        assert "start-up transient" in note.get_text()
    (note,) = [t for t in res.texts if "scale from" in t.get_text()]
    start = float(note.get_text().split("t ≥ ")[1].split(" s")[0])
    assert 0.04 <= start < 0.1  # the first 2 % of 2 s, and the transient is over well before


def test_residual_scale_keeps_every_sample_of_a_record_without_transient():
    t, u, x, loop, _ = record_with_transient()
    lo, hi, start, clipped = figures.robust_limits(t, [loop])
    assert not clipped and lo < -0.3e-6 and hi > 0.3e-6 and start == int(np.ceil(0.02 * t.size))


def test_simulation_and_fit_plots_show_micrometres(caught):
    from bondgraph.plotting import plot_fit, plot_signals

    t, u, x, loop, transient = record_with_transient()
    plot_signals(t, {"V": u, "x": x}, {"V": "V", "x": "m"}, "s.png")
    labels = [a.get_ylabel() for a in caught[0].axes]
    assert labels == ["V (V)", "x (µm)"]
    assert np.max(caught[0].axes[1].lines[0].get_ydata()) == pytest.approx(100.0, rel=1e-3)
    plot_fit(t, x + loop + transient, x, "f.png", name="x", unit="m")
    top, res = caught[1].axes
    assert top.get_ylabel() == "x (µm)" and res.get_ylabel() == "x residual (µm)"
    assert res.get_ylim()[1] < 0.45


def test_compensation_plot_labels_units(caught):
    from bondgraph.cli.compensate import _plot

    t, u, x, loop, transient = record_with_transient()
    res = SimpleNamespace(
        t=t, reference=x, predicted=x + 0.1 * loop, linear_predicted=x + loop, drive=u, linear_drive=u - 1.0
    )
    _plot(res, "c.png", ("V", "V"), ("x", "m"), "apa120ml")
    top, err, drive = caught[0].axes
    assert (top.get_ylabel(), err.get_ylabel(), drive.get_ylabel()) == ("x (µm)", "x error (nm)", "V (V)")
    assert err.get_ylim()[1] == pytest.approx(1.1 * 300.0, rel=0.15)


def test_sweep_plot_labels_metrics_with_units(caught):
    from bondgraph.batch.sweep import SweepResult
    from bondgraph.batch.table import Table

    K = np.random.default_rng(1).normal(10.77e6, 0.5e6, 40)
    rows = [{"job": i, "K": k, "p2p(x)": 1e3 / k, "resonance": 1e-3 * np.sqrt(k)} for i, k in enumerate(K)]
    space, units = {"K": "normal(10.77e6, 5%)"}, {"p2p(x)": "m", "resonance": "Hz"}
    SweepResult(Table(rows), space, "random", ["p2p(x)", "resonance"], 1, units=units).plot("p.png")
    hist_x, hist_f, tornado_x, tornado_f = caught[0].axes
    assert hist_x.get_xlabel() == "p2p(x) (µm)" and tornado_x.get_xlabel() == "p2p(x) (µm)"
    assert hist_f.get_xlabel() == "resonance (Hz)" and tornado_f.get_xlabel() == "resonance (Hz)"
    assert 80 < tornado_x.lines[0].get_xdata()[0] < 110  # the baseline, in µm


def test_a_drive_revisits_its_values_when_it_reverses_over_its_range_twice():
    t = np.linspace(0.0, 0.4, 4001)
    noise = np.random.default_rng(0).normal(0.0, 0.005, t.size)
    assert figures.revisits(60 - 60 * np.cos(2 * np.pi * 5 * t))  # two periods from 0 V
    assert figures.revisits(np.sin(2 * np.pi * 2.5 * t))  # one period from the middle
    assert figures.revisits(np.interp(t, [0, 0.2, 0.4], [0, 1, 0]))  # up and back down
    assert not figures.revisits(np.interp(t, [0, 0.2, 0.4], [0, 1, 0.5]))  # back over half only
    assert not figures.revisits(t)  # a ramp
    assert not figures.revisits(np.where(t > 0.1, 1.0, 0.0) + noise)  # a noisy step
    assert not figures.revisits(np.full(t.size, 3.0))


def test_simulation_plot_draws_the_loop_against_a_periodic_drive(caught):
    from bondgraph.plotting import plot_signals

    t = np.linspace(0.0, 0.4, 4001)
    V = 60 - 60 * np.cos(2 * np.pi * 5 * t)
    x = 100e-6 * (V / 120 + 0.08 * np.sin(2 * np.pi * 5 * t))  # lags the drive: a loop
    plot_signals(t, {"V": V, "x": x, "F": 0 * t}, {"V": "V", "x": "m", "F": "N"}, "s.png", inputs=["V", "F"])
    tv, empty, tx, loop = caught[0].axes  # time panels left, the loop beside x(t); F is constant
    assert (tv.get_ylabel(), tx.get_ylabel(), tx.get_xlabel()) == ("V (V)", "x (µm)", "t (s)")
    assert not empty.axison and not empty.lines
    assert loop.get_xlabel() == "V (V)" and loop.get_ylabel() == "x (µm)"
    xs, ys = loop.lines[0].get_data()
    assert np.allclose(xs, V) and np.allclose(ys, 1e6 * x)


def test_simulation_plot_has_no_loop_under_a_step(caught):
    from bondgraph.plotting import plot_signals

    t = np.linspace(0.0, 0.4, 4001)
    V = np.where(t > 0.1, 120.0, 0.0)
    x = 100e-6 * V / 120 * (1 - np.exp(-np.maximum(t - 0.1, 0) / 0.01))
    plot_signals(t, {"V": V, "x": x}, {"V": "V", "x": "m"}, "s.png", inputs=["V"])
    assert len(caught[0].axes) == 2 and caught[0].axes[-1].get_xlabel() == "t (s)"
