"""Exact scale symmetries of a calibration, and the point of each the diagnosis keeps.

A force-driven mechanism read by a sensor whose gain is solved has an exact symmetry: every
mass, stiffness and damping scaled by one factor s moves a displacement by 1/s, which the
sensor gain takes back, so the calibrated output does not change at all (an RLC circuit read
by a voltage has it without the gain: its response depends on L·C and R·C only).  The data say
nothing about s, and an optimiser ends anywhere along that line — on one machine at the model
file's stiffness, on another at ten times it with ten times the mass and sensor gain — and the
law terms fitted next start from there, with scales taken from those values.

:func:`fix_scales` finds such directions after the calibration (the near-null right singular
vectors of the output's central-difference sensitivities to the logarithms of the calibrated
parameters, the sensor gain and offset projected out, read as small integer exponents) and
keeps one only if scaling along it by ×2 leaves the output exactly proportional to itself.  It
then moves the calibration along each, to the point nearest the model file's values in the
parameters' tolerances (the weighted least squares of their log-ratios), within the search
bounds.  The fitted output is unchanged: this chooses among equal answers, it fits nothing.
:func:`scale_start` does the same along the symmetries of the whole parameter set, held
parameters included, for the plausible device's fit (the calibrated parameters alone have none
of their own when some are held): its held parameters are held where that moves them.
"""

from __future__ import annotations

import math
from typing import Mapping, Sequence

import numpy as np

from .context import Context

#: a singular value of the sensitivities below this share of the largest makes its direction
#: a candidate symmetry
NULL_SHARE = 1e-3
#: a symmetry is exact when a step ×2 along it leaves the output proportional to itself within
#: this share of its norm
EXACT = 1e-7
#: the relative step of the central differences
STEP = 1e-4


def _columns(ctx: Context, names: Sequence[str], values: Mapping[str, float], raw: np.ndarray) -> np.ndarray:
    """Central-difference sensitivities of the raw output to each parameter's logarithm on the
    fit part, the output's own direction and a constant projected out."""
    idx = ctx.ident.fit_idx
    cols = []
    for n in names:
        up, down = dict(values), dict(values)
        up[n], down[n] = values[n] * math.exp(STEP), values[n] * math.exp(-STEP)
        cols.append((ctx.ident.predict(up) - ctx.ident.predict(down))[idx] / (2 * STEP))
    S = np.column_stack(cols)
    Q, _ = np.linalg.qr(np.column_stack([raw[idx], np.ones(idx.size)]))
    return S - Q @ (Q.T @ S)


def _integers(v: np.ndarray) -> np.ndarray | None:
    """``v`` as small integer exponents (multiples of its smallest entry), or None."""
    v = v / np.max(np.abs(v))
    v = np.where(np.abs(v) < 0.05, 0.0, v)
    small = np.min(np.abs(v[v != 0]))
    q = np.round(v / small)
    return q if np.max(np.abs(q - v / small)) < 0.05 and np.max(np.abs(q)) <= 3 else None


def _proportional(ctx: Context, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``b`` equals gain·``a`` + offset on the fit part to :data:`EXACT` of its norm."""
    idx = ctx.ident.fit_idx
    A = np.column_stack([a[idx], np.ones(idx.size)])
    coef, *_ = np.linalg.lstsq(A, b[idx], rcond=None)
    scale = float(np.linalg.norm(b[idx] - b[idx].mean())) or 1.0
    return bool(np.all(np.isfinite(b))) and float(np.linalg.norm(A @ coef - b[idx])) <= EXACT * scale


def scale_symmetries(
    ctx: Context, names: Sequence[str], values: Mapping[str, float], raw: np.ndarray
) -> list[np.ndarray]:
    """Exponent vectors (one entry per name) of the exact scale symmetries at ``values``.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    names : sequence of str
        The calibrated parameters.
    values : mapping of str to float
        Their values.
    raw : numpy.ndarray
        The raw prediction at ``values``.

    Returns
    -------
    list of numpy.ndarray
        Integer exponents: scaling parameter i by s**e[i] leaves the output proportional.
    """
    if len(names) < 2 or any(values[n] == 0 for n in names):
        return []
    S = _columns(ctx, names, values, raw)
    if not np.all(np.isfinite(S)):
        return []
    _, s, Vt = np.linalg.svd(S, full_matrices=False)
    found = []
    for k in range(s.size):
        if s[0] <= 0 or s[k] > NULL_SHARE * s[0]:
            continue
        e = _integers(Vt[k])
        if e is None:
            continue
        moved = {n: values[n] * 2.0 ** e[i] for i, n in enumerate(names)}
        if _proportional(ctx, raw, ctx.ident.predict(moved)):
            found.append(e)
    return found


def _nearest(
    e: np.ndarray,
    names: Sequence[str],
    values: Mapping[str, float],
    nominal: Mapping[str, float],
    factors: Mapping[str, float],
) -> float:
    """The step τ along the exponents ``e`` (parameter i times exp(e[i]·τ)) to the point
    nearest ``nominal``: the least squares of the log-ratios, each weighted by 1/log(factor)²."""
    d = np.array([math.log(abs(values[n]) / abs(nominal[n])) for n in names])
    w = np.array([1.0 / max(math.log(factors[n]), 1e-3) ** 2 for n in names])
    return -float(np.sum(w * e * d) / max(float(np.sum(w * e * e)), 1e-300))


def fix_scales(
    ctx: Context,
    names: Sequence[str],
    values: Mapping[str, float],
    raw: np.ndarray,
    nominal: Mapping[str, float],
    factors: Mapping[str, float],
    bounds: Mapping[str, tuple[float, float]],
) -> tuple[dict[str, float], np.ndarray, list[np.ndarray]]:
    """Move ``values`` along each exact scale symmetry to the point nearest ``nominal`` (see the
    module docstring).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    names : sequence of str
        The calibrated parameters.
    values : mapping of str to float
        Their calibrated values.
    raw : numpy.ndarray
        The raw prediction at ``values``.
    nominal : mapping of str to float
        The model file's values.
    factors : mapping of str to float
        Each parameter's plausible spread (×/÷): the weight of its log-ratio is 1/log(factor)².
    bounds : mapping of str to tuple of float
        Bounds of each parameter's magnitude.

    Returns
    -------
    values : dict of str to float
        The values moved (the same when there is no symmetry).
    raw : numpy.ndarray
        The raw prediction there.
    symmetries : list of numpy.ndarray
        The exponent vectors found.
    """
    names = list(names)
    out = dict(values)
    found = scale_symmetries(ctx, names, out, raw)
    for e in found:
        tau = _nearest(e, names, out, nominal, factors)
        lo, hi = -math.inf, math.inf  # keep every parameter within its bounds
        for i, n in enumerate(names):
            if e[i]:
                a = (math.log(bounds[n][0]) - math.log(abs(out[n]))) / e[i]
                b = (math.log(bounds[n][1]) - math.log(abs(out[n]))) / e[i]
                lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
        tau = min(max(tau, lo), hi) if lo <= hi else 0.0
        moved = {**out, **{n: out[n] * math.exp(e[i] * tau) for i, n in enumerate(names)}}
        moved_raw = ctx.ident.predict(moved)
        if _proportional(ctx, raw, moved_raw):
            out, raw = moved, moved_raw
    return out, raw, found


def scale_start(
    ctx: Context,
    names: Sequence[str],
    values: Mapping[str, float],
    raw: np.ndarray,
    nominal: Mapping[str, float],
    factors: Mapping[str, float],
    bounds: Mapping[str, tuple[float, float]],
) -> dict[str, float] | None:
    """A start for the plausible device's fit: the calibration moved along each exact scale
    symmetry of the whole parameter set ``names`` (held parameters included) to the point
    nearest ``nominal``, then clipped into ``bounds``.

    When parameters are held, the calibrated ones have no exact symmetry of their own and
    :func:`fix_scales` finds none; yet the calibration can slide far along the whole set's
    symmetry, every calibrated value off by about one factor, and end outside the parameters'
    tolerances while the data say nothing about that factor.  Two cases, one answer: a held
    parameter that barely touches the output (a mode above the drive's band) leaves the
    calibrated ones free to slide; a held parameter whose effect is exactly the others'
    together (a damping that is not separable from the masses, stiffnesses and the sensor gain)
    pins the slide at its own value, so the calibration is the device scaled to match it.
    Moving every parameter along the symmetry leaves the output as it is, and the point nearest
    the model file's values is the device at its own scale; a fit confined to the tolerances
    and started from their edges stays in a local minimum instead.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    names : sequence of str
        Every linear parameter of the model.
    values : mapping of str to float
        The values of every name (the held ones at the model file's).
    raw : numpy.ndarray
        The raw prediction at ``values``.
    nominal : mapping of str to float
        The model file's values.
    factors : mapping of str to float
        The plausible spread (×/÷) of each parameter.
    bounds : mapping of str to tuple of float
        Bounds of each parameter's magnitude.

    Returns
    -------
    dict of str to float or None
        The value of every parameter a symmetry moves (held ones included); None without one.
    """
    names = list(names)
    found = scale_symmetries(ctx, names, values, raw)
    if not found:
        return None
    out = {n: values[n] for n in names}
    for e in found:
        tau = _nearest(e, names, out, nominal, factors)
        out = {n: out[n] * math.exp(e[i] * tau) for i, n in enumerate(names)}
    moved = {n for e in found for i, n in enumerate(names) if e[i]}
    return {n: math.copysign(min(max(abs(out[n]), bounds[n][0]), bounds[n][1]), out[n]) for n in names if n in moved}
