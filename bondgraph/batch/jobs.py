"""What runs on a worker: one job → one table row (see :mod:`bondgraph.batch`).

A job is a model file, parameter values and (for diagnose/fit/simulate on data) a data file.
Options shared by every job of a batch travel once per task in :class:`Options`.  Every
exception of a job is caught and becomes its row's ``error``; warnings become ``warnings``.

Simulation jobs reuse compiled models: each worker process keeps a memo of built
simulators keyed by model file (path, modification time, size) and structural parameter
values; real parameters the equations keep symbolic only change the parameter vector, so a
worker derives and loads each model structure once (the machine code itself comes from the
on-disk cache of :mod:`bondgraph.numerics.codegen`, compiled at most once per machine).
"""

from __future__ import annotations

import functools
import math
import os
import time
import warnings
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from ..support import config
from ..support.errors import BondGraphError


@dataclass(frozen=True)
class Job:
    """One row of the table: its index, parameter values, and data file (path and label).

    Parameters
    ----------
    index : int
        The job's number (the table's ``job`` column).
    params : tuple, optional
        (name, value) pairs of the job's parameter set.
    data : str, optional
        Absolute path of its data file.
    label : str, optional
        The data file as the user gave it (the table's ``data`` column).
    """

    index: int
    params: tuple = ()
    data: str | None = None
    label: str | None = None


@dataclass(frozen=True)
class Options:
    """What every job of a batch shares.

    Parameters
    ----------
    kind : {"diagnose", "fit", "simulate"}
        What each job does.
    model : str
        Absolute path of the model file.
    base : tuple, optional
        (name, value) pairs applied to every job.
    input : str, optional
        The model input driven by the data's column.
    output : str, optional
        The model output compared with the data's column.
    data_input : str, optional
        The data's column for ``input`` when its name differs.
    data_output : str, optional
        The data's column for ``output`` when its name differs.
    validation : float, optional
        Diagnose and fit: the held-out share.
    names : tuple, optional
        Fit: the parameters to fit.
    fit : dict, optional
        Fit: ``split``, ``loss`` and ``starts``.
    metrics : tuple, optional
        Simulate: the :class:`~bondgraph.batch.metrics.Metric` objects.
    times : tuple, optional
        Simulate without data: (t_end, dt), s.
    inputs : dict, optional
        Simulate: input signals by name.
    method : str, optional
        Simulate: the integrator.
    rtol : float, optional
        Simulate: its relative tolerance.
    settings : dict, optional
        The caller's :mod:`bondgraph.config` snapshot, restored on the worker.
    """

    kind: str  # "diagnose", "fit" or "simulate"
    model: str  # absolute path of the model file
    base: tuple = ()  # parameter values applied to every job
    input: str | None = None  # model input (driven by the data's column)
    output: str | None = None  # model output (compared with the data's column)
    data_input: str | None = None  # data column names, when they differ
    data_output: str | None = None
    validation: float = 0.3  # diagnose/fit: held-out share
    names: tuple = ()  # fit: parameters to fit
    fit: dict = field(default_factory=dict)  # fit: split, loss, starts
    metrics: tuple = ()  # simulate: Metric objects
    times: tuple = (1.0, 1e-3)  # simulate without data: (t_end, dt)
    inputs: dict = field(default_factory=dict)  # simulate: input signals by name
    method: str = "auto"
    rtol: float = 1e-6
    settings: dict = field(default_factory=dict)  # bondgraph.config snapshot of the caller


def run_chunk(jobs: list[Job], opts: Options) -> list[dict]:
    """Run jobs one after the other on this worker; one row each.

    Parameters
    ----------
    jobs : list of Job
        The jobs.
    opts : Options
        What every job of the batch shares.

    Returns
    -------
    list of dict
        One row per job (:func:`run_job`).
    """
    config.restore(opts.settings)
    return [run_job(job, opts) for job in jobs]


def run_job(job: Job, opts: Options) -> dict:
    """Run one job; its exception, if any, becomes the row's ``error``.

    Parameters
    ----------
    job : Job
        The job.
    opts : Options
        What every job of the batch shares.

    Returns
    -------
    dict
        ``job``, ``data``, the job's parameters, its results, ``error`` ("" on success),
        ``warnings`` (if any) and ``seconds`` (wall time, s).
    """
    row: dict[str, Any] = {"job": job.index}
    if job.data is not None:
        row["data"] = job.label or job.data
    row.update(dict(job.params))
    started = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            row.update(_KINDS[opts.kind](job, opts))
            row["error"] = ""
        except Exception as exc:  # noqa: BLE001 - a failing job is reported in its row
            row["error"] = describe(exc)
    messages = list(dict.fromkeys(str(w.message) for w in caught))
    if messages:
        row["warnings"] = "; ".join(messages)
    row["seconds"] = time.perf_counter() - started
    return row


def describe(exc: BaseException) -> str:
    """One line for the table: the message of a user-facing error, else type and message.

    Parameters
    ----------
    exc : BaseException
        The exception.

    Returns
    -------
    str
        The line, whitespace collapsed.
    """
    text = str(exc) if isinstance(exc, BondGraphError) else f"{type(exc).__name__}: {exc}"
    return " ".join(text.split()) or type(exc).__name__


# ---- the job kinds ------------------------------------------------------------------------------
def _values(job: Job, opts: Options) -> dict:
    return {**dict(opts.base), **dict(job.params)}


def _read(job: Job, opts: Options, need_output: bool):
    from ..data import read_csv

    rename = {}
    if opts.data_input:
        rename[opts.data_input] = opts.input
    if opts.data_output:
        rename[opts.data_output] = opts.output
    required = ("t", opts.input, opts.output) if need_output else ("t", opts.input)
    return read_csv(job.data, required=required, rename=rename or None)


def _diagnose(job: Job, opts: Options) -> dict:
    from ..model.modelfile import load_model

    loaded = load_model(opts.model, _values(job, opts))
    return diagnosis_row(loaded, _read(job, opts, need_output=True), opts)


def diagnosis_row(loaded, data, opts: Options) -> dict:
    """The diagnosis of one record (the one call of the diagnosis API in batch runs): cause,
    causes, gain, RMS before and after, and the best gain of each candidate cause.

    Parameters
    ----------
    loaded : LoadedModel
        The model file, loaded with the job's values.
    data : Dataset
        The record.
    opts : Options
        What every job of the batch shares.

    Returns
    -------
    dict
        ``cause``, ``causes``, ``gain``, ``baseline_rms``, ``extended_rms`` and
        ``gain:CAUSE`` per candidate cause.
    """
    from ..diagnosis import diagnose, model_file_options

    report = diagnose(
        loaded.model,
        data,
        **model_file_options(loaded.module),
        input=opts.input,
        output=opts.output,
        validation=opts.validation,
        workers=1,
        source=str(loaded.path),
    ).as_json()
    causes = report.get("causes", [report["cause"]] if report["cause"] != "none" else [])
    row = {
        "cause": report["cause"],
        "causes": ";".join(c if isinstance(c, str) else str(c.get("cause")) for c in causes) or "none",
        "gain": report["gain"],
        "baseline_rms": report["baseline_rms"],
        "extended_rms": report["extended_rms"],
    }
    for cand in report.get("candidates", []):
        if isinstance(cand, dict) and "cause" in cand and "gain" in cand:
            key = f"gain:{cand['cause']}"
            row[key] = max(row.get(key, -math.inf), float(cand["gain"]))
    return row


def _fit(job: Job, opts: Options) -> dict:
    from ..fit.fitting import fit_parameters
    from ..model.modelfile import load_model

    loaded = load_model(opts.model, _values(job, opts))
    fit = fit_parameters(
        loaded,
        _read(job, opts, need_output=True),
        list(opts.names),
        input=opts.input,
        output=opts.output,
        validation=opts.validation,
        **opts.fit,
    )
    res = fit.result
    row: dict[str, Any] = {}
    for n in opts.names:
        row[f"fit:{n}"] = float(res.values[n])
        row[f"sd:{n}"] = float(res.stderr[n]) if res.stderr.get(n) is not None else None
    row.update(rms_fit=res.rms_fit, rms_validation=res.rms_validation, simulations=res.nfev, converged=res.success)
    return row


def _simulate(job: Job, opts: Options) -> dict:
    from ..model.signals import PiecewiseLinear
    from ..numerics.simulate import Experiment

    sim, numeric = built(opts.model, _values(job, opts))
    inputs = dict(opts.inputs)
    measured = None
    if job.data is not None:
        data = _read(job, opts, need_output=False)
        t = data.t
        inputs[opts.input] = PiecewiseLinear(data.t, data.column(opts.input), label=f"data:{opts.input}")
        measured = data.columns.get(opts.output)
    else:
        t = Experiment(t_end=opts.times[0], dt=opts.times[1]).times()
    res = sim.run(t, inputs, params=numeric, method=opts.method, rtol=opts.rtol)
    row: dict[str, Any] = {}
    if measured is not None and opts.output in sim.output_names:
        row["rms"] = float(np.sqrt(np.mean(np.square(res[opts.output] - measured))))
    linear = _linearized(sim, numeric, opts) if any(m.linear for m in opts.metrics) else None
    for m in opts.metrics:
        try:
            row[m.text] = m.of(res, linear)
        except BondGraphError as exc:  # this metric has no value for this run; the others do
            row[m.text] = None
            warnings.warn(str(exc))
    return row


def _linearized(sim, numeric: Mapping[str, float], opts: Options):
    from ..linear.linearize import linearize

    u = opts.input if opts.input in sim.input_names else sim.input_names[0]
    y = opts.output if opts.output in sim.output_names else sim.output_names[0]
    return linearize(sim.eqs, u, y, params=numeric)


_KINDS = {"diagnose": _diagnose, "fit": _fit, "simulate": _simulate}


# ---- per-worker memo of built simulators ---------------------------------------------------------
def built(path: str, values: Mapping[str, Any]):
    """(Simulator, numeric parameter values) for ``values`` of model file ``path``.

    Values of structural parameters (integers, choices, flags, reals declared
    ``symbolic=False``) select a memoised build; the others are checked against their
    declarations and returned for :meth:`Simulator.run`.  A name the file does not declare (a
    component's parameter) is numeric when the built equations keep it as a symbol.

    Parameters
    ----------
    path : str
        The model file.
    values : mapping of str to object
        Parameter values (text or numbers).

    Returns
    -------
    sim : Simulator
        The memoised build.
    numeric : dict of str to float
        The values to pass as ``params``.
    """
    stamp = _stamp(path)
    declared = _declared(path, stamp)
    structural, numeric, other = {}, {}, {}
    for name, value in values.items():
        decl = declared.get(name)
        if decl is None:
            other[name] = value
        elif decl.symbolic:
            numeric[name] = decl.parse(value)
        else:
            structural[name] = decl.parse(value)
    sim = _simulator(path, stamp, _key(structural))
    symbols = {p.name for p in sim.eqs.params}
    undeclared = {k: v for k, v in other.items() if k not in symbols}
    if undeclared:
        sim = _simulator(path, stamp, _key({**structural, **undeclared}))
    for name in other.keys() - undeclared.keys():
        numeric[name] = sim.eqs.model.parameters[name][0].parse(other[name])
    return sim, {k: v for k, v in numeric.items() if k in symbols}


def _key(values: Mapping[str, Any]) -> tuple:
    return tuple(sorted(values.items(), key=lambda kv: kv[0]))


def _stamp(path: str) -> tuple:
    st = os.stat(path)
    return st.st_mtime_ns, st.st_size


@functools.lru_cache(maxsize=16)
def _declared(path: str, stamp: tuple) -> dict:
    from ..model.modelfile import read_model_module

    _, declared = read_model_module(path)
    return {d.name: d for d in declared}


@functools.lru_cache(maxsize=32)
def _simulator(path: str, stamp: tuple, structural: tuple):
    from ..model.modelfile import load_model
    from ..numerics.simulate import Simulator

    return Simulator(load_model(path, dict(structural)).model)


def memo_info() -> dict:
    """Hits and misses of this process' memo of built simulators (for tests and benchmarks).

    Returns
    -------
    dict
        ``hits``, ``misses`` and ``pid``.
    """
    info = _simulator.cache_info()
    return {"hits": info.hits, "misses": info.misses, "pid": os.getpid()}
