"""Every model file in models/ runs through every CLI command."""

import json

import pytest
from conftest import MODELS

from bondgraph.cli import main
from bondgraph.data import read_csv

MODEL_FILES = sorted(p.name for p in MODELS.glob("*.py"))


def test_model_files_exist():
    for name in (
        "apa120ml.py",
        "stack.py",
        "bimorph_t215.py",
        "bimorph_t226.py",
        "triangular_drive.py",
        "bender_highfield.py",
    ):
        assert name in MODEL_FILES


#: keep the N-layer stack small here (its size is a benchmark workload, not a test)
SETTINGS = {"stack.py": ["--set", "layers=6"]}


@pytest.mark.parametrize("name", MODEL_FILES)
def test_every_command_runs(name, tmp_path, capsys):
    path = str(MODELS / name)
    s = SETTINGS.get(name, [])
    assert main(["params", path, *s]) == 0
    for fmt in ("text", "latex", "markdown"):
        assert main(["equations", path, "--format", fmt, *s]) == 0
    assert main(["causality", path, "--json", *s]) == 0
    assert main(["causality", path, "--plot", str(tmp_path / "bg.png"), *s]) == 0
    capsys.readouterr()
    assert main(["linearize", path, "--json", *s]) == 0
    lin = json.loads(capsys.readouterr().out)
    assert lin["natural_frequencies_rad_s"] == sorted(lin["natural_frequencies_rad_s"])
    assert {"poles", "zeros", "rhp_zeros"} <= set(lin)
    out = tmp_path / "sim.csv"
    assert main(["simulate", path, "--out", str(out), "--quiet", *s]) == 0
    ds = read_csv(out)
    assert "x" in ds.columns and len(ds) > 10
    assert (tmp_path / "bg.png").stat().st_size > 1000


@pytest.mark.parametrize("setting", ["hysteresis=bouc-wen", "hysteresis=pi"])
def test_apa_hysteresis_options_simulate(setting, tmp_path):
    assert (
        main(["simulate", str(MODELS / "apa120ml.py"), "--set", setting, "--quiet", "--out", str(tmp_path / "o.csv")])
        == 0
    )


def test_readme_images_exist_and_are_small():
    """Every image the README shows is committed in docs/img and stays under 100 kB."""
    import re

    from conftest import ROOT

    shown = re.findall(r"!\[[^\]]*\]\((docs/img/[^)]+\.png)\)", (ROOT / "README.md").read_text())
    assert len(shown) >= 6
    for rel in shown:
        path = ROOT / rel
        assert path.exists(), rel
        assert path.stat().st_size < 100_000, rel
