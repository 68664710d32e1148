"""Writing the measured-data CSV format (see :mod:`bondgraph.data.csv_format`).

Every number is written with ``repr`` (the shortest text that reads back to the identical
float64), so ``read_csv(write_csv(...))`` reproduces arrays bit for bit.
"""

from __future__ import annotations

import os
import re
from typing import Mapping

import numpy as np

from ..support.atomic import atomic_write
from ..support.errors import DataError
from .csv_format import META_KEY
from .dataset import Dataset

_LINE_BREAKS = re.compile(r"\s*[\r\n]+\s*")
_CHUNK_ROWS = 65536


def _check_name(name, where) -> None:
    if (
        not isinstance(name, str)
        or not name
        or name != name.strip()
        or any(ch in name for ch in ',\n\r"')
        or name.startswith("#")
    ):
        raise DataError(
            f"{where}: column name {name!r} cannot be written: names must be non-empty, "
            f"without surrounding blanks, commas, quotes or line breaks, and not start with '#'"
        )


def write_csv(
    path: str | os.PathLike,
    t,
    columns: Mapping[str, object],
    metadata: Mapping[str, object] | None = None,
    *,
    index: str = "t",
    progress=None,
) -> None:
    """Write a CSV file that :func:`read_csv` reads back identically, atomically.

    Layout: one ``# key: value`` line per metadata item (values converted with ``str``,
    line breaks replaced by a blank, stripped of surrounding blanks), the header
    ``t,<columns...>``, then one row per sample
    with every number written by ``repr`` (shortest exact round-trip text).  The data are
    validated like a :class:`Dataset` (finite, ``t`` strictly increasing, equal lengths), so
    a file is never written that :func:`read_csv` would refuse.  Written via
    :func:`~bondgraph.support.atomic.atomic_write`: on failure no partial file is left.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (replaced whole, or left as it was on failure).
    t : array_like
        The first column: time in s, strictly increasing (or what ``index`` names).
    columns : mapping of str to array_like
        The other columns by name, each as long as ``t``, in SI units (V, m, N, ...).
    metadata : mapping of str to object, optional
        Written as ``# key: value`` lines above the header.
    index : str, optional
        The first column's name: ``"t"`` (the default, time in s) or e.g.
        ``"omega_rad_s"`` for a frequency response, whose file :func:`read_csv` then does
        not read as a record.
    progress : callable, optional
        ``progress(fraction)`` is called as blocks of rows are written (a large file takes
        seconds).

    Raises
    ------
    bondgraph.support.errors.DataError
        For invalid data, column names or metadata keys, or if the file cannot be written
        (the message names the file).
    """
    dst = os.fspath(path)
    columns = dict(columns)
    for name in columns:
        _check_name(name, dst)
    meta_lines = []
    for key, value in dict(metadata or {}).items():
        if not isinstance(key, str) or not META_KEY.fullmatch(key):
            raise DataError(
                f"{dst}: metadata key {key!r} cannot be written: keys start with a letter or '_', "
                f"hold no ':', '#' or line break, and do not end with a blank"
            )
        value = _LINE_BREAKS.sub(" ", str(value)).strip()
        meta_lines.append(f"# {key}: {value}\n")
    if index != "t":
        _check_name(index, dst)
    ds = Dataset(t, columns, {}, dst)
    table = np.column_stack([ds.t, *ds.columns.values()])
    nrow, ncol = table.shape
    row_fmt = ",".join(["%r"] * ncol) + "\n"
    try:
        with atomic_write(dst, "w", encoding="utf-8", newline="\n") as f:
            f.write("".join(meta_lines))
            f.write(",".join((index, *ds.names[1:])) + "\n")
            for start in range(0, nrow, _CHUNK_ROWS):
                block = table[start : start + _CHUNK_ROWS]
                f.write((row_fmt * len(block)) % tuple(block.ravel().tolist()))
                if progress is not None:
                    progress(min(start + _CHUNK_ROWS, nrow) / nrow)
    except OSError as exc:
        raise DataError(
            f"{dst}: cannot write the file ({exc.strerror or exc}); check that the directory exists and is writable"
        ) from None
