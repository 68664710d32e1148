"""Measured data: the CSV format of the contract, and the :class:`Dataset` it loads into.

File format (see ``CONTRACT.md``, "Measured data (CSV)")::

    # actuator: APA120ML                    <- "# key: value" comments are metadata
    # sensor: capacitive, 10 kHz
    t,V,x                                   <- exactly one header line
    0,0,0
    0.0001,0.5,1.2e-08                      <- numeric rows; comments may sit between rows
    ...

* UTF-8 (a byte-order mark is tolerated), LF or CRLF line endings, comma-separated.
* Lines whose first non-blank character is ``#`` are comments, before or between rows.  A
  comment of the form ``# key: value`` (the key starts with a letter or ``_`` and runs to
  the first ``:``; it holds no ``#``) is metadata, e.g. ``# param k1: 2.5e6``; key and value
  are stripped of surrounding blanks.  If a key repeats, the last value wins.  Blank lines
  are ignored.
* The header names the columns; names are stripped of blanks (and of one pair of enclosing
  double quotes).  ``t`` is time in seconds, strictly increasing; ``V`` drive voltage (V);
  ``x`` displacement (m); optional ``F`` (N), ``i`` (A), ``q`` (C); other columns are kept.
* Cells are plain decimal numbers (``1``, ``-2.5``, ``.5``, ``3e-6``); NaN and inf are
  refused, and so is everything listed in :func:`read_csv`.

Every problem in a file is a :class:`~bondgraph.errors.DataError` whose message is one line
``FILE:LINE: problem; fix`` (``LINE`` 1-based, as an editor counts, with CR, LF and CRLF
each ending one line).

Reading is fast: the text is read once and the data block is parsed by numpy's C parser
(:func:`numpy.loadtxt` on the in-memory text).  Only when that fails is the block walked
line by line in Python, to name the first bad line exactly.  Writing formats every number
with ``repr`` (the shortest text that reads back to the identical float64), so
``read_csv(write_csv(...))`` reproduces arrays bit for bit.
"""
from __future__ import annotations

import io
import math
import os
import re
import warnings
from dataclasses import dataclass, field
from typing import Iterable, Mapping

import numpy as np

from .atomic import atomic_write
from .errors import DataError, UsageError, did_you_mean

__all__ = [
    "Dataset",
    "DataWarning",
    "read_csv",
    "write_csv",
    "check_units",
    "UNIFORM_RTOL",
    "X_MAX_METRES",
]

#: Sampling counts as uniform when every time step is within this fraction of the mean step.
#: 1 % absorbs the rounding of time stamps printed with few digits; see Dataset.is_uniform.
UNIFORM_RTOL = 1e-2

#: A displacement column ``x`` reaching beyond this (metres) triggers a DataWarning: piezo
#: actuators (stacks, amplified stacks, benders) move micrometres to about a millimetre.
X_MAX_METRES = 1e-2

#: Time heuristic: a median step of at least 1 "second" over a span of at least this many
#: "seconds" (about 2.8 h sampled at <= 1 Hz) more likely means milliseconds or sample numbers.
T_SPAN_SUSPICIOUS = 1e4

# A number cell as numpy's parser accepts it: decimal, optional exponent, or nan/inf (which
# are then refused with their own message).  Anything else is "non-numeric".
_NUMBER = re.compile(
    r"[ \t]*[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf(?:inity)?|nan)[ \t]*",
    re.IGNORECASE | re.ASCII,
)
# "# key: value": the key starts with a letter or "_" and runs to the first ":" (no "#").
_META = re.compile(r"#\s*([^\W\d][^:#]*?)\s*:(.*)")
_META_KEY = re.compile(r"[^\W\d](?:[^:#\n\r]*[^:#\s])?")

_LINE_BREAKS = re.compile(r"\s*[\r\n]+\s*")

_CHUNK_ROWS = 65536


class DataWarning(UserWarning):
    """A data file is readable but a column looks like it is in the wrong unit."""


# --------------------------------------------------------------------------- Dataset


def _as_vector(values, what: str, where: str) -> np.ndarray:
    try:
        a = np.array(values, dtype=np.float64)  # always a private copy
    except (TypeError, ValueError) as exc:
        raise DataError(f"{where}: {what} is not numeric ({exc})") from None
    if a.ndim != 1:
        raise DataError(f"{where}: {what} must be one-dimensional, got shape {a.shape}")
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False, repr=False)
class Dataset:
    """A time series of measured (or simulated) signals.

    Attributes
    ----------
    t:
        Time in seconds, float64, strictly increasing, at least 2 samples.
    columns:
        Every other column by name (``"V"``, ``"x"``, ...), float64, same length as ``t``,
        in file order.
    metadata:
        ``# key: value`` comments of the file, in order (values are strings).
    path:
        The file it was read from, or ``None``.

    All arrays are private read-only copies (copy one with ``np.array(ds.t)`` to modify it);
    values must be finite.  Violations raise :class:`~bondgraph.errors.DataError`.
    """

    t: np.ndarray
    columns: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)
    path: str | None = None

    def __post_init__(self) -> None:
        where = self.path if self.path is not None else "dataset"
        t = _as_vector(self.t, "time column 't'", where)
        if len(t) < 2:
            raise DataError(f"{where}: {len(t)} time sample(s); at least 2 are needed")
        cols = {}
        for name, values in dict(self.columns).items():
            if not isinstance(name, str) or not name:
                raise DataError(f"{where}: column names must be non-empty strings, got {name!r}")
            if name == "t":
                raise DataError(f"{where}: 't' is the time axis; do not repeat it in columns")
            a = _as_vector(values, f"column {name!r}", where)
            if len(a) != len(t):
                raise DataError(
                    f"{where}: column {name!r} has {len(a)} values but t has {len(t)}; "
                    f"all columns must have the same length"
                )
            cols[name] = a
        for name, a in (("t", t), *cols.items()):
            bad = ~np.isfinite(a)
            if bad.any():
                i = int(np.argmax(bad))
                raise DataError(
                    f"{where}: column {name!r} has a non-finite value ({a[i]}) at row {i}; "
                    f"data must be finite"
                )
        increasing = t[1:] > t[:-1]  # (no overflow, unlike np.diff on huge values)
        if not increasing.all():
            i = int(np.argmin(increasing))
            raise DataError(
                f"{where}: time not strictly increasing: t[{i + 1}] = {t[i + 1]!r} "
                f"follows t[{i}] = {t[i]!r}"
            )
        meta = {str(k): str(v) for k, v in dict(self.metadata).items()}
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "columns", cols)
        object.__setattr__(self, "metadata", meta)
        object.__setattr__(self, "path", None if self.path is None else os.fspath(self.path))

    # ---------------------------------------------------------------- access
    def __len__(self) -> int:
        return len(self.t)

    def __repr__(self) -> str:
        return (
            f"Dataset(path={self.path!r}, rows={len(self)}, columns={list(self.columns)}, "
            f"t=[{self.t[0]:g} .. {self.t[-1]:g}] s, metadata={self.metadata!r})"
        )

    @property
    def names(self) -> tuple[str, ...]:
        """All column names, ``"t"`` first."""
        return ("t", *self.columns)

    def column(self, name: str, option: str | None = None) -> np.ndarray:
        """The column ``name`` (``"t"`` included); DataError listing the known names if absent."""
        if name == "t":
            return self.t
        try:
            return self.columns[name]
        except KeyError:
            where = self.path or "dataset"
            hint = f"; choose one with {option} COL" if option else ""
            raise DataError(
                f"{where}: {did_you_mean(name, self.names, 'column')}{hint}"
            ) from None

    def input(self, name: str = "V") -> np.ndarray:
        """The input (drive voltage) column, by default ``V``."""
        return self.column(name, "--input")

    def output(self, name: str = "x") -> np.ndarray:
        """The output (displacement) column, by default ``x``."""
        return self.column(name, "--output")

    @property
    def dt(self) -> float:
        """Median time step in seconds."""
        with np.errstate(over="ignore"):
            return float(np.median(np.diff(self.t)))

    @property
    def sample_rate(self) -> float:
        """Median sample rate in Hz (``1 / dt``)."""
        return 1.0 / self.dt

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` in seconds."""
        with np.errstate(over="ignore"):
            return float(self.t[-1] - self.t[0])

    @property
    def is_uniform(self) -> bool:
        """True if every step is within :data:`UNIFORM_RTOL` (1 %) of the mean step."""
        with np.errstate(over="ignore", invalid="ignore"):
            mean = (self.t[-1] - self.t[0]) / (len(self.t) - 1)
            return bool(np.max(np.abs(np.diff(self.t) - mean)) <= UNIFORM_RTOL * mean)

    # ---------------------------------------------------------------- derived datasets
    def _take(self, index) -> Dataset:
        return Dataset(
            self.t[index],
            {k: v[index] for k, v in self.columns.items()},
            self.metadata,
            self.path,
        )

    def slice(self, t0: float | None = None, t1: float | None = None) -> Dataset:
        """The samples with ``t0 <= t <= t1`` (either bound may be None); times are kept
        as they are (not shifted to start at 0)."""
        lo = 0 if t0 is None else int(np.searchsorted(self.t, t0, "left"))
        hi = len(self) if t1 is None else int(np.searchsorted(self.t, t1, "right"))
        if hi - lo < 2:
            where = self.path or "dataset"
            raise DataError(
                f"{where}: the time window [{t0}, {t1}] s holds {max(hi - lo, 0)} sample(s); "
                f"at least 2 are needed (data spans {self.t[0]:g} .. {self.t[-1]:g} s)"
            )
        return self._take(slice(lo, hi))

    def split(self, fraction: float = 0.7) -> tuple[Dataset, Dataset]:
        """Split in time into (fit, validation): the first part covers the first
        ``fraction`` of the time span, the second the rest.  No sample is in both."""
        if not (isinstance(fraction, (int, float)) and 0.0 < fraction < 1.0):
            raise UsageError(
                f"split fraction must be between 0 and 1 (exclusive), not {fraction!r}"
            )
        t_split = self.t[0] + fraction * (self.t[-1] - self.t[0])
        k = int(np.searchsorted(self.t, t_split, "left"))
        if k < 2 or len(self) - k < 2:
            where = self.path or "dataset"
            raise DataError(
                f"{where}: splitting {len(self)} samples at {fraction:g} of the time span "
                f"leaves fewer than 2 samples in one part; use more data or another fraction"
            )
        return self._take(slice(0, k)), self._take(slice(k, None))

    def decimate(self, factor: int, ftype: str = "iir") -> Dataset:
        """Keep every ``factor``-th sample after an anti-alias low-pass filter.

        Uses :func:`scipy.signal.decimate` with ``zero_phase=True`` on every column (so
        input and output see the same filter and stay aligned in time); ``t`` becomes
        ``t[::factor]``.  ``ftype="iir"`` is an order-8 Chebyshev I filter (applied in
        stages of at most 10 for large factors, as scipy recommends), ``"fir"`` a
        Hamming-window FIR.  Content above 0.8 x the new Nyquist frequency is removed, the
        passband ripple is about 0.1 dB per IIR stage, and the first and last few output
        samples carry filter end effects.  Requires uniform sampling (use :meth:`resample`
        first otherwise).
        """
        from scipy import signal

        where = self.path or "dataset"
        if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
            raise UsageError(f"decimation factor must be a positive integer, not {factor!r}")
        if ftype not in ("iir", "fir"):
            raise UsageError(f"decimation filter type must be 'iir' or 'fir', not {ftype!r}")
        factor = int(factor)
        if factor == 1:
            return self
        if not self.is_uniform:
            raise DataError(
                f"{where}: decimate needs uniform sampling; resample first, "
                f"e.g. dataset.resample({self.dt:.6g})"
            )
        if len(self) // factor < 2:
            raise DataError(f"{where}: {len(self)} samples are too few to decimate by {factor}")
        stages = _decimation_stages(factor) if ftype == "iir" else [factor]
        cols = {}
        try:
            for name, values in self.columns.items():
                y = np.asarray(values)
                for q in stages:
                    y = signal.decimate(y, q, ftype=ftype, zero_phase=True)
                cols[name] = y
        except ValueError as exc:
            raise DataError(
                f"{where}: cannot decimate {len(self)} samples by {factor} ({exc}); "
                f"use more data or a smaller factor"
            ) from None
        t = self.t[::factor]
        for name in cols:
            cols[name] = cols[name][: len(t)]
        return Dataset(t, cols, self.metadata, self.path)

    def resample(self, dt: float) -> Dataset:
        """Linear interpolation onto the uniform grid ``t[0], t[0] + dt, ...`` (<= ``t[-1]``).

        Meant to make slightly irregular sampling uniform at about the same rate.  There is
        no anti-alias filter: to reduce the rate of uniform data use :meth:`decimate`.
        """
        where = self.path or "dataset"
        if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
            raise UsageError(f"resample step must be a positive number of seconds, not {dt!r}")
        n = int(math.floor(self.duration / dt * (1 + 1e-12))) + 1
        if n < 2:
            raise DataError(f"{where}: a step of {dt:g} s leaves fewer than 2 samples")
        if n > max(100 * len(self), 10_000_000):
            raise UsageError(
                f"resample step {dt:g} s would make {n} samples from {len(self)}; use a larger step"
            )
        t = self.t[0] + dt * np.arange(n)
        t[-1] = min(t[-1], self.t[-1])
        if n > 2 and t[-1] <= t[-2]:
            t = t[:-1]
        return Dataset(
            t,
            {k: np.interp(t, self.t, v) for k, v in self.columns.items()},
            self.metadata,
            self.path,
        )

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write with :func:`write_csv` (metadata included)."""
        write_csv(path, self.t, self.columns, self.metadata)


def _decimation_stages(factor: int) -> list[int]:
    """Split ``factor`` into IIR stages of at most 10 (prime factors > 13 stay single)."""
    stages, rest = [], factor
    while rest > 13:
        for q in range(10, 1, -1):
            if rest % q == 0:
                stages.append(q)
                rest //= q
                break
        else:
            break
    stages.append(rest)
    return [q for q in stages if q > 1]


# --------------------------------------------------------------------------- unit sanity


def check_units(ds: Dataset, stacklevel: int = 1) -> list[str]:
    """Warn (:class:`DataWarning`) about columns that look like the wrong unit.

    Deliberately conservative, so that correct data never warns:

    * ``x`` (metres): warns if ``max |x| > X_MAX_METRES`` (1 cm); piezo actuators move
      micrometres to about a millimetre, so such values are almost surely micrometres
      (or millimetres).
    * ``t`` (seconds): warns if the median step is >= 1 and the span is >= ``T_SPAN_SUSPICIOUS``
      (1e4); such a record would be hours long at <= 1 Hz, more likely milliseconds or sample
      numbers.  (Long creep records can trigger it; the warning says so.)

    Returns the messages (also issued as warnings; ``stacklevel`` as for
    :func:`warnings.warn`, 1 = the caller of this function).
    """
    where = ds.path or "dataset"
    messages = []
    x = ds.columns.get("x")
    if x is not None:
        peak = float(np.max(np.abs(x)))
        if peak > X_MAX_METRES:
            messages.append(
                f"{where}: column 'x' reaches |x| = {peak:.4g}, which is {peak:.4g} m if in "
                f"metres; piezo displacements are micrometres, so 'x' is probably in µm: "
                f"scale it by 1e-6 (by 1e-3 if in mm)"
            )
    if len(ds) >= 3:
        step = ds.dt
        if step >= 1.0 and ds.duration >= T_SPAN_SUSPICIOUS:
            messages.append(
                f"{where}: time step {step:g} s over {ds.duration:g} s "
                f"({ds.duration / 3600:.3g} h) "
                f"looks like 't' is in milliseconds or sample numbers, not seconds: if so scale "
                f"it by 1e-3 (ms); ignore this for long slow records such as creep tests"
            )
    for m in messages:
        warnings.warn(DataWarning(m), stacklevel=stacklevel + 1)
    return messages


_check_units = check_units  # read_csv has a keyword argument of the same name


# --------------------------------------------------------------------------- reading


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
            f"{src}:{line}: not valid UTF-8 (byte 0x{raw[exc.start]:02x} at column {col}); "
            f"save the file as UTF-8"
        ) from None
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    return text


def _add_metadata(comment: str, metadata: dict) -> None:
    m = _META.fullmatch(comment)
    if m:
        metadata[m.group(1)] = m.group(2).strip()


def _looks_like_header(names: list[str]) -> bool:
    return len(names) >= 2 and all(n and not _NUMBER.fullmatch(n) for n in names)


def _parse_header(src: str, line: str, lineno: int, last_comment) -> list[str]:
    raw_names = line.split(",")
    names = []
    for c in raw_names:
        c = c.strip()
        if len(c) >= 2 and c[0] == c[-1] == '"':
            c = c[1:-1].strip()
        names.append(c)
    if all(_NUMBER.fullmatch(n) for n in names if n):
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
            raise DataError(
                f"{src}:{lineno}: column {j + 1} of the header {_q(line.strip())} has no name; "
                f"{fix}"
            )
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
            return np.loadtxt(
                block, delimiter=",", comments=None, dtype=np.float64, ndmin=2, quotechar=None
            )
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
        if not _NUMBER.fullmatch(c):
            if not c.strip():
                return DataError(
                    f"{src}:{lineno}: empty cell in column {names[j]!r}; every cell needs a number"
                )
            fix = "use a plain number such as 1.5e-3"
            if "," in c or re.fullmatch(r"\s*[+-]?\d+,\d+\s*", c):
                fix = "use '.' as decimal separator"
            return DataError(
                f"{src}:{lineno}: non-numeric cell {_q(c.strip())} in column {names[j]!r}; {fix}"
            )
    return None


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
    """Read a measured-data CSV file (format in the module docstring) into a :class:`Dataset`.

    Parameters
    ----------
    path:
        The file.
    required:
        Canonical column names that must be present (after ``rename``); ``"t"`` always is.
    rename:
        File column name -> canonical name, e.g. ``{"Vin": "V", "disp": "x"}`` for
        ``--input Vin --output disp``.  A file column that already has a target name (``V``
        when ``Vin`` is mapped to ``V``) is dropped in favour of the mapped one.
    check_units:
        Run :func:`check_units` (``DataWarning`` for suspicious units).

    Raises :class:`~bondgraph.errors.DataError` with a one-line ``FILE:LINE: problem; fix``
    message for: a missing, unreadable or non-UTF-8 file; an empty file or one without a
    header or data rows; a header that is numeric, has an empty or duplicate name, or lacks
    a required column; a row with the wrong number of cells; an empty or non-numeric cell;
    NaN or inf; time not strictly increasing; fewer than 2 rows.
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
                f"{src}:1: the file is empty; expected a header line such as 't,V,x' "
                f"followed by numeric rows"
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
            f"{src}:{header_line}: no data rows after the header; add numeric rows such as "
            f"{','.join(['0'] * ncol)!r}"
        )
    finite = np.isfinite(data)
    if not finite.all():
        i = int(np.argmin(finite.all(axis=1)))
        j = int(np.argmin(finite[i]))
        cell = cell_text(i, j)
        overflow = _NUMBER.fullmatch(cell) and not re.search("inf|nan", cell, re.IGNORECASE)
        what = "overflows to inf" if overflow else "is not finite"
        raise DataError(
            f"{src}:{line_of(i)}: value {_q(cell)} in column {file_names[j]!r} {what}; "
            f"measured data must be finite: remove or interpolate the bad samples"
        )
    if nrows < 2:
        raise DataError(
            f"{src}:{line_of(0)}: only 1 data row; at least 2 rows are needed"
        )
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
    columns = {
        name: np.ascontiguousarray(data[:, j]) for name, j in zip(names, keep) if name != "t"
    }
    ds = Dataset(t, columns, metadata, src)
    if check_units:
        _check_units(ds, stacklevel=2)
    return ds


# --------------------------------------------------------------------------- writing


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
) -> None:
    """Write a CSV file that :func:`read_csv` reads back identically, atomically.

    Layout: one ``# key: value`` line per metadata item (values converted with ``str``,
    line breaks replaced by a blank, stripped of surrounding blanks), the header
    ``t,<columns...>``, then one row per sample
    with every number written by ``repr`` (shortest exact round-trip text).  The data are
    validated like a :class:`Dataset` (finite, ``t`` strictly increasing, equal lengths), so
    a file is never written that :func:`read_csv` would refuse.  Written via
    :func:`~bondgraph.atomic.atomic_write`: on failure no partial file is left.

    Raises :class:`DataError` for invalid data, names, metadata, or if the file cannot be
    written (message names the file).
    """
    dst = os.fspath(path)
    columns = dict(columns)
    for name in columns:
        _check_name(name, dst)
    meta_lines = []
    for key, value in dict(metadata or {}).items():
        if not isinstance(key, str) or not _META_KEY.fullmatch(key):
            raise DataError(
                f"{dst}: metadata key {key!r} cannot be written: keys start with a letter or '_', "
                f"hold no ':', '#' or line break, and do not end with a blank"
            )
        value = _LINE_BREAKS.sub(" ", str(value)).strip()
        meta_lines.append(f"# {key}: {value}\n")
    ds = Dataset(t, columns, {}, dst)
    table = np.column_stack([ds.t, *ds.columns.values()])
    nrow, ncol = table.shape
    row_fmt = ",".join(["%r"] * ncol) + "\n"
    try:
        with atomic_write(dst, "w", encoding="utf-8", newline="\n") as f:
            f.write("".join(meta_lines))
            f.write(",".join(ds.names) + "\n")
            for start in range(0, nrow, _CHUNK_ROWS):
                block = table[start : start + _CHUNK_ROWS]
                f.write((row_fmt * len(block)) % tuple(block.ravel().tolist()))
    except OSError as exc:
        raise DataError(
            f"{dst}: cannot write the file ({exc.strerror or exc}); check that the directory "
            f"exists and is writable"
        ) from None
