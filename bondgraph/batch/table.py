"""The result of a batch: one row per job, written as CSV (or Parquet with pyarrow).

Columns come in a fixed order: ``job``, the job's inputs (``data`` file, parameter values),
its results, then ``warnings``, ``seconds`` (wall time of the job on its worker) and
``error`` (empty when the job succeeded; a failed job keeps its inputs and leaves its
results empty).  Files are written atomically: complete or not at all.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any, Iterable, Sequence

import numpy as np

from ..support.atomic import atomic_write
from ..support.errors import UsageError

TRAILING = ("warnings", "seconds", "error")


class Table:
    """Rows (dicts) with an ordered column list; missing cells are ``None``.

    Parameters
    ----------
    rows : sequence of dict
        One dict per job, column name → value (copied).
    leading : iterable of str, optional
        Columns placed right after ``job`` (the job's inputs); the others follow in the order
        first met, then ``warnings``, ``seconds`` and ``error``.
    """

    def __init__(self, rows: Sequence[dict], leading: Iterable[str] = ()):
        self.rows = [dict(r) for r in rows]
        cols = [c for c in ("job", *leading) if any(c in r for r in self.rows) or c == "job"]
        for r in self.rows:
            cols += [k for k in r if k not in cols and k not in TRAILING]
        self.columns = cols + [c for c in TRAILING if any(c in r for r in self.rows)]

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def column(self, name: str) -> np.ndarray:
        """A numeric column as floats (NaN where a row has no number, e.g. a failed job).

        Parameters
        ----------
        name : str
            The column's name.

        Returns
        -------
        numpy.ndarray
            One float per row.

        Raises
        ------
        KeyError
            The table has no such column.
        """
        if name not in self.columns:
            raise KeyError(name)
        return np.array([_as_float(r.get(name)) for r in self.rows], float)

    @property
    def failed(self) -> list[dict]:
        """Rows of jobs that failed."""
        return [r for r in self.rows if r.get("error")]

    def csv_text(self) -> str:
        """The table as CSV text: the header line, then one line per row.

        Returns
        -------
        str
            CSV with ``\\n`` line ends; floats written exactly (``repr``), missing cells empty.
        """
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for r in self.rows:
            w.writerow([_cell(r.get(c)) for c in self.columns])
        return buf.getvalue()

    def to_csv(self, path: str | Path) -> None:
        """CSV with the header line first; numbers written exactly (``repr``).

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write (atomically: complete or not at all).
        """
        with atomic_write(path, "w", newline="") as fh:
            fh.write(self.csv_text())

    def to_parquet(self, path: str | Path) -> None:
        """Parquet (needs pyarrow); integer, float, boolean or text columns as the values are.

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write (atomically: complete or not at all).

        Raises
        ------
        UsageError
            pyarrow is not installed.
        """
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise UsageError(f"{path}: Parquet needs pyarrow: pip install -e '.[parquet]' (or write a .csv)") from None
        table = pa.table({c: _arrow_column(pa, [r.get(c) for r in self.rows]) for c in self.columns})
        with atomic_write(path, "wb") as fh:
            pq.write_table(table, fh)

    def to_pandas(self):
        """A pandas DataFrame of the rows (needs pandas).

        Returns
        -------
        pandas.DataFrame
            One row per job, the columns in the table's order.
        """
        import pandas as pd

        return pd.DataFrame([[r.get(c) for c in self.columns] for r in self.rows], columns=self.columns)

    def write(self, path: str | Path) -> None:
        """CSV or Parquet by the file suffix (``.csv``, ``.parquet``).

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write (atomically: complete or not at all).

        Raises
        ------
        UsageError
            Another suffix, or Parquet without pyarrow.
        """
        suffix = Path(path).suffix.lower()
        if suffix == ".parquet":
            self.to_parquet(path)
        elif suffix == ".csv":
            self.to_csv(path)
        else:
            raise UsageError(f"{path}: unknown table format {suffix or '(none)'}; use .csv or .parquet")


def _as_float(v: Any) -> float:
    if isinstance(v, bool) or v is None:
        return math.nan
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _arrow_column(pa, values: list):
    """Integers (or missing) → int64, numbers → float64, true/false → bool, anything else text."""
    present = [v for v in values if v is not None]
    if not present:
        return pa.array(values, pa.string())
    if all(isinstance(v, bool) for v in present):
        return pa.array(values, pa.bool_())
    if all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in present):
        return pa.array(values, pa.int64())
    if all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) for v in present):
        return pa.array([None if v is None else float(v) for v in values], pa.float64())
    return pa.array([None if v is None else str(v) for v in values], pa.string())
