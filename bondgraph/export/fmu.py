"""FMI 2.0 FMUs (Model Exchange and Co-Simulation in one archive) from derived equations.

:func:`export_fmu` writes ``FILE.fmu``: ``modelDescription.xml`` (parameters with their units
and descriptions, states and their derivatives, inputs, outputs, the model structure with its
dependencies, the default experiment), the C sources (``sources/``: the generated
``bg_model.c``/``bg_model.h``, the model-independent wrapper ``bg_fmu.c`` and the FMI 2.0
headers, 2-clause BSD licence) and a binary for this platform compiled with the system C
compiler (``binaries/linux64/<id>.so``).  See ``docs/fmi.md``.

Variables, in value-reference order: the parameters the equations use (``causality=parameter``,
``variability=fixed``), the continuous states (``exact`` start values when the start is a number,
``calculated`` from the parameters otherwise), their derivatives ``der(state)``, the inputs
(``causality=input``; an input driven inside the FMU by a signal is a ``local`` variable) and
the outputs.
"""

from __future__ import annotations

import hashlib
import math
import os
import platform
import sys
import tempfile
import time
import uuid
import zipfile
from dataclasses import dataclass, field
from importlib import resources
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Mapping
from xml.etree import ElementTree as ET

import numpy as np

from ..equations.derivation import derive
from ..equations.system import Equations
from ..model.experiment import Experiment
from ..model.graph import Model
from ..model.signals import CHIRP, CONST, NPAR, PWL, RAMP, SINE, STEP, TRIANGLE, Signal
from ..numerics.codegen import parameter_vector
from ..numerics.signal_bank import SignalBank
from ..support import config
from ..support.atomic import atomic_write
from ..support.errors import ModelError, SignalError, UsageError
from .c_model import comment, model_source, refuse_input_rates
from .compiler import build_shared, find_compiler
from .units import BASE, base_unit

#: the model-independent C files shipped in every FMU's sources/
STATIC_SOURCES = ("bg_fmu.c", "fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h")


@dataclass
class FMUReport:
    """What :func:`export_fmu` wrote: the file, its model identifier and GUID, the variables'
    counts, the state nominals (by state name) and the compile time (s).

    Parameters
    ----------
    path : pathlib.Path
        The FMU file written.
    model_identifier : str
        The FMI ``modelIdentifier`` (the name of the binary inside the FMU).
    guid : str
        The FMU's GUID.
    n_states : int
        Number of continuous states.
    parameters : list of str
        Names of the FMU's tunable parameters.
    inputs : list of str
        The model inputs that are FMU inputs (set by the importing tool).
    embedded : list of str
        The model inputs driven inside the FMU by the ``signals`` given.
    outputs : list of str
        Names of the FMU's outputs.
    nominals : dict of str to float, optional
        State name → nominal magnitude (state units) written to the FMU.
    compile_seconds : float, optional
        Time the C compiler took, s.
    """

    path: Path
    model_identifier: str
    guid: str
    n_states: int
    parameters: list[str]
    inputs: list[str]
    embedded: list[str]
    outputs: list[str]
    nominals: dict[str, float] = field(default_factory=dict)
    compile_seconds: float = 0.0


@dataclass
class _Variable:
    name: str
    causality: str
    variability: str
    initial: str | None = None
    start: float | None = None
    unit: str = ""
    description: str = ""
    derivative: int | None = None  # 1-based index of the state this is the derivative of
    nominal: float | None = None


def export_fmu(
    model: Model | Equations,
    path: str | os.PathLike,
    *,
    signals: Mapping[str, Signal] | None = None,
    experiment: Experiment | None = None,
    nominals: Mapping[str, float] | None = None,
    cc: str | None = None,
) -> FMUReport:
    """Write an FMI 2.0 FMU (Model Exchange and Co-Simulation) of ``model`` to ``path``.

    Parameters
    ----------
    model : Model or Equations
        The model, or its derived equations.
    path : path-like
        The FMU file to write (written completely or not at all).
    signals : mapping, optional
        Input name → :class:`~bondgraph.model.signals.Signal`: inputs driven inside the FMU
        (then not FMU inputs); their jumps are time events.  The other inputs are FMU inputs.
    experiment : Experiment, optional
        Written as the FMU's default experiment (start 0, stop ``t_end``, tolerance ``rtol``,
        step ``dt``); without ``nominals`` the state nominals are the peaks of a native run of
        it at relative tolerance 1e-3 (driven by ``signals`` where given, else by its inputs).
    nominals : mapping, optional
        State name → nominal magnitude (> 0), the scale a solver's absolute tolerance is
        relative to (``fmi2GetNominalsOfContinuousStates``); states not given get 1.
    cc : str, optional
        The C compiler (default ``$CC``, else ``cc``).

    Returns
    -------
    FMUReport
        The file written and what it holds.

    Raises
    ------
    ModelError
        The model holds something the exporter cannot carry to C (the message names the
        element): a memory operator without :meth:`~bondgraph.MemoryOperator.c_source`, a
        law with a function that has no C translation, or a law that reads the rate of an
        input the FMU receives from outside.
    SignalError
        ``signals`` names an input the model does not have.
    UsageError
        No C compiler, or a platform without an FMI 2.0 binary folder.
    """
    eqs = model if isinstance(model, Equations) else derive(model)
    signals = dict(signals or {})
    names = [str(u) for u in eqs.inputs]
    unknown = sorted(set(signals) - set(names))
    if unknown:
        raise SignalError(f"the model has no input {unknown[0]!r}; inputs: {', '.join(names) or 'none'}")
    refuse_input_rates(eqs, set(names) - set(signals))
    compiler = find_compiler(cc)
    folder, suffix = _platform()
    if nominals is None and experiment is not None:
        nominals = estimate_nominals(eqs, experiment, signals)
    nominals = dict(nominals or {})
    states = [str(s) for s in eqs.state_symbols]
    bad = sorted(set(nominals) - set(states))
    if bad:
        raise ModelError(f"nominal given for {bad[0]!r}, which is not a state; states: {', '.join(states)}")
    nominal = [float(nominals.get(s, 1.0)) for s in states]
    if not all(math.isfinite(v) and v > 0 for v in nominal):
        raise ModelError("state nominals must be finite and positive")

    ident = model_identifier(eqs.model.name)
    variables, slots = _variables(eqs, signals, nominal)
    placeholder = "{00000000-0000-0000-0000-000000000000}"
    body = model_source(eqs, comment(f"{eqs.model.name}: the model's equations, generated by bondgraph"))
    header = _header(eqs, ident, placeholder, signals, len(slots))
    data = _data(eqs, slots, nominal, signals)
    xml = _model_description(eqs, ident, placeholder, variables, experiment)
    digest = hashlib.sha256("\0".join((body.source, header, data, xml)).encode()).digest()
    guid = "{" + str(uuid.UUID(bytes=digest[:16])) + "}"
    files = {
        "bg_model.c": body.source + data,
        "bg_model.h": header.replace(placeholder, guid),
        **{name: resources.files(__package__).joinpath("csrc", name).read_text() for name in STATIC_SOURCES},
    }
    xml = xml.replace(placeholder, guid)
    with tempfile.TemporaryDirectory(prefix="bondgraph-fmu-") as tmp:
        src = Path(tmp)
        for name, text in files.items():
            (src / name).write_text(text)
        binary = src / f"{ident}{suffix}"
        started = time.perf_counter()
        _compile(compiler, src, binary, eqs)
        seconds = time.perf_counter() - started
        with atomic_write(path, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("modelDescription.xml", xml)
            zf.write(binary, f"binaries/{folder}/{binary.name}")
            for name, text in files.items():
                zf.writestr(f"sources/{name}", text)
    external = [n for n in names if n not in signals]
    return FMUReport(
        Path(path),
        ident,
        guid,
        len(states),
        [v.name for v in variables if v.causality == "parameter"],
        external,
        [n for n in names if n in signals],
        list(eqs.outputs),
        dict(zip(states, nominal)),
        seconds,
    )


def estimate_nominals(eqs: Equations, experiment: Experiment, signals: Mapping[str, Signal] | None = None) -> dict:
    """Nominal magnitudes of the states from a native run of ``experiment``.

    Parameters
    ----------
    eqs : Equations
        The model's equations.
    experiment : Experiment
        Run at relative tolerance 1e-3 over its times, driven by its inputs.
    signals : mapping, optional
        Input name → signal, replacing the experiment's for those inputs.

    Returns
    -------
    dict
        State name → peak |x| over the run (in the state's units); 1 for a state that stays 0.
    """
    from ..numerics.simulate import Simulator

    inputs = {**experiment.inputs, **(signals or {})}
    res = Simulator(eqs).run(experiment.times(), inputs, method=experiment.method, rtol=1e-3)
    return {name: float(np.max(np.abs(x))) or 1.0 for name, x in res.states.items()}


def model_identifier(name: str) -> str:
    """The FMU's model identifier (a C identifier, the binary's name) for a model name.

    Parameters
    ----------
    name : str
        The model's name, e.g. ``"APA-120ML"``.

    Returns
    -------
    str
        Letters, digits and single underscores, e.g. ``"APA_120ML"``; ``bg_`` before a digit.
    """
    ident = "".join(ch if ch.isascii() and (ch.isalnum() or ch == "_") else "_" for ch in name).strip("_")
    ident = "_".join(filter(None, ident.split("_"))) or "model"
    return f"bg_{ident}" if ident[0].isdigit() else ident


def _platform() -> tuple[str, str]:
    """The FMI 2.0 binaries folder and library suffix of this machine."""
    machine = platform.machine().lower()
    if sys.platform.startswith("linux") and machine in ("x86_64", "amd64"):
        return "linux64", ".so"
    if sys.platform == "darwin":
        return "darwin64", ".dylib"
    raise UsageError(
        f"FMI 2.0 names binary folders for linux64, darwin64, win32 and win64; this machine is "
        f"{sys.platform}/{machine}, for which the exporter builds no binary"
    )


def _compile(cc: str, src: Path, binary: Path, eqs: Equations) -> None:
    error = build_shared(cc, src, ["bg_fmu.c", "bg_model.c"], binary)
    if error is not None:
        ops = ", ".join(f"'{ob.symbol}'" for ob in eqs.operators)
        hint = f" (check the C source of the memory operators {ops})" if ops else ""
        raise ModelError(f"{eqs.model.name}: the C compiler refused the exported code: {error}{hint}")


# ---- variables ------------------------------------------------------------------------------


def _exposed_parameters(eqs: Equations) -> list[int]:
    """θ slots of the parameters the equations use (laws, initial states, operators)."""
    roots = [*eqs.rates.values(), *eqs.outputs.values(), *(s.x0 for s in eqs.states)]
    stmts, used = eqs.needed(roots)
    for st in stmts:
        if st.op is not None:
            used |= set(st.op.params)
    return [i for i, p in enumerate(eqs.params) if p in used]


def _variables(eqs: Equations, signals: Mapping[str, Signal], nominal: list[float]):
    decl = eqs.model.all_parameters()
    theta = parameter_vector(eqs)
    slots = _exposed_parameters(eqs)
    out: list[_Variable] = []
    for i in slots:
        p = decl.get(str(eqs.params[i]))
        out.append(
            _Variable(
                str(eqs.params[i]),
                "parameter",
                "fixed",
                "exact",
                float(theta[i]),
                p.unit if p else "",
                p.doc if p else "",
            )
        )
    values = dict(zip(eqs.params, theta))
    first_state = len(out) + 1
    for s, nom in zip(eqs.states, nominal):
        exact = not s.x0.free_symbols
        out.append(
            _Variable(
                str(s.symbol),
                "local",
                "continuous",
                "exact" if exact else "calculated",
                float(s.x0.xreplace(values)) if exact else None,
                description=f"state ({s.kind}) of {s.origin}",
                nominal=nom,
            )
        )
    for k, s in enumerate(eqs.states):
        out.append(
            _Variable(
                f"der({s.symbol})", "local", "continuous", description=f"rate of {s.symbol}", derivative=first_state + k
            )
        )
    for u in eqs.inputs:
        spec = eqs.model.inputs[str(u)]
        if str(u) in signals:
            text = f"{spec.doc}; driven inside the FMU by {signals[str(u)]}".lstrip("; ")
            out.append(_Variable(str(u), "local", "continuous", "calculated", unit=spec.unit, description=text))
        else:
            out.append(_Variable(str(u), "input", "continuous", None, 0.0, spec.unit, spec.doc))
    for name in eqs.outputs:
        spec = eqs.model.outputs[name]
        out.append(_Variable(name, "output", "continuous", "calculated", unit=spec.unit, description=spec.doc))
    seen: dict[str, str] = {}
    for v in out:
        if v.name in seen:
            raise ModelError(
                f"{eqs.model.name}: the name '{v.name}' is both a {seen[v.name]} and a {v.causality} variable; "
                f"FMI variable names must be unique: rename one"
            )
        seen[v.name] = v.causality if v.causality != "local" else "state or input"
    return out, slots


def _model_description(eqs: Equations, ident: str, guid: str, variables: list[_Variable], experiment) -> str:
    try:
        tool = f"bondgraph {version('bondgraph')}"
    except PackageNotFoundError:
        tool = "bondgraph"
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "2.0",
            "modelName": eqs.model.name,
            "guid": guid,
            "description": " ".join((eqs.model.doc or "").strip().split("\n\n")[0].split()) or eqs.model.name,
            "generationTool": tool,
            "variableNamingConvention": "flat",
            "numberOfEventIndicators": "0",
        },
    )
    common = {
        "modelIdentifier": ident,
        "needsExecutionTool": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "false",
        "canSerializeFMUstate": "false",
        "providesDirectionalDerivative": "false",
    }
    kinds = [
        ("ModelExchange", {"completedIntegratorStepNotNeeded": "false"}),
        (
            "CoSimulation",
            {
                "canHandleVariableCommunicationStepSize": "true",
                "canInterpolateInputs": "true",
                "maxOutputDerivativeOrder": "0",
                "canRunAsynchronuously": "false",
            },
        ),
    ]
    for tag, extra in kinds:
        el = ET.SubElement(root, tag, {**common, **extra})
        files = ET.SubElement(el, "SourceFiles")
        for name in ("bg_fmu.c", "bg_model.c"):
            ET.SubElement(files, "File", {"name": name})
    units = sorted({v.unit for v in variables if v.unit})
    if units:
        defs = ET.SubElement(root, "UnitDefinitions")
        for unit in units:
            el = ET.SubElement(defs, "Unit", {"name": unit})
            parsed = base_unit(unit)
            if parsed is not None:
                factor, exps = parsed
                attrs = {b: str(exps[b]) for b in BASE if b in exps}
                if factor != 1.0:
                    attrs["factor"] = repr(factor)
                ET.SubElement(el, "BaseUnit", attrs)
    cats = ET.SubElement(root, "LogCategories")
    ET.SubElement(cats, "Category", {"name": "logStatusError", "description": "errors"})
    ET.SubElement(cats, "Category", {"name": "logAll", "description": "everything"})
    if experiment is not None:
        ET.SubElement(
            root,
            "DefaultExperiment",
            {
                "startTime": "0.0",
                "stopTime": repr(float(experiment.t_end)),
                "tolerance": repr(float(experiment.rtol)),
                "stepSize": repr(float(experiment.dt)),
            },
        )
    mv = ET.SubElement(root, "ModelVariables")
    for vr, v in enumerate(variables):
        attrs = {"name": v.name, "valueReference": str(vr)}
        if v.description:
            attrs["description"] = v.description
        attrs.update(causality=v.causality, variability=v.variability)
        if v.initial is not None:
            attrs["initial"] = v.initial
        sv = ET.SubElement(mv, "ScalarVariable", attrs)
        real = {}
        if v.start is not None:
            real["start"] = repr(float(v.start))
        if v.unit:
            real["unit"] = v.unit
        if v.derivative is not None:
            real["derivative"] = str(v.derivative)
        if v.nominal is not None:
            real["nominal"] = repr(float(v.nominal))
        ET.SubElement(sv, "Real", real)
    index = {v.name: k + 1 for k, v in enumerate(variables)}
    knowns = {s: index[str(s)] for s in eqs.state_symbols}
    knowns.update({u: index[str(u)] for u in eqs.inputs if variables[index[str(u)] - 1].causality == "input"})

    def deps(expr) -> str:
        reached = eqs.needed([expr])[1]
        return " ".join(str(i) for i in sorted(knowns[s] for s in reached if s in knowns))

    ms = ET.SubElement(root, "ModelStructure")
    if eqs.outputs:  # an empty list is left out (the schema wants at least one entry)
        outs = ET.SubElement(ms, "Outputs")
        for name, expr in eqs.outputs.items():
            ET.SubElement(outs, "Unknown", {"index": str(index[name]), "dependencies": deps(expr)})
    if eqs.states:
        ders = ET.SubElement(ms, "Derivatives")
        for s in eqs.state_symbols:
            ET.SubElement(ders, "Unknown", {"index": str(index[f"der({s})"]), "dependencies": deps(eqs.rates[s])})
    initial = {
        k + 1
        for k, v in enumerate(variables)
        if v.initial == "calculated" and (v.causality == "output" or v.nominal is not None)
    }
    initial |= {index[f"der({s})"] for s in eqs.state_symbols}
    if initial:
        inits = ET.SubElement(ms, "InitialUnknowns")
        for i in sorted(initial):
            ET.SubElement(inits, "Unknown", {"index": str(i)})
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


# ---- generated C: header and data --------------------------------------------------------------


def _uses_input_rates(eqs: Equations) -> bool:
    roots = [*eqs.rates.values(), *eqs.outputs.values()]
    return bool(eqs.needed(roots)[1] & set(eqs.input_rates))


def _header(eqs: Equations, ident: str, guid: str, signals: Mapping[str, Signal], n_exposed: int) -> str:
    nops = sum(st.op is not None for st in eqs.program)  # operator inputs the program computes
    nx, nu, ny, npar = len(eqs.states), len(eqs.inputs), len(eqs.outputs), len(eqs.params)
    nmem = sum(ob.operator.n_memory for ob in eqs.operators)
    bank = SignalBank({str(u): signals[str(u)] for u in eqs.inputs if str(u) in signals})
    h_max = config.get("simulate.table_steps") * bank.table_spacing()
    kinds = dict(CONST=CONST, STEP=STEP, RAMP=RAMP, SINE=SINE, CHIRP=CHIRP, TRIANGLE=TRIANGLE, PWL=PWL)
    defs = {
        "BG_MODEL_IDENTIFIER": f'"{ident}"',
        "BG_GUID": f'"{guid}"',
        "BG_NX": nx,
        "BG_NU": nu,
        "BG_NY": ny,
        "BG_NP": npar,
        "BG_NPX": n_exposed,
        "BG_NOPS": nops,
        "BG_NMEM": nmem,
        **{f"{k}1": f"{max(v, 1)}" for k, v in (("BG_NX", nx), ("BG_NU", nu), ("BG_NY", ny), ("BG_NP", npar))},
        "BG_NPX1": max(n_exposed, 1),
        "BG_NOPS1": max(nops, 1),
        "BG_NMEM1": max(nmem, 1),
        "BG_VR_X": n_exposed,
        "BG_VR_DX": n_exposed + nx,
        "BG_VR_U": n_exposed + 2 * nx,
        "BG_VR_Y": n_exposed + 2 * nx + nu,
        "BG_VR_END": n_exposed + 2 * nx + nu + ny,
        "BG_KINKS": int(_uses_input_rates(eqs) or bool(nops)),
        "BG_RTOL": repr(float(config.get("simulate.rtol"))),
        "BG_ATOL": repr(float(config.get("simulate.atol_floor"))),
        "BG_HMAX": repr(float(h_max)) if math.isfinite(h_max) else "INFINITY",
        "BG_MAX_STEPS": f"{int(config.get('simulate.max_steps'))}L",
        **{f"BG_{k}": v for k, v in kinds.items()},
    }
    args = "double t, const double *x, const double *u, const double *du, const double *th"
    lines = [
        comment(f"{eqs.model.name}: sizes, value references and data of the generated model (bondgraph)"),
        "#ifndef BG_MODEL_H",
        "#define BG_MODEL_H",
        "",
        *(f"#define {k} {v}" for k, v in defs.items()),
        "",
        "extern const double bg_theta0[BG_NP1];      /* parameter vector at its defaults */",
        "extern const int bg_param_slot[BG_NPX1];    /* value reference -> slot in the parameter vector */",
        "extern const double bg_x_start[BG_NX1];     /* initial states at the default parameters */",
        "extern const int bg_x_exact[BG_NX1];        /* 1: the start value is a number (settable) */",
        "extern const double bg_x_nominal[BG_NX1];",
        "extern const int bg_sig_kind[BG_NU1];       /* -1: an FMU input; else the signal kind */",
        f"extern const double bg_sig_par[BG_NU1][{NPAR}];",
        "extern const long bg_sig_off[BG_NU1], bg_sig_len[BG_NU1];",
        "extern const double bg_sig_tt[], bg_sig_tv[];",
        "extern const double bg_dp_a[6][5], bg_dp_b[6], bg_dp_c[6], bg_dp_e[7], bg_dp_p[7][4];",
        "",
        f"void bg_rhs({args}, const double *mem, double *out);",
        f"void bg_output({args}, const double *mem, double *out);",
        f"void bg_opin({args}, const double *mem, double *out);",
        f"void bg_commit({args}, double *mem, double *out);",
        "void bg_x0(const double *th, double *x);",
        f"void bg_init_memory({args}, double *mem);",
        "",
        "#endif",
    ]
    return "\n".join(lines) + "\n"


def _array(values, fmt=lambda v: repr(float(v))) -> str:
    values = list(values)
    return "{" + ", ".join(fmt(v) for v in values) + "}" if values else "{0}"


def _data(eqs: Equations, slots: list[int], nominal: list[float], signals: Mapping[str, Signal]) -> str:
    from scipy.integrate import RK45

    theta = parameter_vector(eqs)
    values = dict(zip(eqs.params, theta))
    x_start = [float(s.x0.xreplace(values)) if not s.x0.free_symbols else 0.0 for s in eqs.states]
    exact = [int(not s.x0.free_symbols) for s in eqs.states]
    sigs = [signals.get(str(u)) for u in eqs.inputs]
    tt = [x for s in sigs if s is not None for x in s.table_t]
    tv = [x for s in sigs if s is not None for x in s.table_v]
    offs, pos = [], 0
    for s in sigs:
        offs.append(pos)
        pos += len(s.table_t) if s is not None else 0
    par = [list(s.par) if s is not None else [0.0] * NPAR for s in sigs]

    def matrix(rows) -> str:
        return "{" + ", ".join(_array(r) for r in rows) + "}" if len(rows) else "{{0}}"

    lines = [
        "",
        "/* ---- data ---- */",
        f"const double bg_theta0[BG_NP1] = {_array(theta)};",
        f"const int bg_param_slot[BG_NPX1] = {_array(slots, str)};",
        f"const double bg_x_start[BG_NX1] = {_array(x_start)};",
        f"const int bg_x_exact[BG_NX1] = {_array(exact, str)};",
        f"const double bg_x_nominal[BG_NX1] = {_array(nominal)};",
        f"const int bg_sig_kind[BG_NU1] = {_array([s.kind if s is not None else -1 for s in sigs], str)};",
        f"const double bg_sig_par[BG_NU1][{NPAR}] = {matrix(par)};",
        f"const long bg_sig_off[BG_NU1] = {_array(offs, str)};",
        f"const long bg_sig_len[BG_NU1] = {_array([len(s.table_t) if s is not None else 0 for s in sigs], str)};",
        f"const double bg_sig_tt[] = {_array(tt)};",
        f"const double bg_sig_tv[] = {_array(tv)};",
        "/* Dormand-Prince 5(4) tableau and dense output, as scipy's RK45 (the native integrator's) */",
        f"const double bg_dp_a[6][5] = {matrix(np.asarray(RK45.A, float)[:, :5])};",
        f"const double bg_dp_b[6] = {_array(RK45.B)};",
        f"const double bg_dp_c[6] = {_array(RK45.C)};",
        f"const double bg_dp_e[7] = {_array(RK45.E)};",
        f"const double bg_dp_p[7][4] = {matrix(np.asarray(RK45.P, float))};",
    ]
    return "\n".join(lines) + "\n"
