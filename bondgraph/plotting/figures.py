"""Figures: the shared pieces of every plot (matplotlib, optional extra ``plot``).

Every figure is written atomically, in the format of its file name (png, pdf or svg);
without matplotlib a one-line error names the extra to install.
"""

from __future__ import annotations

import os

import numpy as np

from ..support.atomic import atomic_write
from ..support.errors import UsageError


def pyplot():
    """matplotlib's pyplot on the Agg backend, or a one-line :class:`UsageError` without it.

    Returns
    -------
    module
        ``matplotlib.pyplot``, with the non-interactive Agg backend selected.

    Raises
    ------
    UsageError
        matplotlib is not installed (the message names the ``plot`` extra).
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise UsageError("plots need matplotlib: pip install 'bondgraph[plot]'") from None
    return plt


def save(fig, path: str) -> None:
    """Write ``fig`` atomically and close it; the format follows the file name's suffix.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to write (closed afterwards, written or not).
    path : str or path-like
        The file to write: ``.png`` (the default without a suffix), ``.pdf`` or ``.svg``.

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = pyplot()
    fmt = os.path.splitext(os.fspath(path))[1].lstrip(".").lower() or "png"
    try:
        with atomic_write(path, "wb") as fh:
            fig.savefig(fh, format=fmt, dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)


def axis_label(name: str, unit: str) -> str:
    """``x (m)``, or just ``x`` for a quantity without unit (``(m)`` without a name).

    Parameters
    ----------
    name : str
        The quantity's name.
    unit : str
        Its unit ("" for none).

    Returns
    -------
    str
        The axis label.
    """
    return f"{name} ({unit})".strip() if unit else name


#: SI prefixes an axis may take, by power of ten
PREFIXES = {-12: "p", -9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}
#: units that take an SI prefix on an axis (a compound unit such as m/s keeps its own scale)
PREFIXABLE = frozenset({"m", "V", "A", "N", "C", "W", "J", "Pa", "F", "H", "Hz", "Ω"})
#: share of a record at its start that never sets the scale of a residual panel
START_SHARE = 0.02
#: percentiles of the settled part of the residuals that set a residual panel's scale
ROBUST_PERCENTILES = (0.1, 99.9)


def si_scale(unit: str, *values) -> tuple[float, str]:
    """The factor to multiply ``values`` by and the SI-prefixed unit to show them in, chosen
    so that their largest magnitude reads between 1 and 1000 (``(1e6, "µm")`` for a stroke of
    1e-4 m); ``(1.0, unit)`` for a unit that takes no prefix or values that are all zero."""
    if unit not in PREFIXABLE:
        return 1.0, unit
    peaks = [np.nanmax(np.abs(v)) for v in (np.asarray(v, float).ravel() for v in values) if np.isfinite(v).any()]
    peak = max(peaks, default=0.0)
    if not np.isfinite(peak) or peak <= 0:
        return 1.0, unit
    power = int(np.clip(3 * np.floor(np.log10(peak) / 3), min(PREFIXES), max(PREFIXES)))
    return 10.0**-power, PREFIXES[power] + unit


def scaled_label(name: str, unit: str, *values) -> tuple[str, float]:
    """The axis label of ``name`` in the SI-prefixed ``unit`` that suits ``values`` (see
    :func:`si_scale`) and the factor to multiply the values by: ``("x (µm)", 1e6)``."""
    factor, shown = si_scale(unit, *values)
    return axis_label(name, shown), factor


def settled_start(t, *residuals) -> int:
    """The first sample from which residuals set a panel's scale: after the first
    :data:`START_SHARE` of the record, and after a start-up transient (the last sample of the
    record's first half at which a residual is more than three times as far from its centre as
    the second half's 0.1–99.9 % spread reaches)."""
    n = len(np.asarray(t))
    start = int(np.ceil(START_SHARE * n))
    half = n // 2
    for r in residuals:
        r = np.asarray(r, float)
        tail = r[half:][np.isfinite(r[half:])]
        if tail.size < 2:
            continue
        lo, hi = np.percentile(tail, ROBUST_PERCENTILES)
        centre, width = (lo + hi) / 2, max((hi - lo) / 2, 1e-300)
        away = np.flatnonzero(np.abs(r[:half] - centre) > 3 * width)
        if away.size:
            start = max(start, int(away[-1]) + 1)
    return min(start, half)


def robust_limits(t, residuals, noise: float = 0.0) -> tuple[float, float, int, bool]:
    """The y-limits of a residual panel, set by the part of the record after its start-up
    transient (:func:`settled_start`): the :data:`ROBUST_PERCENTILES` of every residual there,
    widened by 10 % (and to the noise band ±``noise``).

    Returns
    -------
    (lo, hi, start, clipped)
        The limits, the first sample that set them, and whether some sample (of the transient,
        or an outlier) lies outside them.
    """
    residuals = [np.asarray(r, float) for r in residuals]
    start = settled_start(t, *residuals)
    part = np.concatenate([r[start:] for r in residuals])
    part = part[np.isfinite(part)]
    if part.size == 0:
        return -1.0, 1.0, start, False
    lo, hi = np.percentile(part, ROBUST_PERCENTILES)
    lo, hi = min(lo, -noise), max(hi, noise)
    pad = 0.1 * (hi - lo) or max(abs(hi), 1.0) * 0.1
    lo, hi = float(lo - pad), float(hi + pad)
    every = np.concatenate(residuals)
    every = every[np.isfinite(every)]
    return lo, hi, start, bool(np.any((every < lo) | (every > hi)))


def residual_scale(ax, t, residuals, noise: float = 0.0, time_unit: str = "s") -> None:
    """Set a residual panel's y-limits by :func:`robust_limits` (the data stay plotted) and,
    when samples lie outside them, say in the panel which part of the record set the scale."""
    lo, hi, start, clipped = robust_limits(t, residuals, noise)
    ax.set_ylim(lo, hi)
    if clipped:
        t = np.asarray(t, float)
        ax.text(
            0.99,
            0.02,
            f"scale from t ≥ {t[start]:.3g} {time_unit} ({ROBUST_PERCENTILES[0]:g}–{ROBUST_PERCENTILES[1]:g} %): "
            "start-up transient and outliers off scale",
            transform=ax.transAxes,
            ha="right",
            va="bottom",
            fontsize=7,
            color="0.3",
        )


def varies(y) -> bool:
    """Whether a sampled signal changes at all (beyond rounding).

    Parameters
    ----------
    y : array_like
        The samples.

    Returns
    -------
    bool
        True when the peak-to-peak range exceeds 1e-12 of the peak magnitude (and the signal
        has two samples or more and is not all zero).
    """
    y = np.asarray(y, float)
    if y.size < 2:
        return False
    peak = float(np.max(np.abs(y)))
    return peak > 0 and float(np.ptp(y)) > 1e-12 * peak


def revisits(u, deadband: float = 0.1) -> bool:
    """Whether a drive comes back over its values: it reverses at least once and travels its
    range at least twice (a periodic or back-and-forth drive, whose output against it is a
    loop; not a step, a ramp or a single rise).  Moves smaller than ``deadband`` times the
    range are not reversals (noise on a measured step is not a loop).

    Parameters
    ----------
    u : array_like
        The drive's samples.
    deadband : float, optional
        Share of the range a move must exceed to count as a reversal.

    Returns
    -------
    bool
        True for a drive whose output is worth drawing against it.
    """
    u = np.asarray(u, float)
    if not varies(u):
        return False
    span = float(np.ptp(u))
    band = deadband * span
    lo = hi = float(u[0])
    direction, turns, extreme = 0, [], 0.0
    for v in u.tolist():
        if direction == 0:  # the first leg: its direction once the drive has moved a band
            lo, hi = min(lo, v), max(hi, v)
            if hi - lo > band:
                direction = 1 if v == hi else -1
                turns, extreme = [lo if direction > 0 else hi], v
        elif direction * (v - extreme) > 0:  # the leg goes on
            extreme = v
        elif direction * (extreme - v) > band:  # a reversal
            turns.append(extreme)
            direction, extreme = -direction, v
    if direction == 0:
        return False
    turns.append(extreme)
    return len(turns) >= 3 and float(np.sum(np.abs(np.diff(turns)))) >= 2 * (1 - deadband) * span


def envelope(t, y, limit: int = 20000):
    """At most about ``limit`` points that keep every bucket's minimum and maximum (a
    million-sample signal draws as fast as a short one and loses no peak).

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s.
    y : numpy.ndarray
        Samples at ``t``.
    limit : int, optional
        About the most points returned.

    Returns
    -------
    t : numpy.ndarray
        The thinned times in order (the input itself when short enough).
    y : numpy.ndarray
        The samples at them.
    """
    n = t.size
    if n <= limit:
        return t, y
    k = int(np.ceil(n / (limit // 2)))
    m = n // k * k
    tb, yb = t[:m].reshape(-1, k), y[:m].reshape(-1, k)
    lo, hi = yb.argmin(axis=1), yb.argmax(axis=1)
    rows = np.arange(tb.shape[0])
    first, second = np.minimum(lo, hi), np.maximum(lo, hi)
    tt = np.column_stack([tb[rows, first], tb[rows, second]]).ravel()
    yy = np.column_stack([yb[rows, first], yb[rows, second]]).ravel()
    return np.concatenate([tt, t[m:]]), np.concatenate([yy, y[m:]])
