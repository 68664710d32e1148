"""What stays fixed through one diagnosis: the prepared data, the split, the working model
(the nominal model with a sensor gain on its output), its linear route and time-scale cut,
the drive's band and the noise floor; and the :class:`State` a chain step starts from."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import numpy as np
import sympy as sp
from scipy import ndimage, signal, stats

from ..data import Dataset, uniform_step
from ..data.sampling import interpolation_compensated
from ..equations.derivation import derive
from ..fit.identify import Identification, check_varies
from ..linear.lti import LTI, first_input, first_output
from ..model.graph import Model
from ..numerics.simulate import Simulator
from ..support.errors import DataError
from .settings import Settings

SENSOR_GAIN = "sensor.gain"

#: readings of the recorded drive between its samples: ``band-limited`` (the samples of a smooth
#: analog signal, as an anti-aliased acquisition records it; the first-order hold's sinc² loss is
#: compensated) and ``linear`` (the analog drive is the linear interpolation of its samples, as a
#: DAC with linear interpolation or a simulation with a first-order hold makes it)
READINGS = ("band-limited", "linear")


@dataclass
class State:
    """The model a chain step starts from: its structure, values and prediction.

    ``raw`` is its output with sensor gain 1 and no offset; the prediction is
    ``gain·raw + offset``.  ``drive``/``drive_expr`` is what the linear core sees (None once a
    structural extension made the model more than a drive transform of its linear core).

    Parameters
    ----------
    model : Model
        The current model.
    values : dict of str to float
        Its parameter values.
    raw : numpy.ndarray
        Its output on every sample, sensor gain 1, no offset.
    gain : float
        The sensor gain (its sign is the sensor's orientation).
    offset : float
        The output offset, output units.
    drive : numpy.ndarray or None
        The series the linear core sees.
    drive_expr : sympy.Expr or None
        Its expression in the model's inputs.
    causes : list of str, optional
        The causes named so far.
    linear : bool, optional
        No structural extension was named (the model is its core plus drive transforms).
    terms : tuple, optional
        Nonlinear terms in elements' laws named so far.
    core_drive : numpy.ndarray, optional
        The series the linear core sees under those terms.
    core_extra : numpy.ndarray, optional
        The output part outside the core, sensor gain 1.
    additive : AdditiveDrive, optional
        The drive as a sum of effects.
    core_model : Model, optional
        The linear model the held terms extend, when it is not the calibrated nominal one.
    """

    model: Model
    values: dict[str, float]
    raw: np.ndarray
    gain: float
    offset: float
    drive: np.ndarray | None
    drive_expr: sp.Expr | None
    causes: list[str] = field(default_factory=list)
    linear: bool = True
    #: nonlinear terms in elements' laws named so far (see :class:`Extension`), the series the
    #: linear core sees under them (the drive, or its transform) and the output part outside
    #: the core (e.g. an added parallel mode), sensor gain 1
    terms: tuple = ()
    core_drive: np.ndarray | None = None
    core_extra: np.ndarray | None = None
    #: the drive as a sum of effects (:class:`~bondgraph.diagnosis.additive.AdditiveDrive`),
    #: when the extensions named so far were additive
    additive: object | None = None
    #: the linear model the held terms extend when it is not the calibrated nominal model (a
    #: linear structural extension named before them, e.g. a compliant output stage)
    core_model: Model | None = None

    @property
    def prediction(self) -> np.ndarray:
        """gain·raw + offset, output units, on every sample."""
        return self.gain * self.raw + self.offset


class Context:
    """Data, split, working model and linear route of one diagnosis (see the module doc).

    Parameters
    ----------
    model : Model
        The nominal model.
    data : Dataset
        The measured record (resampled here when not uniformly sampled).
    input : str, optional
        The model input the data drive (default: its first declared one).
    output : str, optional
        The compared output (default: its first declared one).
    data_input : str, optional
        The drive's data column (default: the input's name).
    data_output : str, optional
        The output's data column (default: the output's name).
    validation : float, optional
        Share held out as validation blocks.
    say : callable, optional
        ``say(line)`` receives notes on the preparation.
    reading : str, optional
        How the drive is read between its samples (one of ``READINGS``).

    Raises
    ------
    ValueError
        An unknown reading.
    DataError
        The output does not follow the drive (:func:`check_follows`).
    """

    def __init__(
        self,
        model: Model,
        data: Dataset,
        input: str | None = None,
        output: str | None = None,
        data_input: str | None = None,
        data_output: str | None = None,
        validation: float = 0.3,
        say=None,
        reading: str = "band-limited",
        settings: Settings | None = None,
    ):
        say = say or (lambda s: None)
        #: the diagnosis's settings (frozen; :meth:`Settings.from_config` when not given)
        self.settings = settings if settings is not None else Settings.from_config()
        if reading not in READINGS:
            raise ValueError(f"unknown drive reading {reading!r}: one of {', '.join(READINGS)}")
        #: how the recorded drive is read between its samples (see :data:`READINGS`)
        self.reading = reading
        self.notes: list[str] = []
        self.nominal_model = model
        eqs0 = derive(model)
        self.input = input if input is not None else first_input(eqs0)
        self.output = output if output is not None else first_output(eqs0)
        self.data_input, self.data_output = data_input or self.input, data_output or self.output
        if uniform_step(data.t) is None:  # the exact linear route needs a uniform grid
            dt = float(np.median(np.diff(data.t)))
            data = data.resample(dt)
            self.notes.append(f"data not uniformly sampled: resampled at the median step {dt:.4g} s")
        self.source_rate = 1.0 / float(np.median(np.diff(data.t)))
        self.source_samples = len(data)
        self.model = with_sensor_gain(model, self.output)
        self.eqs = derive(self.model)
        lti = LTI(self.eqs, self.input, self.output)
        self.exact = lti.exact
        u = data.column(self.data_input)
        y = data.column(self.data_output)
        check_varies(u, self.data_input, data.path)
        fs = self.source_rate
        check_follows(u, y, fs, self.data_input, self.data_output, data.path, self.settings.min_coherence)
        self.band_hz = drive_band(u, fs)
        self.main_hz = drive_peak(u, fs)
        noise_density = noise_psd(y, u, fs, self.band_hz)
        th0 = _theta(self.eqs)
        self.cut = None
        self.slow_hz: list[float] = []
        #: the lightly damped ones among them (damping ratio < 0.5): the model's resonances
        self.resonance_hz: list[float] = []
        #: the lowest resonance of the whole nominal model, kept or residualised (None without one)
        self.lowest_resonance_hz: float | None = None
        if lti.exact:
            full = lti.state_space(th0).poles()
            light = [abs(p) / (2 * math.pi) for p in full if p.imag != 0 and abs(p.real) < 0.5 * abs(p)]
            self.lowest_resonance_hz = min(light) if light else None
            data, fs = self._decimate(lti, th0, data, fs, output_band(y, fs, noise_density))
            self.cut = self.settings.fast_factor * math.pi * fs
            ss = lti.state_space(th0, self.cut)
            self.slow_hz = sorted({round(abs(p) / (2 * math.pi), 6) for p in ss.poles()})
            self.resonance_hz = sorted(
                {round(abs(p) / (2 * math.pi), 6) for p in ss.poles() if p.imag != 0 and abs(p.real) < 0.5 * abs(p)}
            )
            self.n_states, self.n_fast = lti.n, ss.fast
            if ss.fast:
                fastest_kept = max(self.slow_hz, default=0.0)
                what = (
                    f"the model reduces to its static gain (the static route): every one of its {lti.n} "
                    f"states is faster than the data resolve"
                    if ss.n == 0
                    else f"{ss.fast} of {lti.n} states residualised (quasi-static), {ss.n} kept exactly "
                    f"(slowest removed mode above {self.cut / (2 * math.pi):.4g} Hz, fastest kept "
                    f"{fastest_kept:.4g} Hz)"
                )
                self.notes.append(f"time-scale separation: data at {fs:.4g} Hz (Nyquist {fs / 2:.4g} Hz); {what}")
        else:
            self.n_states, self.n_fast = lti.n, 0
            self.notes.append(
                "the model is not linear in its states: calibration and candidates use the compiled integrator"
            )
        self.fs = fs
        #: white-noise equivalent of the measurement noise in the (decimated) record
        self.noise_psd = noise_density
        self.noise = math.sqrt(noise_density * fs / 2) if noise_density is not None else None
        #: |value| bounds of the plausible device by parameter (set by the calibration)
        self.plausible: dict[str, tuple[float, float]] = {}
        #: equal time blocks of the split (see :func:`drive_sweep`)
        blocks = int(self.settings.blocks)
        sweep = drive_sweep(data.column(self.data_input), fs, blocks, self.settings.sweep_ratio)
        self.n_blocks = blocks if sweep is None else int(self.settings.sweep_blocks)
        if sweep is not None:
            self.notes.append(
                f"the drive sweeps from {sweep[0]:.4g} to {sweep[1]:.4g} Hz: the record is split into "
                f"{self.n_blocks} blocks instead of {blocks}, so that the fit part brackets every "
                f"frequency the validation part holds"
            )
        say(
            f"{len(data)} samples at {fs:.6g} Hz, drive band {self.band_hz:.4g} Hz"
            + (f", {self.n_fast} fast states residualised" if self.n_fast else "")
        )
        self.validation = validation
        #: the drive as recorded (after resampling and decimation)
        self.u_recorded = data.column(self.data_input)
        self._lti = lti if lti.exact else None
        self._data = data
        self._sim = Simulator(self.eqs)
        #: the validation blocks are this many blocks later than the first fold's
        self.shift = 0
        #: delay (in samples) of the measured output behind the drive, solved by the calibration
        self.delay = 0.0
        #: linear sensor drift removed from the output (units per second; see remove_drift)
        self.drift = 0.0
        self.set_delay(0.0)
        #: parameter names of the working model (the linear core of every chain state)
        self.core_parameters = frozenset(p.name for p in self.eqs.params)

    def drive_with_delay(self, delay: float, reading: str | None = None) -> np.ndarray:
        """The recorded drive as the exact route must see it, read as ``reading`` (default the
        context's; band-limited: compensated for the route's linear interpolation) and delayed
        by ``delay`` samples (the measurement chain's delay of the output behind the drive).

        Parameters
        ----------
        delay : float
            Delay in samples (fractional).
        reading : str, optional
            The reading (default: the context's).

        Returns
        -------
        numpy.ndarray
            The drive's samples, drive units.
        """
        reading = reading or self.reading
        if reading == "band-limited":
            return interpolation_compensated(self.u_recorded, delay)
        return interpolation_compensated(self.u_recorded, delay, edge=0.0)

    def reading_factor(self, omega: np.ndarray) -> np.ndarray | float:
        """What the drive's reading multiplies a continuous frequency response by at ``omega``
        (rad/s): 1 band-limited, sinc²(f/fs) linear between samples.

        Parameters
        ----------
        omega : numpy.ndarray
            Angular frequencies, rad/s.

        Returns
        -------
        numpy.ndarray or float
            The factor (1.0 for the band-limited reading).
        """
        if self.reading == "band-limited":
            return 1.0
        return np.sinc(np.asarray(omega, float) * self.dt / (2 * math.pi)) ** 2

    def reading_gap(self, values: dict, gain: float) -> float:
        """RMS difference on the validation part between the outputs of the model at ``values``
        (sensor gain ``gain``) under the two readings of the drive: what the choice of reading
        can change (0 off the exact linear route).

        Parameters
        ----------
        values : dict
            Parameter values.
        gain : float
            The sensor gain.

        Returns
        -------
        float
            The RMS difference, output units.
        """
        if self.lti is None:
            return 0.0
        other = next(r for r in READINGS if r != self.reading)
        raw = self.ident.predict(values)
        alt = self.ident.predict(values, drive=self.drive_with_delay(self.delay, other))
        d = gain * (alt - raw)[self.ident.val_mask]
        return float(np.sqrt(np.mean(d**2)))

    def set_delay(self, delay: float) -> None:
        """Use the drive delayed by ``delay`` samples from now on (data, identification, u).

        Parameters
        ----------
        delay : float
            Delay in samples (fractional).
        """
        self.delay = float(delay)
        cols = {k: self._data.column(k) for k in self._data.names if k != "t"}
        cols[self.data_input] = self.drive_with_delay(delay)
        self.data = Dataset(self._data.t, cols, self._data.metadata, self._data.path)
        self.ident = Identification(
            self._sim,
            self.data,
            self.input,
            self.output,
            self.data_input,
            self.data_output,
            self.validation,
            max_fit_points=self.settings.max_fit_points,
            lti=self._lti,
            cut=self.cut,
            blocks=self.n_blocks,
            shift=self.shift,
        )
        self.u, self.y, self.t = self.ident.u, self.ident.y, self.ident.t
        self.dt = self.ident.dt
        self.lti = self.ident.lti
        self.blocks = _blocks(self.ident.val_mask)

    @property
    def trend(self) -> np.ndarray:
        """A straight line over the record: -1 at its start, 0 at its middle, 1 at its end (a
        sensor drift's shape; its coefficient over half the span is the drift per second)."""
        t = self.t
        return (t - 0.5 * (t[0] + t[-1])) / max(0.5 * (t[-1] - t[0]), 1e-300)

    def remove_drift(self, rate: float) -> None:
        """Subtract a linear sensor drift of ``rate`` (output units per second, zero at the
        record's middle) from the measured output, from now on.

        Parameters
        ----------
        rate : float
            The drift, output units per second.
        """
        t = self._data.t
        cols = {k: self._data.column(k) for k in self._data.names if k != "t"}
        cols[self.data_output] = cols[self.data_output] - rate * 0.5 * (t[-1] - t[0]) * self.trend
        self._data = Dataset(t, cols, self._data.metadata, self._data.path)
        self.drift = float(rate)
        self.set_delay(self.delay)

    def refold(self, shift: int) -> "Context":
        """The same context with the validation blocks ``shift`` blocks later (another fold:
        disjoint from this one's for a shift of 2 with the default split).

        Parameters
        ----------
        shift : int
            Blocks to move the validation blocks by.

        Returns
        -------
        Context
            A shallow copy with its own split.
        """
        other = copy.copy(self)
        other.shift = int(shift)
        other.set_delay(self.delay)
        return other

    def _decimate(self, lti: LTI, th0, data: Dataset, fs: float, y_band: float | None):
        """Decimate while the new Nyquist frequency stays ``decimate_margin`` times above the
        drive's band and 1.25 times above the band where the measured output stands above its
        noise floor (``y_band``: resonances the drive rings, harmonics an effect makes); without
        a noise floor, above every mode of the model the data can resolve instead."""
        margin = self.settings.decimate_margin
        if y_band is not None:
            q = int(min(fs / (2 * margin * max(self.band_hz, 1e-300)), fs / (2 * 1.25 * max(y_band, 1e-300))))
            why = f"the output stands above its noise floor up to {y_band:.4g} Hz"
        else:
            ss = lti.state_space(th0, self.settings.fast_factor * math.pi * fs)
            modes = [abs(p) / (2 * math.pi) for p in ss.poles()]
            q = int(fs / (2 * margin * max([self.band_hz] + modes)))
            why = f"the fastest mode the data resolve is at {max(modes):.4g} Hz" if modes else ""
        q = min(q, len(data) // 2000)
        if q < 2:
            return data, fs
        out = data.decimate(q)
        self.notes.append(
            f"decimated by {q} ({fs:.6g} → {fs / q:.6g} Hz): the drive's band ends near "
            f"{self.band_hz:.4g} Hz" + (f" and {why}" if why else "")
        )
        return out, fs / q

    @property
    def span(self) -> float:
        """The record's duration, s."""
        return float(self.t[-1] - self.t[0])


def _theta(eqs) -> np.ndarray:
    from ..numerics.codegen import parameter_vector

    return parameter_vector(eqs)


def with_sensor_gain(model: Model, output: str) -> Model:
    """A copy of ``model`` whose output ``output`` is multiplied by a parameter ``sensor.gain``
    (1 by default): the sensor's scale, solved exactly by the diagnosis.

    Parameters
    ----------
    model : Model
        The model.
    output : str
        The output the sensor measures.

    Returns
    -------
    Model
        The copy.
    """
    m = model.copy()
    g = m.parameter(SENSOR_GAIN, 1.0, "", "sensor gain (solved exactly by the diagnosis)")
    out = m.outputs[output]
    out.expr = g * out.expr
    return m


def welch_length(n: int, parts: float, top: int) -> int:
    """Welch segment length for ``n`` samples: the largest power of two not above n/parts, within
    2**8..2**top samples, and never longer than the record.

    Parameters
    ----------
    n : int
        Samples in the record.
    parts : float
        About how many segments the record should hold.
    top : int
        Exponent of the longest segment.

    Returns
    -------
    int
        The segment length, samples.
    """
    return int(min(n, 2 ** max(8, min(top, int(math.log2(max(n, 256) / parts))))))


def welch(x: np.ndarray, fs: float, nper: int, y: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(f Hz, density) of ``x``, or the cross density of ``x`` and ``y``: Welch, half-overlapping
    Hann segments of ``nper`` samples, each detrended, averaged over two segmentations of the
    record, one from its first sample and one ending at its last.  One segmentation alone stops
    up to half a segment short of the end, which for a sweep drops its last frequencies.

    Parameters
    ----------
    x : numpy.ndarray
        The signal.
    fs : float
        Sample rate, Hz.
    nper : int
        Segment length, samples.
    y : numpy.ndarray, optional
        A second signal for the cross density.

    Returns
    -------
    f : numpy.ndarray
        Frequencies, Hz.
    density : numpy.ndarray
        One-sided (cross) power spectral density, units² per Hz.
    """
    n = len(x)
    nper = int(min(nper, n))
    step = nper - nper // 2

    def density(a, b):
        if b is None:
            return signal.welch(a, fs, nperseg=nper, detrend="linear")
        return signal.csd(a, b, fs, nperseg=nper, detrend="linear")

    f, P = density(x, y)
    off = (n - nper) % step
    if off:
        P = (P + density(x[off:], None if y is None else y[off:])[1]) / 2
    return f, P


def drive_band(u: np.ndarray, fs: float, share: float = 1e-4) -> float:
    """Frequency (Hz) below which all but ``share`` of the drive's (detrended) power lies.

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    fs : float
        Sample rate, Hz.
    share : float, optional
        The power left above the band.

    Returns
    -------
    float
        The band's upper edge, Hz (Nyquist for a drive without power).
    """
    n = len(u)
    nper = welch_length(n, 4, 16)
    f, P = welch(u, fs, nper)
    c = np.cumsum(P[1:])
    if c.size == 0 or c[-1] <= 0:
        return fs / 2
    k = int(np.searchsorted(c, (1 - share) * c[-1]))
    return float(f[1:][min(k, c.size - 1)])


def drive_peak(u: np.ndarray, fs: float) -> float:
    """Frequency (Hz) where the drive's (detrended) power spectrum peaks.

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    float
        The peak's frequency, Hz (0 for a record too short).
    """
    n = len(u)
    nper = welch_length(n, 4, 16)
    f, P = welch(u, fs, nper)
    return float(f[1 + int(np.argmax(P[1:]))]) if f.size > 1 else 0.0


def drive_held_share(u: np.ndarray, fs: float, length: float, band: float = 0.01) -> float:
    """Share of the record (0-1) lying in holds of the drive: stretches of ``length`` s or
    longer over which it stays within ``band`` of its range (steps, holds, rests between
    bursts; about 0 for sines, triangles, chirps and noise).

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    fs : float
        Sample rate, Hz.
    length : float
        Shortest hold counted, s.
    band : float, optional
        Tolerance as a share of the drive's range.

    Returns
    -------
    float
        The share, between 0 and 1.
    """
    w = 2 * int(round(length * fs / 2)) + 1  # odd: windows centred on a sample
    if w >= len(u):
        return 0.0
    tol = band * float(np.ptp(u))
    still = (ndimage.maximum_filter1d(u, w) - ndimage.minimum_filter1d(u, w)) <= tol
    still[: w // 2] = still[len(u) - w // 2 :] = False  # windows that reach past the record
    return float(ndimage.maximum_filter1d(still.astype(np.uint8), w, mode="constant").mean())


def drive_sweep(u: np.ndarray, fs: float, blocks: int, ratio: float) -> tuple[float, float] | None:
    """(first, last) mean frequency (Hz) of the drive's blocks when it sweeps, else None.

    The record is cut into ``blocks`` equal blocks; each block where the drive moves (RMS about
    its mean at least a tenth of the largest block's) has a power-weighted mean frequency.  The
    drive sweeps when these frequencies are ordered in time (Spearman |ρ| ≥ 0.8) and span a
    factor ``ratio`` (setting ``diagnosis.sweep_ratio``): a chirp, never a periodic drive, steps or noise, whose
    blocks look alike.  A record of fewer than eight samples per block never sweeps.

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    fs : float
        Sample rate, Hz.
    blocks : int
        Number of equal blocks.
    ratio : float
        The span of block frequencies (last over first, or first over last) that makes a sweep.

    Returns
    -------
    tuple of float or None
        (first, last) frequency, Hz, or None.
    """
    if len(u) < 8 * blocks:
        return None
    edges = np.linspace(0, len(u), blocks + 1).astype(int)
    centre, level = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        seg = u[a:b] - np.mean(u[a:b])
        power = np.abs(np.fft.rfft(seg))[1:] ** 2
        f = np.fft.rfftfreq(seg.size, 1.0 / fs)[1:]
        centre.append(float(power @ f / power.sum()) if power.sum() > 0 else 0.0)
        level.append(float(np.std(seg)))
    level = np.asarray(level)
    if level.max() <= 0:
        return None
    c = np.asarray(centre)[level >= 0.1 * level.max()]
    if c.size < 5 or c.min() <= 0 or c.max() / c.min() < ratio:
        return None
    if abs(stats.spearmanr(np.arange(c.size), c).statistic) < 0.8:
        return None
    return float(c[0]), float(c[-1])


def noise_psd(y: np.ndarray, u: np.ndarray, fs: float, band: float) -> float | None:
    """One-sided noise density of ``y`` (units²/Hz) in the frequencies the drive does not
    reach (above 5× its band, where only noise is left), or None if there is no such band.

    Parameters
    ----------
    y : numpy.ndarray
        The measured output.
    u : numpy.ndarray
        The drive's samples.
    fs : float
        Sample rate, Hz.
    band : float
        The drive's band, Hz.

    Returns
    -------
    float or None
        The median density in the quiet band, output units² per Hz.
    """
    n = len(y)
    nper = welch_length(n, 8, 14)
    f, Pyy = welch(y, fs, nper)
    _, Puu = welch(u, fs, nper)
    quiet = (f > 5 * band) & (f < 0.9 * fs / 2) & (Puu < 1e-6 * Puu.max())
    if np.count_nonzero(quiet) < 4:
        return None
    return float(np.median(Pyy[quiet]))


def residual_floor(e: np.ndarray, fs: float, share: float = 0.05) -> float:
    """RMS of the white noise whose density is the ``share`` quantile of the residual ``e``'s
    Welch spectrum below 0.9× Nyquist: the floor under what a model misses in a few bands (an
    upper estimate of the measurement noise when the drive leaves no quiet band for
    :func:`noise_psd`).

    Parameters
    ----------
    e : numpy.ndarray
        The residual.
    fs : float
        Sample rate, Hz.
    share : float, optional
        The quantile.

    Returns
    -------
    float
        The RMS, output units.
    """
    nper = welch_length(len(e), 8, 14)
    f, P = welch(e, fs, nper)
    keep = (f > 0) & (f < 0.9 * fs / 2)
    return float(math.sqrt(np.quantile(P[keep], share) * fs / 2)) if keep.any() else float(np.std(e))


def output_band(y: np.ndarray, fs: float, noise_density: float | None, above: float = 10.0) -> float | None:
    """Highest frequency (Hz) where the output's power density exceeds ``above`` times the
    noise density (Welch, at least 8 segments), or None without a noise estimate.

    Parameters
    ----------
    y : numpy.ndarray
        The measured output.
    fs : float
        Sample rate, Hz.
    noise_density : float or None
        The noise density, output units² per Hz.
    above : float, optional
        The factor over the noise density.

    Returns
    -------
    float or None
        The frequency, Hz.
    """
    if noise_density is None or noise_density <= 0:
        return None
    n = len(y)
    nper = welch_length(n, 8, 14)
    f, Pyy = welch(y, fs, nper)
    loud = np.nonzero(Pyy[1:] > above * noise_density)[0]
    return float(f[1 + loud[-1]]) if loud.size else float(f[1])


def _blocks(mask: np.ndarray) -> list[slice]:
    """Contiguous runs of ``mask`` as slices."""
    d = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return [slice(a, b) for a, b in zip(np.nonzero(d == 1)[0], np.nonzero(d == -1)[0])]


def check_follows(
    u: np.ndarray,
    y: np.ndarray,
    fs: float,
    drive: str,
    output: str,
    path: str | None,
    min_coherence: float,
) -> None:
    """Refuse an output that does not follow the drive: constant (a dead or unplugged
    sensor), or with no coherence with the drive where the drive has power (noise unrelated
    to it: a wrong column, a sensor out of range).  A model can explain nothing in such a
    record, and an answer of no cause would read as a healthy device.

    The coherence is Welch's magnitude-squared coherence, less its bias for the averaged
    segments, averaged over the frequencies that hold the drive's power (weighted by it); the
    record is refused below ``min_coherence`` (setting ``diagnosis.min_coherence``).

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    y : numpy.ndarray
        The measured output.
    fs : float
        Sample rate, Hz.
    drive : str
        The drive's column name (for the message).
    output : str
        The output's column name (for the message).
    path : str or None
        The data file (for the message).
    min_coherence : float
        The least mean coherence, 0-1.

    Raises
    ------
    DataError
        With one line naming the column and what to check.
    """
    where = f"{path}: " if path else ""
    scale = max(float(np.max(np.abs(y))), 1e-300)
    if float(np.ptp(y)) <= 1e-9 * scale:
        raise DataError(
            f"{where}output column '{output}' is constant ({y[0]:g}): it does not follow the drive '{drive}'; "
            f"check the sensor and the column"
        )
    nper = welch_length(len(u), 8, 15)
    f, Puu = welch(u, fs, nper)
    Pyy, Puy = welch(y, fs, nper)[1], welch(u, fs, nper, y)[1]
    bias = 1.0 / max(2.0 * len(u) / nper - 1.0, 2.0)
    coh = np.clip((np.abs(Puy) ** 2 / np.maximum(Puu * Pyy, 1e-300) - bias) / (1 - bias), 0.0, 1.0)
    w = np.where(f > 0, Puu, 0.0)
    mean = float(np.sum(coh * w) / np.sum(w)) if np.sum(w) > 0 else 0.0
    if mean < min_coherence:
        raise DataError(
            f"{where}output column '{output}' does not follow the drive '{drive}' (coherence {mean:.2g} where the "
            f"drive has power): noise unrelated to it; check the sensor, its range and the columns"
        )
