"""FMU export (bondgraph.export, docs/fmi.md), checked by FMPy: every model file in models/ (and
its memory-operator and formulation variants) exports to an FMI 2.0 FMU that FMPy validates,
and FMPy's simulation of it, Model Exchange with CVode and Co-Simulation, matches the native
simulation of the model file's experiment (shortened to keep the suite fast).

Tolerances, as a fraction of each signal's peak over the run (states and outputs):

* Co-Simulation: 1e-5 at rtol 1e-8.  The FMU integrates with the native Dormand–Prince 5(4)
  pair and step control ported to C; the two runs differ only in where steps end (the FMU
  stops at every communication point), so they agree to within their global errors, which
  at rtol 1e-8 are below 3e-6 of the peak on every model here (measured against a native run
  at rtol 1e-10).
* Model Exchange: 1e-4 at rtol 1e-8 for models without memory operators.  FMPy drives the FMU
  with CVode (BDF), whose global error at the same tolerance is larger than Dormand–Prince's
  on these lightly damped resonators (up to 2e-5 of the peak over the test horizons).
* Model Exchange with memory operators: 1e-3.  The memory is committed in
  fmi2CompletedIntegratorStep, which FMPy calls once per output interval (other tools call it
  after every integrator step), so a turning point of an operator's input inside an interval
  is followed only at the interval's end: an error quadratic in the interval, largest on the
  APA's drive current, a difference of two nearly equal voltages (6e-4 of its peak).
"""

from __future__ import annotations

import dataclasses
import zipfile

import numpy as np
import pytest
import sympy as sp
from conftest import MODELS

import bondgraph as bg
from bondgraph.cli import main
from bondgraph.export import export_fmu
from bondgraph.export.c_operators import c_runs
from bondgraph.export.units import base_unit
from bondgraph.model.modelfile import load_model

fmpy = pytest.importorskip("fmpy")
from fmpy import simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

RTOL = 1e-8
TOL_CS, TOL_ME, TOL_ME_MEMORY = 1e-5, 1e-4, 1e-3

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
    assert f"binaries/linux64/{report.model_identifier}.so" in files
    assert {"sources/bg_fmu.c", "sources/bg_model.c", "sources/fmi2Functions.h"} <= files


def test_cosimulation_matches_native(exported):
    path, _, exp, native, _ = exported
    dev = _deviation(path, exp, native, "CoSimulation")
    print("CS", max(dev.values()), max(dev, key=dev.get))
    assert max(dev.values()) < TOL_CS, dev


def test_model_exchange_matches_native(exported):
    path, _, exp, native, memory = exported
    dev = _deviation(path, exp, native, "ModelExchange")
    print("ME", max(dev.values()), max(dev, key=dev.get))
    assert max(dev.values()) < (TOL_ME_MEMORY if memory else TOL_ME), dev
