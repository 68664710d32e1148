"""Bad inputs through the command line: exit status 2, exactly one line on stderr starting
with 'bondgraph: error:', no traceback, and a message that names the problem.

The cases are one table (``CASES``); each runs in-process through ``bondgraph.cli.main``.
A few also run as real processes (``python -m bondgraph``) to check the exit status the
shell sees.  The small model files the cases need are written into a temporary directory.
"""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from bondgraph.cli import main
from bondgraph.data import read_csv

HEAD = "from bondgraph import *\nPARAMETERS = [Parameter('k', 1.0, 'N/m', 'stiffness')]\n"


def _model(body: str) -> str:
    return HEAD + textwrap.dedent(body)


GOOD = textwrap.dedent("""\
    from bondgraph import *
    PARAMETERS = [
        Parameter("k", 100.0, "N/m", "spring stiffness"),
        Parameter("m", 1.0, "kg", "mass"),
        Parameter("c", 2.0, "N s/m", "damping"),
        Parameter("lumped", True, "", "a boolean switch"),
        Parameter("mode", "a", "", "a choice", choices=("a", "b")),
        Parameter("layers", 3, "", "an integer"),
    ]
    EXPERIMENT = Experiment(t_end=0.05, dt=1e-3, inputs={"V": Step(1.0)})

    def build(p):
        g = Model("good")
        V = g.input("V", "N")
        g.add(Se("force", V), J1("v"), I("mass", p.m), C("spring", 1 / p.k), R("damper", p.c))
        g.bond("force", "v")
        for e in ("mass", "spring", "damper"):
            g.bond("v", e)
        g.output("x", g.displacement("spring"), "m")
        return g
    """)

FILES = {
    "good.py": GOOD,
    "typo_port.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(Se("s", 1.0), TF("tf", 2.0), C("c", p.k))
            g.bond("s", "tf.p1")
            g.bond("tf.p3", "c")
            return g
        """),
    "typo_elem.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(Se("source", 1.0), J1("j"), C("spring", p.k))
            g.bond("source", "j")
            g.bond("j", "sprng")
            return g
        """),
    "twoport_bare.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(Se("s", 1.0), TF("tf", 2.0))
            g.bond("s", "tf")
            return g
        """),
    "syntax.py": HEAD + "def build(p)\n    return 1\n",
    "import_error.py": "from bondgraph import *\nPARAMETERS = [Parameter('k', 1.0)]\nx = undefined_name + 1\n",
    "raises.py": HEAD + "def build(p):\n    x = 1\n    raise RuntimeError('boom here')\n",
    "noparams.py": "from bondgraph import *\ndef build(p):\n    return Model('x')\n",
    "nobuild.py": HEAD,
    "nonmodel.py": HEAD + "def build(p):\n    return 42\n",
    "badparams.py": "PARAMETERS = [1, 2]\ndef build(p):\n    return None\n",
    "badexperiment.py": HEAD + "EXPERIMENT = 5\n" + textwrap.dedent("""\
        def build(p):
            g = Model("t")
            g.add(Se("s", 1.0), C("c", p.k))
            g.bond("s", "c")
            return g
        """),
    "duplicate.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(C("c", p.k), C("c", 2.0))
            return g
        """),
    "badlaw.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(C("cap", "1/+"))
            return g
        """),
    "nobonds.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(C("c", p.k))
            return g
        """),
    "oneport2.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(Se("s", 1.0), C("cap", p.k), J0("a"))
            g.bond("s", "cap")
            g.bond("cap", "a")
            return g
        """),
    "junction1.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(Se("s", 1.0), J1("j"), C("c", p.k), J0("lonely"))
            g.bond("s", "j")
            g.bond("j", "c")
            g.bond("j", "lonely")
            return g
        """),
    "selfbond.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(J1("j"))
            g.bond("j", "j")
            return g
        """),
    "unconnected.py": _model("""\
        def build(p):
            g = Model("t")
            g.add(Se("s", 1.0), J1("j"), C("c", p.k), I("orphan", 1.0))
            g.bond("s", "j")
            g.bond("j", "c")
            return g
        """),
    "conflict.py": _model("""\
        def build(p):
            g = Model("t")
            V = g.input("V")
            g.add(Se("e1", V), Se("e2", 2.0), J0("n"), C("c", p.k))
            g.bond("e1", "n")
            g.bond("e2", "n")
            g.bond("n", "c")
            g.output("x", g.displacement("c"))
            return g
        """),
    "blowup.py": textwrap.dedent("""\
        from bondgraph import *
        PARAMETERS = [Parameter("R", 1.0)]
        EXPERIMENT = Experiment(t_end=2.0, dt=0.01)

        def build(p):
            g = Model("blowup")          # dq/dt = q**2/R: q -> infinity at t = R/q0 = 1 s
            g.add(C("c", law=lambda q: -q**2, q0=1.0), R("r", p.R))
            g.bond("c", "r")
            g.output("q", g.displacement("c"))
            return g
        """),
    "notpy.txt": "this is not a python model {{{\n",
    "bad.json": "{not json",
    "list.json": "[1, 2]",
    "unknown.json": '{"params": {"zz_top": 1.0}}',
}
BINARY = b"\xff\xfe\x00\x01garbage\x00"

N = "!"  # needle prefix: this text must NOT be in the message

CASES = [
    # ---- model files --------------------------------------------------------------------
    pytest.param(["equations", "typo_port.py"], ["typo_port.py", "tf.p3", "did you mean", "tf.p1"],
                 id="wrong-port-name"),
    pytest.param(["equations", "typo_elem.py"], ["typo_elem.py", "'sprng'", "did you mean 'spring'"],
                 id="misspelt-element"),
    pytest.param(["params", "twoport_bare.py"], ["'tf'", "p1"], id="two-port-without-port"),
    pytest.param(["params", "syntax.py"], ["syntax.py:3", "syntax error"], id="syntax-error-file-line"),
    pytest.param(["params", "import_error.py"], ["import_error.py:3", "NameError", "undefined_name"],
                 id="error-at-import-file-line"),
    pytest.param(["equations", "raises.py"], ["raises.py:5", "RuntimeError", "boom here"], id="raise-in-build"),
    pytest.param(["params", "noparams.py"], ["noparams.py", "PARAMETERS"], id="missing-PARAMETERS"),
    pytest.param(["params", "nobuild.py"], ["nobuild.py", "build"], id="missing-build"),
    pytest.param(["params", "nonmodel.py"], ["nonmodel.py", "Model", "int"], id="build-returns-non-model"),
    pytest.param(["params", "badparams.py"], ["badparams.py", "PARAMETERS", "Parameter"],
                 id="PARAMETERS-not-parameters"),
    pytest.param(["params", "badexperiment.py"], ["EXPERIMENT", "Experiment"], id="EXPERIMENT-wrong-type"),
    pytest.param(["params", "duplicate.py"], ["'c'", "twice"], id="duplicate-element-name"),
    pytest.param(["params", "badlaw.py"], ["'cap'", "1/+"], id="unparsable-law"),
    pytest.param(["equations", "nobonds.py"], ["no bonds"], id="graph-without-bonds"),
    pytest.param(["equations", "oneport2.py"], ["'cap'", "already has a bond"], id="one-port-with-two-bonds"),
    pytest.param(["equations", "junction1.py"], ["'lonely'", "1 bond"], id="junction-with-one-bond"),
    pytest.param(["equations", "selfbond.py"], ["'j'", "itself"], id="bond-to-itself"),
    pytest.param(["equations", "unconnected.py"], ["'orphan'", "not connected"], id="unconnected-element"),
    pytest.param(["equations", "conflict.py"], ["causal conflict", "'e1'", "'e2'", "'n'"],
                 id="two-effort-sources-on-a-0-junction"),
    pytest.param(["causality", "conflict.py"], ["causal conflict"], id="conflict-causality-command"),
    pytest.param(["linearize", "conflict.py", "--json"], ["causal conflict"], id="conflict-linearize-command"),
    pytest.param(["simulate", "conflict.py"], ["causal conflict"], id="conflict-simulate-command"),
    pytest.param(["params", "nonexistent.py"], ["nonexistent.py", "not found"], id="nonexistent-model-file"),
    pytest.param(["params", "subdir"], ["subdir"], id="directory-as-model-file"),
    pytest.param(["params", "notpy.txt"], ["notpy.txt", "not a Python file"], id="non-python-file"),
    pytest.param(["params", "binary.py"], ["binary.py:"], id="binary-file"),
    pytest.param(["params", "binary.py"], ["binary.py:", N + ":None:"], id="binary-file-has-no-line-None"),
    # ---- --set ----------------------------------------------------------------------------
    pytest.param(["params", "good.py", "--set", "kk=2"], ["'kk'", "did you mean 'k'"], id="set-unknown-close"),
    pytest.param(["params", "good.py", "--set", "zzz=2"], ["'zzz'", "known:", "k", "lumped", "mode", "layers"],
                 id="set-unknown-lists-known"),
    pytest.param(["params", "good.py", "--set", "k=abc"], ["'abc'", "'k'", "real number"], id="set-non-numeric"),
    pytest.param(["params", "good.py", "--set", "k=nan"], ["'nan'", "'k'"], id="set-nan"),
    pytest.param(["params", "good.py", "--set", "k=inf"], ["'inf'", "'k'"], id="set-inf"),
    pytest.param(["params", "good.py", "--set", "lumped=maybe"], ["'maybe'", "'lumped'", "true or false"],
                 id="set-bool-maybe"),
    pytest.param(["params", "good.py", "--set", "mode=c"], ["'c'", "'mode'", "one of a, b"], id="set-unknown-choice"),
    pytest.param(["params", "good.py", "--set", "layers=2.5"], ["'layers'", "integer"], id="set-int-fraction"),
    pytest.param(["params", "good.py", "--set", "k"], ["--set 'k'", "NAME=VALUE"], id="set-missing-equals"),
    pytest.param(["params", "good.py", "--set", "k="], ["--set 'k='", "NAME=VALUE"], id="set-empty-value"),
    pytest.param(["params", "good.py", "--set", "=1"], ["--set '=1'"], id="set-empty-name"),
    # ---- --params-file ----------------------------------------------------------------------
    pytest.param(["params", "good.py", "--params-file", "bad.json"], ["bad.json:1", "not valid JSON"],
                 id="params-file-bad-json"),
    pytest.param(["params", "good.py", "--params-file", "missing.json"], ["missing.json", "not found"],
                 id="params-file-missing"),
    pytest.param(["params", "good.py", "--params-file", "list.json"], ["list.json", "JSON object"],
                 id="params-file-not-an-object"),
    pytest.param(["params", "good.py", "--params-file", "unknown.json"], ["'zz_top'", "known:"],
                 id="params-file-unknown-parameter"),
    # ---- --input ----------------------------------------------------------------------------
    pytest.param(["simulate", "good.py", "--input", "V=foo(amplitude=1)"], ["unknown signal kind 'foo'", "sine"],
                 id="input-unknown-kind"),
    pytest.param(["simulate", "good.py", "--input", "V=foo(1)"], ["unknown signal kind 'foo'"],
                 id="input-unknown-kind-positional"),
    pytest.param(["simulate", "good.py", "--input", "V=sine(amplitude=x)"], ["sine(amplitude=x)", "numbers"],
                 id="input-non-numeric"),
    pytest.param(["simulate", "good.py", "--input", "V=sine(amp=1)"], ["amp", "amplitude"], id="input-unknown-argument"),
    pytest.param(["simulate", "good.py", "--input", "V=sine(1, 2)"], ["key=value"], id="input-positional-arguments"),
    pytest.param(["simulate", "good.py", "--input", "V=pwl(0:1, 2)"], ["pwl("], id="input-bad-pwl-pair"),
    pytest.param(["simulate", "good.py", "--input", "V=pwl(1:0, 0:1)"], ["strictly increasing"],
                 id="input-pwl-time-decreasing"),
    pytest.param(["simulate", "good.py", "--input", "V=chirp(t1=0)"], ["t1", "positive"], id="input-chirp-t1-zero"),
    pytest.param(["simulate", "good.py", "--input", "V=sine(amplitude=1"], ["sine(amplitude=1"],
                 id="input-unbalanced-parenthesis"),
    pytest.param(["simulate", "good.py", "--input", "V=inf"], ["'inf'", "finite"], id="input-infinite-constant"),
    pytest.param(["simulate", "good.py", "--input", "V=sine(amplitude=nan)"], ["nan", "finite"],
                 id="input-nan-argument"),
    pytest.param(["simulate", "good.py", "--input", "W=1"], ["'W'", "V"], id="input-unknown-name"),
    pytest.param(["simulate", "good.py", "--input", "V"], ["--input 'V'", "NAME=SIGNAL"], id="input-missing-equals"),
    pytest.param(["simulate", "good.py", "--input", "V=csv(file=nothere.csv, column=V)"], ["nothere.csv"],
                 id="input-csv-missing-file"),
    # ---- times, tolerances, options -------------------------------------------------------------
    pytest.param(["simulate", "good.py", "--t-end", "-1"], ["t_end=-1"], id="negative-t-end"),
    pytest.param(["simulate", "good.py", "--dt", "-0.1"], ["dt=-0.1"], id="negative-dt"),
    pytest.param(["simulate", "good.py", "--dt", "0"], ["dt=0"], id="zero-dt"),
    pytest.param(["simulate", "good.py", "--t-end", "nan"], ["t_end=nan"], id="nan-t-end"),
    pytest.param(["simulate", "good.py", "--t-end", "1e9", "--dt", "1e-9"], ["samples"], id="too-many-samples"),
    pytest.param(["simulate", "good.py", "--t-end", "abc"], ["--t-end", "'abc'"], id="non-numeric-t-end"),
    pytest.param(["simulate", "good.py", "--method", "euler"], ["'euler'", "dopri5"], id="unknown-method"),
    pytest.param(["equations", "good.py", "--format", "pdf"], ["'pdf'", "latex"], id="unknown-format"),
    pytest.param(["linearize", "good.py", "--input", "U"], ["'U'", "V"], id="linearize-unknown-input"),
    pytest.param(["linearize", "good.py", "--output", "y"], ["'y'", "x"], id="linearize-unknown-output"),
    pytest.param(["simulate", "blowup.py"], ["integration failed", "t = 1"], id="integration-failure"),
    # ---- argparse usage errors ------------------------------------------------------------------
    pytest.param(["frobnicate", "good.py"], ["'frobnicate'", "invalid choice"], id="unknown-subcommand"),
    pytest.param(["simulate"], ["MODEL", "required"], id="missing-model-argument"),
    pytest.param(["params", "good.py", "--bogus"], ["--bogus"], id="unknown-option"),
    pytest.param(["params", "good.py", "--set"], ["--set", "expected one argument"], id="option-missing-value"),
    pytest.param(["--no-such-flag"], ["--no-such-flag"], id="unknown-global-option"),
    pytest.param([], ["command"], id="no-arguments"),
]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    for name, text in FILES.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    (tmp_path / "binary.py").write_bytes(BINARY)
    (tmp_path / "subdir").mkdir()
    monkeypatch.chdir(tmp_path)
    return tmp_path


def run_cli(argv, capsys):
    try:
        rc = main(list(argv))
    except SystemExit as exc:  # argparse must not exit on its own
        rc = f"SystemExit({exc.code})"
    out, err = capsys.readouterr()
    return rc, out, err


def check_one_error_line(rc, out, err, needles):
    assert rc == 2, f"exit status {rc!r}, stderr: {err!r}"
    assert "Traceback" not in err and "Traceback" not in out
    lines = err.splitlines()
    assert len(lines) == 1, f"expected one line on stderr, got {len(lines)}: {err!r}"
    line = lines[0]
    assert line.startswith("bondgraph: error: "), line
    for needle in needles:
        if needle.startswith(N):
            assert needle[1:] not in line, f"{needle[1:]!r} should not be in {line!r}"
        else:
            assert needle in line, f"{needle!r} not in {line!r}"


@pytest.mark.parametrize("argv, needles", CASES)
def test_bad_input_is_one_error_line_and_exit_2(argv, needles, workdir, capsys):
    rc, out, err = run_cli(argv, capsys)
    check_one_error_line(rc, out, err, needles)
    assert not [p for p in os.listdir(workdir) if p.endswith(".tmp") or p.endswith(".csv")]


def test_the_good_model_runs(workdir, capsys):
    """The reference model of the table is itself fine (so the cases fail for their own reason)."""
    for argv in (["params", "good.py"], ["equations", "good.py"], ["causality", "good.py"],
                 ["linearize", "good.py", "--json"], ["simulate", "good.py", "--quiet", "--t-end", "0.01"]):
        rc, out, err = run_cli(argv, capsys)
        assert rc == 0, (argv, err)
        assert err == "", (argv, err)
        assert out


# ---- real processes ---------------------------------------------------------------------------------
SUBPROCESS_CASES = [
    (["equations", "typo_port.py"], ["tf.p3", "did you mean"]),
    (["simulate", "good.py", "--set", "lumped=maybe"], ["'maybe'"]),
    (["frobnicate"], ["'frobnicate'"]),
    (["simulate", "good.py", "--input", "V=sine(amp=1)", "--out", "never.csv"], ["amp"]),
]


def test_real_processes_exit_2_without_traceback(workdir):
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    procs = [subprocess.Popen([sys.executable, "-m", "bondgraph", *argv], cwd=workdir, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for argv, _ in SUBPROCESS_CASES]
    for proc, (argv, needles) in zip(procs, SUBPROCESS_CASES):
        out, err = proc.communicate(timeout=120)
        check_one_error_line(proc.returncode, out, err, needles)
    assert not (workdir / "never.csv").exists()


# ---- --out: nothing on failure, the CONTRACT CSV on success --------------------------------------------
@pytest.mark.parametrize("argv", [
    pytest.param(["simulate", "conflict.py"], id="causal-conflict"),
    pytest.param(["simulate", "typo_elem.py"], id="model-error"),
    pytest.param(["simulate", "blowup.py"], id="integration-failure"),
    pytest.param(["simulate", "good.py", "--input", "V=bogus(x=1)"], id="bad-input"),
    pytest.param(["simulate", "good.py", "--t-end", "-1"], id="bad-t-end"),
])
def test_failed_simulate_leaves_no_output_file(argv, workdir, capsys):
    before = set(os.listdir(workdir))
    rc, out, err = run_cli([*argv, "--out", "result.csv"], capsys)
    check_one_error_line(rc, out, err, [])
    assert set(os.listdir(workdir)) == before, "files left behind: " + str(set(os.listdir(workdir)) - before)


def test_failed_simulate_keeps_an_existing_output_file(workdir, capsys):
    (workdir / "result.csv").write_text("t,x\n0,1\n1,2\n")
    before = set(os.listdir(workdir))
    rc, out, err = run_cli(["simulate", "blowup.py", "--out", "result.csv"], capsys)
    check_one_error_line(rc, out, err, ["integration failed"])
    assert (workdir / "result.csv").read_text() == "t,x\n0,1\n1,2\n"
    assert set(os.listdir(workdir)) == before


def test_out_into_a_missing_directory_is_an_input_error(workdir, capsys):
    rc, out, err = run_cli(["simulate", "good.py", "--out", "no/such/dir/result.csv"], capsys)
    check_one_error_line(rc, out, err, ["no/such/dir/result.csv"])
    assert not (workdir / "no").exists()


def test_simulate_out_writes_the_contract_csv(workdir, capsys):
    rc, out, err = run_cli(["simulate", "good.py", "--out", "result.csv", "--quiet", "--states",
                            "--set", "k=400", "--t-end", "0.02", "--dt", "0.001"], capsys)
    assert rc == 0, err
    assert err == "" and out == ""
    assert sorted(os.listdir(workdir)) == sorted([*FILES, "binary.py", "subdir", "result.csv"])
    text = (workdir / "result.csv").read_text(encoding="utf-8")
    lines = text.splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    data = [ln for ln in lines if not ln.startswith("#")]
    assert comments and all(": " in ln for ln in comments)
    assert lines[:len(comments)] == comments, "metadata comments come before the header"
    header = data[0].split(",")
    assert header[0] == "t" and "V" in header and "x" in header
    ds = read_csv(workdir / "result.csv", required=("t", "V", "x"))
    assert ds.names[0] == "t"
    assert len(ds) == 21
    np.testing.assert_allclose(ds.t, np.linspace(0, 0.02, 21), rtol=0, atol=1e-15)
    assert np.all(np.diff(ds.t) > 0)
    np.testing.assert_array_equal(ds.columns["V"], np.ones(21))  # EXPERIMENT: V = Step(1.0) at t = 0
    assert ds.metadata["model"] == "good.py"
    assert ds.metadata["param k"] == "400.0"
    assert "input V" in ds.metadata and "method" in ds.metadata
    assert {"p_mass", "q_spring"} <= set(ds.columns)
    np.testing.assert_allclose(ds.columns["x"], ds.columns["q_spring"])
    # the step response of m x'' + c x' + k x = 1 rises from 0 towards 1/k
    assert ds.columns["x"][0] == 0 and 0 < ds.columns["x"][-1] < 2 / 400
