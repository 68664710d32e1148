"""The command line as a user runs it: fit files that reproduce the fit, measured inputs that
set the time span, outputs committed only when a run succeeds, Ctrl-C and SIGTERM, plots with
units, python-control export, fast start-up.

Each test reproduces one deviation a new user reported (the issue's items 1-10) or one
promise of the README.  Real processes are used where the behaviour lives in the process
(signals, exit status, start-up imports); everything else runs in-process.
"""

from __future__ import annotations

import importlib.util
import json
import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from bondgraph.cli import main
from bondgraph.data import read_csv, write_csv

MODEL = textwrap.dedent("""\
    from bondgraph import *
    PARAMETERS = [
        Parameter("k", 100.0, "N/m", "spring stiffness"),
        Parameter("m", 1.0, "kg", "mass"),
        Parameter("c", 2.0, "N*s/m", "damping"),
    ]
    EXPERIMENT = Experiment(t_end=0.05, dt=1e-3, inputs={"V": Step(1e-3)})

    def build(p):
        g = Model("oscillator")
        V = g.input("V", "N", "drive force")
        F = g.input("F", "N", "a second force, unused by default")
        g.add(Se("drive", V), Se("load", F), J1("v"), I("mass", p.m), C("spring", 1 / p.k), R("damper", p.c))
        for e in ("drive", "load"):
            g.bond(e, "v")
        for e in ("mass", "spring", "damper"):
            g.bond("v", e)
        g.output("x", g.displacement("spring"), "m", "displacement")
        g.output("x2", 2 * g.displacement("spring"), "m", "twice the displacement")
        g.output("v", g.flow("mass"), "m/s", "velocity")
        return g
    """)

TRUE = {"k": 150.0, "c": 3.0}
OFFSET = 3e-6  # m: about 20 % of the stroke, as a sensor zero would be
NOISE = 1e-7  # m


def run(argv, capsys):
    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """A 4 s record of the oscillator with k, c of TRUE, a sensor offset and noise."""
    from bondgraph.model.modelfile import load_model
    from bondgraph.model.signals import PiecewiseLinear
    from bondgraph.numerics.simulate import Simulator

    d = tmp_path_factory.mktemp("rec")
    (d / "osc.py").write_text(MODEL)
    lm = load_model(d / "osc.py", TRUE)
    t = np.arange(0.0, 4.0, 1e-3)
    V = 1e-3 * (np.sin(2 * np.pi * 1.3 * t) + 0.5 * np.sign(np.sin(2 * np.pi * 0.4 * t)))
    x = Simulator(lm.model).run(t, {"V": PiecewiseLinear(t, V)}).outputs["x"]
    x = x + OFFSET + np.random.default_rng(1).normal(0.0, NOISE, t.size)
    write_csv(d / "data.csv", t, {"V": V, "x": x}, {"source": "synthetic oscillator"})
    return d


@pytest.fixture
def work(recording, tmp_path, monkeypatch):
    for name in ("osc.py", "data.csv"):
        (tmp_path / name).write_bytes((recording / name).read_bytes())
    monkeypatch.chdir(tmp_path)
    return tmp_path


# ---- item 1: the fit file reproduces the fit ----------------------------------------------------------
def test_fit_file_reproduces_the_fit_offset_included(work, capsys):
    rc, out, err = run(["fit", "osc.py", "data.csv", "--params", "k,c", "--out", "fitted.json", "--quiet"], capsys)
    assert rc == 0, err
    lines = out.splitlines()
    assert lines[0].split()[:2] == ["k", lines[0].split()[1]] and "N/m" in lines[0]
    assert "N*s/m" in lines[1]
    offset_line = next(ln for ln in lines if ln.startswith("offset of x"))
    assert "m" in offset_line.split() and "measured = model output + offset" in offset_line
    assert float(offset_line.split()[3]) == pytest.approx(OFFSET, rel=0.05)  # the report prints the offset
    assert "rms error: fit" in lines[-1] and " m," in lines[-1]
    fit = json.loads((work / "fitted.json").read_text())
    assert fit["format"] == "bondgraph-fit/1" and fit["output"] == "x" and fit["input"] == "V"
    assert set(fit["params"]) == {"k", "m", "c"} and fit["fitted"] == ["k", "c"]
    assert fit["params"]["k"] == pytest.approx(TRUE["k"], rel=1e-3)
    assert fit["offset"] == pytest.approx(OFFSET, rel=0.05) and fit["offset_unit"] == "m"
    assert fit["settings"] == {"validation": 0.3, "split": "blocks", "loss": "linear", "starts": 1}
    from conftest import ROOT

    docs = (ROOT / "docs" / "json-outputs.md").read_text().split("## Fit files")[1].split("\n## ")[0]
    documented = {
        k for row in docs.splitlines() if row.startswith("| `") for k in re.findall(r"`(\w+)`", row.split("|")[1])
    }
    assert documented == set(fit), "docs/json-outputs.md lists every field of the fit file"

    # re-simulate with the fit file and the measured drive: the RMS is the fit's
    rc, out, err = run(
        [
            "simulate",
            "osc.py",
            "--params-file",
            "fitted.json",
            "--input",
            "V=csv(file=data.csv, column=V)",
            "--out",
            "re.csv",
        ],
        capsys,
    )
    assert rc == 0, err
    assert "offset" in err
    data, re_ = read_csv(work / "data.csv"), read_csv(work / "re.csv")
    np.testing.assert_array_equal(re_.t, data.t)  # the data's own time stamps
    assert re_.metadata["offset x"] == repr(fit["offset"])
    rms = float(np.sqrt(np.mean((re_.columns["x"] - data.columns["x"]) ** 2)))
    assert rms == pytest.approx(fit["rms_fit"], rel=0.05)
    assert rms < 1.5 * NOISE

    # the same parameters without the offset miss by the offset: it is what made the difference
    (work / "flat.json").write_text(json.dumps(fit["params"]))
    rc, out, err = run(
        [
            "simulate",
            "osc.py",
            "--params-file",
            "flat.json",
            "--input",
            "V=csv(file=data.csv, column=V)",
            "--out",
            "flat.csv",
            "--quiet",
        ],
        capsys,
    )
    assert rc == 0, err
    flat = read_csv(work / "flat.csv")
    assert np.sqrt(np.mean((flat.columns["x"] - data.columns["x"]) ** 2)) > 10 * rms

    # linearize and a --set over the file read the same file
    rc, out, err = run(["linearize", "osc.py", "--params-file", "fitted.json", "--format", "json"], capsys)
    assert rc == 0, err
    assert json.loads(out)["dc_gain"] == pytest.approx(1 / fit["params"]["k"], rel=1e-9)
    rc, out, err = run(["linearize", "osc.py", "--params-file", "fitted.json", "--set", "k=400", "--json"], capsys)
    assert json.loads(out)["dc_gain"] == pytest.approx(1 / 400, rel=1e-9)


def test_fit_reports_progress_and_plots(work, capsys, monkeypatch):
    from bondgraph.support.progress import Progress

    monkeypatch.setitem(Progress.__init__.__kwdefaults__, "delay", 0.0)
    monkeypatch.setitem(Progress.__init__.__kwdefaults__, "interval", 0.0)
    monkeypatch.setenv("BONDGRAPH_PROGRESS", "lines")
    rc, out, err = run(["fit", "osc.py", "data.csv", "--params", "k", "--plot", "fit.png"], capsys)
    assert rc == 0, err
    assert "fitting: 1 simulations" in err and "fitting: done in" in err
    assert (work / "fit.png").stat().st_size > 1000


# ---- item 10: a measured input sets the time span ----------------------------------------------------------
def test_csv_input_spans_the_data_not_the_experiment(work, capsys):
    rc, out, err = run(["simulate", "osc.py", "--input", "V=csv(file=data.csv, column=V)", "--quiet"], capsys)
    assert rc == 0, err
    rows = out.splitlines()
    assert rows[0] == "t,V,F,x,x2,v"
    assert len(rows) - 1 == 4000 and float(rows[-1].split(",")[0]) == pytest.approx(3.999)
    rc, out, err = run(
        ["simulate", "osc.py", "--input", "V=csv(file=data.csv, column=V)", "--dt", "0.01", "--t-end", "2", "--quiet"],
        capsys,
    )
    t = np.array([float(r.split(",")[0]) for r in out.splitlines()[1:]])
    np.testing.assert_allclose(t, np.arange(201) * 0.01, atol=1e-12)
    rc, out, err = run(["simulate", "osc.py", "--input", "V=csv(file=data.csv, column=V)", "--t-end", "4.5"], capsys)
    assert rc == 2 and "beyond the end of the input data" in err and "3.999 s" in err


def test_unused_text_column_is_left_out_not_refused(work, capsys):
    lines = (work / "data.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln for ln in lines if not ln.startswith("#")]
    noted = [rows[0] + ",note,stamp"] + [
        f"{r},{'pause' if k % 500 == 0 else ''},2026-11-23T10:00:{k % 60:02d}" for k, r in enumerate(rows[1:])
    ]
    (work / "noted.csv").write_text("\n".join(head + noted) + "\n")
    rc, out, err = run(["fit", "osc.py", "noted.csv", "--params", "k", "--quiet"], capsys)
    assert rc == 0, err
    rc, out, err = run(
        ["simulate", "osc.py", "--input", "V=csv(file=noted.csv, column=V)", "--quiet", "--t-end", "0.1"], capsys
    )
    assert rc == 0, err
    rc, out, err = run(["fit", "osc.py", "noted.csv", "--params", "k", "--output", "note"], capsys)
    assert rc == 2 and "non-numeric cell" in err and "'note'" in err  # a needed text column is still refused


# ---- items 4 and 5: nothing replaced unless the whole run succeeded ---------------------------------------
def test_a_run_failing_at_its_last_step_keeps_the_existing_file(work, capsys, monkeypatch):
    import bondgraph.plotting as plotting

    (work / "precious.csv").write_text("keep me\n")

    def broken_plot(t, signals, units, path, title="", inputs=()):
        raise OSError(f"disk full while writing {path}")

    monkeypatch.setattr(plotting, "plot_signals", broken_plot)
    before = sorted(os.listdir(work))
    rc, out, err = run(["simulate", "osc.py", "--out", "precious.csv", "--plot", "p.png"], capsys)
    assert rc == 1
    assert (work / "precious.csv").read_text() == "keep me\n"
    assert sorted(os.listdir(work)) == before, "no temporary file left behind"
    assert "p.png" in err and ".tmp" not in err, "the message names the user's file, not a temporary one"


def test_outputs_of_a_run_appear_together(work, capsys):
    rc, out, err = run(["simulate", "osc.py", "--out", "r.csv", "--plot", "r.png", "--quiet"], capsys)
    assert rc == 0, err
    assert sorted(p for p in os.listdir(work) if p.startswith("r.")) == ["r.csv", "r.png"]
    assert not [p for p in os.listdir(work) if ".tmp" in p]


# ---- item 10: --debug after the subcommand ------------------------------------------------------------
def test_debug_after_the_subcommand(work, capsys):
    rc, out, err = run(["params", "osc.py", "--debug"], capsys)
    assert rc == 0 and "spring stiffness" in out
    rc, out, err = run(["params", "osc.py", "--set", "kk=1", "--debug"], capsys)
    assert (
        rc == 2 and "Traceback" in err and err.splitlines()[-1].startswith("bondgraph: error: unknown parameter 'kk'")
    )


# ---- plots: units, only what varies, legends ----------------------------------------------------------
def test_plots_carry_units_skip_constants_and_label_shared_axes(work, capsys, monkeypatch):
    import bondgraph.plotting as plotting

    figs = []
    monkeypatch.setattr(plotting.figures, "save", lambda fig, path: (figs.append(fig), open(path, "wb").write(b"png")))
    rc, out, err = run(
        [
            "simulate",
            "osc.py",
            "--input",
            "V=sine(amplitude=1e-3, frequency=5)",
            "--t-end",
            "0.5",
            "--out",
            "r.csv",
            "--plot",
            "r.png",
            "--quiet",
        ],
        capsys,
    )
    assert rc == 0, err
    # the time panels (the first column; the sine drive also gets loops beside them)
    axes = [a for a in figs[0].axes if a.get_subplotspec().colspan.start == 0]
    labels = [a.get_ylabel() for a in axes]
    # F (unused, constant) is left out; a 1 mN drive and its µm response read in SI-prefixed units
    assert labels == ["V (mN)", "x, x2 (µm)", "v (m/s)"], labels
    loops = [a for a in figs[0].axes if a.get_subplotspec().colspan.start == 1 and a.lines]
    assert [a.get_ylabel() for a in loops] == ["x, x2 (µm)", "v (m/s)"] and loops[-1].get_xlabel() == "V (mN)"
    assert "constant F = 0 N" in axes[0].get_title()
    assert axes[-1].get_xlabel() == "t (s)"
    assert axes[0].get_legend() is None and axes[2].get_legend() is None
    assert [t.get_text() for t in axes[1].get_legend().get_texts()] == ["x", "x2"]
    rc, out, err = run(["linearize", "osc.py", "--plot", "b.png"], capsys)
    assert rc == 0, err
    assert figs[1].axes[0].get_ylabel() == "|x/V| (m/N)" and figs[1].axes[1].get_xlabel() == "ω (rad/s)"


# ---- linearize: python-control ------------------------------------------------------------------------
def test_python_control_export_matches_the_poles(work, capsys):
    pytest.importorskip("control")
    import control

    rc, out, err = run(["linearize", "osc.py", "--format", "python-control", "--out", "lin_osc.py"], capsys)
    assert rc == 0, err
    spec = importlib.util.spec_from_file_location("lin_osc", work / "lin_osc.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert isinstance(mod.model, control.StateSpace)
    assert mod.model.input_labels == ["V"] and mod.model.output_labels == ["x"]
    rc, out, err = run(["linearize", "osc.py", "--json"], capsys)
    poles = sorted((complex(*p) for p in json.loads(out)["poles"]), key=lambda z: (z.real, z.imag))
    np.testing.assert_allclose(sorted(control.poles(mod.model), key=lambda z: (z.real, z.imag)), poles, rtol=1e-12)
    # wn = sqrt(k/m) = 10 rad/s, zeta = c / (2 sqrt(k m)) = 0.1: an independent check of both routes
    assert control.damp(mod.model)[0] == pytest.approx([10.0, 10.0], rel=1e-12)
    assert control.dcgain(mod.model) == pytest.approx(1 / 100.0)


def test_python_control_missing_is_one_line(work, capsys, monkeypatch):
    import bondgraph.cli.linearize as cli_lin
    from bondgraph.equations.derivation import derive
    from bondgraph.linear.linearize import linearize
    from bondgraph.model.modelfile import load_model
    from bondgraph.support.errors import UsageError

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "control" else real(name, *a))
    rc, out, err = run(["linearize", "osc.py", "--format", "python-control"], capsys)
    assert (
        rc == 2
        and err == "bondgraph: error: --format python-control needs python-control: pip install 'bondgraph[control]'\n"
    )
    assert cli_lin  # the module that checked
    monkeypatch.setitem(sys.modules, "control", None)
    lin = linearize(derive(load_model(work / "osc.py").model), "V", "x")
    with pytest.raises(UsageError, match=r"pip install 'bondgraph\[control\]'"):
        lin.to_control()


# ---- choices and start-up ------------------------------------------------------------------------------
def test_choices_come_from_the_modules():
    from bondgraph.cli import build_parser
    from bondgraph.equations.printing import FORMATS
    from bondgraph.numerics.simulate import METHODS

    p = build_parser()
    sub = p._subparsers._group_actions[0].choices
    method = next(a for a in sub["simulate"]._actions if a.dest == "method")
    fmt = next(a for a in sub["equations"]._actions if a.dest == "format")
    assert tuple(method.choices) == METHODS
    assert tuple(fmt.choices) == FORMATS


def test_help_imports_neither_sympy_nor_numba():
    code = (
        "import sys, io, contextlib\n"
        "from bondgraph.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    try:\n        main(['--help'])\n    except SystemExit:\n        pass\n"
        "    try:\n        main(['simulate', '--help'])\n    except SystemExit:\n        pass\n"
        "import bondgraph\n"
        "print(sorted(m for m in ('sympy', 'numba', 'scipy', 'numpy', 'matplotlib') if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_help_exits_0_and_names_every_command():
    for argv, needles in (
        (["--help"], ["COMMAND", "simulate", "fit", "130"]),
        (["simulate", "--help"], ["--params-file", "--plot", "auto", "dopri5", "--debug"]),
    ):
        proc = subprocess.run([sys.executable, "-m", "bondgraph", *argv], capture_output=True, text=True)
        assert proc.returncode == 0 and proc.stderr == "", proc.stderr
        for needle in needles:
            assert needle in proc.stdout
        for jargon in ("CONTRACT", "seed 00", "../shared"):
            assert jargon not in proc.stdout


def test_lazy_package_names_still_import():
    code = (
        "import bondgraph.numerics.simulate, bondgraph.linear.linearize\n"
        "import bondgraph as bg\n"
        "from bondgraph import C, Model, Parameter, Sine, simulate\n"
        "assert callable(bg.simulate) and callable(bg.linearize) and bg.simulate is simulate\n"
        "assert 'Model' in dir(bg) and bg.Model is Model\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "ok", out.stderr


def test_printouts_equal_sympys_own_printer(tmp_path):
    """The remembering printers give the same text as sympy's (on the 20-layer stack)."""
    import sympy as sp
    from conftest import MODELS

    from bondgraph.equations.derivation import derive
    from bondgraph.equations.printing import render
    from bondgraph.model.modelfile import load_model

    eqs = derive(load_model(MODELS / "stack.py").model)
    text, latex = render(eqs, "text"), render(eqs, "latex")
    for s, rhs in list(eqs.state_equations().items())[:6]:
        assert f"  d{s}/dt = {sp.sstr(rhs)}" in text
        assert sp.latex(rhs) in latex


# ---- Ctrl-C and SIGTERM (real processes) -------------------------------------------------------------------
def _spawn(argv, cwd, **kw):
    env = dict(os.environ, BONDGRAPH_PROGRESS="lines", PYTHONWARNINGS="ignore")
    return subprocess.Popen(
        [sys.executable, "-m", "bondgraph", *map(str, argv)],
        cwd=cwd,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        **kw,
    )


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except OSError:
        return False


def _assert_interrupted(proc, sent_at, code=130, word="interrupted"):
    err = proc.communicate(timeout=30)[1]
    elapsed = time.monotonic() - sent_at if sent_at is not None else 0.0
    assert proc.returncode == code, err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if not ln.startswith(("simulating:", "fitting:", "diagnose:"))]
    assert (
        lines == [f"bondgraph: {word}; no output file was changed"]
        if code == 130
        else lines == ["bondgraph: terminated (SIGTERM); no output file was changed"]
    ), err
    assert elapsed < 2.0, f"took {elapsed:.2f} s to stop"


def _handlers_installed(pid: int) -> bool:
    """Whether the process catches SIGTERM: the bondgraph command's first statement did that
    (Python itself catches SIGINT from its start, never SIGTERM)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            caught = next(int(ln.split()[1], 16) for ln in fh if ln.startswith("SigCgt:"))
    except (OSError, StopIteration):
        return False
    return bool(caught >> (signal.SIGTERM - 1) & 1)


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_ctrl_c_during_start_up_ends_every_command(work):
    """SIGINT as soon as the command runs (its imports), or 0.4 s later (sympy, numba, the
    model): one line, status 130, within 2 s, for every command."""
    commands = [
        ["params", "osc.py"],
        ["equations", "osc.py"],
        ["causality", "osc.py"],
        ["simulate", "osc.py", "--out", "r.csv"],
        ["linearize", "osc.py"],
        ["fit", "osc.py", "data.csv", "--params", "k"],
        ["diagnose", "osc.py", "data.csv"],
    ]
    for delay in (0.0, 0.4):
        procs = [_spawn(argv, work) for argv in commands]
        due, sent, ended = {}, {}, {}
        deadline = time.monotonic() + 60
        while len(ended) < len(procs) and time.monotonic() < deadline:
            now = time.monotonic()
            for i, p in enumerate(procs):
                if i not in due and _handlers_installed(p.pid):
                    due[i] = now + delay
                if i in due and i not in sent and now >= due[i]:
                    p.send_signal(signal.SIGINT)
                    sent[i] = time.monotonic()
                if i in sent and i not in ended and p.poll() is not None:
                    ended[i] = time.monotonic()
            time.sleep(0.002)
        assert len(ended) == len(procs), "some commands never started or never ended"
        for i, p in enumerate(procs):
            assert ended[i] - sent[i] < 2.0, f"{commands[i][0]} took {ended[i] - sent[i]:.2f} s to stop"
            _assert_interrupted(p, None)
    assert not (work / "r.csv").exists() and not [p for p in os.listdir(work) if ".tmp" in p]


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_ctrl_c_during_a_long_simulation(work):
    (work / "r.csv").write_text("keep me\n")
    proc = _spawn(
        [
            "simulate",
            "osc.py",
            "--input",
            "V=sine(amplitude=1e-3, frequency=50)",
            "--t-end",
            "2000",
            "--dt",
            "1e-3",
            "--out",
            "r.csv",
        ],
        work,
    )
    line = proc.stderr.readline()  # the first progress line: the simulation runs
    assert line.startswith("simulating:"), line
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _assert_interrupted(proc, sent)
    assert (work / "r.csv").read_text() == "keep me\n"
    assert not [p for p in os.listdir(work) if ".tmp" in p]


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_sigterm_while_writing_removes_the_temporary_file(work):
    proc = _spawn(
        [
            "simulate",
            "osc.py",
            "--input",
            "V=sine(amplitude=1e-3, frequency=3)",
            "--t-end",
            "40",
            "--dt",
            "1e-4",
            "--out",
            "big.csv",
            "--quiet",
        ],
        work,
    )
    deadline = time.monotonic() + 60
    tmp = None
    while time.monotonic() < deadline and proc.poll() is None:
        tmp = next(
            (
                p
                for p in os.listdir(work)
                if ".big.csv." in p and p.endswith(".tmp") and (work / p).exists() and (work / p).stat().st_size > 0
            ),
            None,
        )  # the CSV writer's file, being filled
        if tmp:
            break
        time.sleep(0.005)
    assert tmp, "the write never started (or finished before it could be seen)"
    sent = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _assert_interrupted(proc, sent, code=143)
    assert sorted(os.listdir(work)) == ["data.csv", "osc.py"]


SPIN = textwrap.dedent("""\
    import multiprocessing as mp, sys
    from concurrent.futures import ProcessPoolExecutor
    from bondgraph.cli import main, registry

    def spin(_):
        x = 0
        while True:
            x += 1

    @registry.command("spin", "two busy worker processes", [])
    def run(args):
        with ProcessPoolExecutor(2, mp_context=mp.get_context("fork")) as pool:
            futures = [pool.submit(spin, i) for i in range(2)]
            print("started", flush=True)
            for f in futures:
                f.result()

    from bondgraph.__main__ import run as entry
    sys.argv = ["bondgraph", "spin"]
    entry()
    """)


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads /proc")
def test_ctrl_c_in_a_terminal_ends_the_worker_processes_too(work):
    """The terminal sends SIGINT to the whole process group: the workers leave silently, the
    command prints one line; after it no worker process is left."""
    (work / "spin.py").write_text(SPIN)
    proc = subprocess.Popen(
        [sys.executable, "spin.py"],
        cwd=work,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    assert proc.stdout.readline().strip() == "started"
    children = []
    for _ in range(200):
        children = [int(p) for p in os.listdir("/proc") if p.isdigit() and _ppid(int(p)) == proc.pid]
        if len([c for c in children if _alive(c)]) >= 2:
            break
        time.sleep(0.01)
    assert len(children) >= 2
    sent = time.monotonic()
    os.killpg(proc.pid, signal.SIGINT)
    _assert_interrupted(proc, sent)
    time.sleep(0.2)
    assert not [c for c in children if _alive(c)], "worker processes survived"


def _ppid(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return int(fh.read().rsplit(")", 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return -1


# ---- bondgraph.support.atomic.Outputs: the machinery behind items 4-6 ----------------------------------------------
def test_outputs_commit_together_or_not_at_all(tmp_path):
    from bondgraph.support.atomic import Outputs
    from bondgraph.support.errors import UsageError
    from bondgraph.support.interrupt import TEMPORARY

    (tmp_path / "a.csv").write_text("old a\n")
    os.chmod(tmp_path / "a.csv", 0o640)
    with pytest.raises(RuntimeError):
        with Outputs() as out:
            out.add(tmp_path / "a.csv")
            out.add(tmp_path / "b.png", "--plot", suffixes=(".png",))
            with out.open(tmp_path / "a.csv") as fh:
                fh.write("new a\n")
            raise RuntimeError("the plot failed")
    assert sorted(os.listdir(tmp_path)) == ["a.csv"] and (tmp_path / "a.csv").read_text() == "old a\n"
    with Outputs() as out:
        out.add(tmp_path / "a.csv")
        out.add(tmp_path / "never.csv")  # reserved but not written: not created
        with out.path(tmp_path / "a.csv") as tmp:
            assert tmp.endswith(".csv") and os.path.basename(tmp).startswith(".a.csv.")
            with open(tmp, "w") as fh:
                fh.write("new a\n")
    assert sorted(os.listdir(tmp_path)) == ["a.csv"] and (tmp_path / "a.csv").read_text() == "new a\n"
    assert os.stat(tmp_path / "a.csv").st_mode & 0o777 == 0o640, "the file keeps its permissions"
    assert not [t for t in TEMPORARY if str(tmp_path) in t]
    out = Outputs(inputs=[tmp_path / "a.csv"])
    for path, needle in (
        (tmp_path / "a.csv", "would overwrite the input"),
        (tmp_path, "is a directory"),
        (tmp_path / "no" / "x.csv", "does not exist"),
    ):
        with pytest.raises(UsageError, match=needle):
            out.add(path)
    out.add(tmp_path / "x.csv", "--out")
    with pytest.raises(UsageError, match="already the output of --out"):
        out.add(tmp_path / "x.csv", "--bode")
    out.discard()
    assert sorted(os.listdir(tmp_path)) == ["a.csv"]


AFTER_COMMIT = textwrap.dedent("""\
    import sys, time
    from bondgraph.cli import registry

    @registry.command("slow-end", "writes its output, then takes its time", [registry.arg("--out")])
    def run(args):
        with registry.outputs(args, "out") as out:
            with out.open(args.out) as fh:
                fh.write("done\\n")
        print("committed", flush=True)
        time.sleep(60)

    from bondgraph.__main__ import run as entry
    sys.argv = ["bondgraph", "slow-end", "--out", "result.txt"]
    entry()
    """)


def test_an_interrupt_after_the_outputs_are_in_place_says_so(tmp_path):
    (tmp_path / "after.py").write_text(AFTER_COMMIT)
    proc = subprocess.Popen(
        [sys.executable, "after.py"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert proc.stdout.readline().strip() == "committed"
    proc.send_signal(signal.SIGINT)
    err = proc.communicate(timeout=30)[1]
    assert proc.returncode == 130 and err == "bondgraph: interrupted; after writing result.txt\n"
    assert (tmp_path / "result.txt").read_text() == "done\n"
