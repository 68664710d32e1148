"""Bad inputs through the command line: exit status 2, exactly one line on stderr starting
with 'bondgraph: error:', no traceback, a message that names the problem (and the fix, where
the table says so), and nothing written: the working directory is byte for byte the same.

The cases are one table (``CASES``), built from the deviations a new user reported and from
every promise the README and ``--help`` make; each runs in-process through
``bondgraph.cli.main``.  A few also run as real processes (``python -m bondgraph``) to check
the exit status the shell sees.  The small model and data files the cases need are written
into a temporary directory.
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
        Parameter("layers", 3, "", "an integer", bounds=(1, 100)),
        Parameter("zeta", 0.1, "", "a bounded real", bounds=(0.0, 1.0)),
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
    "badexperiment.py": HEAD
    + "EXPERIMENT = 5\n"
    + textwrap.dedent("""\
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
FILES.update(
    {
        "exits.py": HEAD + "import sys\nsys.exit(3)\n",
        "exits_in_build.py": HEAD + "import sys\ndef build(p):\n    sys.exit(4)\n",
        "twice.py": "from bondgraph import *\nPARAMETERS = [Parameter('k', 1.0), Parameter('k', 2.0)]\n"
        "def build(p):\n    return Model('x')\n",
        "badname.py": "from bondgraph import *\nPARAMETERS = [Parameter('1k', 1.0)]\ndef build(p):\n    return Model('x')\n",
        "textparam.py": "from bondgraph import *\nPARAMETERS = [Parameter('mode', 'a')]\ndef build(p):\n    return Model('x')\n",
        "recursion.py": HEAD + "def build(p):\n    return build(p)\n",
        "empty.py": "",
        "returns_none.py": HEAD + "def build(p):\n    return None\n",
        "noio.py": _model("""\
        def build(p):
            g = Model("noio")
            g.add(Se("s", 1.0), J1("j"), C("c", p.k), R("r", 1.0))
            g.bond("s", "j")
            g.bond("j", "c")
            g.bond("j", "r")
            return g
        """),
        "badexpinput.py": GOOD.replace('inputs={"V": Step(1.0)}', 'inputs={"W": Step(1.0)}'),
        "dup_key.json": '{"k": 1.0, "k": 2.0}',
        "null.json": '{"k": null}',
        "params_list.json": '{"params": [1, 2]}',
        "bad_offset.json": '{"params": {"k": 100.0}, "output": "x", "offset": "abc"}',
        "offset_elsewhere.json": '{"params": {"k": 100.0}, "output": "y", "offset": 0.001}',
        "bounds.json": '{"zeta": 5}',
        "params_dir.json/": None,
        "data.csv": "t,V,x\n" + "".join(f"{k * 1e-3!r},{(k % 7) * 0.1!r},{(k % 5) * 1e-6!r}\n" for k in range(60)),
        "data_nan.csv": "t,V,x\n0,0,0\n0.001,nan,0\n0.002,1,0\n",
        "data_decreasing.csv": "t,V,x\n0,0,0\n0.002,1,0\n0.001,1,0\n",
        "data_text.csv": "t,V,x\n0,0,0\n0.001,abc,0\n0.002,1,0\n",
        "data_header_only.csv": "t,V,x\n",
        "data_empty.csv": "",
        "data_no_x.csv": "t,V,y\n0,0,0\n0.001,1,0\n0.002,1,0\n",
        "ref.csv": "t,x\n0,0\n0.01,1e-6\n0.02,2e-6\n",
        "data_const.csv": "t,V,x\n" + "".join(f"{k * 1e-3!r},2.5,{(k % 5) * 1e-6!r}\n" for k in range(60)),
    }
)
BINARY = b"\xff\xfe\x00\x01garbage\x00"

N = "!"  # needle prefix: this text must NOT be in the message

CASES = [
    # ---- model files --------------------------------------------------------------------
    pytest.param(
        ["equations", "typo_port.py"], ["typo_port.py", "tf.p3", "did you mean", "tf.p1"], id="wrong-port-name"
    ),
    pytest.param(
        ["equations", "typo_elem.py"], ["typo_elem.py", "'sprng'", "did you mean 'spring'"], id="misspelt-element"
    ),
    pytest.param(["params", "twoport_bare.py"], ["'tf'", "p1"], id="two-port-without-port"),
    pytest.param(["params", "syntax.py"], ["syntax.py:3", "syntax error"], id="syntax-error-file-line"),
    pytest.param(
        ["params", "import_error.py"],
        ["import_error.py:3", "NameError", "undefined_name"],
        id="error-at-import-file-line",
    ),
    pytest.param(["equations", "raises.py"], ["raises.py:5", "RuntimeError", "boom here"], id="raise-in-build"),
    pytest.param(["params", "noparams.py"], ["noparams.py", "PARAMETERS"], id="missing-PARAMETERS"),
    pytest.param(["params", "nobuild.py"], ["nobuild.py", "build"], id="missing-build"),
    pytest.param(["params", "nonmodel.py"], ["nonmodel.py", "Model", "int"], id="build-returns-non-model"),
    pytest.param(
        ["params", "badparams.py"], ["badparams.py", "PARAMETERS", "Parameter"], id="PARAMETERS-not-parameters"
    ),
    pytest.param(["params", "badexperiment.py"], ["EXPERIMENT", "Experiment"], id="EXPERIMENT-wrong-type"),
    pytest.param(["params", "duplicate.py"], ["'c'", "twice"], id="duplicate-element-name"),
    pytest.param(["params", "badlaw.py"], ["'cap'", "1/+"], id="unparsable-law"),
    pytest.param(["equations", "nobonds.py"], ["no bonds"], id="graph-without-bonds"),
    pytest.param(["equations", "oneport2.py"], ["'cap'", "already has a bond"], id="one-port-with-two-bonds"),
    pytest.param(["equations", "junction1.py"], ["'lonely'", "1 bond"], id="junction-with-one-bond"),
    pytest.param(["equations", "selfbond.py"], ["'j'", "itself"], id="bond-to-itself"),
    pytest.param(["equations", "unconnected.py"], ["'orphan'", "not connected"], id="unconnected-element"),
    pytest.param(
        ["equations", "conflict.py"],
        ["causal conflict", "'e1'", "'e2'", "'n'"],
        id="two-effort-sources-on-a-0-junction",
    ),
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
    pytest.param(
        ["params", "good.py", "--set", "zzz=2"],
        ["'zzz'", "known:", "k", "lumped", "mode", "layers"],
        id="set-unknown-lists-known",
    ),
    pytest.param(["params", "good.py", "--set", "k=abc"], ["'abc'", "'k'", "real number"], id="set-non-numeric"),
    pytest.param(["params", "good.py", "--set", "k=nan"], ["'nan'", "'k'"], id="set-nan"),
    pytest.param(["params", "good.py", "--set", "k=inf"], ["'inf'", "'k'"], id="set-inf"),
    pytest.param(
        ["params", "good.py", "--set", "lumped=maybe"], ["'maybe'", "'lumped'", "true or false"], id="set-bool-maybe"
    ),
    pytest.param(["params", "good.py", "--set", "mode=c"], ["'c'", "'mode'", "one of a, b"], id="set-unknown-choice"),
    pytest.param(["params", "good.py", "--set", "layers=2.5"], ["'layers'", "integer"], id="set-int-fraction"),
    pytest.param(["params", "good.py", "--set", "k"], ["--set 'k'", "NAME=VALUE"], id="set-missing-equals"),
    pytest.param(["params", "good.py", "--set", "k="], ["--set 'k='", "NAME=VALUE"], id="set-empty-value"),
    pytest.param(["params", "good.py", "--set", "=1"], ["--set '=1'"], id="set-empty-name"),
    # ---- --params-file ----------------------------------------------------------------------
    pytest.param(
        ["params", "good.py", "--params-file", "bad.json"], ["bad.json:1", "not valid JSON"], id="params-file-bad-json"
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "missing.json"], ["missing.json", "not found"], id="params-file-missing"
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "list.json"],
        ["list.json", "JSON object"],
        id="params-file-not-an-object",
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "unknown.json"],
        ["'zz_top'", "known:"],
        id="params-file-unknown-parameter",
    ),
    # ---- --input ----------------------------------------------------------------------------
    pytest.param(
        ["simulate", "good.py", "--input", "V=foo(amplitude=1)"],
        ["unknown signal kind 'foo'", "sine"],
        id="input-unknown-kind",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=foo(1)"],
        ["unknown signal kind 'foo'"],
        id="input-unknown-kind-positional",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=sine(amplitude=x)"],
        ["sine(amplitude=x)", "numbers"],
        id="input-non-numeric",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=sine(amp=1)"], ["amp", "amplitude"], id="input-unknown-argument"
    ),
    pytest.param(["simulate", "good.py", "--input", "V=sine(1, 2)"], ["key=value"], id="input-positional-arguments"),
    pytest.param(["simulate", "good.py", "--input", "V=pwl(0:1, 2)"], ["pwl("], id="input-bad-pwl-pair"),
    pytest.param(
        ["simulate", "good.py", "--input", "V=pwl(1:0, 0:1)"], ["strictly increasing"], id="input-pwl-time-decreasing"
    ),
    pytest.param(["simulate", "good.py", "--input", "V=chirp(t1=0)"], ["t1", "positive"], id="input-chirp-t1-zero"),
    pytest.param(
        ["simulate", "good.py", "--input", "V=sine(amplitude=1"],
        ["sine(amplitude=1"],
        id="input-unbalanced-parenthesis",
    ),
    pytest.param(["simulate", "good.py", "--input", "V=inf"], ["'inf'", "finite"], id="input-infinite-constant"),
    pytest.param(
        ["simulate", "good.py", "--input", "V=sine(amplitude=nan)"], ["nan", "finite"], id="input-nan-argument"
    ),
    pytest.param(["simulate", "good.py", "--input", "W=1"], ["'W'", "V"], id="input-unknown-name"),
    pytest.param(["simulate", "good.py", "--input", "V"], ["--input 'V'", "NAME=SIGNAL"], id="input-missing-equals"),
    pytest.param(
        ["simulate", "good.py", "--input", "V=csv(file=nothere.csv, column=V)"],
        ["nothere.csv"],
        id="input-csv-missing-file",
    ),
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
    # ---- model files: more ---------------------------------------------------------------------
    pytest.param(["params", "exits.py"], ["exits.py:4", "sys.exit(3)"], id="model-file-calls-sys-exit"),
    pytest.param(
        ["equations", "exits_in_build.py"], ["exits_in_build.py:5", "sys.exit(4)", "return"], id="build-calls-sys-exit"
    ),
    pytest.param(["params", "twice.py"], ["'k'", "declared twice", "once"], id="parameter-declared-twice"),
    pytest.param(["params", "badname.py"], ["'1k'", "identifier"], id="parameter-name-not-identifier"),
    pytest.param(["params", "textparam.py"], ["'mode'", "choices"], id="text-parameter-without-choices"),
    pytest.param(["equations", "recursion.py"], ["recursion.py:4", "RecursionError"], id="build-recurses-forever"),
    pytest.param(["params", "empty.py"], ["empty.py", "PARAMETERS"], id="empty-model-file"),
    pytest.param(["params", "returns_none.py"], ["Model", "NoneType"], id="build-returns-none"),
    pytest.param(["simulate", "badexpinput.py"], ["'W'", "V"], id="EXPERIMENT-drives-unknown-input"),
    pytest.param(["linearize", "noio.py"], ["declares no input"], id="linearize-model-without-input"),
    pytest.param(["fit", "noio.py", "data.csv", "--params", "k"], ["declares no input"], id="fit-model-without-input"),
    # ---- degenerate and out-of-range parameter values ---------------------------------------------
    pytest.param(
        ["simulate", "good.py", "--set", "m=0", "--out", "r.csv"],
        ["m=0", "divide by zero", "physical value"],
        id="simulate-mass-zero",
    ),
    pytest.param(
        ["simulate", "good.py", "--set", "m=1e-300", "--out", "r.csv"],
        ["m=1e-300", "time constant"],
        id="simulate-mass-1e-300",
    ),
    pytest.param(["linearize", "good.py", "--set", "m=0"], ["m=0", "not finite"], id="linearize-mass-zero"),
    pytest.param(["linearize", "good.py", "--set", "m=1e-300"], ["m=1e-300"], id="linearize-mass-1e-300"),
    pytest.param(["fit", "good.py", "data.csv", "--params", "k", "--set", "m=0"], ["m=0"], id="fit-mass-zero"),
    pytest.param(["simulate", "good.py", "--set", "k=1e400"], ["'1e400'", "'k'", "finite"], id="set-overflows-to-inf"),
    pytest.param(
        ["params", "good.py", "--set", "zeta=2"],
        ["'zeta'", "outside its bounds [0.0, 1.0]"],
        id="set-real-out-of-bounds",
    ),
    pytest.param(
        ["params", "good.py", "--set", "layers=0"],
        ["'layers'", "outside its bounds [1, 100]"],
        id="set-int-out-of-bounds",
    ),
    pytest.param(
        ["params", "good.py", "--set", "k=1", "--set", "k=2"], ["--set k given twice", "once"], id="set-same-name-twice"
    ),
    # ---- parameter files: more --------------------------------------------------------------------
    pytest.param(
        ["params", "good.py", "--params-file", "dup_key.json"],
        ["dup_key.json", "'k'", "twice"],
        id="params-file-duplicate-name",
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "null.json"], ["null.json", "'k'", "null"], id="params-file-null-value"
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "params_list.json"],
        ["'params'", "object"],
        id="params-file-params-not-object",
    ),
    pytest.param(
        ["simulate", "good.py", "--params-file", "bad_offset.json"],
        ["'offset'", "finite number"],
        id="params-file-offset-not-number",
    ),
    pytest.param(
        ["simulate", "good.py", "--params-file", "offset_elsewhere.json"],
        ["output 'y'", "x"],
        id="params-file-offset-for-unknown-output",
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "bounds.json"],
        ["'zeta'", "bounds"],
        id="params-file-value-out-of-bounds",
    ),
    pytest.param(
        ["params", "good.py", "--params-file", "params_dir.json"],
        ["params_dir.json", "directory"],
        id="params-file-is-a-directory",
    ),
    # ---- output paths: checked before any work, nothing written -------------------------------------
    pytest.param(
        ["simulate", "good.py", "--out", "r.csv", "--plot", "no/such/p.png"],
        ["--plot no/such/p.png", "does not exist", "create it"],
        id="plot-into-missing-directory",
    ),
    pytest.param(
        ["simulate", "good.py", "--out", "subdir"],
        ["--out subdir", "is a directory", "file name"],
        id="out-is-a-directory",
    ),
    pytest.param(
        ["simulate", "good.py", "--plot", "p.txt"], ["--plot p.txt", "'.txt'", ".png"], id="plot-unknown-format"
    ),
    pytest.param(["simulate", "good.py", "--plot", "p"], ["--plot p", ".png"], id="plot-without-suffix"),
    pytest.param(
        ["simulate", "good.py", "--out", "r.png", "--plot", "r.png"],
        ["r.png", "same file"],
        id="out-and-plot-same-file",
    ),
    pytest.param(
        ["simulate", "good.py", "--out", "good.py"],
        ["--out good.py", "overwrite the input file"],
        id="out-overwrites-the-model-file",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=csv(file=data.csv, column=V)", "--out", "data.csv"],
        ["--out data.csv", "overwrite the input"],
        id="out-overwrites-a-csv-input",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--out", "data.csv"],
        ["--out data.csv", "overwrite the input"],
        id="fit-out-overwrites-the-data",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--out", "f.json", "--params-file", "f.json"],
        ["--out f.json", "overwrite the input file f.json"],
        id="fit-out-overwrites-the-params-file",
    ),
    pytest.param(
        ["simulate", "raises.py", "--out", "no/dir/r.csv"],
        ["--out no/dir/r.csv", "does not exist"],
        id="output-checked-before-the-model-is-built",
    ),
    pytest.param(["simulate", "good.py", "--out", ""], ["--out", "empty file name"], id="out-empty-name"),
    pytest.param(
        ["equations", "good.py", "--out", "no/dir/eq.txt"],
        ["--out no/dir/eq.txt", "does not exist"],
        id="equations-out-missing-directory",
    ),
    pytest.param(
        ["causality", "good.py", "--plot", "no/dir/bg.png"],
        ["--plot no/dir/bg.png", "does not exist"],
        id="causality-plot-missing-directory",
    ),
    pytest.param(
        ["linearize", "good.py", "--bode", "no/dir/b.csv"],
        ["--bode no/dir/b.csv", "does not exist"],
        id="linearize-bode-missing-directory",
    ),
    pytest.param(
        ["linearize", "good.py", "--plot", "b.jpeg"], ["--plot b.jpeg", "'.jpeg'"], id="linearize-plot-unknown-format"
    ),
    pytest.param(
        ["linearize", "good.py", "--out", "no/dir/lin.py"],
        ["--out no/dir/lin.py", "does not exist"],
        id="linearize-out-missing-directory",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--plot", "f.gif"],
        ["--plot f.gif", "'.gif'"],
        id="fit-plot-unknown-format",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--out", "no/dir/f.json"],
        ["--out no/dir/f.json", "does not exist"],
        id="fit-out-missing-directory",
    ),
    pytest.param(
        ["diagnose", "good.py", "data.csv", "--plot", "no/dir/d.png"],
        ["--plot no/dir/d.png", "does not exist"],
        id="diagnose-plot-missing-directory",
    ),
    # ---- measured inputs of simulate --------------------------------------------------------------
    pytest.param(
        ["simulate", "good.py", "--input", "V=csv(file=data.csv, column=V)", "--t-end", "5"],
        ["--t-end 5", "beyond the end of the input data", "0.059", "shorten --t-end"],
        id="t-end-beyond-the-csv-input",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=csv(file=data.csv, column=Q)"],
        ["data.csv", "'Q'"],
        id="csv-input-unknown-column",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=csv(column=V)"],
        ["csv(file=PATH, column=NAME)"],
        id="csv-input-without-file",
    ),
    pytest.param(
        ["simulate", "good.py", "--input", "V=1", "--input", "V=2"],
        ["--input V given twice", "once"],
        id="input-given-twice",
    ),
    pytest.param(["simulate", "good.py", "--input", "=1"], ["--input '=1'", "NAME=SIGNAL"], id="input-empty-name"),
    # ---- tolerances and counts --------------------------------------------------------------------
    pytest.param(["simulate", "good.py", "--rtol", "0"], ["--rtol", "between 0 and 1"], id="rtol-zero"),
    pytest.param(["simulate", "good.py", "--rtol", "2"], ["--rtol", "between 0 and 1"], id="rtol-above-one"),
    pytest.param(["simulate", "good.py", "--rtol", "nan"], ["--rtol", "between 0 and 1"], id="rtol-nan"),
    pytest.param(["simulate", "good.py", "--atol", "-1"], ["--atol", "positive"], id="atol-negative"),
    pytest.param(["simulate", "good.py", "--t-end", "0"], ["t_end=0"], id="zero-t-end"),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--starts", "0"],
        ["--starts", "at least 1"],
        id="fit-starts-zero",
    ),
    pytest.param(
        ["diagnose", "good.py", "data.csv", "--workers", "0"], ["--workers", "at least 1"], id="diagnose-workers-zero"
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--validation", "0"],
        ["--validation", "between 0 and 1"],
        id="fit-validation-zero",
    ),
    pytest.param(
        ["diagnose", "good.py", "data.csv", "--validation", "1.5"],
        ["--validation", "between 0 and 1"],
        id="diagnose-validation-above-one",
    ),
    # ---- fit ---------------------------------------------------------------------------------------
    pytest.param(["fit", "good.py", "data.csv"], ["give the parameters to fit", "--params"], id="fit-without-params"),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "kk"], ["'kk'", "did you mean 'k'"], id="fit-unknown-parameter"
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k,k"], ["k listed twice", "once"], id="fit-parameter-listed-twice"
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "lumped"],
        ["'lumped'", "true or false", "only real-valued"],
        id="fit-boolean-parameter",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--split", "random"],
        ["'random'", "blocks"],
        id="fit-unknown-split",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--loss", "l3"], ["'l3'", "soft_l1"], id="fit-unknown-loss"
    ),
    pytest.param(["fit", "good.py", "missing.csv", "--params", "k"], ["missing.csv"], id="fit-data-file-missing"),
    pytest.param(
        ["fit", "good.py", "data_no_x.csv", "--params", "k"],
        ["data_no_x.csv", "'x'", "--output"],
        id="fit-data-without-output-column",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--input", "Vin"],
        ["data.csv", "'Vin'"],
        id="fit-data-input-column-missing",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--model-input", "W"],
        ["'W'", "V"],
        id="fit-unknown-model-input",
    ),
    pytest.param(
        ["fit", "good.py", "data.csv", "--params", "k", "--model-output", "y"],
        ["'y'", "x"],
        id="fit-unknown-model-output",
    ),
    pytest.param(["fit", "good.py", "data_nan.csv", "--params", "k"], ["data_nan.csv:3", "nan"], id="fit-data-nan"),
    pytest.param(
        ["fit", "good.py", "data_decreasing.csv", "--params", "k"],
        ["data_decreasing.csv", "increasing"],
        id="fit-data-time-decreasing",
    ),
    pytest.param(
        ["fit", "good.py", "data_text.csv", "--params", "k"], ["data_text.csv:3", "abc"], id="fit-data-non-numeric-cell"
    ),
    pytest.param(
        ["fit", "good.py", "data_header_only.csv", "--params", "k"], ["data_header_only.csv"], id="fit-data-header-only"
    ),
    pytest.param(
        ["fit", "good.py", "data_empty.csv", "--params", "k"], ["data_empty.csv", "empty"], id="fit-data-empty-file"
    ),
    pytest.param(["diagnose", "good.py", "missing.csv"], ["missing.csv"], id="diagnose-data-file-missing"),
    pytest.param(
        ["fit", "good.py", "data_const.csv", "--params", "k", "--out", "f.json"],
        ["data_const.csv", "'V'", "constant"],
        id="fit-constant-input",
    ),
    pytest.param(
        ["diagnose", "good.py", "data_const.csv", "--plot", "d.png"],
        ["data_const.csv", "'V'", "constant"],
        id="diagnose-constant-input",
    ),
    # ---- linearize -------------------------------------------------------------------------------------
    pytest.param(
        ["linearize", "good.py", "--json", "--format", "python-control"],
        ["--json", "contradict"],
        id="linearize-json-and-python-control",
    ),
    pytest.param(
        ["linearize", "good.py", "--format", "matlab"], ["'matlab'", "python-control"], id="linearize-unknown-format"
    ),
    # ---- compensate and batch ----------------------------------------------------------------------------
    pytest.param(
        ["compensate", "good.py", "ref.csv", "--plot", "no/dir/c.png"],
        ["--plot no/dir/c.png", "does not exist"],
        id="compensate-plot-missing-directory",
    ),
    pytest.param(
        ["compensate", "good.py", "ref.csv", "--out", "ref.csv"],
        ["--out ref.csv", "overwrite the input"],
        id="compensate-out-overwrites-the-reference",
    ),
    pytest.param(
        ["compensate", "good.py", "missing.csv"], ["missing.csv", "no such file"], id="compensate-reference-missing"
    ),
    pytest.param(
        ["compensate", "good.py", "data_no_x.csv"],
        ["data_no_x.csv", "'x'"],
        id="compensate-reference-without-output-column",
    ),
    pytest.param(
        ["compensate", "good.py", "ref.csv", "--iterations", "0"],
        ["--iterations", "at least 1"],
        id="compensate-iterations-zero",
    ),
    pytest.param(
        ["compensate", "good.py", "ref.csv", "--tol", "2"], ["--tol", "between 0 and 1"], id="compensate-tol-above-one"
    ),
    pytest.param(
        ["batch", "fit", "good.py", "--params", "k"], ["batch fit", "data files"], id="batch-fit-without-data"
    ),
    pytest.param(
        ["batch", "sweep", "good.py", "data.csv"], ["batch sweep", "no data files"], id="batch-sweep-with-data"
    ),
    pytest.param(["batch", "frobnicate", "good.py"], ["'frobnicate'", "diagnose"], id="batch-unknown-action"),
    # ---- options after the subcommand -----------------------------------------------------------------
    pytest.param(["params", "good.py", "--set", "kk=2", "--no-debug"], ["--no-debug"], id="unknown-option-near-debug"),
    pytest.param(["equations", "--format", "latex"], ["MODEL", "required"], id="equations-without-model"),
    pytest.param(["fit", "good.py"], ["DATA", "required"], id="fit-without-data"),
]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    for name, text in FILES.items():
        if text is None:
            (tmp_path / name.rstrip("/")).mkdir()
        else:
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


def snapshot(directory):
    """Every file below ``directory`` with its size, modification time and content hash."""
    import hashlib

    out = {}
    for root, dirs, files in os.walk(directory):
        for name in dirs + files:
            p = os.path.join(root, name)
            st = os.stat(p)
            digest = hashlib.sha1(open(p, "rb").read()).hexdigest() if os.path.isfile(p) else "dir"
            out[os.path.relpath(p, directory)] = (st.st_size, st.st_mtime_ns, digest)
    return out


@pytest.mark.parametrize("argv, needles", CASES)
def test_bad_input_is_one_error_line_and_exit_2(argv, needles, workdir, capsys):
    before = snapshot(workdir)
    rc, out, err = run_cli(argv, capsys)
    check_one_error_line(rc, out, err, needles)
    after = snapshot(workdir)
    assert after == before, f"files changed: {sorted(set(after.items()) ^ set(before.items()))}"


def test_the_table_has_the_promised_size():
    assert len(CASES) >= 116
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids)), "case ids are unique"


def test_the_good_model_runs(workdir, capsys):
    """The reference model of the table is itself fine (so the cases fail for their own reason)."""
    for argv in (
        ["params", "good.py"],
        ["equations", "good.py"],
        ["causality", "good.py"],
        ["linearize", "good.py", "--json"],
        ["simulate", "good.py", "--quiet", "--t-end", "0.01"],
    ):
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
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "bondgraph", *argv],
            cwd=workdir,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for argv, _ in SUBPROCESS_CASES
    ]
    for proc, (argv, needles) in zip(procs, SUBPROCESS_CASES):
        out, err = proc.communicate(timeout=120)
        check_one_error_line(proc.returncode, out, err, needles)
    assert not (workdir / "never.csv").exists()


# ---- --out: nothing on failure, the documented CSV on success --------------------------------------------
@pytest.mark.parametrize(
    "argv",
    [
        pytest.param(["simulate", "conflict.py"], id="causal-conflict"),
        pytest.param(["simulate", "typo_elem.py"], id="model-error"),
        pytest.param(["simulate", "blowup.py"], id="integration-failure"),
        pytest.param(["simulate", "good.py", "--input", "V=bogus(x=1)"], id="bad-input"),
        pytest.param(["simulate", "good.py", "--t-end", "-1"], id="bad-t-end"),
    ],
)
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


def test_simulate_out_writes_the_documented_csv(workdir, capsys):
    rc, out, err = run_cli(
        [
            "simulate",
            "good.py",
            "--out",
            "result.csv",
            "--quiet",
            "--states",
            "--set",
            "k=400",
            "--t-end",
            "0.02",
            "--dt",
            "0.001",
        ],
        capsys,
    )
    assert rc == 0, err
    assert err == "" and out == ""
    assert sorted(os.listdir(workdir)) == sorted([*(f.rstrip("/") for f in FILES), "binary.py", "subdir", "result.csv"])
    text = (workdir / "result.csv").read_text(encoding="utf-8")
    lines = text.splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    data = [ln for ln in lines if not ln.startswith("#")]
    assert comments and all(": " in ln for ln in comments)
    assert lines[: len(comments)] == comments, "metadata comments come before the header"
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
