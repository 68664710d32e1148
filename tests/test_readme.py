"""Examples are tests: every command and the model file shown in README.md run, and the
printed equations match what the README shows."""
import re
import shlex

import pytest

import numpy as np

import bondgraph as bg
from bondgraph.cli import main
from bondgraph.data import write_csv
from conftest import ROOT
from truth import apa_data

README = (ROOT / "README.md").read_text()


def blocks(lang):
    return re.findall(rf"```{lang}\n(.*?)```", README, re.S)


def readme_commands():
    """The bondgraph commands of each shell block (a block's commands run in order)."""
    out = []
    for block in blocks("sh"):
        cmds = []
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            cmds += [part.strip() for part in line.split("&&") if part.strip().startswith("bondgraph ")]
        if cmds:
            out.append(cmds)
    return out


def test_readme_starts_with_install_run_and_test_commands():
    first, second = blocks("sh")[:2]
    assert "pip install -e" in first and "bondgraph simulate" in first
    assert second.strip() == "python -m pytest -n 2 -q"
    ci = (ROOT / ".ci" / "run").read_text()
    assert second.strip() in ci.splitlines()


@pytest.mark.parametrize("cmds", readme_commands(), ids=lambda c: c[0][:40])
def test_readme_commands_run(cmds, tmp_path, monkeypatch, capsys):
    data = apa_data("creep", duration=2.0, rate=2000.0)  # the README's data.csv: a creeping APA
    write_csv(tmp_path / "data.csv", data.t, data.columns, data.metadata)
    monkeypatch.chdir(tmp_path)
    for cmd in cmds:
        argv = [str(ROOT / a) if a.startswith("models/") else a for a in shlex.split(cmd)[1:]]
        assert main(argv) == 0, (cmd, capsys.readouterr().err)
        for a in argv:
            if a.endswith((".csv", ".png", ".json")) and not a.startswith("-"):
                assert (tmp_path / a).exists(), a


def test_readme_model_file_prints_the_equations_shown(tmp_path, capsys):
    (tmp_path / "msd.py").write_text(blocks("python")[0])
    assert main(["equations", str(tmp_path / "msd.py")]) == 0
    out = capsys.readouterr().out
    shown = [ln.strip() for ln in re.findall(r"prints\n\n```\n(.*?)```", README, re.S)[0].splitlines() if ln.strip()]
    assert shown, "README shows the equations"
    for line in shown:
        assert line in out


def test_readme_operator_example_makes_a_backlash_loop(tmp_path, monkeypatch):
    (tmp_path / "backlash_example.py").write_text(blocks("python")[1])
    monkeypatch.syspath_prepend(str(tmp_path))
    from backlash_example import Backlash
    g = bg.Model("gap")
    V = g.input("V")
    h = g.operator("gap", Backlash(0.5), V)
    g.add(bg.Se("drive", h), bg.J1("j"), bg.R("r", 1.0))
    g.bond("drive", "j")
    g.bond("j", "r")
    g.output("y", g.effort("r"))
    t = np.linspace(0, 2, 801)
    res = bg.simulate(g, t, {"V": bg.Triangle(2.0, 1.0)})
    up = res["y"][(t > 0.3) & (t < 0.45)] - res["V"][(t > 0.3) & (t < 0.45)]
    down = res["y"][(t > 0.8) & (t < 0.95)] - res["V"][(t > 0.8) & (t < 0.95)]
    assert np.allclose(up, -0.5, atol=1e-9) and np.allclose(down, 0.5, atol=1e-9)  # lags by r each way
