"""Batch diagnosis, fitting and simulation over many data files and parameter sets.

Every function builds one job per (data file, parameter set) pair, runs the jobs on a Dask
cluster (:mod:`bondgraph.batch.cluster`) and returns a :class:`~bondgraph.batch.table.Table`
with one row per job, in job order.  The model file and the options are checked here, before
any job starts; a job that fails (an unreadable data file, a failed fit) is reported in its
row's ``error`` and the others go on.

Common keyword arguments: ``sets`` (list of ``{parameter: value}``, one per parameter set;
default: one empty set), ``params`` (values applied to every job, like ``--set``),
``input``/``output`` (model input driven by the data, model output compared with it; default:
the model's first declared input and output),
``data_input``/``data_output`` (the data's column names when they differ), ``scheduler``,
``workers`` (see :func:`~bondgraph.batch.cluster.connect`), ``progress(done, total)`` and
``say(line)`` callbacks.
"""

from __future__ import annotations

import csv
import os
from pathlib import Path
from typing import Callable, Iterable, Mapping, Sequence

from ..support import config
from ..support.errors import ParameterError, UsageError, did_you_mean
from .cluster import chunk_size, chunked, connect, run_tasks, worker_count
from .jobs import Job, Options, describe, run_chunk
from .metrics import parse_metrics
from .table import Table

OnProgress = Callable[[int, int], None]  # progress(done, total)


def diagnose(
    model,
    data: Sequence,
    *,
    sets: Sequence[Mapping] | None = None,
    params: Mapping | None = None,
    input: str | None = None,
    output: str | None = None,
    data_input: str | None = None,
    data_output: str | None = None,
    validation: float = 0.3,
    scheduler=None,
    workers: int | None = None,
    progress: OnProgress | None = None,
    say=None,
) -> Table:
    """Diagnose every data file (× parameter set): ``cause``, ``causes``, ``gain``,
    ``baseline_rms``, ``extended_rms`` and the best gain of each candidate cause (``gain:CAUSE``).

    Parameters
    ----------
    model : str or path-like
        The model file (built once here, so that its errors come before any job).
    data : sequence of str or path-like
        The measured CSV records, one job per file (× parameter set).
    sets : sequence of mapping, optional
        Parameter sets, each ``{parameter: value}`` (SI units), one job per set and data file
        (default: one empty set); see :func:`read_sets`.
    params : mapping of str to float, optional
        Values applied to every job, like ``--set``.
    input : str, optional
        The model input driven by the data (default: the model's first declared input).
    output : str, optional
        The model output compared with the data (default: the model's first declared output).
    data_input : str, optional
        The data's column for ``input`` when its name differs.
    data_output : str, optional
        The data's column for ``output`` when its name differs.
    validation : float, optional
        Share of the record held out for validation, between 0 and 1 (default 0.3).
    scheduler : str or distributed.Client, optional
        Where the jobs run (see :func:`~bondgraph.batch.connect`; default: an embedded local
        cluster).
    workers : int, optional
        Worker processes of the embedded cluster.
    progress : callable, optional
        ``progress(done, total)``, called as jobs finish.
    say : callable, optional
        ``say(line)`` receives status lines (where the jobs run).

    Returns
    -------
    Table
        One row per job, in job order: ``job``, ``data``, the set's parameters, the results
        (empty for a failed job), ``warnings``, ``seconds`` and ``error``.

    Raises
    ------
    UsageError
        A bad option or model file, no data file, or no cluster (before any job runs; a job
        that fails is reported in its row's ``error``).
    ParameterError
        A parameter set names a parameter the model does not have.
    """
    lm = checked_model(model, params, sets)
    input, output = model_io(lm, input, output)
    opts = Options(
        "diagnose",
        str(lm.path.resolve()),
        _items(params),
        input,
        output,
        data_input,
        data_output,
        validation,
        settings=config.snapshot(),
    )
    return execute(opts, data_jobs(data, sets), scheduler, workers, progress, say, per_task=1)


def fit(
    model,
    data: Sequence,
    names: Sequence[str],
    *,
    sets: Sequence[Mapping] | None = None,
    params: Mapping | None = None,
    input: str | None = None,
    output: str | None = None,
    data_input: str | None = None,
    data_output: str | None = None,
    validation: float = 0.3,
    split: str = "blocks",
    loss: str = "linear",
    starts: int = 1,
    scheduler=None,
    workers: int | None = None,
    progress: OnProgress | None = None,
    say=None,
) -> Table:
    """Fit ``names`` to every data file (× parameter set): ``fit:NAME``, ``sd:NAME`` (standard
    error), ``rms_fit``, ``rms_validation``, ``simulations``, ``converged``.

    Parameters
    ----------
    model : str or path-like
        The model file (built once here, so that its errors come before any job).
    data : sequence of str or path-like
        The measured CSV records, one job per file (× parameter set).
    names : sequence of str
        The parameters to fit (at least one).
    sets : sequence of mapping, optional
        Parameter sets, each ``{parameter: value}`` (SI units), one job per set and data file
        (default: one empty set); see :func:`read_sets`.
    params : mapping of str to float, optional
        Values applied to every job, like ``--set``.
    input : str, optional
        The model input driven by the data (default: the model's first declared input).
    output : str, optional
        The model output compared with the data (default: the model's first declared output).
    data_input : str, optional
        The data's column for ``input`` when its name differs.
    data_output : str, optional
        The data's column for ``output`` when its name differs.
    validation : float, optional
        Share of the record held out for validation, between 0 and 1 (default 0.3).
    split : {"blocks", "tail"}, optional
        How the validation share is held out: time blocks spread over the record, or its end.
    loss : str, optional
        The least-squares loss of ``scipy.optimize.least_squares`` (``linear``, ``soft_l1``,
        ``huber``, ...).
    starts : int, optional
        Number of start points of the fit (the best one is kept).
    scheduler : str or distributed.Client, optional
        Where the jobs run (see :func:`~bondgraph.batch.connect`; default: an embedded local
        cluster).
    workers : int, optional
        Worker processes of the embedded cluster.
    progress : callable, optional
        ``progress(done, total)``, called as jobs finish.
    say : callable, optional
        ``say(line)`` receives status lines (where the jobs run).

    Returns
    -------
    Table
        One row per job, in job order: ``job``, ``data``, the set's parameters, the fitted
        values (the parameters' units), the RMS errors (the output's unit), ``warnings``,
        ``seconds`` and ``error``.

    Raises
    ------
    UsageError
        No parameter to fit, a bad option or model file, no data file, or no cluster (before any job runs; a job
        that fails is reported in its row's ``error``).
    ParameterError
        A parameter set names a parameter the model does not have.
    """
    names = list(names)
    if not names:
        raise UsageError("batch fit: give the parameters to fit, e.g. --params a,c,K")
    lm = checked_model(model, params, sets, names)
    input, output = model_io(lm, input, output)
    opts = Options(
        "fit",
        str(lm.path.resolve()),
        _items(params),
        input,
        output,
        data_input,
        data_output,
        validation,
        tuple(names),
        {"split": split, "loss": loss, "starts": starts},
        settings=config.snapshot(),
    )
    return execute(opts, data_jobs(data, sets), scheduler, workers, progress, say, per_task=1)


def simulate(
    model,
    data: Sequence = (),
    *,
    sets: Sequence[Mapping] | None = None,
    params: Mapping | None = None,
    metrics: Sequence[str] = (),
    inputs: Mapping | None = None,
    t_end: float | None = None,
    dt: float | None = None,
    method: str | None = None,
    rtol: float | None = None,
    input: str | None = None,
    output: str | None = None,
    data_input: str | None = None,
    data_output: str | None = None,
    scheduler=None,
    workers: int | None = None,
    progress: OnProgress | None = None,
    say=None,
    per_task: int | None = None,
) -> Table:
    """Simulate every data file (its ``input`` column drives the model; ``rms`` of the model's
    ``output`` against the data's) or, without data, the model's experiment (``inputs``,
    ``t_end``, ``dt`` override it), for every parameter set; one column per metric
    (:mod:`bondgraph.batch.metrics`).

    Parameters
    ----------
    model : str or path-like
        The model file (built once here, so that its errors come before any job).
    data : sequence of str or path-like, optional
        Measured CSV records whose input column drives the model; without them the model's
        experiment runs once per parameter set.
    sets : sequence of mapping, optional
        Parameter sets, each ``{parameter: value}`` (SI units), one job per set and data file
        (default: one empty set); see :func:`read_sets`.
    params : mapping of str to float, optional
        Values applied to every job, like ``--set``.
    metrics : sequence of str, optional
        Scalar outputs of each run (:mod:`bondgraph.batch.metrics`), e.g. ``"peak(x)"``,
        ``"resonance"``; one column each.
    inputs : mapping of str to Signal or float, optional
        Input name → signal, overriding the experiment's (without data).
    t_end : float, optional
        Simulated time, s (default: the experiment's).
    dt : float, optional
        Output sample interval, s (default: the experiment's).
    method : str, optional
        Integrator (see :meth:`bondgraph.Simulator.run`; default: the experiment's).
    rtol : float, optional
        Relative tolerance of the integrator (default: the experiment's).
    input : str, optional
        The model input driven by the data, and the input of the linear metrics (default:
        the model's first declared input).
    output : str, optional
        The model output compared with the data (``rms``), and the output of the linear
        metrics (default: the model's first declared output).
    data_input : str, optional
        The data's column for ``input`` when its name differs.
    data_output : str, optional
        The data's column for ``output`` when its name differs.
    scheduler : str or distributed.Client, optional
        Where the jobs run (see :func:`~bondgraph.batch.connect`; default: an embedded local
        cluster).
    workers : int, optional
        Worker processes of the embedded cluster.
    progress : callable, optional
        ``progress(done, total)``, called as jobs finish.
    say : callable, optional
        ``say(line)`` receives status lines (where the jobs run).
    per_task : int, optional
        Jobs per Dask task (default: sized to the number of jobs and workers).

    Returns
    -------
    Table
        One row per job, in job order: ``job``, ``data`` (with data), the set's parameters,
        ``rms`` (with data, the output's unit) and the metrics, ``warnings``, ``seconds`` and
        ``error``.

    Raises
    ------
    UsageError
        An unknown metric, input or method, a bad option or model file, no data file, or no cluster (before any job runs; a job
        that fails is reported in its row's ``error``).
    ParameterError
        A parameter set names a parameter the model does not have.
    """
    lm = checked_model(model, params, sets)
    input, output = model_io(lm, input, output, required=bool(data))
    opts = simulation_options(
        lm, params, metrics, inputs, t_end, dt, method, rtol, input, output, data_input, data_output
    )
    jobs = data_jobs(data, sets) if data else [Job(i, _items(s)) for i, s in enumerate(sets or [{}])]
    return execute(opts, jobs, scheduler, workers, progress, say, per_task=per_task)


# ---- shared by the batch kinds -------------------------------------------------------------------
def checked_model(model, params: Mapping | None, sets: Sequence[Mapping] | None = None, names: Iterable[str] = ()):
    """The model file built with ``params`` (errors now, not in every job), after checking that
    every parameter named by the sets (and ``names``) exists.

    Parameters
    ----------
    model : str or path-like
        The model file.
    params : mapping, optional
        Values applied to every job.
    sets : sequence of mapping, optional
        The parameter sets.
    names : iterable of str, optional
        Further parameter names to check (e.g. those to fit).

    Returns
    -------
    LoadedModel
        The model file built with ``params``.

    Raises
    ------
    ParameterError
        A set or ``names`` names a parameter the model does not have.
    BondGraphError
        The model file cannot be loaded.
    """
    from ..model.modelfile import load_model

    lm = load_model(model, dict(params or {}))
    known = set(lm.model.values) | set(lm.model.parameters)
    for name in [*(k for s in (sets or []) for k in s), *names]:
        if name not in known:
            raise ParameterError(did_you_mean(name, known, "parameter"))
    return lm


def model_io(lm, input: str | None, output: str | None, required: bool = True) -> tuple:
    """(input, output) of the model: the names given (checked), else its first declared ones;
    a model without inputs or outputs is an error when ``required``, else gives ``None``.

    Parameters
    ----------
    lm : LoadedModel
        The loaded model file.
    input : str or None
        The input named, if any.
    output : str or None
        The output named, if any.
    required : bool, optional
        Both must exist (a run on measured data).

    Returns
    -------
    tuple
        (input, output), each a name or None.

    Raises
    ------
    UsageError
        A name the model does not declare, or none declared when ``required``.
    """
    names = []
    for given, declared, what in ((input, lm.model.inputs, "input"), (output, lm.model.outputs, "output")):
        if given is not None and given not in declared:
            raise UsageError(f"model {what}: {did_you_mean(given, declared, what)}")
        if given is None and declared:
            given = next(iter(declared))
        if given is None and required:
            raise UsageError(f"model {lm.path} declares no {what}; a run on measured data needs one")
        names.append(given)
    return tuple(names)


def simulation_options(
    lm, params, metrics, inputs, t_end, dt, method, rtol, input=None, output=None, data_input=None, data_output=None
) -> Options:
    """Options of simulation jobs: the model's experiment with the given overrides, checked.

    Parameters
    ----------
    lm : LoadedModel
        The loaded model file.
    params : mapping or None
        Values applied to every job.
    metrics : sequence of str
        The metrics' texts.
    inputs : mapping or None
        Input signals overriding the experiment's.
    t_end : float or None
        Simulated time, s.
    dt : float or None
        Output sample interval, s.
    method : str or None
        The integrator.
    rtol : float or None
        Its relative tolerance.
    input, output : str, optional
        The model input and output of runs on data.
    data_input, data_output : str, optional
        The data's columns when their names differ.

    Returns
    -------
    Options
        The options of every simulation job.

    Raises
    ------
    UsageError
        A bad metric, input, time or method.
    """
    from ..numerics.simulate import METHODS

    parsed = parse_metrics(metrics)
    signals = set(lm.model.inputs) | set(lm.model.outputs)
    unknown = [m for m in parsed if not m.linear and m.arg not in signals]
    if unknown:
        from ..equations.derivation import derive

        states = {str(s) for s in derive(lm.model).state_symbols}
        for m in unknown:
            if m.arg not in states:
                raise UsageError(f"metric {m.text}: {did_you_mean(m.arg, signals | states, 'signal')}")
    exp = lm.experiment
    sig = {**exp.inputs, **dict(inputs or {})}
    for name in sig:
        if name not in lm.model.inputs:
            raise UsageError(f"--input {name}: {did_you_mean(name, lm.model.inputs, 'input')}")
    exp.times(t_end, dt)  # checks t_end and dt
    method = method or exp.method
    if method not in METHODS:
        raise UsageError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
    return Options(
        "simulate",
        str(lm.path.resolve()),
        _items(params),
        input,
        output,
        data_input,
        data_output,
        metrics=tuple(parsed),
        times=(exp.t_end if t_end is None else t_end, exp.dt if dt is None else dt),
        inputs=sig,
        method=method,
        rtol=exp.rtol if rtol is None else rtol,
        settings=config.snapshot(),
    )


def data_jobs(data: Sequence, sets: Sequence[Mapping] | None) -> list[Job]:
    """One job per (data file, parameter set), data files outermost.

    Parameters
    ----------
    data : sequence of str or path-like
        The data files.
    sets : sequence of mapping or None
        The parameter sets (default: one empty set).

    Returns
    -------
    list of Job
        The jobs, numbered from 0.

    Raises
    ------
    UsageError
        No data file.
    """
    if not data:
        raise UsageError("give at least one data file")
    jobs = []
    for path in data:
        for s in sets or [{}]:
            jobs.append(Job(len(jobs), _items(s), os.path.abspath(os.fspath(path)), os.fspath(path)))
    return jobs


def _items(values: Mapping | None) -> tuple:
    return tuple((dict(values or {})).items())


def execute(
    opts: Options,
    jobs: Sequence[Job],
    scheduler=None,
    workers: int | None = None,
    progress: OnProgress | None = None,
    say=None,
    per_task: int | None = None,
) -> Table:
    """Run ``jobs`` on the cluster, ``per_task`` jobs per Dask task (default: sized to the
    number of jobs and workers); the table in job order.

    Parameters
    ----------
    opts : Options
        What every job shares.
    jobs : sequence of Job
        The jobs.
    scheduler : str or distributed.Client, optional
        Where they run (see :func:`~bondgraph.batch.connect`).
    workers : int, optional
        Worker processes of the embedded cluster.
    progress : callable, optional
        ``progress(done, total)`` as tasks finish.
    say : callable, optional
        ``say(line)`` receives status lines.
    per_task : int, optional
        Jobs per Dask task.

    Returns
    -------
    Table
        One row per job, in job order (a task whose worker died gives its jobs an ``error``).
    """
    rows: list[dict] = []
    done = [0]

    def finished(_i, chunk_rows):
        done[0] += len(chunk_rows)
        if progress is not None:
            progress(done[0], len(jobs))

    def failed(chunk, exc):  # the task itself failed (its worker died): every job of it
        return [
            {
                "job": j.index,
                **({"data": j.label} if j.data else {}),
                **dict(j.params),
                "error": f"worker failed: {describe(exc)}",
            }
            for j in chunk
        ]

    with connect(scheduler, workers, say) as client:
        size = per_task or chunk_size(len(jobs), worker_count(client))
        for chunk_rows in run_tasks(client, run_chunk, chunked(list(jobs), size), {"opts": opts}, finished, failed):
            rows += chunk_rows
    leading = ["data", *dict.fromkeys(k for j in jobs for k, _ in j.params)]
    return Table(rows, leading)


def read_sets(path: str | os.PathLike) -> list[dict]:
    """Parameter sets from a CSV file: a header of parameter names, one set per row.

    Lines starting with ``#`` are comments.

    Parameters
    ----------
    path : str or path-like
        The CSV file.

    Returns
    -------
    list of dict
        One ``{parameter: value}`` per row, values as the text written (the model file
        converts them).

    Raises
    ------
    UsageError
        The file cannot be read, has no header and row, or a row has the wrong number of values.
    """
    p = Path(path)
    try:
        with open(p, newline="", encoding="utf-8") as fh:
            rows = [(k, r) for k, r in enumerate(csv.reader(fh), start=1) if r and not r[0].lstrip().startswith("#")]
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"parameter sets {path}: cannot read ({getattr(exc, 'strerror', None) or exc})") from None
    if len(rows) < 2:
        raise UsageError(f"parameter sets {path}: expected a header of parameter names and at least one row")
    header = [h.strip() for h in rows[0][1]]
    out = []
    for k, r in rows[1:]:
        if len(r) != len(header):
            raise UsageError(f"{path}:{k}: {len(r)} values for {len(header)} parameters")
        out.append({h: v.strip() for h, v in zip(header, r)})
    return out
