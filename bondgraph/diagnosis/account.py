"""What stays unexplained: an honest account of every answer, ``none`` included.

* ``unexplained_share``: the final model's validation RMS error over the output's RMS about
  its mean (on the validation part): 0 is a perfect model, 1 a model that explains nothing.
* ``unexplained_linear_share``: how much of that residual's energy is linear in the drive —
  what a linear filter from the drive to the residual can explain (missing dynamics: a mode,
  a stage) — measured by the magnitude-squared coherence of residual and drive, weighted by
  the residual's spectrum (the best linear approximation of Pintelon and Schoukens,
  *System Identification: A Frequency Domain Approach*, 2nd ed., Wiley, 2012, ch. 3), with
  the coherence estimate's bias for the number of averaged segments removed.  The rest is a
  nonlinearity no candidate covers, or noise.
* ``noise_rms``: the measurement noise, estimated from the data on every drive: where the
  drive leaves a quiet band, the output's density there; else the floor of the residual's
  spectrum (an upper estimate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

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
        linear_share(u, e, fs),
        floor,
        source,
        res,
    )
