"""Examples are tests: the code in docs/ runs and does what the text says; the settings table
covers the framework's settings; the repository explains itself."""

from __future__ import annotations

import re
import types

import numpy as np
import pytest
from conftest import ROOT

import bondgraph as bg
from bondgraph import config
from bondgraph.cli import main
from bondgraph.data import Dataset
from bondgraph.model.modelfile import load_model

DOCS = ROOT / "docs"


def python_blocks(page: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", (DOCS / page).read_text(), re.S)


def module_of(code: str, name: str) -> types.ModuleType:
    mod = types.ModuleType(name)
    exec(compile(code, f"docs/{name}.md", "exec"), mod.__dict__)
    return mod


def test_model_file_example_is_a_damped_oscillator(tmp_path, capsys):
    (tmp_path / "oscillator.py").write_text(python_blocks("model-files.md")[0])
    assert main(["equations", str(tmp_path / "oscillator.py")]) == 0
    assert "spring" in capsys.readouterr().out
    lm = load_model(tmp_path / "oscillator.py")
    t = lm.experiment.times()
    x = bg.simulate(lm.model, t, lm.experiment.inputs, rtol=1e-9)["x"]
    m, k, c = 1.0, 100.0, 2.0  # step response of m x'' + c x' + k x = 1
    wn, z = np.sqrt(k / m), c / (2 * np.sqrt(k * m))
    wd = wn * np.sqrt(1 - z**2)
    exact = (1 - np.exp(-z * wn * t) * (np.cos(wd * t) + z / np.sqrt(1 - z**2) * np.sin(wd * t))) / k
    assert np.max(np.abs(x - exact)) < 1e-6 / k


def test_element_kind_example_simulates_its_law():
    mod = module_of(python_blocks("extending.md")[0], "extending_element")
    g = bg.Model("m")
    g.add(bg.Se("f", 0.0), bg.J1("v"), bg.I("m", 1.0, p0=2.0), mod.CubicDamper("d", g.parameter("c", 0.5)))
    g.bond("f", "v")
    g.bond("v", "m")
    g.bond("v", "d")
    g.output("v", g.flow("m"))
    t = np.linspace(0, 1, 101)
    res = bg.simulate(g, t, rtol=1e-10)
    assert np.allclose(res["v"], 2.0 / np.sqrt(1 + 2 * 0.5 * 4.0 * t), rtol=1e-7)
    assert g.elements["d"].describe() == "e = c·f³"


def test_operator_example_lags_by_its_half_width():
    mod = module_of(python_blocks("extending.md")[1], "extending_operator")
    v = np.r_[np.linspace(0, 2, 50), np.linspace(2, -2, 100)]
    y = mod.Backlash(0.5).run(v)
    assert np.allclose(y[15:50], v[15:50] - 0.5) and np.allclose(y[-40:], v[-40:] + 0.5)
    g = bg.Model("gap")
    h = g.operator("gap", mod.Backlash(0.5), g.input("V"))
    g.add(bg.Se("s", h), bg.J1("j"), bg.R("r", 1.0))
    g.chain("s", "j", "r")
    g.output("y", g.effort("r"))
    assert "gap.r" in g.parameters


def end_stop_record(seed: int = 3) -> Dataset:
    """A 1 kg mass on a spring of 1.2e4 N/m and a 12 N·s/m damper, the spring meeting stops at
    60 % of its peak travel (a cubic contact force k_s·(|q| − g)³, 0.3× the spring's force at
    the peak), driven by a two-tone force below its resonance; integrated by scipy (Radau,
    rtol 1e-9), output noise 0.5 % of its spread."""
    from scipy.integrate import solve_ivp

    t = np.arange(0.0, 4.0, 1e-3)
    u = 40.0 * np.sin(2 * np.pi * 3.0 * t) + 25.0 * np.sin(2 * np.pi * 7.3 * t + 1.0)
    peak = 65.0 / 1.2e4
    gap, ks = 0.6 * peak, 0.5e4 / (0.3 * peak) ** 2

    def rhs(tt, s):
        q, v = s
        contact = ks * max(abs(q) - gap, 0.0) ** 3 * np.sign(q)
        return [v, np.interp(tt, t, u) - 1.2e4 * q - contact - 12.0 * v]

    sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0], t_eval=t, method="Radau", rtol=1e-9, atol=1e-14, max_step=1e-3)
    y = sol.y[0] + 0.005 * np.std(sol.y[0]) * np.random.default_rng(seed).standard_normal(t.size)
    return Dataset(t, {"F": u, "x": y})


def test_effect_kind_example_is_named_at_its_spring():
    """The docs' own law term, beside the built-in kinds of the same spring, names end stops
    (a truth of another form: a cubic contact beyond a gap, no quintic)."""
    from bondgraph.diagnosis import diagnose
    from bondgraph.diagnosis.laws import Clearance, Hardening, Softening
    from bondgraph.diagnosis.sites import element_sites

    mod = module_of(next(b for b in python_blocks("extending.md") if "class EndStops" in b), "extending_law")
    g = bg.Model("mass on a spring")
    F = g.input("F", "N")
    k = g.parameter("k", 1.25e4, "N/m")
    g.add(bg.Se("force", F), bg.J1("v"), bg.I("mass", g.parameter("m", 1.0, "kg")), bg.C("spring", 1 / k))
    g.add(bg.R("damper", g.parameter("c", 10.0, "N*s/m")))
    g.bond("force", "v")
    for e in ("mass", "spring", "damper"):
        g.bond("v", e)
    g.output("x", g.displacement("spring"), "m")
    (site,) = element_sites(g, ("C",))
    kinds = [Softening(site), Hardening(site), Clearance(site), mod.EndStops(site)]
    rep = diagnose(g, end_stop_record(), candidates=kinds)
    assert rep.causes[:1] == ["end-stops"], rep.text()
    assert rep.steps[0].site == "spring" and rep.steps[0].gain > 2.5


def test_data_check_example_flags_micrometres():
    mod = module_of(
        next(b for b in python_blocks("extending.md") if "def displacement_in_metres" in b), "extending_check"
    )
    assert mod.displacement_in_metres(Dataset([0.0, 1.0], {"x": [0.0, 12.0]}))
    assert not mod.displacement_in_metres(Dataset([0.0, 1.0], {"x": [0.0, 12e-6]}))


def test_command_page_lists_every_command():
    from bondgraph.cli.registry import COMMANDS  # filled when bondgraph.cli is imported (above)

    text = (DOCS / "command-line.md").read_text()
    assert COMMANDS and all(re.search(rf"^\| `{name}[ `]", text, re.M) for name in COMMANDS), sorted(COMMANDS)


def test_plot_commands_of_the_command_page_draw_their_figures(tmp_path, monkeypatch):
    """The commands under "Plots" run as written (in a scratch directory) and write their PNGs."""
    import shlex

    text = (DOCS / "command-line.md").read_text().split("## Plots", 1)[1]
    block = re.search(r"```sh\n(.*?)```", text, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    for line in block.strip().splitlines():
        argv = shlex.split(line.replace("models/", f"{ROOT / 'models'}/"))
        assert argv[0] == "bondgraph" and main(argv[1:]) == 0, line
        plot = argv[argv.index("--plot") + 1]
        assert (tmp_path / plot).stat().st_size > 10_000, line


def test_record_start_example_sets_the_declared_start():
    block = next(b for b in python_blocks("fitting.md") if "record.start" in b)
    try:
        exec(block, {})
        assert config.get("record.start") == "rest"
    finally:
        config.reset("record.start")
    assert config.get("record.start") == "steady"


def test_diagnosis_settings_example_runs():
    block = next(b for b in python_blocks("diagnosis.md") if "Settings.from_config" in b)
    mod = module_of(block, "diagnosis_settings")
    assert mod.strict.min_gain == 1.5 and mod.strict.equivalent == config.get("diagnosis.equivalent")


def test_settings_page_lists_the_framework_settings():
    page = (DOCS / "settings.md").read_text()
    for name in config.DEFAULTS:
        if name.split(".")[0] in ("simulate", "causality", "codegen", "data", "diagnosis", "record"):
            assert f"`{name}`" in page, name


def test_docs_cite_the_papers_in_full_and_the_readme_links_them():
    refs = (DOCS / "references.md").read_text()
    for author, venue in (
        ("Rodriguez-Fortun", "(2010) 303–314"),
        ("Ghafarirad", "doi:10.1080/13873954.2014.906472"),
        ("Shahabi", "doi:10.1016/j.crme.2019.10.007"),
        ("Wood", "Barcelona, 2005"),
        ("Hassani", "Mechanical Systems and Signal Processing"),
    ):
        assert author in refs and venue in refs
    for page in DOCS.glob("*.md"):
        text = page.read_text()
        assert not re.search(r"seed 00\d|CONTRACT\.md|REFERENCE\.md|\.\./shared", text), page.name
        for link in re.findall(r"\]\(([\w-]+\.md)", text):
            assert (DOCS / link).exists(), (page.name, link)
    assert "docs/" in (ROOT / "README.md").read_text()


@pytest.mark.parametrize(
    "field",
    [
        "cause",
        "gain",
        "baseline_rms",
        "extended_rms",
        "candidates",
        "causes",
        "steps",
        "natural_frequencies_rad_s",
        "rhp_zeros",
        "dc_gain",
    ],
)
def test_json_page_describes_the_fields(field):
    assert f"`{field}`" in (DOCS / "json-outputs.md").read_text()
