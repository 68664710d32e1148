"""Visibility of a hidden effect: what of it no plausible *linear* device explains.

:func:`linear_refit` fits the effect-free (linear) truth to the noise-free response with the
effect, over the device's linear parameters within plausible bounds around the model file's
values (a factor ``BOUND``; damping a factor ``DAMPING_BOUND``; natural frequencies 15 %),
plus a sensor offset; what is left, in units of the record's noise RMS, is the visible size.  A large series resistance or a missing mode
is thus visible only as far as no plausible recalibration absorbs it, and a nonlinear effect
only beyond its best linear approximation within the model's structure.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from .system import simulate

BOUND = 2.5  # plausible factor on a linear parameter
DAMPING_BOUND = 12.0  # on viscous damping / damping ratios
MAX_POINTS = 6000  # residual points used by the refit (evenly spaced)


def _layout(p: dict):
    """[(key, index or None, bound factor)] of the refitted linear parameters of ``p``."""
    out = []
    for key, value in p.items():
        damping = key in ("c", "zeta")
        factor = DAMPING_BOUND if damping else (1.15 if key == "omega" else BOUND)
        if key in ("phi",):
            continue
        if isinstance(value, (list, tuple)):
            out.extend((key, i, factor) for i in range(len(value)))
        else:
            out.append((key, None, factor))
    return out


def _with(p: dict, layout, log_factors):
    q = {k: (list(v) if isinstance(v, (list, tuple)) else v) for k, v in p.items()}
    for (key, i, _), t in zip(layout, log_factors):
        if i is None:
            q[key] = p[key] * np.exp(t)
        else:
            q[key][i] = p[key][i] * np.exp(t)
    return q


def _log_ratio(p, nominal, layout):
    return np.array([np.log(p[k] / nominal[k]) if i is None else np.log(p[k][i] / nominal[k][i]) for k, i, _ in layout])


def linear_refit(physics, p: dict, nominal: dict, V: np.ndarray, h: float, target: np.ndarray, every: int):
    """(fitted response on the grid, fitted parameters): the effect-free device closest to
    ``target`` (least squares on every ``every``-th grid point, thinned to MAX_POINTS), started
    from the drawn parameters ``p``, bounded around the file's ``nominal`` ones."""
    layout = _layout(p)
    idx = np.arange(0, len(V), every)
    if len(idx) > MAX_POINTS:
        idx = idx[np.linspace(0, len(idx) - 1, MAX_POINTS).astype(int)]
    y_t = target[idx]
    scale = max(float(np.std(y_t)), 1e-30)
    bounds = np.log([f for *_, f in layout])

    def log_factors(phi):  # unbounded phi -> log factor over nominal within +-bound (MINPACK has no bounds)
        return bounds * np.tanh(phi / bounds)

    def response(phi):
        return simulate(physics.system(_with(nominal, layout, log_factors(phi))), V, h)[0]

    def residual(phi):
        r = y_t - response(phi)[idx]
        return (r - r.mean()) / scale

    start = bounds * np.arctanh(np.clip(_log_ratio(p, nominal, layout) / bounds, -0.999, 0.999))
    fit = least_squares(
        residual, start, x_scale=0.1, diff_step=1e-4, max_nfev=15 * len(layout), ftol=1e-6, xtol=1e-6, method="lm"
    )
    y = response(fit.x)
    return y + float(np.mean(target[idx] - y[idx])), _with(nominal, layout, log_factors(fit.x))
