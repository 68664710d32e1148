"""Reading the measured-data CSV format (see :mod:`bondgraph.data.csv_format`).

Reading is fast: the text is read once and the data block is parsed by numpy's C parser
(:func:`numpy.loadtxt` on the in-memory text).  Only when that fails is the block walked
line by line in Python, to name the first bad line exactly.
"""

from __future__ import annotations

import io
import os
import re
import warnings
from typing import Iterable, Mapping

import numpy as np

from ..support.errors import DataError, UsageError
from .checks import check_units as _check_units
from .csv_format import META, NUMBER
from .dataset import Dataset


def _q(text: str, limit: int = 40) -> str:
    """Quote a piece of file text for a one-line message (control characters escaped)."""
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return repr(text)


def _list_names(names: Iterable[str]) -> str:
    names = list(names)
    shown = ", ".join(names[:12])
    return shown + (f", ... ({len(names)} in all)" if len(names) > 12 else "")


def _read_text(src: str) -> str:
    try:
        with open(src, "rb") as f:
            raw = f.read()
    except FileNotFoundError:
        raise DataError(f"{src}: no such file; check the path") from None
    except IsADirectoryError:
        raise DataError(f"{src}: is a directory, not a CSV file") from None
    except PermissionError:
        raise DataError(f"{src}: permission denied; make the file readable") from None
    except OSError as exc:
        raise DataError(f"{src}: cannot read the file ({exc.strerror or exc})") from None
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise DataError(f"{src}:1: the file is UTF-16 encoded; save it as UTF-8 (e.g. 'CSV UTF-8')")
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise DataError(
            f"{src}:{line}: not valid UTF-8 (byte 0x{raw[exc.start]:02x} at column {col}); save the file as UTF-8"
        ) from None
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text


def _add_metadata(comment: str, metadata: dict) -> None:
    m = META.fullmatch(comment)
    if m:
        metadata[m.group(1)] = m.group(2).strip()


def _looks_like_header(names: list[str]) -> bool:
    return len(names) >= 2 and all(n and not NUMBER.fullmatch(n) for n in names)


def _parse_header(src: str, line: str, lineno: int, last_comment) -> list[str]:
    raw_names = line.split(",")
    names = []
    for c in raw_names:
        c = c.strip()
        if len(c) >= 2 and c[0] == c[-1] == '"':
            c = c[1:-1].strip()
        names.append(c)
    if all(NUMBER.fullmatch(n) for n in names if n):
        hint = ""
        if last_comment is not None:
            cl, ctext = last_comment
            cnames = [c.strip() for c in ctext.lstrip("#").split(",")]
            if _looks_like_header(cnames):
                hint = f" (the header seems commented out at line {cl}: remove its '#')"
        raise DataError(
            f"{src}:{lineno}: expected a header line naming the columns, found numbers "
            f"{_q(line.strip())}{hint}; the first non-comment line must be a header such as 't,V,x'"
        )
    if len(names) == 1:
        for sep, what in ((";", "semicolon"), ("\t", "tab")):
            if sep in names[0]:
                raise DataError(
                    f"{src}:{lineno}: the header {_q(line.strip())} is {what}-separated; "
                    f"columns must be separated by commas"
                )
    for j, n in enumerate(names):
        if not n:
            fix = "remove the trailing comma" if j == len(names) - 1 else "name every column"
            raise DataError(f"{src}:{lineno}: column {j + 1} of the header {_q(line.strip())} has no name; {fix}")
    seen: dict[str, int] = {}
    for j, n in enumerate(names):
        if n in seen:
            raise DataError(
                f"{src}:{lineno}: duplicate column name {n!r} (columns {seen[n] + 1} and {j + 1}); "
                f"column names must be unique"
            )
        seen[n] = j
    return names


def _apply_rename(src, lineno, names, rename, required) -> tuple[list[str], list[int]]:
    """Canonical names and the indices (into the file's columns) to keep."""
    rename = dict(rename or {})
    for old in rename:
        if old not in names:
            raise DataError(
                f"{src}:{lineno}: no column {old!r} to use (as requested by --input/--output); "
                f"columns found: {_list_names(names)}"
            )
    targets: dict[str, str] = {}
    for old, new in rename.items():
        if not isinstance(new, str) or not new:
            raise UsageError(f"rename: the new name for column {old!r} must be a non-empty string")
        if new in targets and targets[new] != old:
            raise UsageError(f"rename: both {targets[new]!r} and {old!r} are mapped to {new!r}")
        targets[new] = old
    new_names, keep = [], []
    for j, n in enumerate(names):
        if n in rename:
            new_names.append(rename[n])
            keep.append(j)
        elif n in targets:
            continue  # displaced by an explicitly mapped column (documented)
        else:
            new_names.append(n)
            keep.append(j)
    need = list(dict.fromkeys(["t", *required]))
    missing = [r for r in need if r not in new_names]
    if missing:
        fixes = []
        for r in missing:
            if r == "t":
                fixes.append("name the time column (seconds) 't' in the header")
            elif r == "V":
                fixes.append("name the voltage column 'V' or choose it with --input COL")
            elif r == "x":
                fixes.append("name the displacement column 'x' or choose it with --output COL")
            else:
                fixes.append(f"add a column {r!r} (or map one with --input COL / --output COL)")
        what = ", ".join(repr(m) for m in missing)
        raise DataError(
            f"{src}:{lineno}: missing required column{'s' if len(missing) > 1 else ''} {what}; "
            f"columns found: {_list_names(names)}; {', and '.join(fixes)}"
        )
    return new_names, keep


def _loadtxt(block) -> np.ndarray | None:
    """numpy's C parser on a text block or list of lines; None if it refuses."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return np.loadtxt(block, delimiter=",", comments=None, dtype=np.float64, ndmin=2, quotechar=None)
    except (ValueError, TypeError):
        return None


def _cell_error(src, lineno, line, names) -> DataError | None:
    """The precise problem with one data line, or None if it is fine."""
    cells = line.split(",")
    ncol = len(names)
    if len(cells) != ncol:
        fix = f"every row needs {ncol} comma-separated numbers ({', '.join(names)})"
        if len(cells) == ncol + 1 and not cells[-1].strip():
            fix = "remove the trailing comma"
        elif len(cells) == 1 and (";" in line or "\t" in line):
            fix = "separate the cells with commas (not semicolons or tabs)"
        return DataError(
            f"{src}:{lineno}: {len(cells)} cell{'s' if len(cells) != 1 else ''} but the header "
            f"names {ncol} column{'s' if ncol != 1 else ''}; {fix}"
        )
    for j, c in enumerate(cells):
        if not NUMBER.fullmatch(c):
            if not c.strip():
                return DataError(f"{src}:{lineno}: empty cell in column {names[j]!r}; every cell needs a number")
            fix = "use a plain number such as 1.5e-3"
            if "," in c or re.fullmatch(r"\s*[+-]?\d+,\d+\s*", c):
                fix = "use '.' as decimal separator"
            return DataError(f"{src}:{lineno}: non-numeric cell {_q(c.strip())} in column {names[j]!r}; {fix}")
    return None


def _text_columns(body: str, ncol: int, droppable: set[int]) -> list[int]:
    """The columns among ``droppable`` that hold no number at all (text only, e.g. a note or a
    time stamp string): a data file may carry such columns where the run does not need them.
    Empty when any row has the wrong number of cells (that row's own error comes first)."""
    if not droppable:
        return []
    has_number = dict.fromkeys(droppable, False)
    for line in body.split("\n"):
        s = line.strip()
        if not s or s[0] == "#":
            continue
        cells = line.split(",")
        if len(cells) != ncol:
            return []
        for j in droppable:
            if not has_number[j] and NUMBER.fullmatch(cells[j]):
                has_number[j] = True
    return sorted(j for j, numeric in has_number.items() if not numeric)


def _drop_columns(body: str, drop: list[int]) -> str:
    """``body`` without the cells of columns ``drop`` (comments and blank lines unchanged)."""
    out = []
    for line in body.split("\n"):
        s = line.strip()
        if not s or s[0] == "#":
            out.append(line)
            continue
        cells = line.split(",")
        out.append(",".join(c for j, c in enumerate(cells) if j not in drop))
    return "\n".join(out)


def _slow_parse(src, body, first_lineno, names, metadata):
    """Walk the data block line by line: skip blanks, collect comment metadata, and either
    parse the rows or raise the first bad line's exact error."""
    rows, lines_of_rows = [], []
    for k, line in enumerate(body.split("\n")):
        s = line.strip()
        if not s:
            continue
        if s[0] == "#":
            _add_metadata(s, metadata)
            continue
        rows.append(line)
        lines_of_rows.append(first_lineno + k)
    row_lines = np.asarray(lines_of_rows, dtype=np.int64)
    if not rows:
        return np.empty((0, len(names))), row_lines
    data = _loadtxt(rows)
    if data is not None and data.shape == (len(rows), len(names)):
        return data, row_lines
    for line, lineno in zip(rows, lines_of_rows):
        err = _cell_error(src, lineno, line, names)
        if err is not None:
            raise err
    # numpy refused something the validator accepts: parse in Python (still exact).
    data = np.array([[float(c) for c in line.split(",")] for line in rows], dtype=np.float64)
    return data.reshape(len(rows), len(names)), row_lines


def read_csv(
    path: str | os.PathLike,
    required: Iterable[str] = ("t",),
    rename: Mapping[str, str] | None = None,
    *,
    check_units: bool = True,
) -> Dataset:
    """Read a measured-data CSV file (format in :mod:`bondgraph.data.csv_format`) into a :class:`Dataset`.

    A column that holds no number at all (a note, a time stamp string) and that is neither
    ``t`` nor required is left out of the :class:`Dataset` instead of being refused.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    required : iterable of str, optional
        Canonical column names that must be present (after ``rename``); ``"t"`` always is.
    rename : mapping of str to str, optional
        File column name -> canonical name, e.g. ``{"Vin": "V", "disp": "x"}`` for
        ``--input Vin --output disp``.  A file column that already has a target name (``V``
        when ``Vin`` is mapped to ``V``) is dropped in favour of the mapped one.
    check_units : bool, optional
        Run :func:`check_units` (``DataWarning`` for suspicious units); True by default.

    Returns
    -------
    Dataset
        The record: time in s and every numeric column, with the file's metadata.

    Raises
    ------
    bondgraph.support.errors.DataError
        With a one-line ``FILE:LINE: problem; fix`` message for: a missing, unreadable or
        non-UTF-8 file; an empty file or one without a header or data rows; a header that
        is numeric, has an empty or duplicate name, or lacks a required column; a row with
        the wrong number of cells; an empty or non-numeric cell; NaN or inf; time not
        strictly increasing; fewer than 2 rows.
    """
    src = os.fspath(path)
    if isinstance(src, bytes):
        src = os.fsdecode(src)
    text = _read_text(src)
    metadata: dict[str, str] = {}

    # Comment lines and the header: walk only the first few lines.
    pos, lineno, n = 0, 0, len(text)
    header = None
    last_comment = None
    while pos < n:
        end = text.find("\n", pos)
        if end < 0:
            end = n
        line = text[pos:end]
        lineno += 1
        pos = end + 1
        s = line.strip()
        if not s:
            continue
        if s[0] == "#":
            _add_metadata(s, metadata)
            last_comment = (lineno, s)
            continue
        header = line
        break
    if header is None:
        if last_comment is None:
            raise DataError(
                f"{src}:1: the file is empty; expected a header line such as 't,V,x' followed by numeric rows"
            )
        raise DataError(
            f"{src}:{lineno}: no header line, the file holds only comments; add a header "
            f"such as 't,V,x' followed by numeric rows"
        )
    header_line = lineno
    file_names = _parse_header(src, header, header_line, last_comment)
    names, keep = _apply_rename(src, header_line, file_names, rename, tuple(required))
    body = text[pos:]
    ncol = len(file_names)

    # Fast path: no comments or blank lines in the data block -> one C-level parse.
    data = row_lines = None
    if body and "#" not in body:
        nrows = body.count("\n") + (0 if body.endswith("\n") else 1)
        a = _loadtxt(io.StringIO(body))
        if a is not None and a.shape == (nrows, ncol):
            data = a
    if data is None:
        # a text column the caller does not need (not t, not required) is left out, not refused
        needed = set(["t", *required]) | set((rename or {}).values())
        droppable = {j for j, name in zip(keep, names) if name not in needed}
        drop = _text_columns(body, ncol, droppable)
        if drop:
            body = _drop_columns(body, drop)
            kept = [(name, j) for name, j in zip(names, keep) if j not in drop]
            names = [name for name, _ in kept]
            keep = [j - sum(d < j for d in drop) for _, j in kept]
            file_names = [n for j, n in enumerate(file_names) if j not in drop]
            ncol = len(file_names)
        data, row_lines = _slow_parse(src, body, header_line + 1, file_names, metadata)

    def line_of(i: int) -> int:
        return int(row_lines[i]) if row_lines is not None else header_line + 1 + i

    def cell_text(i: int, j: int) -> str:
        ln = line_of(i)
        line = text.split("\n", ln)[ln - 1]
        return line.split(",")[j].strip()

    nrows = data.shape[0]
    if nrows == 0:
        raise DataError(
            f"{src}:{header_line}: no data rows after the header; add numeric rows such as {','.join(['0'] * ncol)!r}"
        )
    finite = np.isfinite(data)
    if not finite.all():
        i = int(np.argmin(finite.all(axis=1)))
        j = int(np.argmin(finite[i]))
        cell = cell_text(i, j)
        overflow = NUMBER.fullmatch(cell) and not re.search("inf|nan", cell, re.IGNORECASE)
        what = "overflows to inf" if overflow else "is not finite"
        raise DataError(
            f"{src}:{line_of(i)}: value {_q(cell)} in column {file_names[j]!r} {what}; "
            f"measured data must be finite: remove or interpolate the bad samples"
        )
    if nrows < 2:
        raise DataError(f"{src}:{line_of(0)}: only 1 data row; at least 2 rows are needed")
    t = data[:, keep[names.index("t")]]
    increasing = t[1:] > t[:-1]
    if not increasing.all():
        i = int(np.argmin(increasing))
        a_, b_ = line_of(i), line_of(i + 1)
        jt = keep[names.index("t")]
        raise DataError(
            f"{src}:{b_}: time not strictly increasing: t = {cell_text(i + 1, jt)} "
            f"at line {b_} follows t = {cell_text(i, jt)} at line {a_}; "
            f"sort the rows by time and remove repeated samples"
        )
    columns = {name: np.ascontiguousarray(data[:, j]) for name, j in zip(names, keep) if name != "t"}
    ds = Dataset(t, columns, metadata, src)
    if check_units:
        _check_units(ds, stacklevel=2)
    return ds
