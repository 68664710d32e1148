"""Batch runs on Dask: many diagnoses, fits or simulations, parameter sweeps and Monte Carlo
tolerance analysis, on one machine or a cluster (the ``dask`` extra: ``pip install -e ".[dask]"``).

    from bondgraph import batch
    table = batch.diagnose("models/apa120ml.py", ["unit01.csv", "unit02.csv"])  # one row per file
    table.write("lot.csv")                                                     # or lot.parquet
    res = batch.sweep("models/bimorph_t215.py", {"omega_1": "normal(2247.4, 3%)"}, draws=1000, seed=1,
                      metrics=["p2p(x)", "resonance"], scheduler="tcp://head:8786")

* :func:`diagnose`, :func:`fit`, :func:`simulate` over data files × parameter sets
  (:mod:`~bondgraph.batch.runs`), returning a :class:`Table`;
* :func:`sweep` over a parameter space (:mod:`~bondgraph.batch.sampling`) with scalar outputs
  (:mod:`~bondgraph.batch.metrics`), returning a :class:`SweepResult` (table, statistics,
  sensitivity ranking, histograms and tornado plots);
* where the jobs run: :mod:`~bondgraph.batch.cluster` (an embedded ``LocalCluster`` by default,
  ``scheduler=ADDRESS`` for an existing cluster);
* what runs on a worker: :mod:`~bondgraph.batch.jobs` (compiled models reused per worker).
"""

from .cluster import connect
from .runs import diagnose, fit, read_sets, simulate
from .sampling import linspace, logspace, loguniform, normal, parse_space, parse_spec, uniform, values
from .sweep import SweepResult, sweep
from .table import Table

__all__ = [
    "connect",
    "diagnose",
    "fit",
    "read_sets",
    "simulate",
    "loguniform",
    "linspace",
    "logspace",
    "normal",
    "parse_space",
    "parse_spec",
    "uniform",
    "values",
    "SweepResult",
    "sweep",
    "Table",
]
