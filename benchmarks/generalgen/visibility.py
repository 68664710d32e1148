"""The visibility rule: an effect counts only if what it adds to the output is at least
:data:`RATIO` times the record's noise RMS beyond what a linear explanation absorbs.

* For a nonlinear effect, a hysteretic drive and a sensor drift: beyond a **flexible linear
  model from the drive** (:func:`flexible_linear_residual`): the least-squares combination of
  the effect-free truth's own output and, for each of its modes, second-order sections (and
  their derivatives) at 0.85, 1 and 1.18 times its frequency with its damping and with
  3 ζ + 0.03, plus the drive itself, two first-order lags of it and a constant.
* For missing modes: beyond **recalibrating the model file's own parameters**
  (:func:`recalibrated_residual`): every mass, stiffness and damping of the model file's
  structure fitted freely (×/÷ 10 about the truth's) together with a sensor gain and offset;
  for two missing modes also beyond the best structure with one of them put back.  The fit
  is local (trust-region least squares, at most 100 evaluations) but starts from the truth's
  own values, the best start there is.

Both fits are made on the noise-free truth, so the residual is the effect's visible part
alone; the linear responses come from the exact frequency-domain route
(:func:`~.network.linear_response`), not from the integrator.
"""

from __future__ import annotations

import numpy as np
import scipy.optimize

from .network import Network, Spectrum, linear_response, response

#: an effect is visible when its unexplained part is at least this many noise RMS
RATIO = 3.0


def _rms(x) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def _project(columns: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Residual of ``y`` after least squares on ``columns`` (n x p)."""
    scale = np.sqrt(np.mean(columns**2, axis=0))
    scale[scale == 0] = 1.0
    coef = np.linalg.lstsq(columns / scale, y, rcond=1e-12)[0]
    return y - (columns / scale) @ coef


def flexible_linear_residual(y: np.ndarray, y_lin: np.ndarray, spec: Spectrum, net: Network, f1: float) -> np.ndarray:
    """What of ``y`` a flexible linear model from the drive leaves unexplained.

    Parameters
    ----------
    y : ndarray
        The noise-free measured output (with the effect).
    y_lin : ndarray
        The effect-free truth's output on the same drive.
    spec : Spectrum
        The drive's spectrum.
    net : Network
        The effect-free truth (its modes place the sections).
    f1 : float
        The lowest natural frequency (Hz), for the lags.

    Returns
    -------
    ndarray
        The residual, same length as ``y``.
    """
    s = 2j * np.pi * spec.freqs
    nyq = np.pi / spec.dt
    cols = [y_lin, np.ones_like(y), response(np.ones_like(s), spec)]
    for tau in (1 / (2 * np.pi * f1), 10 / (2 * np.pi * f1)):
        cols.append(response(1 / (1 + s * tau), spec))
    omegas, zetas = net.modes()
    for w, z in zip(omegas, zetas):
        for r in (0.85, 1.0, 1.18):
            wr = w * r
            if wr > 0.8 * nyq:
                continue
            for zz in (z, 3 * z + 0.03):
                den = s * s + 2 * zz * wr * s + wr * wr
                cols.append(response(wr * wr / den, spec))
                cols.append(response(wr * s / den, spec))
    return _project(np.column_stack(cols), y)


def _values(net: Network) -> np.ndarray:
    return np.concatenate([net.masses, [lk.k for lk in net.links], [lk.c for lk in net.links]])


def _with_values(net: Network, v: np.ndarray) -> Network:
    out = net.copy()
    n, nl = net.masses.size, len(net.links)
    out.masses = v[:n].copy()
    for i, lk in enumerate(out.links):
        lk.k, lk.c = float(v[n + i]), float(v[n + nl + i])
    return out


def recalibrated_residual(y: np.ndarray, spec: Spectrum, structure: Network, f_top: float) -> np.ndarray:
    """What of ``y`` the linear ``structure`` leaves unexplained with every mass, stiffness
    and damping refitted (×/÷ 10 about its values) and a sensor gain and offset.

    Parameters
    ----------
    y : ndarray
        The noise-free measured output.
    spec : Spectrum
        The drive's spectrum.
    structure : Network
        The linear structure, at its starting values.
    f_top : float
        The highest frequency that matters (Hz): the drive's top and the truth's top mode.
        The values are fitted on the record seen at a rate of at least 8 ``f_top`` (a power
        of two of samples, the spectra cut there), at 6000 of its instants at most (a fixed
        random subset), and the residual is then taken at every sample.

    Returns
    -------
    ndarray
        The residual at the best values found.
    """
    v0 = _values(structure)
    D = 1
    while D < 64 and spec.M % (4 * D) == 0 and 1 / (4 * D * spec.dt) >= 4 * f_top:
        D *= 2
    low = spec.decimated(D)
    y_low = y[::D]
    # at most 6000 instants enter the fit (a fixed random subset: no aliasing with a period)
    rows = np.sort(np.random.default_rng(0).permutation(y_low.size)[:6000])

    def fit_rows(theta):
        ym = linear_response(_with_values(structure, v0 * np.exp(theta)), low)[rows]
        if not np.all(np.isfinite(ym)):
            return y_low[rows]
        return _project(np.column_stack([ym, np.ones_like(ym)]), y_low[rows])

    lim = np.log(10.0)
    sol = scipy.optimize.least_squares(
        fit_rows,
        np.zeros(v0.size),
        bounds=(-lim, lim),
        x_scale="jac",
        diff_step=1e-5,
        max_nfev=100,
        ftol=1e-10,
        xtol=1e-10,
    )
    best = min((np.zeros(v0.size), sol.x), key=lambda th: _rms(fit_rows(th)))
    ym = linear_response(_with_values(structure, v0 * np.exp(best)), spec)
    return _project(np.column_stack([ym, np.ones_like(y)]), y)
