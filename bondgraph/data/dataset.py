"""The :class:`Dataset`: a validated, read-only time series of measured (or simulated) signals."""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from ..support.errors import DataError, UsageError, did_you_mean
from . import sampling


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

    All arrays are private read-only copies (copy one with ``np.array(ds.t)`` to modify it);
    values must be finite.  The fields below are also the attributes of the same names.

    Parameters
    ----------
    t : array_like
        Time in s, float64, strictly increasing, at least 2 samples.
    columns : dict of str to array_like, optional
        Every other column by name (``"V"`` in V, ``"x"`` in m, ...), float64, same length
        as ``t``, in file order.  ``"t"`` may not appear here.
    metadata : dict of str to str, optional
        ``# key: value`` comments of the file, in order (values are kept as strings).
    path : str or os.PathLike, optional
        The file it was read from, or ``None``; used to name the data in error messages.

    Raises
    ------
    bondgraph.support.errors.DataError
        If a column is not numeric, not one-dimensional, of another length than ``t`` or
        holds a non-finite value, if a column name is empty or ``"t"``, if ``t`` has fewer
        than 2 samples or is not strictly increasing.
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
                    f"{where}: column {name!r} has a non-finite value ({a[i]}) at row {i}; data must be finite"
                )
        increasing = t[1:] > t[:-1]  # (no overflow, unlike np.diff on huge values)
        if not increasing.all():
            i = int(np.argmin(increasing))
            raise DataError(
                f"{where}: time not strictly increasing: t[{i + 1}] = {t[i + 1]!r} follows t[{i}] = {t[i]!r}"
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
    def _where(self) -> str:
        return self.path or "dataset"

    @property
    def names(self) -> tuple[str, ...]:
        """All column names, ``"t"`` first."""
        return ("t", *self.columns)

    def column(self, name: str, option: str | None = None) -> np.ndarray:
        """The column ``name`` (``"t"`` included).

        Parameters
        ----------
        name : str
            The column's name.
        option : str, optional
            The command-line option that chooses the column (``"--input"``), named in the
            hint of the error message.

        Returns
        -------
        numpy.ndarray
            The read-only column, in the unit of the file.

        Raises
        ------
        bondgraph.support.errors.DataError
            If there is no such column; the message lists the known names.
        """
        if name == "t":
            return self.t
        try:
            return self.columns[name]
        except KeyError:
            hint = f"; choose one with {option} COL" if option else ""
            raise DataError(f"{self._where}: {did_you_mean(name, self.names, 'column')}{hint}") from None

    def input(self, name: str = "V") -> np.ndarray:
        """The column that drives a model.

        Parameters
        ----------
        name : str, optional
            The column's name, by default ``"V"`` (a voltage in V).

        Returns
        -------
        numpy.ndarray
            The read-only column.

        Raises
        ------
        bondgraph.support.errors.DataError
            If there is no such column (the hint names ``--input``).
        """
        return self.column(name, "--input")

    def output(self, name: str = "x") -> np.ndarray:
        """The column a model output is compared with.

        Parameters
        ----------
        name : str, optional
            The column's name, by default ``"x"`` (a displacement in m).

        Returns
        -------
        numpy.ndarray
            The read-only column.

        Raises
        ------
        bondgraph.support.errors.DataError
            If there is no such column (the hint names ``--output``).
        """
        return self.column(name, "--output")

    @property
    def dt(self) -> float:
        """Median time step in seconds."""
        return sampling.median_step(self.t)

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
        """True if the sampling is uniform (see :func:`bondgraph.data.sampling.uniform_step`)."""
        return sampling.uniform_step(self.t) is not None

    # ---------------------------------------------------------------- derived datasets
    def _take(self, index) -> Dataset:
        return Dataset(self.t[index], {k: v[index] for k, v in self.columns.items()}, self.metadata, self.path)

    def slice(self, t0: float | None = None, t1: float | None = None) -> Dataset:
        """The samples with ``t0 <= t <= t1``; times are kept as they are (not shifted to 0).

        Parameters
        ----------
        t0, t1 : float, optional
            The window's bounds in s, inclusive; ``None`` leaves that side open.

        Returns
        -------
        Dataset
            The samples in the window, all columns and the metadata kept.

        Raises
        ------
        bondgraph.support.errors.DataError
            If the window holds fewer than 2 samples.
        """
        lo = 0 if t0 is None else int(np.searchsorted(self.t, t0, "left"))
        hi = len(self) if t1 is None else int(np.searchsorted(self.t, t1, "right"))
        if hi - lo < 2:
            raise DataError(
                f"{self._where}: the time window [{t0}, {t1}] s holds {max(hi - lo, 0)} sample(s); "
                f"at least 2 are needed (data spans {self.t[0]:g} .. {self.t[-1]:g} s)"
            )
        return self._take(slice(lo, hi))

    def split(self, fraction: float = 0.7) -> tuple[Dataset, Dataset]:
        """Split in time into (fit, validation); no sample is in both.

        Parameters
        ----------
        fraction : float, optional
            The share of the time span (not of the samples) the first part covers, strictly
            between 0 and 1; 0.7 by default.

        Returns
        -------
        fit, validation : Dataset
            The first ``fraction`` of the time span, and the rest.

        Raises
        ------
        bondgraph.support.errors.UsageError
            If ``fraction`` is not a number strictly between 0 and 1.
        bondgraph.support.errors.DataError
            If either part would hold fewer than 2 samples.
        """
        if not (isinstance(fraction, (int, float)) and 0.0 < fraction < 1.0):
            raise UsageError(f"split fraction must be between 0 and 1 (exclusive), not {fraction!r}")
        t_split = self.t[0] + fraction * (self.t[-1] - self.t[0])
        k = int(np.searchsorted(self.t, t_split, "left"))
        if k < 2 or len(self) - k < 2:
            raise DataError(
                f"{self._where}: splitting {len(self)} samples at {fraction:g} of the time span "
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

        Parameters
        ----------
        factor : int
            Keep every ``factor``-th sample (1 returns the dataset itself).
        ftype : {"iir", "fir"}, optional
            The anti-alias filter, ``"iir"`` by default.

        Returns
        -------
        Dataset
            The decimated dataset, sample rate divided by ``factor``.

        Raises
        ------
        bondgraph.support.errors.UsageError
            If ``factor`` is not a positive integer or ``ftype`` is unknown.
        bondgraph.support.errors.DataError
            If the sampling is not uniform or fewer than 2 samples would remain.
        """
        if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
            raise UsageError(f"decimation factor must be a positive integer, not {factor!r}")
        if ftype not in ("iir", "fir"):
            raise UsageError(f"decimation filter type must be 'iir' or 'fir', not {ftype!r}")
        factor = int(factor)
        if factor == 1:
            return self
        if not self.is_uniform:
            raise DataError(
                f"{self._where}: decimate needs uniform sampling; resample first, e.g. dataset.resample({self.dt:.6g})"
            )
        if len(self) // factor < 2:
            raise DataError(f"{self._where}: {len(self)} samples are too few to decimate by {factor}")
        cols = sampling.decimate_columns(self.columns, factor, ftype, self._where, len(self))
        t = self.t[::factor]
        return Dataset(t, {k: v[: len(t)] for k, v in cols.items()}, self.metadata, self.path)

    def resample(self, dt: float) -> Dataset:
        """Linear interpolation onto the uniform grid ``t[0], t[0] + dt, ...`` (<= ``t[-1]``).

        Meant to make slightly irregular sampling uniform at about the same rate.  There is
        no anti-alias filter: to reduce the rate of uniform data use :meth:`decimate`.

        Parameters
        ----------
        dt : float
            The new time step in s, positive.

        Returns
        -------
        Dataset
            The dataset on the uniform grid, every column interpolated linearly.

        Raises
        ------
        bondgraph.support.errors.UsageError
            If ``dt`` is not a positive finite number, or would make far more samples than
            the data hold.
        bondgraph.support.errors.DataError
            If the grid would hold fewer than 2 samples.
        """
        t = sampling.uniform_grid(self.t[0], self.t[-1], dt, self._where, len(self))
        return Dataset(t, {k: np.interp(t, self.t, v) for k, v in self.columns.items()}, self.metadata, self.path)
