"""What stays unexplained: an honest account of every answer, ``none`` included.

* ``unexplained_share``: the final model's validation RMS error over the output's RMS about
  its mean (on the validation part): 0 is a perfect model, 1 a model that explains nothing.
* ``unexplained_linear_share``: how much of that residual's energy is linear in the drive —
  what a linear filter from the drive to the residual can explain (missing dynamics: a mode,
  a stage) — by two routes, each a lower bound, of which the larger is reported: the
  magnitude-squared coherence of residual and drive, weighted by the residual's spectrum (the
  best linear approximation of Pintelon and Schoukens, *System Identification: A Frequency
  Domain Approach*, 2nd ed., Wiley, 2012, ch. 3), with the coherence estimate's bias for the
  number of averaged segments removed (:func:`linear_share`); and the validation energy that
  a rational filter of the drive (an output-error fit, Steiglitz-McBride) fitted on the fit
  part predicts from the drive alone (:func:`filtered_linear_share`).  The coherence misses
  what a lightly damped residual carries from one Welch segment into the next (a mode ringing
  longer than a segment, under a sweep); the filter misses what its order cannot follow.  The
  rest is a nonlinearity no candidate covers, or noise.
* ``noise_rms``: the measurement noise, estimated from the data on every drive: where the
  drive leaves a quiet band, the output's density there; else the floor of the residual's
  spectrum (an upper estimate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

from .calibration import cross_spectra, rms
from .context import residual_floor, welch_length


@dataclass(frozen=True)
class Account:
    """What the final model leaves unexplained (see the module docstring).

    Parameters
    ----------
    unexplained_share : float
        Validation RMS of the final residual over the output's validation RMS about its mean.
    unexplained_linear_share : float
        Share (0-1) of the residual's energy that is linear in the drive.
    noise_rms : float
        The noise floor, in output units.
    noise_source : str
        ``"quiet band"`` (the output's density where the drive has no power) or
        ``"residual floor"`` (the floor of the residual's spectrum, an upper estimate).
    residual_rms : float
        The final model's validation RMS error, in output units.
    """

    unexplained_share: float
    unexplained_linear_share: float
    noise_rms: float
    noise_source: str
    residual_rms: float

    @property
    def over_noise(self) -> float:
        """The residual's RMS in units of the noise floor."""
        return self.residual_rms / self.noise_rms if self.noise_rms > 0 else math.inf

    def sentence(self, named: bool) -> str:
        """One sentence for the report.

        Parameters
        ----------
        named : bool
            Whether the diagnosis named a cause (the extended, else the calibrated model).

        Returns
        -------
        str
            The sentence, without a final full stop.
        """
        head = (
            f"the {'extended' if named else 'calibrated'} model leaves {self.unexplained_share:.0%} of the "
            f"output unexplained, {self.over_noise:.2g}× the noise floor"
        )
        if self.over_noise < 2:
            return head + ": about what noise leaves"
        if self.unexplained_linear_share >= 0.5:
            return (
                head + f"; {self.unexplained_linear_share:.0%} of it is linear in the drive: missing dynamics "
                "(a mode, a stage, a compliance) that no candidate placed"
            )
        return (
            head + f"; most of it ({1 - self.unexplained_linear_share:.0%}) is not linear in the drive: a "
            "nonlinearity or memory that no candidate covers"
        )

    def as_json(self) -> dict:
        """The account as a JSON object (part of :meth:`Report.as_json`).

        Returns
        -------
        dict
            The five fields by name.
        """
        return {
            "unexplained_share": self.unexplained_share,
            "unexplained_linear_share": self.unexplained_linear_share,
            "noise_rms": self.noise_rms,
            "noise_source": self.noise_source,
            "residual_rms": self.residual_rms,
        }


def linear_share(u: np.ndarray, e: np.ndarray, fs: float) -> float:
    """Share (0-1) of the energy of ``e`` that is linear in ``u``: Σ γ²·P_ee / Σ P_ee over the
    frequencies above 0, γ² the coherence of ``e`` and ``u`` less its bias 1/K for K averaged
    segments.

    Parameters
    ----------
    u, e : ndarray
        The drive and the residual, uniformly sampled.
    fs : float
        Sampling rate (Hz).

    Returns
    -------
    float
    """
    f, Puu, Pee, Pue = cross_spectra(u, e, fs)
    nper = welch_length(len(u), 8, 15)
    segments = max(2.0 * len(u) / nper - 1.0, 2.0)
    bias = 1.0 / segments
    coh = np.abs(Pue) ** 2 / np.maximum(Puu * Pee, 1e-300)
    coh = np.clip((coh - bias) / (1 - bias), 0.0, 1.0)
    keep = (f > 0) & (Puu > 1e-10 * Puu.max(initial=0.0))
    total = float(np.sum(Pee[f > 0]))
    return float(np.sum(coh[keep] * Pee[keep]) / total) if total > 0 else 0.0


#: orders (poles, and zeros less one) of the filters :func:`filtered_linear_share` tries
ORDERS = (2, 4, 8, 16)
#: at most this many Steiglitz-McBride passes per order
PASSES = 10


def _arx(u: np.ndarray, e: np.ndarray, rows: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """(denominator, numerator) of the order-``m`` ARX fit e[n] = Σ a_i·e[n−i] + Σ b_j·u[n−j]
    on ``rows`` (linear least squares, columns scaled to unit norm)."""
    A = np.column_stack([e[rows - i] for i in range(1, m + 1)] + [u[rows - j] for j in range(m + 1)])
    scale = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    coef = np.linalg.lstsq(A / scale, e[rows], rcond=None)[0] / scale
    return np.concatenate([[1.0], -coef[:m]]), coef[m:]


def _stable(den: np.ndarray) -> bool:
    return bool(np.max(np.abs(np.roots(den)), initial=0.0) < 1.0)


def filtered_linear_share(u: np.ndarray, e: np.ndarray, val: np.ndarray) -> float:
    """Share (0-1) of the validation energy of ``e`` (about its mean) that a linear filter of
    ``u`` fitted on the fit part (``~val``) predicts from ``u`` alone.

    The filters B(q)/A(q) of the orders m in :data:`ORDERS` (m poles, m + 1 numerator terms)
    are output-error fits by the iteration of Steiglitz and McBride ("A technique for the
    identification of linear systems", *IEEE Trans. Automatic Control* 10(4), 1965,
    pp. 461-464): an ARX fit e[n] = Σ a_i·e[n−i] + Σ b_j·u[n−j] by linear least squares on the
    samples whose lag window lies in the fit part, then up to :data:`PASSES` refits of the same
    form on the drive and the residual both filtered by 1/A(q) of the pass before, which turns
    the equation error into the output error (an ARX fit alone weighs the noise by A(q) and
    misplaces lightly damped poles).  The equations are the fit part's; through the filter's
    memory its filtered residual also carries earlier held-out samples, which lends a filter
    of at most 2·max(ORDERS) + 1 coefficients little (the tests' signal-to-noise splits come
    out as the analytic share).  Each filter is simulated from the drive alone over the record
    (from rest; an unstable one is dropped); the order whose simulation errs least on the fit part is scored on the
    validation part: one less the validation error's energy over the residual's (each about
    its mean, as the coherence leaves the mean out), 0 when no filter predicts anything.

    Parameters
    ----------
    u, e : ndarray
        The drive and the residual, uniformly sampled.
    val : ndarray of bool
        The validation part.

    Returns
    -------
    float
    """
    u, e, val = np.asarray(u, float), np.asarray(e, float), np.asarray(val, bool)
    fit = ~val
    if not fit.any() or not val.any():
        return 0.0
    u0, e0 = u - u[fit].mean(), e - e[fit].mean()
    inside = np.concatenate([[0], np.cumsum(fit)])
    best, best_err = None, math.inf
    for m in ORDERS:
        rows = np.arange(m, e.size)
        rows = rows[inside[rows + 1] - inside[rows - m] == m + 1]
        if rows.size < 10 * (2 * m + 1):
            continue
        den, num = _arx(u0, e0, rows, m)
        if not _stable(den):
            continue
        sim = signal.lfilter(num, den, u0)
        for _ in range(PASSES):
            den_k, num_k = _arx(signal.lfilter([1.0], den, u0), signal.lfilter([1.0], den, e0), rows, m)
            if not _stable(den_k):
                break
            converged = np.allclose(den_k, den, rtol=1e-9, atol=1e-12)
            den, num = den_k, num_k
            sim = signal.lfilter(num, den, u0)
            if converged:
                break
        err = float(np.mean((e0 - sim)[fit] ** 2))
        if err < best_err:
            best, best_err = sim, err
    if best is None:
        return 0.0
    left, whole = (e0 - best)[val], e0[val]
    spread = float(np.sum((whole - whole.mean()) ** 2))
    share = 1.0 - float(np.sum((left - left.mean()) ** 2)) / spread if spread > 0 else 0.0
    return min(max(share, 0.0), 1.0)


def incoherent_rms(u: np.ndarray, e: np.ndarray, fs: float) -> float:
    """RMS of the part of ``e`` that no linear filter of ``u`` explains: measurement noise plus
    any distortion nonlinear in the drive, an upper estimate of the noise on a drive that leaves
    no quiet band (on a record with nothing to find the residual is the noise, white or
    coloured, and all of it is incoherent with the drive).

    Parameters
    ----------
    u, e : ndarray
        The drive and the residual, uniformly sampled.
    fs : float
        Sampling rate (Hz).

    Returns
    -------
    float
        The RMS, in the units of ``e``.
    """
    e = np.asarray(e, float) - float(np.mean(e))
    return rms(e) * math.sqrt(max(1.0 - linear_share(u, e, fs), 0.0))


def account(u: np.ndarray, y: np.ndarray, prediction: np.ndarray, val: np.ndarray, fs: float, noise) -> Account:
    """The account of a final model's ``prediction`` of ``y`` (see the module docstring).

    Parameters
    ----------
    u, y, prediction : ndarray
        Drive, measured output and the final model's prediction, on every sample.
    val : ndarray of bool
        The validation part.
    fs : float
        Sampling rate (Hz).
    noise : float or None
        The noise floor from a quiet band of the drive, if the record has one.

    Returns
    -------
    Account
    """
    e = y - prediction
    spread = rms(y[val] - y[val].mean())
    res = rms(e[val])
    if noise:
        floor, source = float(noise), "quiet band"
    else:
        floor, source = residual_floor(e, fs), "residual floor"
    return Account(
        res / spread if spread > 0 else math.inf,
        max(linear_share(u, e, fs), filtered_linear_share(u, e, val)),
        floor,
        source,
        res,
    )
