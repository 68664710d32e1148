"""FMU export (bondgraph.export, docs/fmi.md), checked by FMPy: every model file in models/ (and
its memory-operator and formulation variants) exports to an FMI 2.0 FMU that FMPy validates,
and FMPy's simulation of it, Model Exchange with CVode and Co-Simulation, matches the native
simulation of the model file's experiment (shortened to keep the suite fast).

Tolerances, as a fraction of each signal's peak over the run (states and outputs), both
sides at relative tolerance 1e-8:

* Co-Simulation: 2e-5.  The FMU integrates with the native Dormand–Prince 5(4) pair, error
  weights and step control ported to C; the two runs differ only in where steps end (the FMU
  stops at every communication point), so they agree to within their global errors: the
  native run's own is at most 4e-6 of the peak here (against a run at 1e-11; the Maxwell-slip
  bender), and the largest deviation measured is 5e-6.
* Model Exchange, models without memory operators: 1e-4.  FMPy drives the FMU with CVode (BDF),
  whose global error at the same tolerance is larger than Dormand–Prince's on these lightly
  damped resonators and shifts with its step sequence (measured: at most 6e-6 here, up to
  2e-5 with other state nominals).
* Model Exchange with memory operators: 5e-4.  The memory is committed in
  fmi2CompletedIntegratorStep, which FMPy calls once per output interval (other tools call it
  after every integrator step), so a turning point of an operator's input inside an interval
  is followed only at the interval's end, an error quadratic in the interval (the FMU asks for
  an event at each such reversal, so CVode restarts on the new memory).  Measured: at most
  1.6e-4 (the Maxwell-slip bender through its resonance).
"""

from __future__ import annotations

import ctypes
import dataclasses
import json
import re
import shlex
import types
import zipfile

import numpy as np
import pytest
import sympy as sp
from conftest import MODELS, ROOT
from hypothesis import given, settings
from hypothesis import strategies as st

import bondgraph as bg
import library.hysteresis as hy
from bondgraph.cli import main
from bondgraph.export import export_fmu
from bondgraph.export.c_operators import c_runs
from bondgraph.export.units import base_unit
from bondgraph.model.modelfile import load_model

fmpy = pytest.importorskip("fmpy")
from fmpy import simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

RTOL = 1e-8
TOL_CS, TOL_ME, TOL_ME_MEMORY = 2e-5, 1e-4, 5e-4
#: models whose states include a stiff one (the P-885's amplifier charges the stack in 0.5 ms,
#: a hundredth of a sample): both integrators hold it to their absolute tolerance only
#: (rtol × its peak, 4e-15 C) at every step while it drifts quasi-statically, so its global
#: error reaches a few 1e-5 of its peak (its outputs agree to 1e-9)
STIFF_STATE = {"p885_stack": 3.0}

#: (model file, --set overrides, test horizon in s): every file in models/, each memory-operator
#: variant (Bouc-Wen, play PI, modified PI absolute and relative, Maxwell slip) and formulation
VARIANTS = [
    ("stack", {}, 0.003),
    ("stack", {"lumped": True}, 0.003),
    ("apa120ml", {}, 0.15),
    ("apa120ml", {"hysteresis": "bouc-wen"}, 0.15),
    ("apa120ml", {"hysteresis": "pi"}, 0.15),
    ("apa120ml", {"hysteresis": "pi", "table3": "absolute-signed"}, 0.15),
    ("bender_highfield", {}, 0.02),
    ("bender_highfield", {"saturation": True}, 0.02),
    ("bimorph_t215", {}, 0.05),
    ("bimorph_t215", {"hysteresis": "pi"}, 0.05),
    ("bimorph_t226", {}, 0.02),
    ("bimorph_t226", {"nonlinear": True}, 0.02),
    ("triangular_drive", {}, 0.03),
    ("triangular_drive", {"stroke": "hysteretic"}, 0.03),
    ("triangular_drive", {"formulation": "layers"}, 0.03),
    ("p885_stack", {}, 0.2),
    ("p885_stack", {"hysteresis": "none"}, 0.2),
]


def _id(v) -> str:
    return v[0] + "".join(f"-{k}={x}" for k, x in v[1].items())


def test_variants_cover_every_model_file():
    assert {p.stem for p in MODELS.glob("*.py")} == {v[0] for v in VARIANTS}


@pytest.fixture(scope="module", params=VARIANTS, ids=_id)
def exported(request, tmp_path_factory):
    """The FMU of a variant, with the experiment's inputs driven inside it, and the native run."""
    name, overrides, horizon = request.param
    lm = load_model(MODELS / f"{name}.py", overrides)
    exp = dataclasses.replace(lm.experiment, t_end=horizon)
    path = tmp_path_factory.mktemp("fmu") / f"{name}.fmu"
    report = export_fmu(lm.model, path, signals=exp.inputs, experiment=exp)
    sim = bg.Simulator(lm.model)
    t = exp.times()
    native = sim.run(t, exp.inputs, rtol=RTOL)
    return path, report, exp, native, bool(sim.eqs.operators)


def _deviation(path, exp, native, kind) -> dict:
    """Peak-relative max deviation of every state and output, FMPy vs native."""
    names = [*native.states, *native.outputs]
    res = simulate_fmu(
        str(path),
        fmi_type=kind,
        stop_time=exp.t_end,
        output_interval=exp.dt,
        relative_tolerance=RTOL,
        record_events=False,
        output=names,
    )
    assert np.allclose(res["time"], native.t, rtol=0, atol=1e-9 * exp.t_end)
    ref = {**native.states, **native.outputs}
    return {n: float(np.max(np.abs(res[n] - ref[n])) / max(np.max(np.abs(ref[n])), 1e-300)) for n in names}


def test_fmu_passes_fmpy_validation(exported):
    path, report, *_ = exported
    assert validate_fmu(str(path)) == []
    with zipfile.ZipFile(path) as zf:
        files = set(zf.namelist())
    binary = f"binaries/linux64/{report.model_identifier}.so"
    assert binary in files
    assert {"sources/bg_fmu.c", "sources/bg_model.c", "sources/fmi2Functions.h"} <= files
    with zipfile.ZipFile(path) as zf:
        lib = ctypes.CDLL(zf.extract(binary, path.parent / report.model_identifier))
    # the binary exports the FMI functions only: two FMUs in one process never call into each other
    assert hasattr(lib, "fmi2Instantiate") and not hasattr(lib, "bg_rhs") and not hasattr(lib, "bg_theta0")


def test_cosimulation_matches_native(exported):
    path, _, exp, native, _ = exported
    dev = _deviation(path, exp, native, "CoSimulation")
    assert max(dev.values()) < TOL_CS * STIFF_STATE.get(path.stem, 1.0), dev


def test_model_exchange_matches_native(exported):
    path, _, exp, native, memory = exported
    dev = _deviation(path, exp, native, "ModelExchange")
    assert max(dev.values()) < (TOL_ME_MEMORY if memory else TOL_ME), dev


# ---- inputs the FMU receives ----------------------------------------------------------------


@pytest.fixture(scope="module")
def apa_with_inputs(tmp_path_factory):
    """The APA with the modified-PI operator, exported with its inputs V and F as FMU inputs."""
    lm = load_model(MODELS / "apa120ml.py", {"hysteresis": "pi"})
    exp = dataclasses.replace(lm.experiment, t_end=0.15)
    path = tmp_path_factory.mktemp("fmu") / "apa.fmu"
    report = export_fmu(lm.model, path, experiment=exp)
    return lm, exp, path, report


def test_inputs_are_fmu_inputs_with_units_and_dependencies(apa_with_inputs):
    lm, _, path, report = apa_with_inputs
    assert report.inputs == ["V", "F"] and report.embedded == []
    md = fmpy.read_model_description(str(path))
    var = {v.name: v for v in md.modelVariables}
    assert var["V"].causality == "input" and var["V"].unit == "V"
    assert var["K"].causality == "parameter" and var["K"].unit == "N/m" and var["K"].start == "10770000.0"
    assert var["K"].description == "actuator stiffness, 10.77 N/um (Table 1)"
    assert "stack.C_NL.H.w1" in var and "kw" not in var  # the operator's parameters; not Bouc-Wen's
    units = {u.name: u.baseUnit for u in md.unitDefinitions}
    assert (units["N/m"].kg, units["N/m"].s, units["N/m"].m) == (1, -2, 0)
    deps = {u.variable.name: {d.name for d in u.dependencies} for u in md.outputs}
    assert "V" in deps["i"] and "V" not in deps["x"]  # the drive current feeds through
    assert deps["x"] == {"q_stack.K", "q_stack.C_NL"}


def _cosimulate(path, lm, t, drive, params=None) -> np.ndarray:
    """The outputs at times ``t`` of a co-simulation in which the master sets V and its slope at
    each communication point, after setting ``params`` (FMPy's FMU2Slave, step by step: its
    simulate_fmu cannot set the derivatives of two inputs)."""
    from fmpy.fmi2 import FMU2Slave

    md = fmpy.read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(
        guid=md.guid,
        unzipDirectory=fmpy.extract(str(path)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="apa",
    )
    fmu.instantiate()
    fmu.setupExperiment(tolerance=RTOL, startTime=0.0)
    fmu.setReal([vr[name] for name in params or {}], list((params or {}).values()))
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    outputs = [vr[name] for name in lm.model.outputs]
    got = [fmu.getReal(outputs)]
    for k in range(t.size - 1):
        fmu.setReal([vr["V"]], [drive[k]])
        fmu.setRealInputDerivatives([vr["V"]], [1], [(drive[k + 1] - drive[k]) / (t[k + 1] - t[k])])
        fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=t[k + 1] - t[k])
        got.append(fmu.getReal(outputs))
    fmu.terminate()
    fmu.freeInstance()
    return np.array(got)


@pytest.mark.parametrize("params", [None, {"c": 2000.0, "stack.C_NL.H.w2": -1.0e12}], ids=["defaults", "set"])
def test_cosimulation_interpolates_the_inputs_it_receives(apa_with_inputs, params):
    """The FMU follows the straight line between the communication points, as the native run
    on the same table does, with the parameters set through the FMU."""
    lm, exp, path, _ = apa_with_inputs
    t = exp.times()
    drive = bg.Simulator(lm.model).signal_bank(exp.inputs).sample(t)[:, 0]
    got = _cosimulate(path, lm, t, drive, params)
    native = bg.simulate(lm.model, t, {"V": bg.PiecewiseLinear(t, drive)}, params=params, rtol=RTOL)
    for j, name in enumerate(lm.model.outputs):
        assert np.max(np.abs(got[:, j] - native[name])) < TOL_CS * np.max(np.abs(native[name])), name


def test_model_exchange_follows_a_step_it_receives(tmp_path):
    lm = load_model(MODELS / "stack.py", {"lumped": True})
    path = tmp_path / "stack.fmu"
    export_fmu(lm.model, path, nominals={"q_stack.K": 1e-6, "q_stack.C_NL": 2e-6, "p_M": 1e-6})
    table = np.rec.fromarrays([[0.0, 1e-3, 1e-3, 3e-3], [0.0, 0.0, 100.0, 100.0]], names=["time", "V"])
    res = simulate_fmu(
        str(path), stop_time=3e-3, output_interval=1e-5, relative_tolerance=RTOL, input=table, record_events=False
    )
    native = bg.simulate(lm.model, res["time"], {"V": bg.Step(100.0, t0=1e-3)}, rtol=RTOL)
    assert np.max(np.abs(res["x"] - native["x"])) < TOL_ME * np.max(np.abs(native["x"]))


def _rc_on_source() -> bg.Model:
    """A capacitor on a voltage source: its current is C dV/dt (the law reads the input's rate)."""
    g = bg.Model("rc_on_source")
    V = g.input("V", "V", "source voltage")
    g.add(bg.Se("s", V), bg.J0("n"), bg.C("c", g.parameter("Cc", 2e-6, "F", "capacitance")), bg.R("r", 1e3))
    g.bond("s", "n")
    g.bond("n", "c")
    g.bond("n", "r")
    g.output("i", g.flow("c"), "A", "capacitor current")
    return g


def test_a_law_on_an_input_rate_needs_the_input_inside(tmp_path):
    with pytest.raises(bg.ModelError, match=r"element 'c' uses the rate dV/dt of input V"):
        export_fmu(_rc_on_source(), tmp_path / "rc.fmu")
    assert not (tmp_path / "rc.fmu").exists()
    path = tmp_path / "rc.fmu"
    export_fmu(_rc_on_source(), path, signals={"V": bg.Sine(2.0, 50.0)})
    assert validate_fmu(str(path)) == []
    for kind in ("ModelExchange", "CoSimulation"):
        for c in (2e-6, 5e-6):  # the default capacitance, and one set as a start value
            res = simulate_fmu(str(path), fmi_type=kind, stop_time=0.04, output_interval=1e-4, start_values={"Cc": c})
            exact = c * 2.0 * 2 * np.pi * 50.0 * np.cos(2 * np.pi * 50.0 * res["time"])  # C dV/dt
            assert np.allclose(res["i"], exact, rtol=0, atol=1e-12), (kind, c)


def test_model_exchange_asks_for_an_event_when_an_operator_input_turns_back(tmp_path):
    """Stepping a play-operator model by hand (FMPy's FMU2Model): fmi2CompletedIntegratorStep
    asks for an event at the first step after each turning point of the operator's input (a
    1 Hz sine driven inside the FMU: t = 0.25 s and 0.75 s), and at no other step."""
    from fmpy.fmi2 import FMU2Model

    g = bg.Model("play")
    h = g.operator("H", hy.PrandtlIshlinskii([0.0, 0.2], [1.0, 0.5]), g.input("V"))
    g.add(bg.Se("s", h), bg.J1("j"), bg.I("m", 1.0), bg.R("r", 10.0))
    g.chain("s", "j")
    g.bond("j", "m")
    g.bond("j", "r")
    g.output("v", g.flow("m"))
    path = tmp_path / "play.fmu"
    export_fmu(g, path, signals={"V": bg.Sine(1.0, 1.0)})
    md = fmpy.read_model_description(str(path))
    fmu = FMU2Model(
        guid=md.guid,
        unzipDirectory=fmpy.extract(str(path)),
        modelIdentifier=md.modelExchange.modelIdentifier,
        instanceName="play",
    )
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    events = []
    for t in np.arange(1, 101) * 0.01:
        fmu.setTime(t)
        if fmu.completedIntegratorStep()[0]:
            events.append(round(t, 2))
            fmu.enterEventMode()
            fmu.newDiscreteStates()
            fmu.enterContinuousTimeMode()
    fmu.terminate()
    fmu.freeInstance()
    assert events == [0.26, 0.76]


# ---- what cannot be carried is refused ----------------------------------------------------------


class Gap(bg.MemoryOperator):
    """A play of half-width r without C source."""

    kind = "gap"
    parameter_names = ("r",)

    def parameter_values(self):
        return np.array([0.5])

    @property
    def n_memory(self):
        return 1

    def initial_memory(self, v0, prm):
        return np.array([0.0])

    def small_signal_gain(self, prm):
        return 0.0

    @staticmethod
    def output(v, mem, prm):
        return max(v - prm[0], min(v + prm[0], mem[0]))

    @staticmethod
    def commit(v, mem, prm):
        mem[0] = max(v - prm[0], min(v + prm[0], mem[0]))


GAP_MODEL = """
import numpy as np
from bondgraph import J1, Model, R, Se, MemoryOperator
from test_fmu import Gap

PARAMETERS = []

def build(p):
    g = Model("gap")
    h = g.operator("gap", Gap(), g.input("V"))
    g.add(Se("s", h), J1("j"), R("r", 1.0))
    g.chain("s", "j", "r")
    g.output("y", g.effort("r"))
    return g
"""


def test_an_operator_without_c_source_is_refused(tmp_path, capsys):
    model = tmp_path / "gap.py"
    model.write_text(GAP_MODEL)
    out = tmp_path / "gap.fmu"
    assert main(["export", str(model), "--fmu", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "memory operator 'gap'" in err and "c_source()" in err
    assert not out.exists()


def test_a_law_without_c_translation_is_refused(tmp_path):
    g = bg.Model("bessel")
    g.add(bg.Se("s", g.input("V")), bg.J1("j"), bg.I("m", 1.0), bg.R("r", law=lambda f: sp.besselj(0, f)))
    g.chain("s", "j")
    g.bond("j", "m")
    g.bond("j", "r")
    g.output("v", g.flow("m"))
    with pytest.raises(bg.ModelError, match=r"element 'r' cannot be exported to C: besselj has no C translation"):
        export_fmu(g, tmp_path / "b.fmu")


def test_a_name_used_twice_is_refused(tmp_path):
    g = bg.Model("twice")
    V = g.input("V", "V")
    g.add(bg.Se("s", V), bg.J1("j"), bg.R("r", 1.0), bg.I("m", 1.0))
    g.chain("s", "j")
    g.bond("j", "r")
    g.bond("j", "m")
    g.output("V", g.flow("m"), "A")
    with pytest.raises(bg.ModelError, match=r"the name 'V' is both"):
        export_fmu(g, tmp_path / "t.fmu")


# ---- the command line ----------------------------------------------------------------------------


def _commands(page: str) -> list[list[str]]:
    """The ``bondgraph ...`` command lines of the sh blocks of a docs page, as argument lists."""
    blocks = re.findall(r"```sh\n(.*?)```", (ROOT / "docs" / page).read_text(), re.S)
    return [shlex.split(line)[1:] for block in blocks for line in block.splitlines() if line.startswith("bondgraph ")]


def test_the_documented_export_commands_work(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    runs = _commands("fmi.md")
    assert [r[0] for r in runs] == ["export", "export"]
    for args in runs:
        args[args.index("--fmu") + 1] = str(tmp_path / args[args.index("--fmu") + 1])
        assert main(args) == 0
    assert "inputs: V, F, outputs: x, i, p, E" in capsys.readouterr().err
    for name in ("apa.fmu", "apa-test.fmu"):
        assert validate_fmu(str(tmp_path / name)) == []
    md = fmpy.read_model_description(str(tmp_path / "apa-test.fmu"))
    var = {v.name: v for v in md.modelVariables}
    assert var["V"].causality == "local" and "sine(amplitude=60" in var["V"].description
    assert md.defaultExperiment.stopTime == "0.4" and md.defaultExperiment.tolerance == "1e-06"
    res = simulate_fmu(str(tmp_path / "apa-test.fmu"), fmi_type="CoSimulation", stop_time=0.15)
    lm = load_model(MODELS / "apa120ml.py", {"hysteresis": "pi"})
    native = bg.simulate(lm.model, res["time"], lm.experiment.inputs, rtol=1e-6)
    assert np.max(np.abs(res["x"] - native["x"])) < 1e-5 * np.max(np.abs(native["x"]))


def test_export_command_takes_a_fit_file(tmp_path):
    fit = tmp_path / "fit.json"
    fit.write_text(json.dumps({"params": {"zeta_1": 0.02}, "output": "x", "offset": 1e-3}))
    out = tmp_path / "t226.fmu"
    assert main(["export", str(MODELS / "bimorph_t226.py"), "--params-file", str(fit), "--fmu", str(out)]) == 0
    var = {v.name: v for v in fmpy.read_model_description(str(out)).modelVariables}
    assert var["zeta_1"].start == "0.02"
    res = simulate_fmu(str(out), fmi_type="CoSimulation", stop_time=1e-3)
    assert res["x"][0] == pytest.approx(1e-3, rel=1e-12)  # at rest: the sensor zero alone


def test_export_command_needs_an_fmu_name(tmp_path, capsys):
    assert main(["export", str(MODELS / "stack.py"), "--fmu", str(tmp_path / "s.zip")]) == 2
    assert "must end in .fmu" in capsys.readouterr().err


# ---- the operators' C twins and the units ----------------------------------------------------------

OPERATORS = [
    hy.PrandtlIshlinskii([0.0, 0.3, 0.7, 1.2], [1.0, 0.4, -0.2, 0.3]),
    hy.PrandtlIshlinskii([0.0, 0.3, 0.7, 1.2], [1.0, 0.4, -0.2, 0.3], prior=1.5),
    hy.PIStop([0.0, 0.3, 0.7], [1.0, 0.4, 0.3]),
    hy.ModifiedPI([0.0, 0.3, 0.7], [1.0, 0.4, 0.3], [0.0, 0.5, -0.4], [1.0, 0.3, 0.2]),
    hy.ModifiedPI([0.0, 0.3, 0.7], [1.0, 0.4, 0.3], [0.0, 0.5, -0.4], [1.0, 0.3, 0.2]).inverse(),
    hy.RelativeModifiedPI([0.0, 0.3, 0.7], [1.0, 0.4, 0.3], [0.0, 0.5, 1.0], [1.0, 0.3, 0.2]),
    hy.RelativeModifiedPI([0.0, 0.3, 0.7], [1.0, 0.4, 0.3], [0.0, 0.5, 1.0], [1.0, 0.3, 0.2]).inverse(),
    hy.MaxwellSlip([1.0, 2.0, 0.5], [0.3, 0.0, 1.0]),
]


@pytest.fixture(scope="module")
def c_twins():
    return c_runs(OPERATORS)


def test_every_library_operator_has_a_c_twin():
    kinds = {type(op) for op in OPERATORS}
    assert kinds == {getattr(hy, name) for name in hy.__all__ if isinstance(getattr(hy, name), type)}


@settings(max_examples=30, deadline=None)
@given(
    start=st.floats(-2.0, 2.0),
    steps=st.lists(st.floats(-1.0, 1.0, allow_subnormal=False), min_size=1, max_size=300),
)
def test_c_twins_follow_the_numba_kernels(c_twins, start, steps):
    v = start + np.concatenate([[0.0], np.cumsum(steps)])
    for op, run in zip(OPERATORS, c_twins):
        y = op.run(v)
        np.testing.assert_allclose(run(v), y, rtol=1e-12, atol=1e-12 * max(1.0, np.max(np.abs(y))))


@pytest.mark.parametrize(
    "unit, factor, exponents",
    [
        ("N/m", 1.0, {"kg": 1, "s": -2}),
        ("V/(C*m^2)", 1.0, {"kg": 1, "s": -4, "A": -2}),
        ("1/(C^2 s^2)", 1.0, {"s": -4, "A": -2}),
        ("V/um", 1e6, {"kg": 1, "m": 1, "s": -3, "A": -1}),
        ("deg", np.pi / 180, {"rad": 1}),
        ("1", 1.0, {}),
    ],
)
def test_units_become_fmi_base_units(unit, factor, exponents):
    f, e = base_unit(unit)
    assert f == pytest.approx(factor, rel=1e-15) and e == exponents


def test_a_unit_that_does_not_parse_has_no_base_unit():
    assert base_unit("furlong/fortnight") is None and base_unit("m/") is None


# ---- the examples of docs/fmi.md ----------------------------------------------------------------


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "fmi.md").read_text(), re.S)


def test_docs_operator_example_runs_in_c(capsys):
    module = types.ModuleType("fmi_operator")
    exec(compile(_python_blocks()[0], "docs/fmi_operator.md", "exec"), module.__dict__)
    assert capsys.readouterr().out.split() == ["0.0"]


def test_docs_fmpy_example(tmp_path, monkeypatch, capsys):
    code = _python_blocks()[1].replace('"models/', f'"{MODELS}/')
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "docs/fmi_fmpy.md", "exec"), types.ModuleType("fmi_fmpy").__dict__)
    assert capsys.readouterr().out.splitlines() == ["stack_of_20_layers_lumped 3 []", "x = 94.80 um"]
