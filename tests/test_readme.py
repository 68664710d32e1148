"""Examples are tests: every command and Python example of README.md and of the user-guide
pages in docs/ runs (a shell block's commands in order, in a directory with the README's
model file and data), and the numbers the README shows are the numbers they give."""

import contextlib
import io
import re
import shlex

import numpy as np
import pytest
from conftest import ROOT
from truth import apa_data

from bondgraph.cli import main
from bondgraph.data import read_csv, write_csv

README = (ROOT / "README.md").read_text()
#: the user-guide pages whose shell examples run with the README's (docs/papers.md's figure
#: commands run, with their numbers asserted, in the tests of each paper's model)
GUIDES = [(ROOT / "docs" / page).read_text() for page in ("batch.md", "fitting.md")]


def blocks(lang, texts=(README,)):
    return [b for text in texts for b in re.findall(rf"```{lang}\n(.*?)```", text, re.S)]


def python_block(containing: str) -> str:
    return next(b for b in blocks("python") if containing in b)


def _commands(block: str) -> list[str]:
    """The bondgraph commands of one shell block, in order."""
    cmds = []
    for line in block.splitlines():
        line = line.split("  #")[0].strip()
        cmds += [part.strip() for part in line.split("&&") if part.strip().startswith("bondgraph ")]
    return cmds


def readme_commands():
    """The bondgraph commands of each shell block (a block's commands run in order)."""
    return [cmds for block in blocks("sh", (README, *GUIDES)) if (cmds := _commands(block))]


def shown_number(pattern: str) -> float:
    """A number the README prints, found by a regular expression with one group."""
    m = re.search(pattern, README.replace("\n", " "))
    assert m, f"README shows {pattern}"
    return float(m.group(1))


def test_readme_starts_with_install_run_and_test_commands():
    first, second = blocks("sh")[:2]
    assert "pip install -e" in first and "bondgraph simulate" in first
    assert second.strip() == "python -m pytest -n 2 -q"
    ci = (ROOT / ".ci" / "run").read_text()
    assert second.strip() in ci.splitlines()


def setup_dir(d):
    """The reader's working directory: the README's model file as msd.py and its data.csv (a
    creeping APA record)."""
    (d / "msd.py").write_text(blocks("python")[0])
    data = apa_data("creep", duration=2.0, rate=2000.0)
    write_csv(d / "data.csv", data.t, data.columns, data.metadata)
    return d


def run_commands(cmds, d, monkeypatch) -> dict:
    """Run README commands in ``d``; returns {command: (stdout, stderr)}."""
    monkeypatch.chdir(d)
    outputs = {}
    for cmd in cmds:
        argv = [str(ROOT / a) if a.startswith("models/") else a for a in shlex.split(cmd)[1:]]
        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = main(argv)
        assert rc == 0, (cmd, err.getvalue())
        for a in argv:
            if a.endswith((".csv", ".png", ".json", ".py")) and not a.startswith("-") and "=" not in a:
                assert (d / a).exists(), a
        outputs[cmd] = (out.getvalue(), err.getvalue())
    return outputs


def block_with(text: str) -> list[str]:
    return next(cmds for cmds in readme_commands() if any(text in c for c in cmds))


#: blocks with a test of their own (they need an earlier block's output or show numbers; the
#: real stack's block is docs/papers.md's, run by tests/test_compensate.py)
FIT_FILE, PLANT, STACK = "apa.csv --params", "--format python-control", "p885_stack.py"
MONTE_CARLO = "bimorph_t215.py --vary"


@pytest.mark.parametrize(
    "cmds",
    [c for c in readme_commands() if not any(FIT_FILE in x or PLANT in x or STACK in x or MONTE_CARLO in x for x in c)],
    ids=lambda c: c[0][:40],
)
def test_readme_commands_run(cmds, tmp_path, monkeypatch):
    run_commands(cmds, setup_dir(tmp_path), monkeypatch)


def test_readme_fit_file_numbers(tmp_path, monkeypatch):
    d = setup_dir(tmp_path)
    ran = run_commands(readme_commands()[0] + block_with(FIT_FILE), d, monkeypatch)
    fit_cmd = next(c for c in ran if FIT_FILE in c)
    out = ran[fit_cmd][0]
    offset = float(re.search(r"offset of x\s+(\S+)\s+m", out).group(1))
    rms_fit, rms_val = map(float, re.search(r"rms error: fit (\S+) m, validation (\S+) m", out).groups())
    assert offset == pytest.approx(shown_number(r"prints `offset of x\s+(\S+)\s+m`"), rel=2e-3)
    assert rms_fit == pytest.approx(shown_number(r"rms error: fit (\S+) m,"), rel=2e-3)
    assert rms_val == pytest.approx(shown_number(r"validation\s+(\S+) m`"), rel=2e-3)
    rho = float(re.search(r"lag-1 autocorrelation (\S+)\)", out).group(1))
    assert rho == pytest.approx(shown_number(r"`lag-1 autocorrelation (\S+)`"), abs=0.005)
    assert "understate the error" in out
    apa, refit = read_csv(d / "apa.csv"), read_csv(d / "refit.csv")
    np.testing.assert_array_equal(refit.t, apa.t)
    miss = float(np.sqrt(np.mean((refit.columns["x"] - apa.columns["x"]) ** 2)))
    assert miss == pytest.approx(shown_number(r"`apa.csv` by (\S+) m RMS"), rel=1e-2)
    assert miss == pytest.approx(rms_val, rel=0.1), "re-simulating with the fit file reproduces the fit"
    stroke = np.ptp(apa.columns["x"])
    assert stroke * 1e6 == pytest.approx(shown_number(r"RMS of a (\d+) µm stroke"), abs=0.5)
    without = float(np.sqrt(np.mean((refit.columns["x"] - offset - apa.columns["x"]) ** 2)))
    assert without * 1e6 == pytest.approx(shown_number(r"without the offset it would miss by (\d+) µm"), abs=0.5)


def test_readme_real_stack_block_is_the_tested_one():
    """The README's real-stack commands are docs/papers.md's, which
    tests/test_compensate.py::test_p885_model_file_fit_then_compensate_end_to_end runs and
    whose figures (2.50 and 0.72 µm held out, 3.5×) it asserts; the README shows those."""
    papers = (ROOT / "docs" / "papers.md").read_text()
    shown = block_with(STACK)
    assert shown in [_commands(b) for b in blocks("sh", (papers,))]
    text = " ".join(README.split())
    assert "by 2.50 µm RMS and the compensated drive by 0.72 µm" in text and "3.5× less" in text
    assert "| linear inverse (no compensation) | 2.50 µm" in papers and "| 0.72 µm |" in papers


def test_readme_python_control_example(tmp_path, monkeypatch):
    pytest.importorskip("control")
    run_commands(block_with(PLANT), setup_dir(tmp_path), monkeypatch)
    monkeypatch.syspath_prepend(str(tmp_path))
    namespace = {}
    exec(python_block("from plant import model"), namespace)
    import control

    wn, zeta, _ = control.damp(namespace["model"], doprint=False)
    assert wn == pytest.approx([10.0, 10.0]) and zeta == pytest.approx([0.1, 0.1])
    assert control.dcgain(namespace["model"]) == pytest.approx(0.01)


def test_readme_energy_example_prints_what_it_shows(capsys):
    exec(python_block("energy drift"), {})
    shown = re.search(r"energy drift.*?prints\n\n```\n(.*?)```", README, re.S).group(1)
    assert capsys.readouterr().out == shown
    drifts = [float(x) for x in re.findall(r"drift (\S+)", shown)]
    assert abs(drifts[1]) < 1e-4 < abs(drifts[0]), "rtol 1e-8 keeps the drift within 1e-4, the default does not"


def test_readme_model_file_prints_the_equations_shown(tmp_path, capsys):
    (tmp_path / "msd.py").write_text(blocks("python")[0])
    assert main(["equations", str(tmp_path / "msd.py")]) == 0
    out = capsys.readouterr().out
    shown = [ln.strip() for ln in re.findall(r"prints\n\n```\n(.*?)```", README, re.S)[0].splitlines() if ln.strip()]
    assert shown, "README shows the equations"
    for line in shown:
        assert line in out


NUMBER = re.compile(r"[-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?")


def test_batch_guide_monte_carlo_numbers(tmp_path, monkeypatch):
    """docs/batch.md's tolerance analysis of the T215 bimorph's first mode prints the
    statistics and rankings the page shows, line by line (numbers to 4 digits)."""
    pytest.importorskip("dask.distributed")
    ran = run_commands(block_with(MONTE_CARLO), setup_dir(tmp_path), monkeypatch)
    printed = ran[next(c for c in ran if MONTE_CARLO in c)][0]
    shown = next(b for b in blocks("console", GUIDES) if "sensitivity of p2p(x)" in b)
    sections = [sec.splitlines() for sec in printed.split("\n\n")]
    for part in shown.strip().split("\n\n"):
        lines = part.splitlines()
        head = NUMBER.sub("#", lines[0]).strip()
        (section,) = [sec for sec in sections if NUMBER.sub("#", sec[0]).strip() == head]
        assert len(section) == len(lines), section
        for want, got in zip(lines, section):
            assert NUMBER.sub("#", want).split() == NUMBER.sub("#", got).split(), (want, got)
            numbers = [float(v) for v in NUMBER.findall(want)]
            assert [float(v) for v in NUMBER.findall(got)] == pytest.approx(numbers, rel=1e-3, abs=1e-12), (want, got)
    # what the page's text says of them
    stats = {ln.split()[0]: [float(v) for v in ln.split()[2:4]] for ln in sections[1][1:]}
    text = " ".join(GUIDES[0].split())
    f, df = map(float, re.search(r"resonance \((\d+) ± (\d+) Hz\)", text).groups())
    assert (f, df) == (round(stats["resonance"][0]), round(stats["resonance"][1]))
    x, dx = map(float, re.search(r"\(([\d.]+) ± ([\d.]+) µm peak to peak\)", text).groups())
    assert (x, dx) == (round(1e6 * stats["p2p(x)"][0], 1), round(1e6 * stats["p2p(x)"][1], 1))
