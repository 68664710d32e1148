"""Statistics of a sweep: summary of each output and the sensitivity of each output to each
varied parameter (what the tornado plot draws).

Sensitivity by design (``swing`` ranks the parameters; ``low``/``high`` are the output values
the tornado bars reach from ``baseline``):

* ``oat``: the output at each parameter's low and high value, the others nominal;
  baseline: the nominal run.
* ``grid``: main effects: the mean output over all runs at the parameter's first and last
  level; swing: the range of the mean over its levels; baseline: the mean of all runs.
* ``random``/``lhs``: a linear regression of the output on the parameters (least squares):
  the predicted output with the parameter at its 5th and 95th percentile and the others at
  their means; also the standardised regression coefficient ``src``, Spearman's rank
  correlation ``spearman`` (scipy) and the regression's ``r2``; baseline: the mean output.

Failed runs (no value) are left out and counted.

A metric whose values over the runs spread by less than :data:`NOISE_SPREAD` of their size
(range over the largest magnitude) is not ranked: such a spread is the integrator's rounding,
not the parameters' effect (its ranking comes back empty, with the relative spread as
``noise``); a parameter whose swing is below that share of the metric's size is marked
``"negligible": True``.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from scipy import stats

from .table import Table

#: relative spread (range over largest magnitude) below which a metric's variation over the
#: runs is taken for numerical noise and not ranked
NOISE_SPREAD = 1e-6


def relative_spread(y: np.ndarray) -> float:
    """The range of the finite values of ``y`` over their largest magnitude (0 for a metric
    that is zero in every run, NaN without a value)."""
    ok = y[np.isfinite(y)]
    if not ok.size:
        return math.nan
    size = float(np.max(np.abs(ok)))
    return float(np.ptp(ok)) / size if size > 0 else 0.0


def summary(table: Table, metrics: Sequence[str]) -> list[dict]:
    """Per output: runs with a value, runs without, mean, sample std, min, 5/50/95 % percentiles, max.

    Parameters
    ----------
    table : Table
        The runs.
    metrics : sequence of str
        The metric columns.

    Returns
    -------
    list of dict
        Per metric: ``metric``, ``n``, ``failed`` and, when ``n`` > 0, ``mean``, ``std``,
        ``min``, ``p5``, ``median``, ``p95``, ``max`` in the metric's unit.
    """
    out = []
    for m in metrics:
        y = table.column(m)
        ok = y[np.isfinite(y)]
        row = {"metric": m, "n": int(ok.size), "failed": int(y.size - ok.size)}
        if ok.size:
            p5, p50, p95 = np.percentile(ok, [5, 50, 95])
            row.update(
                mean=float(np.mean(ok)),
                std=float(np.std(ok, ddof=1)) if ok.size > 1 else 0.0,
                min=float(np.min(ok)),
                p5=float(p5),
                median=float(p50),
                p95=float(p95),
                max=float(np.max(ok)),
            )
        out.append(row)
    return out


def sensitivity(table: Table, params: Sequence[str], metric: str, design: str) -> dict:
    """Ranking of ``params`` by their effect on ``metric`` (see the module docstring):
    ``{"metric", "baseline", "ranking": [{"parameter", "low", "high", "swing", ...}, ...]}``.

    Parameters
    ----------
    table : Table
        The runs.
    params : sequence of str
        The varied parameters.
    metric : str
        The metric column.
    design : {"random", "lhs", "grid", "oat"}
        How the runs were drawn (it decides how effects are estimated).

    Returns
    -------
    dict
        ``metric``, ``baseline`` and ``ranking`` (largest swing first; ``low``/``high`` are
        the metric at the parameter's low and high end, in the metric's unit), and for
        random and lhs designs ``r2`` and each parameter's ``src`` and ``spearman``; for a
        metric whose runs spread by less than :data:`NOISE_SPREAD` of its size, an empty
        ranking and ``noise``, the relative spread.
    """
    y = table.column(metric)
    spread = relative_spread(y)
    if spread < NOISE_SPREAD:
        return {"metric": metric, "baseline": _mean(y), "ranking": [], "noise": spread}
    if design == "oat":
        base = float(y[0])
        ranking = [
            {"parameter": p, "low": float(y[1 + 2 * i]), "high": float(y[2 + 2 * i])} for i, p in enumerate(params)
        ]
        for r in ranking:
            r["swing"] = abs(r["high"] - r["low"])
        extra = {}
    elif design == "grid":
        base = _mean(y)
        ranking = []
        for p in params:
            cells = [r.get(p) for r in table.rows]
            levels = list(dict.fromkeys(cells))
            means = [_mean(y[[c == lv for c in cells]]) for lv in levels]
            finite = [v for v in means if math.isfinite(v)]
            ranking.append(
                {
                    "parameter": p,
                    "low": means[0],
                    "high": means[-1],
                    "swing": (max(finite) - min(finite)) if finite else math.nan,
                }
            )
        extra = {}
    else:
        ranking, extra = _regression(table, params, y)
        base = extra.pop("mean")
    ranking.sort(key=lambda r: -r["swing"] if math.isfinite(r["swing"]) else math.inf)
    size = float(np.nanmax(np.abs(y))) if np.isfinite(y).any() else math.nan
    for r in ranking:
        if r["swing"] < NOISE_SPREAD * size:
            r["negligible"] = True
    return {"metric": metric, "baseline": base, "ranking": ranking, **extra}


def _mean(y: np.ndarray) -> float:
    ok = y[np.isfinite(y)]
    return float(np.mean(ok)) if ok.size else math.nan


def _regression(table: Table, params: Sequence[str], y: np.ndarray) -> tuple[list[dict], dict]:
    X = np.column_stack([table.column(p) for p in params])
    ok = np.isfinite(y) & np.all(np.isfinite(X), axis=1)
    X, y = X[ok], y[ok]
    nan = [
        {"parameter": p, "low": math.nan, "high": math.nan, "swing": math.nan, "src": math.nan, "spearman": math.nan}
        for p in params
    ]
    if y.size < len(params) + 2:
        return nan, {"mean": _mean(y), "r2": math.nan}
    xm, ym = X.mean(axis=0), float(y.mean())
    A = np.column_stack([np.ones(y.size), X - xm])
    coef, *_ = np.linalg.lstsq(A, y - ym, rcond=None)
    b = coef[1:]
    resid = y - ym - A @ coef
    sy = float(np.std(y))
    r2 = 1.0 - float(np.sum(resid**2)) / float(np.sum((y - ym) ** 2)) if sy > 0 else math.nan
    q5, q95 = np.percentile(X, [5, 95], axis=0)
    ranking = []
    for j, p in enumerate(params):
        low, high = ym + b[j] * (q5[j] - xm[j]), ym + b[j] * (q95[j] - xm[j])
        rho = stats.spearmanr(X[:, j], y).statistic if sy > 0 and np.std(X[:, j]) > 0 else math.nan
        ranking.append(
            {
                "parameter": p,
                "low": float(low),
                "high": float(high),
                "swing": float(abs(high - low)),
                "src": float(b[j] * np.std(X[:, j]) / sy) if sy > 0 else math.nan,
                "spearman": float(rho),
            }
        )
    return ranking, {"mean": ym, "r2": r2}
