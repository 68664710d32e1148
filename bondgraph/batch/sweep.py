"""Parameter sweeps and Monte Carlo tolerance analysis of a model file's simulation.

    from bondgraph import batch
    res = batch.sweep("models/bimorph_t215.py", {"omega_1": "normal(2247.4, 3%)", "zeta_1": "uniform(0.008, 0.016)"},
                      draws=1000, seed=1, metrics=["p2p(x)", "resonance"])
    res.table.write("mc.csv"); print(res.text()); res.plot("mc.png")

The runs come from :mod:`~bondgraph.batch.sampling` (reproducible with ``seed``), each one
simulation of the model's experiment (or ``inputs``/``t_end``/``dt``) with the scalar outputs of
:mod:`~bondgraph.batch.metrics`; statistics and sensitivities from :mod:`~bondgraph.batch.analysis`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

from ..support.errors import UsageError
from . import analysis
from .jobs import Job
from .runs import OnProgress, checked_model, execute, model_io, simulation_options
from .sampling import Distribution, Grid, default_design, design_points, parse_spec
from .table import Table


@dataclass
class SweepResult:
    """The runs of a sweep (``table``: one row per run, the varied parameters then the metrics)
    and what produced them.

    Parameters
    ----------
    table : Table
        One row per run: ``job``, the varied parameters' values, the metrics, then
        ``warnings``, ``seconds`` and ``error``.
    space : dict of str to Distribution or Grid
        The parameter space swept, name → specification.
    design : {"random", "lhs", "grid", "oat"}
        How the runs were drawn from ``space``.
    metrics : list of str
        The metrics' texts (column names of ``table``), e.g. ``"peak(x)"``.
    seed : int, optional
        The random seed of ``random`` and ``lhs`` designs.
    nominal : dict, optional
        The model's values of the varied parameters, name → value.
    units : dict, optional
        Each metric's unit (SI), name → unit string, for tables and plot axes.
    """

    table: Table
    space: dict
    design: str
    metrics: list[str]
    seed: int | None = None
    nominal: dict = field(default_factory=dict)
    #: metric → unit (empty when the model declares none)
    units: dict = field(default_factory=dict)

    @property
    def params(self) -> list[str]:
        """The varied parameters' names, in the order of :attr:`space`."""
        return list(self.space)

    def summary(self) -> list[dict]:
        """Statistics of each metric over the runs (:func:`bondgraph.batch.analysis.summary`).

        Returns
        -------
        list of dict
            Per metric: ``metric``, ``n`` (runs with a value), ``failed`` and, when ``n`` > 0,
            ``mean``, ``std`` (sample), ``min``, ``p5``, ``median``, ``p95``, ``max`` in the
            metric's unit.
        """
        return analysis.summary(self.table, self.metrics)

    def sensitivity(self) -> list[dict]:
        """One ranking per metric (see :func:`bondgraph.batch.analysis.sensitivity`).

        Returns
        -------
        list of dict
            Per metric: ``metric``, ``baseline`` and ``ranking``, a list of
            ``{"parameter", "low", "high", "swing", ...}`` (metric values at the parameter's
            low and high end and their difference), largest swing first.
        """
        return [analysis.sensitivity(self.table, self.params, m, self.design) for m in self.metrics]

    def as_json(self) -> dict:
        """Statistics and sensitivities as strict JSON (a missing or non-finite number is null).

        Returns
        -------
        dict
            ``design``, ``runs``, ``failed``, ``seed``, ``space`` (name → specification text),
            ``nominal``, ``summary`` (:meth:`summary`) and ``sensitivity`` (:meth:`sensitivity`).
        """
        return _finite(
            {
                "design": self.design,
                "runs": len(self.table),
                "failed": len(self.table.failed),
                "seed": self.seed,
                "space": {k: str(v) for k, v in self.space.items()},
                "nominal": self.nominal,
                "summary": self.summary(),
                "sensitivity": self.sensitivity(),
            }
        )

    def text(self) -> str:
        """The sweep as a plain-text report: the space, a statistics table, the rankings.

        Returns
        -------
        str
            Lines ending with a newline, as ``bondgraph sweep`` prints them.
        """
        lines = [
            f"{self.design} sweep: {len(self.table)} runs, {len(self.table.failed)} failed"
            + (f", seed {self.seed}" if self.seed is not None and self.design in ("random", "lhs") else "")
        ]
        lines += [f"  {k} = {v}" for k, v in self.space.items()]
        lines += [
            "",
            f"  {'metric':<16} {'n':>5} {'mean':>12} {'std':>11} {'min':>12} {'p5':>12} {'median':>12} "
            f"{'p95':>12} {'max':>12}",
        ]
        for s in self.summary():
            if s["n"]:
                lines.append(
                    f"  {s['metric']:<16} {s['n']:>5} {s['mean']:>12.5g} {s['std']:>11.4g} {s['min']:>12.5g} "
                    f"{s['p5']:>12.5g} {s['median']:>12.5g} {s['p95']:>12.5g} {s['max']:>12.5g}"
                )
            else:
                lines.append(f"  {s['metric']:<16} {0:>5}  (every run failed)")
        for sens in self.sensitivity():
            if "noise" in sens:
                spread = (
                    f"its runs spread by {sens['noise']:.2g} of its value, the level of numerical noise "
                    f"(below {analysis.NOISE_SPREAD:g})"
                    if sens["noise"] > 0
                    else "it is the same in every run"
                )
                lines += ["", f"  sensitivity of {sens['metric']}: not ranked, {spread}"]
                continue
            lines += [
                "",
                f"  sensitivity of {sens['metric']} (baseline {sens['baseline']:.5g}"
                + (f", linear fit R² {sens['r2']:.3f}" if "r2" in sens else "")
                + "):",
            ]
            for r in sens["ranking"]:
                if r.get("negligible"):
                    lines.append(f"    {r['parameter']:<14} no effect above numerical noise")
                    continue
                extra = f"  SRC {r['src']:+.3f}  Spearman {r['spearman']:+.3f}" if "src" in r else ""
                lines.append(
                    f"    {r['parameter']:<14} swing {r['swing']:<11.4g} low {r['low']:<12.5g} "
                    f"high {r['high']:<12.5g}{extra}"
                )
        return "\n".join(lines) + "\n"

    def plot(self, path: str) -> None:
        """Histograms of the metrics (top) and tornado plots of their sensitivities (bottom).

        Parameters
        ----------
        path : str
            The image to write (png, pdf or svg; written atomically).

        Raises
        ------
        UsageError
            matplotlib is not installed.
        """
        from .plots import plot_sweep

        plot_sweep(self, path)


def sweep(
    model,
    space: Mapping[str, str | Distribution | Grid],
    *,
    metrics: Sequence[str],
    design: str | None = None,
    draws: int | None = None,
    seed: int | None = None,
    params: Mapping | None = None,
    inputs: Mapping | None = None,
    t_end: float | None = None,
    dt: float | None = None,
    method: str | None = None,
    rtol: float | None = None,
    input: str | None = None,
    output: str | None = None,
    scheduler=None,
    workers: int | None = None,
    progress: OnProgress | None = None,
    say=None,
    per_task: int | None = None,
) -> SweepResult:
    """Simulate the model at every point of ``design`` over ``space`` (default: ``grid`` when
    every parameter has grid levels, else ``random`` with ``draws`` draws) and evaluate
    ``metrics`` on each run.

    Parameters
    ----------
    model : str or path-like or Model
        A model file (or a model) with a declared experiment, or give ``inputs`` and
        ``t_end``.
    space : mapping of str to str or Distribution or Grid
        Parameter name → specification (text as for ``--vary``, see
        :func:`~bondgraph.batch.parse_spec`, or built with :func:`~bondgraph.batch.uniform`
        and the others).
    metrics : sequence of str
        Scalar outputs of each run (:mod:`bondgraph.batch.metrics`), e.g. ``"peak(x)"``,
        ``"resonance"``; at least one.
    design : {"random", "lhs", "grid", "oat"}, optional
        How runs are drawn (see :mod:`bondgraph.batch.sampling`).
    draws : int, optional
        Number of runs of a ``random`` or ``lhs`` design.
    seed : int, optional
        Random seed: the same space, design, draws and seed give the same runs.
    params : mapping of str to float, optional
        Fixed parameter values, name → value, overriding the model's.
    inputs : mapping of str to Signal or float, optional
        Input name → signal, instead of the experiment's.
    t_end : float, optional
        Simulated time, s.
    dt : float, optional
        Output sample interval, s.
    method : str, optional
        Integrator (see :meth:`bondgraph.Simulator.run`).
    rtol : float, optional
        Relative tolerance of the integrator.
    input, output : str, optional
        The model input and output the linear metrics (``resonance``, ``damping``) are
        linearised between (default: the model's first declared ones).
    scheduler : str or distributed.Client, optional
        Where the runs execute (see :func:`~bondgraph.batch.connect`).
    workers : int, optional
        Worker processes of the embedded cluster.
    progress : callable, optional
        Called as jobs finish (see :mod:`bondgraph.batch.runs`).
    say : callable, optional
        ``say(line)`` receives status lines.
    per_task : int, optional
        Runs per Dask task (default: chosen from the number of runs and workers).

    Returns
    -------
    SweepResult
        The table of runs, with statistics and sensitivities.

    Raises
    ------
    UsageError
        No metric, a bad specification or design, an unknown parameter, or no cluster.
    """
    if not metrics:
        raise UsageError("give at least one metric, e.g. --metric 'peak(x)'")
    space = {k: parse_spec(v) if isinstance(v, str) else v for k, v in space.items()}
    design = design or default_design(space)
    lm = checked_model(model, params, [space])
    nominal = {n: _nominal(lm.model, n) for n in space}
    points = design_points(space, design, draws, seed, nominal)
    opts = simulation_options(
        lm, params, metrics, inputs, t_end, dt, method, rtol, *model_io(lm, input, output, required=False)
    )
    table = execute(
        opts, [Job(i, tuple(p.items())) for i, p in enumerate(points)], scheduler, workers, progress, say, per_task
    )
    signal_units = {n: v.unit for n, v in {**lm.model.inputs, **lm.model.outputs}.items() if v.unit}
    units = {m.text: m.unit(signal_units) for m in opts.metrics}
    return SweepResult(table, space, design, [m.text for m in opts.metrics], seed, nominal, units)


def _finite(obj):
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def _nominal(model, name: str):
    if name in model.values:
        return model.values[name]
    value = model.parameters[name][1]
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else value
