"""Examples are tests: every command and the model file shown in README.md run, and the
printed equations match what the README shows."""
import re
import shlex

import pytest

from bondgraph.cli import main
from conftest import ROOT

README = (ROOT / "README.md").read_text()


def blocks(lang):
    return re.findall(rf"```{lang}\n(.*?)```", README, re.S)


def readme_commands():
    cmds = []
    for block in blocks("sh"):
        for line in block.splitlines():
            line = line.split("#")[0].strip()
            for part in line.split("&&"):
                part = part.strip()
                if part.startswith("bondgraph "):
                    cmds.append(part)
    return cmds


def test_readme_starts_with_install_run_and_test_commands():
    first, second = blocks("sh")[:2]
    assert "pip install -e" in first and "bondgraph simulate" in first
    assert second.strip() == "python -m pytest -n 2 -q"
    ci = (ROOT / ".ci" / "run").read_text()
    assert second.strip() in ci.splitlines()


@pytest.mark.parametrize("cmd", readme_commands())
def test_readme_command_runs(cmd, tmp_path, monkeypatch, capsys):
    argv = shlex.split(cmd)[1:]
    argv = [str(ROOT / a) if a.startswith("models/") else a for a in argv]
    argv = [str(tmp_path / a) if a.endswith((".csv", ".png")) else a for a in argv]
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 0, capsys.readouterr().err
    for a in argv:
        if a.endswith((".csv", ".png")):
            assert (tmp_path / a).exists() or (tmp_path / a.split("/")[-1]).exists()


def test_readme_model_file_prints_the_equations_shown(tmp_path, capsys):
    (tmp_path / "msd.py").write_text(blocks("python")[0])
    assert main(["equations", str(tmp_path / "msd.py")]) == 0
    out = capsys.readouterr().out
    shown = [ln.strip() for ln in re.findall(r"prints\n\n```\n(.*?)```", README, re.S)[0].splitlines() if ln.strip()]
    assert shown, "README shows the equations"
    for line in shown:
        assert line in out
