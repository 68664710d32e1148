"""Measured data: the :class:`Dataset`, its CSV file format, resampling and plausibility checks.

Modules:

* :mod:`~bondgraph.data.dataset`   the :class:`Dataset` (a validated, read-only time series)
* :mod:`~bondgraph.data.sampling`  what "uniformly sampled" means, resampling, decimation
* :mod:`~bondgraph.data.checks`    unit plausibility checks (:func:`check_units`, :class:`DataWarning`)
  and the ``bondgraph.data_checks`` entry point through which libraries add their own
* :mod:`~bondgraph.data.csv_format` the grammar of the CSV format, shared by reader and writer
* :mod:`~bondgraph.data.csv_reader` :func:`read_csv`
* :mod:`~bondgraph.data.csv_writer` :func:`write_csv`

The file format is described in :mod:`bondgraph.data.csv_format` and in ``docs/data-format.md``.
"""

from .checks import DataWarning, check_units
from .csv_reader import read_csv
from .csv_writer import write_csv
from .dataset import Dataset
from .sampling import uniform_step

__all__ = ["Dataset", "DataWarning", "read_csv", "write_csv", "check_units", "uniform_step"]
