"""The null: the best linear explanation of the data before any effect is named.

1. **Which parameters.** Every parameter the model's linear dynamics depend on is a
   candidate.  Their normalised sensitivities (output change per relative change, on the fit
   part, with the output's own direction and the offset projected out, since the sensor gain
   and offset are solved exactly) are selected greedily, as a pivoted QR does: a parameter is
   calibrated if what it does to the output is not already done by those kept before it (the
   model file's ``CALIBRATE`` patterns first, then by size); the others are held at the
   model's values and reported with the reason.  After the fit, a held parameter whose
   sensitivity alone explains a share ``diagnosis.residual_share`` of the residual is
   calibrated too (the pivots compare parameters with each other, the residual asks the data),
   and so is one whose change across its tolerance moves the output by
   ``diagnosis.tolerance_z`` times the calibrated model's residual (:func:`visible_within_tolerance`:
   the data pin it down within a plausible device's spread).
2. **Bounds.**  Within ×/÷ ``diagnosis.spread`` of the model's values and the parameter's
   declared bounds; the sensor gain and offset are free.  The output's delay behind the drive
   (the measurement chain's: sensor electronics, sampling skew) is solved within ±0.5 sample
   of the recorded rate (also on a decimated record: a wider range trades against the model's
   own dynamics on narrow-band drives) when its effect is clearly apart from the parameters'
   (else, or when it ends on that bound, it is held at 0 and reported).
3. **Fit.** On the empirical frequency response first (multi-start, coherence-weighted,
   gain removed, both signs of the sensor tried: free of the local minima lightly damped
   modes give a time-domain fit), then
   on the time series by variable projection (gain and offset solved at every step); without
   a frequency response, from the model's values and the best three of 48 random points
   within ×/÷2 of them.  When the frequency response's start ends on a search bound, those
   random points are tried too and the better fit kept: a tone near a lightly damped
   resonance is matched in amplitude and phase by a heavily damped mode elsewhere with a large
   sensor gain, a local minimum on the damping's bound.
4. **The plausible device.**  Parameters that end outside their tolerance (the model file's
   ``TOLERANCE``, else ``diagnosis.tolerance``: manufacturing spread) make the null an
   implausible device; the calibration within tolerance is then fitted too, and linear
   structural causes must explain what the implausible values explain (an input stage or a
   missing mode can hide behind a 7× capacitance).  Its held parameters are held where the
   whole set's scale symmetry takes them (:func:`~bondgraph.diagnosis.gauge.scale_start`).
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np
from scipy.optimize import least_squares

from ..fit.identify import Spec
from ..linear.sensitivity import sensitivity
from ..support.errors import UsageError
from .context import SENSOR_GAIN, Context, State, welch, welch_length
from .gauge import fix_scales, scale_start
from .pool import fork_map
from .projection import forward_differences, projected_fit


@dataclass
class Calibration:
    """Outcome of the linear calibration.

    Parameters
    ----------
    values : dict of str to float
        Every linear parameter's value after the calibration.
    nominal : dict of str to float
        The model file's values.
    free : list of str
        The parameters calibrated.
    held : dict of str to str
        Parameters held at the model's value, with why.
    bounds : dict of str to tuple of float
        Search bounds of the |value| of each free parameter.
    at_bounds : list of str
        Free parameters that ended on a search bound.
    gain : float
        The sensor gain.
    offset : float
        The output offset, output units.
    rms_fit : float
        RMS error on the fit part, output units.
    rms_validation : float
        RMS error on the validation part, output units.
    success : bool
        The optimiser's success flag.
    message : str
        The optimiser's message.
    route : str
        How the calibration ran: ``"time series"``, or ``"frequency response, then time
        series"``.
    plausible : dict of str to tuple of float, optional
        |value| bounds of a plausible device.
    outside : dict of str to float, optional
        Calibrated parameters outside their tolerance, with value / model's value.
    rms_plausible : float, optional
        Validation RMS of the plausible device, when it differs.
    delay : float, optional
        Delay of the measured output behind the drive, s.
    drift : float, optional
        Linear sensor drift removed from the record, output units per second.
    notes : list of str, optional
        Notes for the report.
    """

    values: dict[str, float]
    nominal: dict[str, float]
    free: list[str]
    held: dict[str, str]
    bounds: dict[str, tuple[float, float]]
    at_bounds: list[str]
    gain: float
    offset: float
    rms_fit: float
    rms_validation: float
    success: bool
    message: str
    route: str
    #: |value| bounds of a plausible device (each parameter's tolerance around the model's value)
    plausible: dict[str, tuple[float, float]] = field(default_factory=dict)
    #: calibrated parameters outside their tolerance, with value / model's value
    outside: dict[str, float] = field(default_factory=dict)
    #: validation RMS of the plausible device (the calibration within tolerance), when it differs
    rms_plausible: float | None = None
    #: delay of the measured output behind the drive (s): the measurement chain's, solved with
    #: the linear parameters
    delay: float = 0.0
    #: linear sensor drift solved with the parameters and removed from the record (output
    #: units per second), when asked for (``drift``)
    drift: float | None = None
    notes: list[str] = field(default_factory=list)

    def as_json(self) -> dict:
        """The calibration as a JSON object (``calibration`` of :meth:`Report.as_json`).

        Returns
        -------
        dict
            ``params``, ``held``, ``nominal``, ``bounds``, ``at_bounds``, ``sensor_gain``,
            ``offset``, RMS errors, the plausible device's numbers, ``delay``, ``drift`` and
            the optimiser's verdict.
        """
        return {
            "params": {k: self.values[k] for k in self.free},
            "held": self.held,
            "nominal": {k: self.nominal[k] for k in self.free},
            "bounds": self.bounds,
            "at_bounds": self.at_bounds,
            "sensor_gain": self.gain,
            "offset": self.offset,
            "rms_fit": self.rms_fit,
            "rms_validation": self.rms_validation,
            "success": self.success,
            "message": self.message,
            "route": self.route,
            "outside_tolerance": self.outside,
            "rms_plausible": self.rms_plausible,
            "delay": self.delay,
            "drift": self.drift,
        }


def patterns(names: Sequence[str], pats: Sequence[str] | None) -> list[str]:
    """The names matching any of the glob patterns, in pattern order.

    Parameters
    ----------
    names : sequence of str
        The names.
    pats : sequence of str or None
        Glob patterns.

    Returns
    -------
    list of str
        The matching names, each once.
    """
    out: list[str] = []
    for pat in pats or ():
        out += [n for n in names if fnmatch.fnmatchcase(n, pat) and n not in out]
    return out


def linear_parameters(ctx: Context) -> list[str]:
    """Parameters of the working model's linear dynamics (nonzero, not the sensor gain).

    Parameters
    ----------
    ctx : Context
        The prepared record.

    Returns
    -------
    list of str
        Their names.
    """
    from ..linear.lti import LTI

    lti = ctx.lti or LTI(ctx.eqs, ctx.input, ctx.output)
    return [n for n in lti.parameters if n != SENSOR_GAIN and ctx.ident.current(n) != 0.0]


def param_bounds(ctx: Context, name: str, value: float, factor: float | None = None) -> tuple[float, float]:
    """|value| bounds: ×/÷ ``factor`` (default the setting ``diagnosis.spread``), within the
    declared bounds.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    name : str
        The parameter.
    value : float
        Its value.
    factor : float, optional
        The spread.

    Returns
    -------
    lower : float
        Lower bound of |value|.
    upper : float
        Upper bound of |value|.
    """
    spread = ctx.settings.spread if factor is None else factor
    lo, hi = abs(value) / spread, abs(value) * spread
    decl = ctx.model.all_parameters().get(name)
    if decl is not None and decl.bounds is not None and value > 0:
        lo, hi = max(lo, decl.bounds[0]), min(hi, decl.bounds[1])
    return lo, max(hi, lo * (1 + 1e-9))


def sensitivities(ctx: Context, names: Sequence[str], values: dict, raw: np.ndarray, rel: float = 0.01):
    """Output change per relative change of each parameter, on the fit part, with the
    directions of the output itself and of a constant (sensor gain, offset) projected out.

    Parameters
    ----------
    ctx : Context
        The diagnosis context (its identification problem and fit samples).
    names : sequence of str
        The parameters.
    values : dict
        Parameter values by name, where the derivatives are taken.
    raw : ndarray
        The raw prediction (sensor gain 1, no offset) at ``values``.
    rel : float
        The relative step of the forward differences.

    Returns
    -------
    ndarray
        One column per parameter, one row per fit sample (output units per unit relative
        change)."""
    idx = ctx.ident.fit_idx
    cols = []
    for n in names:
        v = dict(values)
        v[n] = values[n] * math.exp(rel)
        cols.append((ctx.ident.predict(v) - raw)[idx] / rel)
    S = np.column_stack(cols) if cols else np.zeros((idx.size, 0))
    Q, _ = np.linalg.qr(np.column_stack([raw[idx], np.ones(idx.size)]))
    return S - Q @ (Q.T @ S)


#: why :func:`select` holds a parameter whose sensitivity is nil (the residual cannot ask for it)
NO_EFFECT = "no visible effect on the output in these data"


def select(S: np.ndarray, names: Sequence[str], priority: Sequence[str], tol: float, scale: float):
    """Greedy pivoted selection of identifiable columns (see the module docstring).
    Returns (kept names, {held name: reason}).

    Parameters
    ----------
    S : numpy.ndarray
        Sensitivities, one column per name.
    names : sequence of str
        The parameters.
    priority : sequence of str
        Names tried first.
    tol : float
        Pivot tolerance relative to the largest column.
    scale : float
        Norm of the output's variation (columns below 1e-6 of it have no effect).

    Returns
    -------
    kept : list of str
        The identifiable parameters.
    held : dict of str to str
        The others, with why.
    """
    norms = np.linalg.norm(S, axis=0)
    ref = float(norms.max()) if norms.size else 0.0
    order = sorted(range(len(names)), key=lambda j: (names[j] not in priority, -norms[j]))
    kept, held, basis = [], {}, []
    for j in order:
        r = S[:, j].copy()
        for b in basis:
            r -= b * (b @ r)
        nr = float(np.linalg.norm(r))
        if norms[j] <= 1e-6 * scale:
            held[names[j]] = NO_EFFECT
        elif nr < tol * ref or nr < 1e-6 * scale:
            corr = [names[k] for k in kept if abs(S[:, k] @ S[:, j]) > 0.5 * norms[k] * norms[j]]
            held[names[j]] = (
                "its effect is a pure output scale (the sensor gain)"
                if not corr
                else f"not separable from {', '.join(corr)} and the sensor gain"
            )
        else:
            kept.append(j)
            basis.append(r / nr)
    return [names[k] for k in kept], held


def _held_columns(ctx: Context, names: Sequence[str], free: Sequence[str], held: Mapping[str, str], values: dict, sol):
    """The held parameters the residual may ask for, and what :func:`residual_asks` and
    :func:`visible_within_tolerance` weigh them by: (names, their sensitivities at the
    calibrated values with the movable kept ones', the sensor gain's and the offset's projected
    out, the same before the projection, the residual on the fit part with them projected out,
    its energy before); None when there is nothing to ask."""
    cands = [n for n in held if n in names and held[n] != NO_EFFECT]
    idx = ctx.ident.fit_idx
    r = (ctx.y - sol.columns @ sol.coef)[idx]
    energy = float(r @ r)
    if not cands or energy <= 0:
        return None
    S = sensitivities(ctx, list(free) + cands, values, sol.columns[:, 0]) * float(sol.coef[0])
    movable = [i for i in range(len(free)) if i not in sol.at_bounds]
    Q, _ = np.linalg.qr(np.column_stack([sol.columns[idx], S[:, movable]]))
    C = S[:, len(free) :]
    return cands, C - Q @ (Q.T @ C), C, r - Q @ (Q.T @ r), energy


def residual_asks(
    ctx: Context, names: Sequence[str], free: Sequence[str], held: Mapping[str, str], values: dict, sol
) -> dict[str, float]:
    """Held parameters the calibrated model's residual asks for, each with the factor one
    Gauss-Newton step would move it by: greedily, the held parameter whose sensitivity (at the
    calibrated values, beside the kept ones', the sensor gain and offset) alone explains at
    least ``diagnosis.residual_share`` of the residual's energy, with a step within ×/÷
    ``diagnosis.spread``.  The pivot rule of :func:`select` compares sensitivities with each
    other, not with the data: a sharp mode's frequency moves the output by many times its size
    and hides a second mode's damping that the data plainly show (a missing parameter a
    structural cause would then stand in for).  A kept parameter that ended on its search
    bound is not projected out: it cannot move further, and a held parameter that duplicates it
    (a stiffness beside a damping that sets only their ratio) can carry the fit past that bound.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    names : sequence of str
        Every linear parameter.
    free : sequence of str
        The calibrated ones.
    held : mapping of str to str
        The held ones, with why.
    values : dict
        The calibrated values.
    sol : Projected
        The calibration's solution.

    Returns
    -------
    dict of str to float
        Held name → the factor one step would move it by.
    """
    share = ctx.settings.residual_share
    columns = _held_columns(ctx, names, free, held, values, sol) if share < 1 else None
    if columns is None:
        return {}
    cands, C, full, r, energy = columns
    full = np.linalg.norm(full, axis=0)
    limit = math.log(ctx.settings.spread)
    asked: dict[str, float] = {}
    while True:  # ends: each round asks for one more parameter or stops
        nc = np.linalg.norm(C, axis=0)
        proj = C.T @ r
        step = proj / np.maximum(nc**2, 1e-300)
        gain = proj**2 / np.maximum(nc**2, 1e-300) / energy
        ok = (nc >= 0.1 * full) & (np.abs(step) <= limit) & (gain >= share)
        ok[[cands.index(n) for n in asked]] = False
        if not ok.any():
            break
        j = int(np.argmax(np.where(ok, gain, -1.0)))
        asked[cands[j]] = math.exp(step[j])
        q = C[:, j] / nc[j]
        r = r - q * (q @ r)
        C = C - np.outer(q, q @ C)
    return asked


def visible_within_tolerance(
    ctx: Context,
    names: Sequence[str],
    free: Sequence[str],
    held: Mapping[str, str],
    values: dict,
    sol,
    factors: Mapping[str, float],
    sigma: float,
) -> dict[str, float]:
    """Held parameters whose effect within their tolerance stands above the residual: greedily,
    the held parameter whose sensitivity (per unit of its logarithm, at the calibrated values,
    with the kept ones', the sensor gain's, the offset's and those taken before projected out)
    times the logarithm of its tolerance factor has an RMS of at least
    ``diagnosis.tolerance_z`` times ``sigma``, the calibrated model's residual RMS on the fit
    part (at least the noise floor).  Its least-squares estimate then has a standard error of
    at most 1/``tolerance_z`` of its tolerance, the residual taken for noise, so the record pins
    it down within a plausible device's spread.  The residual, not the noise floor alone, is
    the yardstick: with an effect in the record the residual is mostly that effect, and a
    parameter whose small effect stands above the noise but not above the misfit would only
    stand in for it (a resistor's lag for a hysteresis loop).  The pivot rule of :func:`select` measures
    a sensitivity against the largest, not against the noise: on a clean record a parameter
    with a thousandth of the first mode's effect can be half the residual, and a structural
    cause then stands in for it.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    names : sequence of str
        Every linear parameter.
    free : sequence of str
        The calibrated ones.
    held : mapping of str to str
        The held ones, with why.
    values : dict
        The calibrated values.
    sol : Projected
        The calibration's solution.
    factors : mapping of str to float
        Each held parameter's tolerance factor (×/÷).
    sigma : float
        The residual's RMS (at least the noise floor's), output units.

    Returns
    -------
    dict of str to float
        Held name → its effect within tolerance in units of ``sigma``.
    """
    z = ctx.settings.tolerance_z
    columns = _held_columns(ctx, names, free, held, values, sol) if sigma > 0 and math.isfinite(z) else None
    if columns is None:
        return {}
    cands, C, _, _, _ = columns
    width = np.array([math.log(factors[n]) for n in cands]) / (sigma * math.sqrt(C.shape[0]))
    seen: dict[str, float] = {}
    while True:  # ends: each round takes one more parameter or stops
        nc = np.linalg.norm(C, axis=0)
        stand = nc * width
        stand[[cands.index(n) for n in seen]] = -1.0
        j = int(np.argmax(stand))
        if stand[j] < z:
            break
        seen[cands[j]] = float(stand[j])
        q = C[:, j] / nc[j]
        C = C - np.outer(q, q @ C)
    return seen


def _delay_identifiable(
    ctx: Context,
    S: np.ndarray,
    names: Sequence[str],
    free: Sequence[str],
    nominal: dict,
    raw0: np.ndarray,
    scale: float,
) -> bool:
    """Whether the output's delay behind the drive (per sample of the recorded rate) does
    something to the output that the calibrated parameters and the sensor gain do not (the
    pivot rule of :func:`select`, the delay taken last)."""
    idx = ctx.ident.fit_idx
    step = 0.1  # recorded samples
    shifted = ctx.ident.predict(nominal, drive=ctx.drive_with_delay(step * ctx.fs / ctx.source_rate))
    col = ((shifted - raw0)[idx] / step)[:, None]
    Q, _ = np.linalg.qr(np.column_stack([raw0[idx], np.ones(idx.size)]))
    col = col - Q @ (Q.T @ col)
    kept = S[:, [names.index(n) for n in free]]
    ref = max(float(np.max(np.linalg.norm(S, axis=0))) if S.size else 0.0, float(np.linalg.norm(col)))
    full = float(np.linalg.norm(col))
    if kept.size:
        Qk, _ = np.linalg.qr(kept)
        col = col - Qk @ (Qk.T @ col)
    nr = float(np.linalg.norm(col))
    # a delay is a nuisance parameter: solved only when clearly apart from the model's own
    # (more than 0.1 rad from their span), else it trades against a time constant
    return nr >= ctx.settings.identifiable * ref and nr >= 0.1 * full and nr >= 1e-6 * scale


#: a frequency whose output is at most this coherent with the input (magnitude-squared: as much
#: noise as response) is not resolved by the record
RESOLVED_COHERENCE = 0.5
#: ... unless the output's spectral density there is at least this many times the noise floor's
#: (the H1 coherence also dips at a resonance narrower than the Welch bins, with no noise at all:
#: a bias of the estimate, not a lack of information)
RESOLVED_SNR = 100.0


def cross_spectra(u: np.ndarray, y: np.ndarray, fs: float):
    """(f Hz, Puu, Pyy, Puy): the input's, the output's and their cross density (:func:`welch`,
    segments of an eighth of the record up to 2**15 samples).

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    y : numpy.ndarray
        The measured output.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    tuple of numpy.ndarray
        f (Hz), Puu, Pyy and Puy (one-sided densities).
    """
    nper = welch_length(len(u), 8, 15)
    f, Puu = welch(u, fs, nper)
    return f, Puu, welch(y, fs, nper)[1], welch(u, fs, nper, y)[1]


def resolved_spectrum(u: np.ndarray, y: np.ndarray, fs: float, noise_psd: float | None):
    """(ω rad/s, coherence, resolved) at every frequency above 0: the record resolves the
    response at a frequency whose coherence is above :data:`RESOLVED_COHERENCE` or whose
    output density is at least :data:`RESOLVED_SNR` times the noise floor's ``noise_psd``
    (white-noise equivalent, output units² per Hz; None: by the coherence alone).

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    y : numpy.ndarray
        The measured output.
    fs : float
        Sample rate, Hz.
    noise_psd : float or None
        The noise floor's density, output units² per Hz.

    Returns
    -------
    omega : numpy.ndarray
        Angular frequencies, rad/s.
    coherence : numpy.ndarray
        Magnitude-squared coherence, between 0 and 1.
    resolved : numpy.ndarray of bool
        Whether the record resolves the response there.
    """
    f, Puu, Pyy, Puy = cross_spectra(u, y, fs)
    coh = _coherence(Puu, Pyy, Puy)[1:]
    return 2 * np.pi * f[1:], coh, _resolved(coh, Pyy[1:], noise_psd)


def _resolved(coh: np.ndarray, Pyy: np.ndarray, noise_psd: float | None, strict: bool = False) -> np.ndarray:
    """Whether each bin is resolved: coherence at (``strict``: above) :data:`RESOLVED_COHERENCE`,
    or output density at least :data:`RESOLVED_SNR` times ``noise_psd``."""
    resolved = coh > RESOLVED_COHERENCE if strict else coh >= RESOLVED_COHERENCE
    return resolved | (Pyy >= RESOLVED_SNR * noise_psd) if noise_psd else resolved


def _coherence(Puu, Pyy, Puy):
    return np.abs(Puy) ** 2 / np.maximum(Puu * Pyy, 1e-300)


def empirical_frf(u: np.ndarray, y: np.ndarray, fs: float, noise_psd: float | None = None):
    """(ω rad/s, H, coherence) of output/input from :func:`cross_spectra`, at the frequencies the
    record resolves (coherence above :data:`RESOLVED_COHERENCE`, or with ``noise_psd`` the
    output's density :data:`RESOLVED_SNR` times the noise floor's, as :func:`resolved_spectrum`
    says) and the drive excites.

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    y : numpy.ndarray
        The measured output.
    fs : float
        Sample rate, Hz.
    noise_psd : float, optional
        The noise floor's density, output units² per Hz (None: by the coherence alone).

    Returns
    -------
    omega : numpy.ndarray
        Angular frequencies, rad/s.
    H : numpy.ndarray
        Complex H1 estimate, output units per input unit.
    coherence : numpy.ndarray
        Between 0 and 1.
    """
    f, Puu, Pyy, Puy = cross_spectra(u, y, fs)
    coh = _coherence(Puu, Pyy, Puy)[1:]
    keep = (Puu[1:] > 1e-8 * Puu.max()) & _resolved(coh, Pyy[1:], noise_psd, strict=True)
    return 2 * np.pi * f[1:][keep], (Puy[1:] / np.maximum(Puu[1:], 1e-300))[keep], coh[keep]


def fit_frf(
    frf_of,
    z0: np.ndarray,
    lb: np.ndarray,
    ub: np.ndarray,
    w: np.ndarray,
    H: np.ndarray,
    coh: np.ndarray,
    starts: Sequence[np.ndarray] = (),
    random: int = 12,
    max_nfev: int = 60,
    workers: int = 1,
    derivatives=None,
):
    """Multi-start fit of ``frf_of(z)`` (complex, at ``w``) to the measured ``H``: log-magnitude
    (its coherence-weighted mean removed: the sensor gain is solved later) and wrapped phase,
    weighted by √coherence.  Starts: ``z0``, ``starts``, and ``random`` perturbations of z0
    (σ = 0.5 in z), fitted in ``workers`` processes (the same result as one).  ``derivatives(z)``,
    when given, returns ∂ log frf_of(z)/∂z (complex, one row per z) or None: the Jacobian then
    comes from it (from forward differences where it returns None).  Returns the best (z, cost)
    or None.

    Parameters
    ----------
    frf_of : callable
        ``frf_of(z)`` → complex response at ``w``.
    z0 : numpy.ndarray
        Start point.
    lb, ub : numpy.ndarray
        Bounds of z.
    w : numpy.ndarray
        Angular frequencies, rad/s.
    H : numpy.ndarray
        The measured response at ``w``.
    coh : numpy.ndarray
        Its coherence at ``w``.
    starts : sequence of numpy.ndarray, optional
        Further start points.
    random : int, optional
        Number of random perturbations of z0.
    max_nfev : int, optional
        Evaluation budget per start.
    workers : int, optional
        Processes.
    derivatives : callable, optional
        ``derivatives(z)`` → ∂ log frf_of(z)/∂z, or None.

    Returns
    -------
    tuple of (numpy.ndarray, float) or None
        The best z and its cost, or None when every start failed.
    """
    wt = np.sqrt(coh)
    share = coh / np.sum(coh)  # the weights of the mean log-magnitude
    log_mag, phase = np.log(np.abs(H) + 1e-300), np.angle(H)
    last: dict = {"z": None}

    def fres(z):  # log|·| and angle: the complex log's parts, 3x cheaper
        Hm = frf_of(z)
        re = np.log(np.abs(Hm) + 1e-300) - log_mag
        im = (np.angle(Hm) - phase + np.pi) % (2 * np.pi) - np.pi  # wrapped to [-π, π)
        r = np.concatenate([wt * (re - share @ re), wt * im])
        ok = bool(np.all(np.isfinite(r)))
        last.update(z=np.array(z, float), r=r, ok=ok)
        return r if ok else np.full(r.size, 1e3)

    def jac(z):  # log|H| and the phase are the real and imaginary parts of log H
        if last["z"] is None or not np.array_equal(last["z"], z):
            fres(z)
        if not last["ok"]:
            return np.zeros((2 * w.size, z.size))
        g = derivatives(z)
        if g is None or not np.all(np.isfinite(g)):
            return forward_differences(fres, z, last["r"], lb, ub)
        re = g.real.T
        return np.concatenate([wt[:, None] * (re - share @ re), wt[:, None] * g.imag.T])

    rng = np.random.default_rng(1)
    points = [np.asarray(z0, float)] + [np.asarray(s, float) for s in starts]
    points += [np.clip(points[0] + rng.normal(0, 0.5, points[0].size), lb, ub) for _ in range(random)]

    def solve(p):
        try:
            sol = least_squares(
                fres,
                np.clip(p, lb, ub),
                jac="2-point" if derivatives is None else jac,
                bounds=(lb, ub),
                max_nfev=max_nfev,
            )
        except (ValueError, np.linalg.LinAlgError):
            return None
        return sol.x, float(sol.cost)

    best = None
    for sol in fork_map(solve, points, workers):
        if sol is not None and (best is None or sol[1] < best[1]):
            best = sol
    return best


#: the measured output's delay behind the drive is sought within ± this many samples (recorded rate)
MAX_DELAY = 0.5


def max_delay(ctx: Context) -> float:
    """:data:`MAX_DELAY` in samples of the (possibly decimated) record the diagnosis works on.

    Parameters
    ----------
    ctx : Context
        The prepared record.

    Returns
    -------
    float
        Samples.
    """
    return MAX_DELAY * ctx.fs / ctx.source_rate


def _frf_starts(ctx: Context, specs: list[Spec], values: dict, z0: np.ndarray, delay: bool, workers: int = 1):
    """The free parameters (and the delay, last, if ``delay``) fitted to the empirical frequency
    response (:func:`fit_frf`), or None when the drive leaves too few coherent frequencies.  Both
    signs of the sensor are tried: the nominal model's correlation with the data does not tell it
    when the data's resonance lies on the other side of the drive's frequency."""
    w, H, coh = empirical_frf(ctx.u_recorded, ctx.y, ctx.fs)
    if w.size < 2 * len(z0) + 2:
        return None

    names = [s.name for s in specs]
    last: dict = {"z": None}

    def modal_at(z):  # (values, H, dH) of the linear route at z (the last one kept), or None
        if last["z"] is None or not np.array_equal(last["z"], z):
            vals = dict(values)
            vals.update({s.name: s.from_z(zi) for s, zi in zip(specs, z)})
            modal = sensitivity(ctx.lti, ctx.ident.sim.theta(vals), names, ctx.cut)
            last.update(z=np.array(z, float), at=None if modal is None else (vals, *modal.frequency(w)))
        return last["at"]

    def frf_of(z):
        at = modal_at(z)
        if at is None:  # no modal form: the state space's own frequency response
            vals = dict(values)
            vals.update({s.name: s.from_z(zi) for s, zi in zip(specs, z)})
            Hl = ctx.lti.state_space(ctx.ident.sim.theta(vals), ctx.cut).frequency_response(w)
        else:
            Hl = at[1]
        Hm = Hl * ctx.reading_factor(w)
        return Hm * np.exp(-1j * w * z[-1] * ctx.dt) if delay else Hm

    def derivatives(z):  # ∂ log H/∂z: the output sensitivities' (log parameters), -iω·dt for the delay
        at = modal_at(z)
        if at is None:
            return None
        vals, Hl, dH = at
        with np.errstate(divide="ignore", invalid="ignore"):
            g = dH / Hl * np.array([vals[n] for n in names])[:, None]
        return np.vstack([g, -1j * w * ctx.dt]) if delay else g

    lb, ub = _z_bounds(specs, max_delay(ctx) if delay else None)
    fits = [
        f
        for f in (
            fit_frf(frf_of, z0, lb, ub, w, sign * H, coh, workers=workers, derivatives=derivatives)
            for sign in (1.0, -1.0)
        )
        if f is not None
    ]
    return min(fits, key=lambda f: f[1])[0] if fits else None


def _z_bounds(specs: list[Spec], delay: float | None):
    lb = [s.z_bounds()[0] for s in specs] + ([-delay] if delay else [])
    ub = [s.z_bounds()[1] for s in specs] + ([delay] if delay else [])
    return np.array(lb, float), np.array(ub, float)


def _fit(
    ctx: Context,
    specs: list[Spec],
    nominal: dict,
    z0: np.ndarray,
    starts=(),
    delay: bool = False,
    drift: bool = False,
    resample: bool = True,
    workers: int = 1,
):
    """Frequency response first when the data allow, then the time series by variable projection
    (sensor gain and offset solved exactly, and with ``drift`` a linear drift, its coefficient
    the solution's third, per half the record's span from its middle); with ``delay``, the
    output's delay behind the drive (samples, last in z) too; with ``resample``, when the
    frequency response's start ends on a search bound, the best of a random sample of starts
    too; ``workers``: processes for the frequency response's starts, threads for the time
    series' finite-difference Jacobians (off the exact linear route; on it the Jacobians come
    from the output sensitivities).  (values, delay, raw prediction, solution, route)."""
    idx = ctx.ident.fit_idx
    route = "time series"
    z0 = np.append(z0, 0.0) if delay else np.asarray(z0, float)
    starts = [np.append(s, 0.0) if delay else s for s in starts]
    z_frf = None
    if z0.size and ctx.lti is not None:
        z_frf = _frf_starts(ctx, specs, nominal, z0, delay, workers)
        if z_frf is not None:
            route = "frequency response, then time series"

    def columns(z, rows):
        vals = dict(nominal)
        vals.update({s.name: s.from_z(zi) for s, zi in zip(specs, z)})
        raw = ctx.ident.predict(vals, drive=ctx.drive_with_delay(z[-1]) if delay else None)
        raw = raw if rows is None else raw[rows]
        return np.column_stack([raw, np.ones(raw.size)] + ([trend if rows is None else trend[rows]] if drift else []))

    def derivatives(z, rows):  # ∂columns/∂z: the output sensitivities, the delay's by the drive's
        vals = dict(nominal)
        vals.update({s.name: s.from_z(zi) for s, zi in zip(specs, z)})
        U = None
        if delay:  # the response to the drive's derivative with respect to the delay (samples)
            step = 1e-3
            U = np.column_stack(
                [
                    ctx.drive_with_delay(z[-1]),
                    (ctx.drive_with_delay(z[-1] + step) - ctx.drive_with_delay(z[-1] - step)) / (2 * step),
                ]
            )
        out = ctx.ident.sensitivities(vals, [s.name for s in specs], U, rows)
        if out is None:
            return None
        Y, dY = out
        dA = np.zeros((z.size, rows.size, lin))
        dA[: len(specs), :, 0] = dY[:, :, 0] * np.array([vals[s.name] for s in specs])[:, None]  # log parameters
        if delay:
            dA[-1, :, 0] = Y[:, 1]
        return dA

    exact = derivatives if ctx.lti is not None else None
    trend = ctx.trend if drift else None
    lin = 3 if drift else 2
    lb, ub = _z_bounds(specs, max_delay(ctx) if delay else None)
    first = z0 if z_frf is None else z_frf
    if z_frf is None and z0.size:  # no frequency response to start from: the best of a random sample
        starts = list(starts) + _sampled_starts(columns, ctx.y, idx, z0, lb, ub)
    sol = projected_fit(
        columns,
        ctx.y,
        idx,
        first,
        lb,
        ub,
        [-np.inf] * lin,
        [np.inf] * lin,
        max_nfev=40,
        starts=([] if z_frf is None else [z0]) + list(starts),
        threads=workers,
        derivatives=exact,
    )
    if resample and z_frf is not None and [i for i in sol.at_bounds if i < len(specs)]:
        # the frequency response's start led to a search bound: that may be a local minimum
        # (a lightly damped mode driven by a tone near its resonance, the free sensor gain
        # matching the tone's amplitude), so the best of a random sample is tried too
        sampled = _sampled_starts(columns, ctx.y, idx, z0, lb, ub)
        other = projected_fit(
            columns,
            ctx.y,
            idx,
            sampled[0],
            lb,
            ub,
            [-np.inf] * lin,
            [np.inf] * lin,
            max_nfev=40,
            starts=sampled[1:],
            threads=workers,
            derivatives=exact,
        )
        sol = other if other.cost < sol.cost else sol
    if not sol.success:  # the baseline must be the best linear explanation: go on from the best point
        more = projected_fit(
            columns,
            ctx.y,
            idx,
            sol.z,
            lb,
            ub,
            [-np.inf] * lin,
            [np.inf] * lin,
            max_nfev=int(40 * ctx.settings.polish_effort),
            threads=workers,
            derivatives=exact,
        )
        sol = more if more.cost <= sol.cost else sol
    values = dict(nominal)
    values.update({s.name: s.from_z(zi) for s, zi in zip(specs, sol.z)})
    return values, (float(sol.z[-1]) if delay else 0.0), sol.columns[:, 0], sol, route


def _sampled_starts(
    columns,
    y: np.ndarray,
    idx: np.ndarray,
    z0: np.ndarray,
    lb: np.ndarray,
    ub: np.ndarray,
    n: int = 48,
    keep: int = 3,
    width: float = math.log(2.0),
) -> list[np.ndarray]:
    """The ``keep`` best of ``n`` points drawn uniformly within ×/÷2 of ``z0`` (in the bounds),
    by the projected cost (gain and offset solved): starts for a time-domain fit whose cost has
    many local minima (a lightly damped mode driven near resonance)."""
    rng = np.random.default_rng(2)
    yi = y[idx]
    scored = []
    for _ in range(n):
        z = np.clip(z0 + rng.uniform(-width, width, z0.size), lb, ub)
        A = columns(z, idx)
        if not np.all(np.isfinite(A)):
            continue
        coef, *_ = np.linalg.lstsq(A, yi, rcond=None)
        scored.append((float(np.sum((A @ coef - yi) ** 2)), z))
    scored.sort(key=lambda p: p[0])
    return [z for _, z in scored[:keep]]


def tolerances(names: Sequence[str], tolerance: Mapping[str, float] | None, default: float) -> dict[str, float]:
    """The plausible factor of each parameter: the first matching pattern of ``tolerance`` (the
    model file's ``TOLERANCE``), else ``default`` (setting ``diagnosis.tolerance``).

    Parameters
    ----------
    names : sequence of str
        The parameters.
    tolerance : mapping of str to float or None
        {glob pattern: factor}.
    default : float
        The factor of a parameter no pattern matches.

    Returns
    -------
    dict of str to float
        Name → factor (×/÷).
    """
    default = float(default)
    out = {}
    for n in names:
        out[n] = next((float(f) for pat, f in (tolerance or {}).items() if fnmatch.fnmatchcase(n, pat)), default)
    return out


def calibrate(
    ctx: Context,
    priority: Sequence[str] | None = None,
    say=None,
    tolerance: Mapping[str, float] | None = None,
    workers: int = 1,
    drift: bool = False,
) -> tuple[State, Calibration, State]:
    """Calibrate every identifiable linear parameter (see the module docstring): the best linear
    explanation within ×/÷ ``diagnosis.spread`` (the null), and the plausible device within each
    parameter's tolerance (:func:`tolerances`), which linear structural causes must beat.
    ``workers``: processes for the multi-start fits (the result is the same with one);
    ``drift``: solve a linear sensor drift with the parameters and remove it from the record.
    Returns (null state, its calibration, plausible state).

    Parameters
    ----------
    ctx : Context
        The prepared record.
    priority : sequence of str, optional
        Names or glob patterns preferred when parameters cannot be told apart.
    say : callable, optional
        ``say(line)`` receives progress notes.
    tolerance : mapping of str to float, optional
        {glob pattern: factor} of plausible spread.
    workers : int, optional
        Processes for the multi-start fits.
    drift : bool, optional
        Solve and remove a linear sensor drift.

    Returns
    -------
    null : State
        The calibrated model's state.
    calibration : Calibration
        How it was calibrated.
    plausible : State
        The plausible device's state.

    Raises
    ------
    UsageError
        A ``CALIBRATE`` or ``TOLERANCE`` pattern matches no parameter.
    """
    say = say or (lambda s: None)
    names = linear_parameters(ctx)
    known = list(ctx.model.all_parameters())
    for pat in priority or ():
        if not patterns(known, [pat]):
            raise UsageError(f"CALIBRATE entry '{pat}' matches no parameter of {ctx.model.name}")
    for pat in tolerance or {}:
        if not patterns(known, [pat]):
            raise UsageError(f"TOLERANCE entry '{pat}' matches no parameter of {ctx.model.name}")
    nominal = {n: ctx.ident.current(n) for n in names}
    factors = tolerances(names, tolerance, ctx.settings.tolerance)  # each parameter's plausible spread
    raw0 = ctx.ident.predict(nominal)
    idx = ctx.ident.fit_idx
    scale = float(np.linalg.norm(ctx.y[idx] - ctx.y[idx].mean())) or 1.0
    S = sensitivities(ctx, names, nominal, raw0)
    free, held = select(S, names, patterns(names, priority), ctx.settings.identifiable, scale)
    bounds = {n: param_bounds(ctx, n, nominal[n]) for n in free}
    specs = [Spec(n, nominal[n], *bounds[n], log=True) for n in free]
    say(
        f"calibrating {', '.join(free) or 'the sensor gain and offset only'}"
        + (f" (held: {', '.join(held)})" if held else "")
    )
    z0 = np.array([s.to_z(s.start) for s in specs])
    with_delay = ctx.lti is not None and _delay_identifiable(ctx, S, names, free, nominal, raw0, scale)
    if ctx.lti is not None and not with_delay:
        held["output delay"] = "not separable from the calibrated parameters"
    values, delay, raw, sol, route = _fit(ctx, specs, nominal, z0, delay=with_delay, drift=drift, workers=workers)
    if with_delay and abs(delay) >= 0.99 * max_delay(ctx):  # a model error the delay mimics: not a delay
        held["output delay"] = (
            f"it went to its search bound (±{MAX_DELAY:g} recorded samples): a model error, not a delay"
        )
        values, delay, raw, sol, route = _fit(ctx, specs, nominal, z0, drift=drift, workers=workers)
    ctx.set_delay(delay)
    asked = residual_asks(ctx, names, free, held, values, sol)
    if asked:
        what = (
            f"{', '.join(asked)} calibrated after all: the first calibration's residual asks for "
            f"{'it' if len(asked) == 1 else 'them'} ({', '.join(f'a step ×{f:.3g}' for f in asked.values())})"
        )
        say(what)
        ctx.notes.append(what)
        for n in asked:
            held.pop(n)
    sigma = max(ctx.noise or 0.0, rms((ctx.y - sol.columns @ sol.coef)[ctx.ident.fit_idx]))
    seen = visible_within_tolerance(ctx, names, free + list(asked), held, values, sol, factors, sigma)
    if seen:
        what = (
            f"{', '.join(seen)} calibrated after all: within {'its' if len(seen) == 1 else 'their'} "
            f"tolerance {'it moves' if len(seen) == 1 else 'they move'} the output by "
            f"{', '.join(f'{z:.3g}×' for z in seen.values())} the calibrated model's residual"
        )
        say(what)
        ctx.notes.append(what)
        for n in seen:
            held.pop(n)
    asked = {**asked, **dict.fromkeys(seen, 1.0)}
    if asked:  # the delay stays at its solved value (ctx); the fit goes on from this one
        free = free + list(asked)
        bounds.update({n: param_bounds(ctx, n, nominal[n]) for n in asked})
        specs = [Spec(n, nominal[n], *bounds[n], log=True) for n in free]
        start = {**values, **{n: values[n] * f for n, f in asked.items()}}
        z1 = np.array([s.to_z(start[s.name]) for s in specs])
        values, _, raw, sol, route = _fit(
            ctx, specs, nominal, z1, starts=[np.array([s.to_z(s.start) for s in specs])], drift=drift, workers=workers
        )
    values, raw, symmetric = fix_scales(ctx, free, values, raw, nominal, factors, bounds)
    if symmetric:
        say(
            "the output cannot tell "
            + "; ".join(_scaled_together(free, e) for e in symmetric)
            + " scaled together: kept nearest the model file's values"
        )
    if drift:
        rate = float(sol.coef[2]) / max(0.5 * ctx.span, 1e-300)
        ctx.remove_drift(rate)
        say(f"sensor drift {rate:.4g} per s solved with the calibration and removed from the record")
    gain, offset, rf, rv = score(ctx, raw)
    plausible = {n: param_bounds(ctx, n, nominal[n], factors[n]) for n in free}
    ctx.plausible = plausible
    outside = {
        n: values[n] / nominal[n]
        for n in free
        if not plausible[n][0] * (1 - 1e-9) <= abs(values[n]) <= plausible[n][1] * (1 + 1e-9)
    }
    cal = Calibration(
        values,
        nominal,
        free,
        held,
        {k: tuple(v) for k, v in bounds.items()},
        [
            name
            for name in ((specs[i].name if i < len(specs) else "delay") for i in sol.at_bounds)
            if name == "delay" or not bounds[name][0] * (1 + 1e-6) < abs(values[name]) < bounds[name][1] * (1 - 1e-6)
        ],
        gain,
        offset,
        rf,
        rv,
        sol.success,
        sol.message,
        route,
        plausible=plausible,
        outside=outside,
        delay=delay * ctx.dt,
        drift=ctx.drift if drift else None,
    )
    state = State(
        ctx.model,
        values,
        raw,
        gain,
        offset,
        ctx.u if ctx.lti is not None else None,
        ctx.model.inputs[ctx.input].symbol if ctx.lti is not None else None,
        [],
        ctx.lti is not None,
    )
    if not outside:
        return state, cal, state
    say(
        f"outside their tolerance: {', '.join(f'{n} ×{r:.3g}' for n, r in outside.items())}; "
        f"calibrating the plausible device too"
    )
    pspecs = [
        Spec(
            n,
            min(max(abs(values[n]), plausible[n][0]), plausible[n][1]) * (1 if values[n] > 0 else -1),
            *plausible[n],
            log=True,
        )
        for n in free
    ]
    pz0 = np.array([s.to_z(s.start) for s in pspecs])
    pstarts = [np.array([s.to_z(nominal[s.name]) for s in pspecs])]
    along = scale_start(
        ctx, names, values, raw, nominal, factors, {n: param_bounds(ctx, n, nominal[n], factors[n]) for n in names}
    )
    base = dict(nominal)
    if along is not None:  # the calibration at the model file's scale, held parameters moved too
        pstarts.append(np.array([s.to_z(along.get(s.name, values[s.name])) for s in pspecs]))
        base.update({n: v for n, v in along.items() if n not in free})
        moved = {n: v / nominal[n] for n, v in along.items() if n not in free and v != nominal[n]}
        if moved:
            what = (
                "the plausible device holds "
                + ", ".join(f"{n} at ×{r:.3g} of the model file's value" for n, r in moved.items())
                + ": where the calibration's scale symmetry takes it"
            )
            say(what)
            ctx.notes.append(what)
    pvalues, _, praw, psol, _ = _fit(
        ctx,
        pspecs,
        base,
        pz0,
        resample=False,
        starts=pstarts,
        workers=workers,
    )
    pvalues, praw, _ = fix_scales(ctx, free, pvalues, praw, nominal, factors, plausible)
    pgain, poffset, _, prv = score(ctx, praw)
    cal.rms_plausible = prv
    pstate = State(ctx.model, pvalues, praw, pgain, poffset, state.drive, state.drive_expr, [], state.linear)
    return state, cal, pstate


def _scaled_together(names: Sequence[str], e: np.ndarray) -> str:
    """A scale symmetry's exponents as text: ``k1, c1 and m1`` or ``R, L and C^-1``."""
    e = e if np.sum(e > 0) >= np.sum(e < 0) else -e
    parts = [n if e[i] == 1 else f"{n}^{int(e[i])}" for i, n in enumerate(names) if e[i]]
    return ", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else parts[0]


def score(ctx: Context, raw: np.ndarray) -> tuple[float, float, float, float]:
    """(sensor gain, offset, RMS on the fit part, RMS on the validation part) of a raw prediction.

    Parameters
    ----------
    ctx : Context
        The prepared record.
    raw : numpy.ndarray
        A raw prediction on every sample.

    Returns
    -------
    tuple of float
        The sensor gain and offset (output units) solved on the fit part, and the RMS errors.

    Raises
    ------
    FloatingPointError
        The prediction is not finite.
    """
    idx = ctx.ident.fit_idx
    if not np.all(np.isfinite(raw)):
        raise FloatingPointError("the prediction is not finite")
    A = np.column_stack([raw[idx], np.ones(idx.size)])
    (g, b), *_ = np.linalg.lstsq(A, ctx.y[idx], rcond=None)
    r = ctx.y - g * raw - b
    return float(g), float(b), rms(r[ctx.ident.fit_mask]), rms(r[ctx.ident.val_mask])


def rms(r: np.ndarray) -> float:
    """Root mean square.

    Parameters
    ----------
    r : numpy.ndarray
        The values.

    Returns
    -------
    float
        The RMS (NaN for no values).
    """
    return float(np.sqrt(np.mean(r**2))) if r.size else float("nan")
