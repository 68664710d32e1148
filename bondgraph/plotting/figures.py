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
