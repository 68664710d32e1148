"""The read-only view a candidate gets of the data, the split and the current model, and the
fitting services it may use (all exact linear where the model allows)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property
from types import MappingProxyType
from typing import Callable, Mapping, Sequence

import numpy as np
import sympy as sp

from ..fit.identify import Identification, Spec
from ..linear.sensitivity import sensitivity
from ..model.graph import Model
from ..numerics.steady import record_start, starts_steady
from ..support.errors import BondGraphError
from .account import incoherent_rms
from .additive import AdditiveDrive, Term
from .calibration import RESOLVED_COHERENCE, empirical_frf, param_bounds, resolved_spectrum, score
from .context import Context, State, drive_held_share, residual_floor
from .lure import Lure
from .projection import forward_step, projected_fit, simulation_deadline
from .screen import FirstOrder, first_order


def _frozen(a: np.ndarray | None) -> np.ndarray | None:
    if a is None:
        return None
    a = np.asarray(a)
    v = a.view()
    v.setflags(write=False)
    return v


@dataclass
class DriveFit:
    """Result of :meth:`View.fit_drive`: coefficients of the basis (in drive units) and of the
    direct columns (in output units at sensor gain 1), the nonlinear parameters z, the
    recalibrated linear values, the raw prediction, and the optimiser's verdict.

    Parameters
    ----------
    coef : numpy.ndarray
        The basis coefficients θ_k, in drive units per basis unit.
    direct : numpy.ndarray
        The direct columns' coefficients, in output units at sensor gain 1.
    z : numpy.ndarray
        The nonlinear parameters fitted.
    values : dict of str to float
        Every parameter value after the fit (the recalibrated linear ones included).
    prediction : numpy.ndarray
        The raw prediction on every sample (sensor gain 1, no offset), output units.
    drive : numpy.ndarray
        u_eff, the drive the linear core now sees, on every sample (drive units).
    success : bool
        The optimiser's success flag.
    message : str
        The optimiser's message.
    at_bounds : list of str
        Parameters (z names, or linear ones) that ended on a search bound.
    additive : AdditiveDrive, optional
        The drive as a sum of effects after an additive fit (``names`` given), else None.
    """

    coef: np.ndarray
    direct: np.ndarray
    z: np.ndarray
    values: dict[str, float]
    prediction: np.ndarray
    drive: np.ndarray
    success: bool
    message: str
    at_bounds: list[str]
    #: the drive as a sum of effects after an additive fit (``names`` given), else None
    additive: AdditiveDrive | None = None


@dataclass(frozen=True)
class Record:
    """The record a candidate is fitted to, and what the engine learnt of it before any
    candidate (read-only arrays).

    Parameters
    ----------
    t, u, y : numpy.ndarray
        Time (s), the recorded drive (input units) and output (output units) on every sample
        (after resampling and decimation).
    dt, fs : float
        The sampling interval (s) and rate (Hz).
    fit_idx : numpy.ndarray
        Sample indices of the fit part.
    fit_mask, val_mask : numpy.ndarray
        Boolean masks of the fit and validation parts.
    input, output : str
        The drive's and the output's names.
    input_symbol : sympy.Symbol
        The drive's symbol in the model.
    noise : float or None
        White-noise equivalent RMS of the measurement noise (output units), or None without
        an estimate.
    band_hz, main_hz : float
        Where the drive's band ends and where its power spectrum peaks (Hz).
    modes_hz : tuple of float
        Frequencies (Hz) of the modes of the calibrated nominal model the data resolve.
    resonances_hz : tuple of float
        ... and of its resonances among them (complex poles with damping ratio < 0.5).
    lowest_resonance_hz : float or None
        The lowest resonance (Hz) of the whole nominal model, resolved or residualised (None
        without one).
    u_recorded : numpy.ndarray
        The drive as recorded, on every sample (its reading between samples aside).
    noise_psd : float or None
        The noise floor's one-sided spectral density (output units²/Hz), or None.
    exact : bool
        The nominal model is linear: the exact linear route (and the Lur'e route of the
        element-law kinds) is open.
    reduced : bool
        Fast states were residualised: the bond graph's structural elements are not all seen.
    state_of : mapping of str to str
        Element → the name of the (first) state it stores in the nominal model's equations
        (the displacement of a spring, the momentum of a mass), read-only.
    """

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    dt: float
    fs: float
    fit_idx: np.ndarray
    fit_mask: np.ndarray
    val_mask: np.ndarray
    input: str
    output: str
    input_symbol: sp.Symbol
    noise: float | None
    band_hz: float
    main_hz: float
    modes_hz: tuple
    resonances_hz: tuple
    lowest_resonance_hz: float | None
    u_recorded: np.ndarray
    noise_psd: float | None
    exact: bool
    reduced: bool
    state_of: Mapping[str, str]

    @classmethod
    def of(cls, ctx: Context) -> Record:
        """The record of a prepared context.

        Parameters
        ----------
        ctx : Context
            The prepared record.

        Returns
        -------
        Record
            Its facts, arrays read-only.
        """
        return cls(
            _frozen(ctx.t),
            _frozen(ctx.u),
            _frozen(ctx.y),
            ctx.dt,
            ctx.fs,
            _frozen(ctx.ident.fit_idx),
            _frozen(ctx.ident.fit_mask),
            _frozen(ctx.ident.val_mask),
            ctx.input,
            ctx.output,
            ctx.model.inputs[ctx.input].symbol,
            ctx.noise,
            ctx.band_hz,
            ctx.main_hz,
            tuple(ctx.slow_hz),
            tuple(ctx.resonance_hz),
            ctx.lowest_resonance_hz,
            _frozen(ctx.u_recorded),
            ctx.noise_psd,
            ctx.lti is not None,
            bool(ctx.n_fast),
            MappingProxyType({o: n for o, n in reversed([(s.origin, str(s.symbol)) for s in ctx.eqs.states])}),
        )

    def held_share(self, length: float) -> float:
        """Share of the record (0-1) in which the measured drive holds still (within 1 % of
        its range) for ``length`` s or longer: steps, holds, rests between bursts.

        Parameters
        ----------
        length : float
            Shortest hold counted, s.

        Returns
        -------
        float
            The share of the record, between 0 and 1.
        """
        return drive_held_share(self.u, self.fs, length)

    def empirical_frf(self):
        """(ω rad/s, H, coherence) of the measured output over the input (Welch), at the bins the
        record resolves (:meth:`resolution_near`'s rule).

        Returns
        -------
        omega : numpy.ndarray
            Angular frequencies of the Welch bins, rad/s.
        H : numpy.ndarray
            Complex H1 estimate, output units per input unit.
        coherence : numpy.ndarray
            Magnitude-squared coherence, between 0 and 1.
        """
        return self._frf

    @cached_property
    def _frf(self):
        """:meth:`empirical_frf`, computed once per record."""
        return empirical_frf(self.u_recorded, self.y, self.fs, self.noise_psd)

    @cached_property
    def resolved(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ω rad/s, coherence, resolved mask) at every Welch bin above 0: what
        :func:`~bondgraph.diagnosis.calibration.resolved_spectrum` returns for the recorded drive
        and the output, computed once per record."""
        return resolved_spectrum(self.u_recorded, self.y, self.fs, self.noise_psd)

    #: coherence above which the record resolves the response (the empirical FRF's bins)
    resolved_coherence = RESOLVED_COHERENCE

    def resolution_near(self, omega: float, width: float = 0.03) -> tuple[float, bool]:
        """(median magnitude-squared coherence, whether the record resolves the response) of
        the measured output with the input within ±``width`` (relative) of ``omega`` (rad/s;
        the nearest Welch bin if none is that close).  Resolved: the coherence is above
        :attr:`resolved_coherence`, or the output's spectral density is at least
        :data:`~bondgraph.diagnosis.calibration.RESOLVED_SNR` times the noise floor's on most
        of those bins (:func:`~bondgraph.diagnosis.calibration.resolved_spectrum`); below, the
        noise is as large as the response.

        Parameters
        ----------
        omega : float
            Angular frequency, rad/s.
        width : float, optional
            Relative half-width of the band.

        Returns
        -------
        coherence : float
            The median coherence, between 0 and 1.
        resolved : bool
            Whether the record resolves the response there.
        """
        w, coh, ok = self.resolved
        near = np.abs(w - omega) <= width * omega
        if not near.any():
            near = np.arange(w.size) == int(np.argmin(np.abs(w - omega)))
        return float(np.median(coh[near])), bool(np.mean(ok[near]) > 0.5)


@dataclass(frozen=True)
class Current:
    """The model a candidate extends: the chain's current model with its values and prediction
    (read-only arrays).

    Parameters
    ----------
    model : Model
        The current model (must not be changed: :meth:`View.rewrite` gives a copy carrying the
        current values).
    values : mapping of str to float
        Its parameter values (read-only).
    calibrated : tuple of str
        The calibrated linear parameters (refitted with a candidate).
    prediction, residual : numpy.ndarray
        Its prediction (output units) and the measured output minus it, on every sample.
    gain : float
        The sensor gain (its sign is the sensor's orientation).
    drive : numpy.ndarray or None
        The series the linear core sees (None once a structural extension made the model more
        than a drive transform of its core).
    drive_expr : sympy.Expr or None
        That series as an expression of the recorded drive.
    additive : AdditiveDrive or None
        The drive as a sum of effects of a base drive (:mod:`.additive`); None when the model
        is not a drive transform of its linear core.
    extra : numpy.ndarray or None
        The part of the output that does not pass through the linear core (e.g. an added
        parallel mode), sensor gain 1; drive-side fits keep it.
    """

    model: Model
    values: Mapping[str, float]
    calibrated: tuple
    prediction: np.ndarray
    residual: np.ndarray
    gain: float
    drive: np.ndarray | None
    drive_expr: sp.Expr | None
    additive: AdditiveDrive | None
    extra: np.ndarray | None

    def drive_plus(self, part: sp.Expr, identity: bool = True) -> sp.Expr:
        """The drive expression after an additive extension adds ``part``, an expression of
        :attr:`additive`'s ``base_expr``; with ``identity=False`` ``part`` replaces the base
        drive's own term.

        Parameters
        ----------
        part : sympy.Expr
            The added part, an expression of the base drive.
        identity : bool, optional
            Keep the base drive's own term (False: ``part`` replaces it).

        Returns
        -------
        sympy.Expr
            The new drive expression.
        """
        expr = self.drive_expr + part
        return expr - self.additive.base_expr if self.additive.identity and not identity else expr


class View:
    """What a candidate sees.  Arrays are read-only; ``current.model`` must not be changed (use
    :meth:`rewrite` for a copy carrying the current values).  ``effort``: a factor on every
    optimiser's evaluation budget (:meth:`fit_drive`, :meth:`fit_model`).

    The engine builds views; a candidate only reads them.  Times are in s, frequencies in Hz
    unless named omega (rad/s); a *raw* prediction is the model's output at sensor gain 1
    without offset, in output units.

    Parameters
    ----------
    ctx : Context
        The prepared record: resampled data, fit and validation split, noise floor, the
        nominal model and its linear core.
    state : State
        The chain's current model, its values, prediction and drive.
    calibrated : sequence of str
        The calibrated linear parameters (refitted with a candidate).
    bounds : mapping of str to tuple of float, optional
        Name → (lower, upper) bounds on a calibrated parameter's magnitude (the plausible
        device's for a linear structural candidate; default ×/÷ ``diagnosis.spread``).
    effort : float, optional
        Factor on every optimiser's evaluation budget.
    """

    def __init__(
        self,
        ctx: Context,
        state: State,
        calibrated: Sequence[str],
        bounds: Mapping[str, tuple[float, float]] | None = None,
        effort: float = 1.0,
    ):
        self._ctx, self._state = ctx, state
        self._effort = float(effort)
        self._bounds = dict(bounds or {})
        #: the record and what the engine learnt of it before any candidate
        self.record = Record.of(ctx)
        #: the diagnosis's settings (:class:`~bondgraph.diagnosis.settings.Settings`, frozen)
        self.settings = ctx.settings
        self._structural = not state.linear
        #: nonlinear terms in elements' laws named so far: (element, partner, term, c, r2)
        self._terms = tuple(state.terms)
        self._core_drive, self._core_extra, self._core_model = state.core_drive, state.core_extra, state.core_model
        drive = _frozen(state.drive)
        #: the model a candidate extends (:class:`Current`)
        self.current = Current(
            state.model,
            MappingProxyType(dict(state.values)),
            tuple(calibrated),
            _frozen(state.prediction),
            _frozen(ctx.y - state.prediction),
            state.gain,
            drive,
            state.drive_expr,
            state.additive
            if state.additive is not None
            else AdditiveDrive(drive, state.drive_expr)
            if state.drive is not None
            else None,
            None,
        )
        if state.drive is not None and ctx.lti is not None:  # the output part outside the core
            extra = state.raw - self.respond([state.drive])[:, 0]
            extra = extra if np.max(np.abs(extra)) > 1e-9 * np.max(np.abs(state.raw)) else np.zeros_like(extra)
            self.current = replace(self.current, extra=_frozen(extra))

    def budget(self, max_nfev: int) -> int:
        """An optimiser's evaluation budget at this view's effort.

        Parameters
        ----------
        max_nfev : int
            The budget at effort 1.

        Returns
        -------
        int
            ``max_nfev`` times the view's effort, at least 1.
        """
        return max(1, int(round(max_nfev * self._effort)))

    # ---- the current model ----------------------------------------------------------------
    def rewrite(self) -> Model:
        """A copy of the current model carrying the current values (to extend).

        Returns
        -------
        Model
            A new model; changing it leaves the view's model alone.
        """
        m = self.current.model.copy()
        known = m.all_parameters()
        m.values.update({k: v for k, v in self.current.values.items() if k in known})
        return m

    @property
    def on_core(self) -> bool:
        """True when the current model is a drive transform of its linear core: a structural
        extension can then extend :meth:`core` and be fitted driven by ``drive``."""
        return self.current.drive is not None and not self._structural and self.record.exact and not self.record.reduced

    def core(self) -> Model:
        """A copy of the linear core carrying the current values: the calibrated nominal model,
        or the linear model the held nonlinear terms extend (one with a linear structural
        extension named before them).

        Returns
        -------
        Model
            A new model.
        """
        m = (self._core_model or self._ctx.model).copy()
        known = m.all_parameters()
        m.values.update({k: v for k, v in self.current.values.items() if k in known})
        return m

    def with_drive(self, model: Model, expr: sp.Expr) -> Model:
        """Make the linear core of ``model`` (the nominal model's elements, states and outputs)
        see ``expr`` where it saw the drive input; the extension's own elements are untouched.

        Parameters
        ----------
        model : Model
            The model to change (a copy from :meth:`rewrite` or :meth:`core`); changed in place.
        expr : sympy.Expr
            The drive the core sees instead of the input symbol (drive units).

        Returns
        -------
        Model
            ``model`` itself.
        """
        nominal = self._ctx.model
        V = self.record.input_symbol
        new = {name: el.xreplace({V: expr}) for name, el in nominal.elements.items() if V in el.free_symbols()}
        for name, el in new.items():
            el.role = getattr(model.elements[name], "role", None)
            model.elements[name] = el
        for name, st in nominal.internal_states.items():
            if V in st.rate.free_symbols:
                model.internal_states[name].rate = st.rate.xreplace({V: expr})
        for name, out in nominal.outputs.items():
            if V in out.expr.free_symbols:
                model.outputs[name].expr = out.expr.xreplace({V: expr})
        return model

    def _nominal_value(self, name: str) -> float:
        """A parameter's value in the model file (before calibration).

        Parameters
        ----------
        name : str
            The parameter.

        Returns
        -------
        float
            Its value, in its unit.
        """
        return self._ctx.ident.current(name)

    def _theta_values(self, values: Mapping[str, float] | None = None) -> np.ndarray:
        """θ of the linear core for the current values (``values`` overriding; others ignored).

        Parameters
        ----------
        values : mapping of str to float, optional
            Parameter values overriding the current ones (others ignored).

        Returns
        -------
        numpy.ndarray
            The core's parameter vector (see :meth:`bondgraph.Simulator.theta`).
        """
        known = self._ctx.core_parameters
        vals = {k: v for k, v in {**self.current.values, **(values or {})}.items() if k in known}
        return self._ctx.ident.sim.theta(vals)

    # ---- linear responses -------------------------------------------------------------------
    def respond(
        self,
        columns: Sequence[np.ndarray] | np.ndarray,
        values: Mapping[str, float] | None = None,
        rows: np.ndarray | None = None,
    ) -> np.ndarray:
        """Output of the linear core (the calibrated nominal dynamics, fast modes residualised,
        sensor gain 1) driven by each column (a sequence of series, or a 2-D array with one
        per column), from where setting ``record.start`` says (by default each column's
        steady state at its first sample, :mod:`bondgraph.numerics.steady`); at the sample
        indices ``rows`` only, if given.

        Parameters
        ----------
        columns : sequence of numpy.ndarray or numpy.ndarray
            Drive series on every sample (drive units).
        values : mapping of str to float, optional
            Parameter values overriding the current ones (others ignored).
        rows : numpy.ndarray, optional
            Sample indices to return.

        Returns
        -------
        numpy.ndarray
            (rows, columns) output, output units at sensor gain 1.
        """
        ctx = self._ctx
        th = self._theta_values(values)
        U = columns if isinstance(columns, np.ndarray) and columns.ndim == 2 else np.column_stack(columns)
        return ctx.lti.state_space(th, ctx.cut).response(ctx.dt, U, rows=rows, steady=starts_steady())

    def _respond_sensitivities(
        self,
        columns: np.ndarray,
        names: Sequence[str],
        values: Mapping[str, float] | None = None,
        rows: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """:meth:`respond` to the columns of the 2-D array ``columns`` and its derivatives with
        respect to the linear core's parameters ``names``: (Y (rows, columns), dY (names, rows,
        columns)) from the output sensitivities (:mod:`bondgraph.linear.sensitivity`), or None
        when the core has no well-conditioned modal form.

        Parameters
        ----------
        columns : numpy.ndarray
            2-D array, one drive series per column (drive units).
        names : sequence of str
            Parameters of the linear core.
        values : mapping of str to float, optional
            Parameter values overriding the current ones (others ignored).
        rows : numpy.ndarray, optional
            Sample indices to return.

        Returns
        -------
        tuple of numpy.ndarray or None
            (Y, dY), dY per unit of each parameter; or None.
        """
        ctx = self._ctx
        modal = sensitivity(ctx.lti, self._theta_values(values), names, ctx.cut)
        return None if modal is None else modal.time(ctx.dt, columns, rows, steady=starts_steady())

    def frequency_response(self, omega: np.ndarray, values: Mapping[str, float] | None = None) -> np.ndarray:
        """The linear core's frequency response at ``omega`` (rad/s) (the current model's after a
        linear structural extension: :attr:`linear_current`), sensor gain 1, with the drive's
        reading and the measurement chain's delay of the output behind the drive (as
        :meth:`respond` sees it).

        Parameters
        ----------
        omega : numpy.ndarray
            Angular frequencies, rad/s.
        values : mapping of str to float, optional
            Parameter values overriding the current ones (others ignored).

        Returns
        -------
        numpy.ndarray
            Complex H(jω), output units per drive unit.
        """
        ctx = self._ctx
        omega = np.asarray(omega, float)
        if self._structural and self.linear_current:  # the current model itself: linear, no core's
            ident = self._current_identification
            known = {p.name for p in ident.sim.eqs.params}
            vals = {k: v for k, v in {**self.current.values, **(values or {})}.items() if k in known}
            ss = ident.lti.state_space(ident.sim.theta(vals), ident.cut)
        else:
            ss = ctx.lti.state_space(self._theta_values(values), ctx.cut)
        return ss.frequency_response(omega) * ctx.reading_factor(omega) * np.exp(-1j * omega * ctx.delay * ctx.dt)

    @cached_property
    def _current_identification(self) -> Identification:
        """An :class:`Identification` of the current model on this record (cached)."""
        return self._identification(self.current.model)

    @property
    def linear_current(self) -> bool:
        """True when the current model is linear on the exact route: its linear core, or the
        core with linear structural extensions named (an added mode), no nonlinear term.  A
        linear structural candidate can then extend the current model itself."""
        if not self.record.exact or self.record.reduced or self._terms:
            return False
        return not self._structural or self._current_identification.lti is not None

    def first_order(self, column: np.ndarray) -> FirstOrder:
        """What a column (an effect's output per unit coefficient, sensor gain applied), or
        several together, explain of the residual's energy on the fit part to first order with
        the calibration, and how likely unrelated columns explain as much (the screen's
        chance floor, :mod:`~bondgraph.diagnosis.screen`): one Gauss–Newton step of the
        effect's coefficients and the calibrated linear parameters, sensor gain and offset.
        On the linear core the columns are regressed beyond the output's sensitivities to
        those parameters (:meth:`_respond_sensitivities`), because every candidate's fit
        refits them: a column that is partly a stiffness change is judged by what the
        stiffness cannot do.  Off the core, beyond the offset only.

        Parameters
        ----------
        column : numpy.ndarray
            The column on every sample (output units per unit coefficient), or one column per
            coefficient (samples × coefficients).

        Returns
        -------
        FirstOrder
            The share, between 0 and 1 (0 for columns that are not finite or are explained
            by the calibration alone), its chance level and effective samples.
        """
        idx = self.record.fit_idx
        full = np.asarray(column, float).reshape(len(self.current.residual), -1)
        q, r = full[idx], np.asarray(self.current.residual, float)[idx]
        if not np.all(np.isfinite(q)):
            return FirstOrder(0.0)
        basis = self._calibration_directions()
        q, r = (
            q - basis @ np.linalg.lstsq(basis, q, rcond=None)[0],
            r - basis @ np.linalg.lstsq(basis, r, rcond=None)[0],
        )
        rr = float(np.sum((np.asarray(self.current.residual, float)[idx] - np.mean(self.current.residual[idx])) ** 2))
        size = np.sqrt(np.sum(full[idx] ** 2, axis=0))
        keep = np.sqrt(np.sum(q**2, axis=0)) > 1e-12 * np.maximum(size, 1e-150)  # beyond the calibration
        if not keep.any() or rr <= 0:
            return FirstOrder(0.0)
        return first_order(q[:, keep], r, rr, self._noise_floor())

    def _noise_floor(self) -> float:
        """The measurement noise's RMS (output units): the record's estimate from a band the
        drive leaves quiet, else an upper estimate from the current residual: the larger of
        its spectrum's floor and its part incoherent with the drive (cached)."""
        if self.record.noise:
            return float(self.record.noise)
        if getattr(self, "_floor", None) is None:
            e = np.asarray(self.current.residual, float)
            fs = self.record.fs
            self._floor = max(residual_floor(e, fs), incoherent_rms(np.asarray(self.record.u, float), e, fs))
        return self._floor

    def _calibration_directions(self) -> np.ndarray:
        """The fit rows' directions the calibration moves the output in (columns): the offset
        and, on the linear core, the raw prediction (sensor gain) and its derivatives with
        respect to the logarithms of the calibrated linear parameters (cached)."""
        if getattr(self, "_directions", None) is not None:
            return self._directions
        idx = self.record.fit_idx
        cols = [np.ones(idx.size)]
        if self.on_core and not self._terms:
            names = [n for n in self.current.calibrated if n in self._ctx.core_parameters]
            out = (
                self._respond_sensitivities(np.asarray(self.current.drive, float)[:, None], names, rows=idx)
                if names
                else None
            )
            if out is not None:
                Y, dY = out
                cols.append(Y[:, 0])
                cols += [dY[i][:, 0] * self.current.values[n] * self.current.gain for i, n in enumerate(names)]
        basis = np.column_stack(cols)
        scale = np.sqrt(np.sum(basis**2, axis=0))
        self._directions = basis[:, scale > 0] / scale[scale > 0]
        return self._directions

    def score(self, raw: np.ndarray) -> tuple[float, float, float, float]:
        """(sensor gain, offset, RMS fit part, RMS validation part) of a raw prediction.

        Parameters
        ----------
        raw : numpy.ndarray
            A raw prediction on every sample.

        Returns
        -------
        tuple of float
            The sensor gain and offset solved on the fit part (output units for the offset),
            and the RMS errors on the fit and validation parts (output units).
        """
        return score(self._ctx, raw)

    # ---- fitting services ---------------------------------------------------------------------
    def _linear_params(self, start: Mapping[str, float] | None = None) -> list[Spec]:
        """The calibrated linear parameters as refit specs (from ``start`` or the current
        values): within the view's bounds (the plausible device's, for a linear structural
        candidate) or ×/÷ ``diagnosis.spread``."""
        out = []
        for n in self.current.calibrated:
            lo, hi = self._bounds.get(n) or param_bounds(self._ctx, n, self._nominal_value(n))
            v = (start or {}).get(n, self.current.values[n])
            out.append(Spec(n, math.copysign(min(max(abs(v), lo), hi), v), lo, hi, log=True))
        return out

    def _strained(self) -> list[str]:
        """The calibrated linear parameters whose current value sits on its search bound: the
        linear calibration went as far as it may to absorb what no linear device explains (a
        resonance that moves with amplitude read as heavy damping), so a fit inside the
        dynamics should not start only from there.

        Returns
        -------
        list of str
            The parameters' names.
        """
        return [
            p.name
            for p in self._linear_params()
            if not p.lower * (1 + 1e-6) < abs(self.current.values[p.name]) < p.upper * (1 - 1e-6)
        ]

    def _implausible(self) -> list[str]:
        """The calibrated linear parameters whose current value lies outside the plausible
        device's tolerance: the calibration may have bent the device to mimic an effect, so a
        fit of that effect should start from the model file's values too.

        Returns
        -------
        list of str
            The parameters' names.
        """
        plausible = self._ctx.plausible
        return [
            n
            for n in self.current.calibrated
            if n in plausible
            and not plausible[n][0] * (1 - 1e-9) <= abs(self.current.values[n]) <= plausible[n][1] * (1 + 1e-9)
        ]

    def fit_starts(self, always: bool = False) -> list[dict[str, float] | None]:
        """Where a fit inside the dynamics starts its linear parameters: the calibration (None)
        and, when the calibration ended on a search bound (:meth:`_strained`) or outside the
        plausible device (:meth:`_implausible`), or with ``always``, the model file's values
        too.

        Parameters
        ----------
        always : bool, optional
            Start from the model file's values whatever the calibration (a fit cheap enough to
            run twice).

        Returns
        -------
        list of dict or None
            ``[None]`` or ``[None, {name: the model file's value}]``.
        """
        again = always or self._strained() or self._implausible()
        return [None] + ([self._model_file_values()] if again else [])

    def _model_file_values(self) -> dict[str, float]:
        """The model file's values of the calibrated linear parameters.

        Returns
        -------
        dict of str to float
            Name → value, in the parameters' units.
        """
        return {n: self._nominal_value(n) for n in self.current.calibrated}

    def fit_drive(
        self,
        basis: Callable[[np.ndarray], Sequence[np.ndarray]] | Sequence[np.ndarray] = (),
        lower: Sequence[float] = (),
        upper: Sequence[float] = (),
        *,
        direct: Callable[[np.ndarray], Sequence[np.ndarray]] | Sequence[np.ndarray] = (),
        identity: bool = True,
        z0: Sequence[float] = (),
        z_bounds: Sequence[tuple[float, float]] = (),
        z_names: Sequence[str] = (),
        refit: bool = True,
        max_nfev: int = 30,
        starts: Sequence[Sequence[float]] = (),
        start: Mapping[str, float] | None = None,
        names: Sequence[str] | None = None,
    ) -> DriveFit:
        """Fit the drive-side extension u_eff = [d] + Σ θ_k·basis_k (d: the current drive) through
        the linear core, plus ``direct`` columns added to the output, by variable projection:
        the coefficients by bounded linear least squares (``lower``/``upper`` for the basis;
        direct ones free), jointly with nonlinear parameters ``z`` (``basis``/``direct`` may be
        functions of z) and, with ``refit``, the calibrated linear parameters (log space, from
        ``start`` or the current values).

        With ``names`` (the parameters that will hold the basis weights) the extension is
        *additive* (:mod:`bondgraph.diagnosis.additive`): the basis is of :attr:`additive`'s
        base drive, d is that sum with the weights named before refitted too (within their
        bounds), and ``identity=False`` replaces only the base drive's own term; the result's
        ``additive`` is the new sum.

        Parameters
        ----------
        basis : sequence of numpy.ndarray or callable, optional
            Basis series on every sample (drive units per unit coefficient), or a function of
            the nonlinear parameters z returning them.
        lower, upper : sequence of float, optional
            Bounds of the basis coefficients, one per basis column.
        direct : sequence of numpy.ndarray or callable, optional
            Columns added to the output (output units at sensor gain 1), or a function of z.
        identity : bool, optional
            Keep the current drive with weight 1 (False: it is replaced).
        z0 : sequence of float, optional
            Start values of the nonlinear parameters z.
        z_bounds : sequence of tuple of float, optional
            (lower, upper) of each z.
        z_names : sequence of str, optional
            Names of the z, for ``at_bounds``.
        refit : bool, optional
            Refit the calibrated linear parameters too.
        max_nfev : int, optional
            The optimiser's evaluation budget (times the view's effort).
        starts : sequence of sequence of float, optional
            Further start points of z.
        start : mapping of str to float, optional
            Start values of the calibrated linear parameters (default: the current ones).
        names : sequence of str, optional
            The parameters that will hold the basis weights: an additive fit.

        Returns
        -------
        DriveFit
            The coefficients, values, drive and raw prediction.

        Raises
        ------
        ValueError
            The current model is not a drive transform of its linear core.
        """
        if self.current.drive is None:
            raise ValueError("the current model is not a drive transform of its linear core")
        held = self.current.additive if names is not None else None
        if held is not None:
            keep = identity and held.identity
            lead = ([np.asarray(held.base)] if keep else []) + [t.column for t in held.terms]
            lead_lo = ([-np.inf] if keep else []) + [t.lower for t in held.terms]
            lead_hi = ([np.inf] if keep else []) + [t.upper for t in held.terms]
            identity = keep
        else:
            lead = [np.asarray(self.current.drive)] if identity else []
            lead_lo, lead_hi = [-np.inf] * len(lead), [np.inf] * len(lead)
        n_lead = len(lead)
        lin = self._linear_params(start) if refit else []
        nz = len(z0)
        call_b = callable(basis)
        call_d = callable(direct)
        fixed_b = None if call_b else list(basis)
        fixed_d = None if call_d else list(direct)
        n_basis = len(lower)

        def parts(z):
            zb = z[:nz]
            vals = {p.name: p.from_z(zi) for p, zi in zip(lin, z[nz:])}
            b = list(basis(zb)) if call_b else fixed_b
            dc = list(direct(zb)) if call_d else fixed_d
            return vals, b, dc

        extra = np.asarray(self.current.extra)
        has_extra = bool(np.any(extra))

        first = [] if call_b else lead + fixed_b
        fixed_U = np.column_stack(first) if first else None

        def columns(z, rows):
            vals, b, dc = parts(z)
            U = fixed_U if fixed_U is not None else np.column_stack(lead + b)
            Y = self.respond(U, vals, rows)
            ex = extra if rows is None else extra[rows]
            if identity:
                Y[:, 0] += ex
            n = Y.shape[0]
            cols = (
                [Y]
                + ([np.column_stack(dc) if rows is None else np.column_stack(dc)[rows]] if dc else [])
                + [np.ones((n, 1))]
            )
            if has_extra and not identity:
                cols.insert(-1, ex[:, None])
            return np.column_stack(cols)

        def derivatives(z, rows):
            """∂columns/∂z: the output sensitivities for the linear parameters; for the basis'
            own parameters, forward differences of the basis (drive side) and of the direct
            columns, the basis' passed through the core in the same call as the columns."""
            vals, b, dc = parts(z)
            U = fixed_U if fixed_U is not None else np.column_stack(lead + b)
            m = U.shape[1]
            moved = []  # (parameter, basis difference quotients, direct ones)
            for i in range(nz) if call_b or call_d else ():
                zi = forward_step(z, i, np.asarray(zl), np.asarray(zu))
                _, bi, dci = parts(zi)
                h = zi[i] - z[i]
                moved.append(
                    (
                        [(np.asarray(p) - np.asarray(q)) / h for p, q in zip(bi, b)] if call_b else [],
                        [(np.asarray(p) - np.asarray(q)) / h for p, q in zip(dci, dc)] if call_d else [],
                    )
                )
            more = [np.asarray(col, float) * np.ones(U.shape[0]) for db, _ in moved for col in db]
            out = self._respond_sensitivities(
                np.column_stack([U] + more) if more else U, [p.name for p in lin], vals, rows
            )
            if out is None:
                return None
            Y, dY = out
            dA = np.zeros((z.size, rows.size, m + n_free))
            dA[nz:, :, :m] = dY[:, :, :m] * np.array([vals[p.name] for p in lin])[:, None, None]  # log parameters
            at = m
            for i, (db, ddc) in enumerate(moved):
                if db:
                    dA[i, :, n_lead:m] = Y[:, at : at + len(db)]
                    at += len(db)
                if ddc:
                    dA[i, :, m : m + n_dir] = np.column_stack(ddc)[rows]
            return dA

        # the bounds are on the drive's weights; the solved coefficients are these times the
        # sensor gain, whose sign is the sensor's orientation, not physics
        lo, hi = lead_lo + list(lower), lead_hi + list(upper)
        if self.current.gain < 0:
            lo, hi = [-b for b in hi], [-a for a in lo]
        # the direct columns and the offset are free
        n_dir = len(direct(np.asarray(z0, float))) if call_d else len(fixed_d)
        n_free = n_dir + 1 + (1 if has_extra and not identity else 0)
        lo += [-np.inf] * n_free
        hi += [np.inf] * n_free
        zb0 = [float(v) for v in z0]
        zl = [float(a) for a, _ in z_bounds] + [p.z_bounds()[0] for p in lin]
        zu = [float(b) for _, b in z_bounds] + [p.z_bounds()[1] for p in lin]
        zlin0 = [p.to_z(p.start) for p in lin]
        more_starts = [list(s) + zlin0 for s in starts]
        sol = projected_fit(
            columns,
            self._ctx.y,
            self._ctx.ident.fit_idx,
            zb0 + zlin0,
            zl,
            zu,
            lo,
            hi,
            max_nfev=self.budget(max_nfev) if (nz or lin) else 1,
            starts=more_starts,
            derivatives=derivatives,
        )
        vals, b, dc = parts(sol.z)
        c = sol.coef
        gain = c[0] if identity else self.current.gain
        gain = gain if gain != 0 else 1.0
        weights = c[:n_lead] / gain
        theta = c[n_lead : n_lead + n_basis] / gain
        phi = c[n_lead + n_basis : n_lead + n_basis + n_dir] / gain
        if identity:
            weights[0] = 1.0
        drive = sum(w * col for w, col in zip(weights, lead)) + (sum(t * bk for t, bk in zip(theta, b)) if b else 0.0)
        drive = np.asarray(drive, float) * np.ones(len(self.current.drive))
        raw = self.respond([drive], vals)[:, 0] + (sum(p * dk for p, dk in zip(phi, dc)) if dc else 0.0)
        if has_extra:
            raw = raw + (extra if identity else c[n_lead + n_basis + n_dir] / gain * extra)
        znames = list(z_names) + [p.name for p in lin]
        at = [znames[i] if i < len(znames) else f"z{i}" for i in sol.at_bounds]
        values = {**self.current.values, **vals}
        additive = None
        if held is not None:
            refitted = weights[1:] if identity else weights
            values.update({t.name: float(w) for t, w in zip(held.terms, refitted)})
            new = tuple(
                Term(n, np.asarray(col, float), float(a), float(bb))
                for n, col, a, bb in zip(names, b or [], lower, upper)
            )
            additive = AdditiveDrive(held.base, held.base_expr, identity, held.terms + new)
        return DriveFit(theta, phi, sol.z[:nz], values, raw, drive, sol.success, sol.message, at, additive)

    def _identification(self, model: Model, integrate: bool = False) -> Identification:
        """An :class:`Identification` of ``model`` on the same data and split (exact linear
        route when the model is linear, unless ``integrate``).

        Parameters
        ----------
        model : Model
            The model (e.g. an extension of the current one).
        integrate : bool, optional
            Always simulate with the compiled integrator.

        Returns
        -------
        Identification
            Ready to predict and fit ``model`` on this record.
        """
        ident = self._ctx.ident.like(model, rtol=1e-6)
        if integrate:
            ident.lti = None
        return ident

    def simulate(self, model: Model, values: Mapping[str, float]) -> np.ndarray:
        """Raw output (sensor gain 1, no offset) of ``model`` with ``values`` on every sample.

        Parameters
        ----------
        model : Model
            The model to simulate.
        values : mapping of str to float
            Parameter values (names the model does not know are ignored).

        Returns
        -------
        numpy.ndarray
            The raw prediction on every sample, output units.

        Raises
        ------
        SimulationError
            The integration failed or passed the context's time limit.
        """
        predict, known = self.predictor(model)
        return predict({k: v for k, v in values.items() if k in known})

    def predictor(self, model: Model, drive: np.ndarray | None = None):
        """(values -> raw prediction of ``model`` on every sample, the parameter names it
        knows): by the exact linear route, driven by ``drive`` when given (for an extension
        of :meth:`core`: the drive it sees, ``self.current.drive``; the output part outside the core,
        ``extra``, is added), else by the compiled integrator within the context's time
        limits (:func:`~bondgraph.diagnosis.projection.simulation_deadline`).

        Parameters
        ----------
        model : Model
            The model to predict with.
        drive : numpy.ndarray, optional
            The drive series an extension of :meth:`core` sees.

        Returns
        -------
        predict : callable
            ``predict(values)`` → raw prediction on every sample.
        known : set of str
            The parameter names ``model`` knows.
        """
        return self._routes(model, drive)[:2]

    def _routes(self, model: Model, drive: np.ndarray | None = None):
        """:meth:`predictor`'s (predict, known), and on the exact linear route a function
        (values, names, rows) -> (raw, ∂raw/∂names) at the rows ``rows`` or None
        (:meth:`~bondgraph.fit.identify.Identification.sensitivities`); None off it."""
        ident = self._identification(model)
        known = {p.name for p in ident.sim.eqs.params}
        if ident.lti is None:  # the integrator: one slow run must not outlast the fit's budget
            return (lambda values: ident.predict(values, deadline=simulation_deadline())), known, None

        def sens(values, names, rows):
            out = ident.sensitivities(values, names, drive, rows)
            return None if out is None else (out[0][:, 0], out[1][:, :, 0])

        if drive is None:
            return ident.predict, known, sens
        extra = 0.0 if self.current.extra is None else self.current.extra
        return (lambda values: ident.predict(values, drive=drive) + extra), known, sens

    def fit_model(
        self,
        model: Model,
        new: Sequence[Spec],
        max_nfev: int = 20,
        refit: bool = True,
        start: Mapping[str, float] | None = None,
        predict: Callable[[Mapping[str, float]], np.ndarray] | None = None,
        drive: np.ndarray | None = None,
    ):
        """Fit the new parameters ``new`` of an extended model (and, with ``refit``, the
        calibrated linear ones, from ``start`` or the current values) by variable projection
        over sensor gain and offset; exact linear route when the extended model stays linear,
        else the compiled integrator, or ``predict(values)`` if given (e.g. :meth:`lure`).  A spec
        with lower = upper is held.  Returns (values, raw prediction, success, message, names at
        a bound).  ``drive``: for an extension of :meth:`core`, the drive it sees (``self.current.drive``);
        the output part outside the core (``extra``) is added.

        Parameters
        ----------
        model : Model
            The extended model.
        new : sequence of Spec
            How each new parameter is fitted.
        max_nfev : int, optional
            The optimiser's evaluation budget (times the view's effort).
        refit : bool, optional
            Refit the calibrated linear parameters too.
        start : mapping of str to float, optional
            Start values of parameters (default: the current values).
        predict : callable, optional
            ``predict(values)`` → raw prediction on every sample, instead of simulating.
        drive : numpy.ndarray, optional
            The drive an extension of :meth:`core` sees.

        Returns
        -------
        values : dict of str to float
            Every parameter value after the fit.
        raw : numpy.ndarray
            The raw prediction on every sample.
        success : bool
            The optimiser's success flag.
        message : str
            The optimiser's message.
        at_bounds : list of str
            Parameters that ended on a search bound.
        """
        sens = None
        if predict is None:
            predict, known, sens = self._routes(model, drive)
        else:
            known = set(model.all_parameters())
        base = {k: v for k, v in {**self.current.values, **(start or {})}.items() if k in known}
        lin = [replace(p, start=base.get(p.name, p.start)) for p in self._linear_params()] if refit else []
        held = {s.name: s.start for s in new if s.lower == s.upper}
        new = [s for s in new if s.lower != s.upper]
        base.update(held)
        specs = list(new)

        def values_of(z):
            vals = dict(base)
            vals.update({s.name: s.from_z(zi) for s, zi in zip(specs, z[: len(specs)])})
            vals.update({p.name: p.from_z(zi) for p, zi in zip(lin, z[len(specs) :])})
            return vals

        def columns(z, rows):
            raw = predict(values_of(z))
            raw = raw if rows is None else raw[rows]
            return np.column_stack([raw, np.ones(raw.size)])

        names = [s.name for s in specs] + [p.name for p in lin]

        def derivatives(z, rows):  # the output sensitivities, per unit z
            vals = values_of(z)
            out = sens(vals, names, rows)
            if out is None:
                return None
            dv = [vals[s.name] if s.log else s.scale for s in specs] + [vals[p.name] for p in lin]
            dv = [0.0 if n in names[i + 1 :] else d for i, (n, d) in enumerate(zip(names, dv))]  # overridden
            dA = np.zeros((z.size, rows.size, 2))
            dA[:, :, 0] = out[1] * np.array(dv)[:, None]
            return dA

        z0 = [s.to_z(s.start) for s in specs] + [p.to_z(p.start) for p in lin]
        lb = [s.z_bounds()[0] for s in specs] + [p.z_bounds()[0] for p in lin]
        ub = [s.z_bounds()[1] for s in specs] + [p.z_bounds()[1] for p in lin]
        sol = projected_fit(
            columns,
            self._ctx.y,
            self._ctx.ident.fit_idx,
            z0,
            lb,
            ub,
            [-np.inf] * 2,
            [np.inf] * 2,
            max_nfev=self.budget(max_nfev),
            derivatives=derivatives if sens is not None else None,
        )
        return (values_of(sol.z), sol.columns[:, 0], sol.success, sol.message, [names[i] for i in sol.at_bounds])

    def lure(self, model: Model, elements: Sequence[str], partners: Mapping[str, str | None]):
        """A :class:`~bondgraph.diagnosis.lure.Lure` system for nonlinear terms on ``elements``,
        on this record's grid: of the linear core when the current model is a drive transform of
        it (:attr:`on_core`: e.g. after hysteresis on the drive) or the core with the terms named
        so far (held), else of ``model`` (e.g. after a linear structural cause: a compliant output
        stage).  Its ``drive`` is the series to feed it and ``extra`` the output part outside it
        (or None); None when that model is not linear.

        Parameters
        ----------
        model : Model
            The extended model (used when the current model is no drive transform of its core).
        elements : sequence of str
            The elements the nonlinear terms act on.
        partners : mapping of str to str or None
            Element → the partner whose displacement its term uses, :data:`DRIVE`, or None.

        Returns
        -------
        Lure or None
            The Lur'e system, or None off the exact linear route.
        """
        if not self.record.exact or self.record.reduced:
            return None
        try:
            if self._terms and self._core_drive is not None:
                lure = Lure(
                    self.core(), self.record.input, self.record.output, elements, partners, self._ctx.dt, self._terms
                )
                lure.drive, lure.extra = np.asarray(self._core_drive), self._core_extra
            elif self.on_core:
                lure = Lure(self.core(), self.record.input, self.record.output, elements, partners, self._ctx.dt)
                lure.drive, lure.extra = np.asarray(self.current.drive), self.current.extra
            else:  # the model itself, when it is linear (a linear structural extension included)
                lure = Lure(model, self.record.input, self.record.output, elements, partners, self._ctx.dt)
                lure.drive, lure.extra = np.asarray(self.record.u), None
        except BondGraphError:
            return None
        return lure

    def states(self, values: Mapping[str, float] | None = None) -> dict[str, np.ndarray]:
        """State trajectories (and the output's rate, key ``"output rate"``) of the current
        model, integrated.

        Parameters
        ----------
        values : mapping of str to float, optional
            Parameter values overriding the current ones (others ignored).

        Returns
        -------
        dict of str to numpy.ndarray
            State name → series on every sample, plus ``"output rate"`` (output units per s).

        Raises
        ------
        SimulationError
            The integration failed or passed the context's time limit.
        """
        ident = self._identification(self.current.model, integrate=True)
        known = {p.name for p in ident.sim.eqs.params}
        vals = {k: v for k, v in {**self.current.values, **(values or {})}.items() if k in known}
        run_inputs = {self.record.input: ident.signal}
        x0 = record_start(ident.sim, ident.sim.theta(vals), run_inputs, float(self._ctx.t[0]))
        res = ident.sim.run(self._ctx.t, run_inputs, params=vals, x0=x0, rtol=1e-5, deadline=simulation_deadline())
        out = dict(res.states)
        out["output rate"] = np.gradient(res.outputs[self.record.output], self._ctx.t)
        return out
