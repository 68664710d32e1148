"""Plausibility checks of a dataset's units: warnings, never errors, and never a changed value.

The framework checks only what holds for any record (the time axis).  What a plausible
column looks like depends on the physics, so component libraries add their own checks
through the ``bondgraph.data_checks`` entry point group: each entry is a callable
``check(dataset) -> list[str]`` returning one-line messages (empty when the data look right).
In ``pyproject.toml``::

    [project.entry-points."bondgraph.data_checks"]
    mylib = "mylib.checks:check_columns"
"""

from __future__ import annotations

import warnings
from functools import lru_cache
from importlib.metadata import entry_points

from ..support import config
from .dataset import Dataset

ENTRY_POINT_GROUP = "bondgraph.data_checks"


class DataWarning(UserWarning):
    """A data file is readable but a column looks like it is in the wrong unit."""


def check_time_axis(ds: Dataset) -> list[str]:
    """A median step of at least 1 "second" over a span of at least ``data.suspicious_time_span``
    seconds (about 2.8 h sampled at <= 1 Hz) more likely means milliseconds or sample numbers.
    (Long creep records can trigger it; the message says so.)"""
    if len(ds) < 3:
        return []
    step = ds.dt
    if step >= 1.0 and ds.duration >= config.get("data.suspicious_time_span"):
        return [
            f"{ds.path or 'dataset'}: time step {step:g} s over {ds.duration:g} s "
            f"({ds.duration / 3600:.3g} h) looks like 't' is in milliseconds or sample numbers, not "
            f"seconds: if so scale it by 1e-3 (ms); ignore this for long slow records such as creep tests"
        ]
    return []


@lru_cache(maxsize=1)
def installed_checks() -> tuple:
    """The checks registered under the ``bondgraph.data_checks`` entry point group."""
    return tuple(ep.load() for ep in entry_points(group=ENTRY_POINT_GROUP))


def check_units(ds: Dataset, stacklevel: int = 1) -> list[str]:
    """Warn (:class:`DataWarning`) about columns that look like the wrong unit.

    Runs :func:`check_time_axis` and every installed check (see the module docstring);
    deliberately conservative, so that correct data never warns.

    Parameters
    ----------
    ds : Dataset
        The data to check (time in s, other columns in SI units: V, m, N, ...).
    stacklevel : int, optional
        As for :func:`warnings.warn`: 1 (the default) blames the caller of this function.

    Returns
    -------
    list of str
        The messages, each also issued as a :class:`DataWarning`; empty for plausible data.
    """
    messages: list[str] = []
    for check in installed_checks():
        messages += check(ds)
    messages += check_time_axis(ds)
    for m in messages:
        warnings.warn(DataWarning(m), stacklevel=stacklevel + 1)
    return messages
