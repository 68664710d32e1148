"""Results a user can trust at a glance: the smaller items of the new user's tour, each
reproduced first (a missing plot library found before the work, an unknown fit-file format,
a PI operator that cannot be inverted, a drive beyond the amplifier's range, the Bode file's
frequency column, negative numbers as option values, an unknown model input)."""

from __future__ import annotations

import json
import sys

import numpy as np
import pytest
from conftest import MODELS

import bondgraph.model.modelfile as modelfile
from bondgraph.cli import main
from bondgraph.data import write_csv
from bondgraph.model.memory import not_monotone
from bondgraph.model.modelfile import load_model
from library.hysteresis import PrandtlIshlinskii

APA = str(MODELS / "apa120ml.py")
P885 = str(MODELS / "p885_stack.py")


def run(capsys, *argv) -> tuple[int, str, str]:
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture
def record(tmp_path):
    """A short APA-like record t, V, x (V in 0..120 V, x in m)."""
    t = np.linspace(0.0, 0.05, 501)
    V = 60 + 50 * np.sin(2 * np.pi * 40 * t)
    write_csv(tmp_path / "d.csv", t, {"V": V, "x": 5e-7 * V}, {})
    return tmp_path / "d.csv"


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", APA, "--out", "{d}/a.csv", "--plot", "{d}/a.png"],
        ["fit", APA, "{data}", "--params", "K", "--plot", "{d}/a.png"],
        ["diagnose", APA, "{data}", "--plot", "{d}/a.png"],
        ["compensate", APA, "{data}", "--column", "x", "--plot", "{d}/a.png"],
        ["linearize", APA, "--plot", "{d}/a.png"],
        ["causality", APA, "--plot", "{d}/a.png"],
    ],
    ids=lambda a: a[0],
)
def test_missing_matplotlib_is_refused_before_any_work(argv, record, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed

    def no_work(*a, **k):
        raise AssertionError("the model was loaded although the plot cannot be written")

    monkeypatch.setattr(modelfile, "load_model", no_work)
    rc, _, err = run(capsys, *[a.format(d=tmp_path, data=record) for a in argv])
    assert rc == 2 and "plots need matplotlib: pip install 'bondgraph[plot]'" in err
    assert len(err.strip().splitlines()) == 1
    assert not list(tmp_path.glob("a.*"))


def test_unknown_fit_file_format_is_refused(tmp_path, capsys):
    fit = {"format": "bondgraph-fit/2", "params": {"K": 1e7}, "output": "x", "offset": 0.0}
    (tmp_path / "f.json").write_text(json.dumps(fit))
    rc, _, err = run(capsys, "simulate", APA, "--params-file", tmp_path / "f.json", "--t-end", "0.001")
    assert rc == 2
    assert "format 'bondgraph-fit/2'" in err and "bondgraph-fit/1" in err and len(err.strip().splitlines()) == 1
    fit["format"] = "bondgraph-fit/1"  # the format this version writes is read
    (tmp_path / "f.json").write_text(json.dumps(fit))
    assert run(capsys, "simulate", APA, "--params-file", tmp_path / "f.json", "--t-end", "0.001")[0] == 0


def test_pi_operator_with_falling_loading_curve_is_named_not_monotone():
    r = np.array([0.0, 1.0, 2.0])
    assert PrandtlIshlinskii(r, [1.0, 0.5, 0.2]).monotone_problem(np.r_[r, 1.0, 0.5, 0.2]) == ""
    # a negative weight whose partial sums stay positive: still monotone (Kuhnen's inverse exists)
    assert PrandtlIshlinskii(r, [1.0, -0.5, 0.2]).monotone_problem(np.r_[r, 1.0, -0.5, 0.2]) == ""
    why = PrandtlIshlinskii(r, [1.0, -1.5, 0.2]).monotone_problem(np.r_[r, 1.0, -1.5, 0.2])
    assert "not monotone" in why and "w2 = -1.5" in why and "threshold 1" in why
    with pytest.raises(Exception, match="not strictly increasing"):
        PrandtlIshlinskii(r, [1.0, -1.5, 0.2]).inverse()  # the inverse agrees: it has none


def test_p885_operator_weights_are_checked_where_used(tmp_path, capsys):
    assert not_monotone(load_model(P885).model) == [], "the model file's identified weights are invertible"
    bad = load_model(P885, {"H.w2": -3.0}).model
    (line,) = not_monotone(bad)
    assert line.startswith("operator H: not monotone") and "H" in line
    t = np.linspace(0.0, 2.0, 201)
    write_csv(tmp_path / "ref.csv", t, {"x": 10e-6 + 5e-6 * np.sin(2 * np.pi * t)}, {})
    rc, _, err = run(
        capsys,
        "compensate",
        P885,
        tmp_path / "ref.csv",
        "--set",
        "H.w2=-3",
        "--iterations",
        "2",
        "--out",
        tmp_path / "c.csv",
    )
    assert "not monotone" in err, err


def test_compensate_keeps_the_drive_within_the_declared_range(tmp_path, capsys):
    """A reference that needs a negative drive of a unipolar 0-120 V amplifier: the drive is
    clipped to the range the model file declares, and the output says so."""
    model = (MODELS / "apa120ml.py").read_text()
    plain = 'V = g.input("V", "V", "drive voltage")'
    assert plain in model
    APA = tmp_path / "apa_unipolar.py"
    APA.write_text(model.replace(plain, 'V = g.input("V", "V", "drive voltage", range=(0.0, 120.0))'))
    t = np.linspace(0.0, 0.1, 201)
    write_csv(tmp_path / "ref.csv", t, {"x": 20e-6 * np.sin(2 * np.pi * 20 * t)}, {})
    out = tmp_path / "c.csv"
    rc, _, err = run(capsys, "compensate", APA, tmp_path / "ref.csv", "--iterations", "2", "--out", out, "--quiet")
    assert rc == 0
    assert "beyond the input's range 0 to 120" in err and "clipped" in err
    from bondgraph.data import read_csv

    drive = read_csv(out).columns["V"]
    assert drive.min() == 0.0 and drive.max() <= 120.0
    rc, _, err = run(
        capsys, "compensate", APA, tmp_path / "ref.csv", "--iterations", "2", "--drive-range=-5,150", "--quiet"
    )
    assert rc == 0 and "beyond the input's range -5 to 150" in err
    rc, _, err = run(capsys, "compensate", APA, tmp_path / "ref.csv", "--drive-range", "120,0")
    assert rc == 2 and "--drive-range" in err


def test_bode_file_names_its_frequency_column(tmp_path, capsys):
    rc, _, _ = run(capsys, "linearize", APA, "--bode", tmp_path / "b.csv")
    assert rc == 0
    lines = (tmp_path / "b.csv").read_text().splitlines()
    header = next(ln for ln in lines if not ln.startswith("#"))
    assert header == "omega_rad_s,magnitude,phase_deg"
    assert any(ln.startswith("# magnitude: |x/V| (m/V)") for ln in lines)


@pytest.mark.parametrize("option", ["--dt", "--t-end"])
@pytest.mark.parametrize("value", ["-1e-3", "-1", "-.5", "0"])
def test_negative_numbers_are_values_refused_with_a_clear_message(option, value, capsys):
    rc, _, err = run(capsys, "simulate", APA, option, value)
    assert rc == 2
    assert f"{option} is the" in err and "must be a positive number" in err, err


def test_unknown_model_input_names_the_models_inputs(record, capsys):
    rc, _, err = run(capsys, "fit", APA, record, "--params", "K", "--model-input", "nosuch")
    assert rc == 2
    assert "--model-input: unknown input of" in err and "F, V" in err and str(record) not in err
    rc, _, err = run(capsys, "diagnose", APA, record, "--model-output", "xx")
    assert rc == 2 and "--model-output: unknown output of" in err and "'x'" in err


def test_a_blocking_compilation_reports_progress_and_its_time():
    import io
    import time

    from bondgraph.support.progress import quiet_if, waiting

    stream = io.StringIO()
    with waiting("compiling the integrator", status="first run", mode="lines", stream=stream, delay=0.1) as w:
        time.sleep(0.5)  # a call that reports nothing itself
    lines = stream.getvalue().splitlines()
    assert lines[0].startswith("compiling the integrator: ") and "elapsed, first run" in lines[0]
    assert lines[-1].startswith("compiling the integrator: done in 0.5 s")
    assert w.seconds >= 0.5
    stream = io.StringIO()
    with quiet_if(True), waiting("compiling", stream=stream, delay=0.0):  # --quiet: nothing
        time.sleep(0.3)
    assert stream.getvalue() == ""


def test_large_csv_reports_progress_while_writing(tmp_path):
    seen = []
    n = 200_000  # four blocks of rows
    write_csv(tmp_path / "big.csv", np.arange(n) * 1e-3, {"x": np.zeros(n)}, {}, progress=seen.append)
    assert len(seen) == 4 and seen[-1] == 1.0 and seen == sorted(seen)
