"""``bondgraph figure``: figures a model file declares (FIGURES), with the example of
docs/model-files.md run as written."""

from __future__ import annotations

import json

import pytest
from test_docs import python_blocks

from bondgraph.cli import main


@pytest.fixture
def oscillator(tmp_path):
    blocks = python_blocks("model-files.md")
    path = tmp_path / "oscillator.py"
    path.write_text(blocks[0] + "\n\n" + next(b for b in blocks if "FIGURES" in b))
    return str(path)


def test_the_docs_example_draws_and_reports_its_numbers(oscillator, tmp_path, capsys):
    """The static gain of m x'' + c x' + k x = F is 1/k: the figure's numbers say so, for each
    k of the family, and --set reaches every member (m does not change the static gain)."""
    assert main(["figure", oscillator]) == 0
    assert "stiffness" in capsys.readouterr().out
    png = tmp_path / "f.png"
    assert main(["figure", oscillator, "stiffness", "--set", "m=3", "--plot", str(png), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["figure"] == "stiffness"
    for k in (50.0, 100.0, 200.0):
        assert out["numbers"][f"static gain at k = {k:g} (m/N)"] == pytest.approx(1 / k, rel=1e-9)
    assert png.stat().st_size > 5000


def test_bad_figure_requests_are_one_line_errors(oscillator, tmp_path, capsys):
    assert main(["figure", oscillator, "stifness", "--json"]) == 2
    assert "did you mean 'stiffness'" in capsys.readouterr().err
    assert main(["figure", oscillator, "stiffness"]) == 2
    assert "--plot" in capsys.readouterr().err
    assert main(["figure", oscillator, "stiffness", "--plot", str(tmp_path / "f.txt")]) == 2
    assert not (tmp_path / "f.txt").exists()
    bad = tmp_path / "bad.py"
    bad.write_text(open(oscillator).read() + "\nFIGURES = {'x': 3}\n")
    assert main(["figure", str(bad), "x", "--json"]) == 2
    assert "FIGURES must map names" in capsys.readouterr().err
    wrong = tmp_path / "wrong.py"
    wrong.write_text(open(oscillator).read() + "\nFIGURES = {'x': lambda load: 3}\n")
    assert main(["figure", str(wrong), "x", "--json"]) == 2
    assert "not a Figure" in capsys.readouterr().err


def test_every_figure_command_of_the_papers_page_names_a_declared_figure():
    """docs/papers.md shows one `bondgraph figure MODEL NAME` per paper; each names a model file
    that exists and a figure it declares (the paper tests run them and check their numbers)."""
    import re

    from conftest import ROOT

    from bondgraph.model.modelfile import read_model_module

    text = (ROOT / "docs" / "papers.md").read_text()
    commands = re.findall(r"^bondgraph figure (\S+) (\S+) --plot (\S+)$", text, re.M)
    assert len(commands) == 5
    for model, name, png in commands:
        module, _ = read_model_module(ROOT / model)
        assert name in module.FIGURES
        assert f"](img/{png})" in text and (ROOT / "docs" / "img" / png).stat().st_size < 100_000
    assert (ROOT / "docs" / "img" / "p885_compensation.png").exists()
