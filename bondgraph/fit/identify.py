"""Parameter identification: least squares of a model's output against measured data.

One input signal (the data column driving the model, linearly interpolated) and one output
are compared at the data's time stamps.  The data is split into a *fit* part and a
*validation* part: by default interleaved time blocks (a share of thirty blocks, spread evenly,
is held out), so every regime of a composite experiment appears in both, while the simulation
runs open loop over the whole record from the model's steady state at the record's first drive
value (setting ``record.start``, :mod:`bondgraph.numerics.steady`).  An output offset (sensor zero) is always
solved by linear least squares.  The model's first declared input and output are used unless
others are named.

Parameters are fitted in a transformed space: positive parameters in log scale, the others
scaled by a typical magnitude.  Groups of parameters the output depends on linearly (gains,
operator weights) are solved exactly by bounded linear least squares (scipy ``lsq_linear``,
non-negative where the bounds say so), alternating with ``scipy.optimize.least_squares`` for
the nonlinear ones.

Uncertainties (``FitResult.stderr``) come from the Jacobian at the solution: the standard
errors of the nonlinearly fitted parameters *conditional on everything else held fixed* (the
parameters not fitted, and the exactly solved linear ones and offset at their solution),
assuming white measurement noise; residuals that are correlated in time (model error) make
them too small.  ``tests/test_identify.py`` checks their coverage on a linear model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np
import scipy.linalg
from scipy.optimize import least_squares, lsq_linear

from ..data import Dataset, uniform_step
from ..linear.lti import LTI, first_input, first_output
from ..linear.sensitivity import sensitivity
from ..model.graph import Model
from ..model.signals import PiecewiseLinear
from ..numerics.simulate import SimulationError, Simulator
from ..numerics.steady import free_states, linear_start, record_start, starts_steady
from ..support.errors import DataError, ParameterError, UsageError, did_you_mean


@dataclass
class Spec:
    """How one parameter is fitted: start value, bounds, scale, log transform, linearity.

    The optimiser works on z, the parameter mapped by :meth:`to_z`: z = log |v| for a log
    parameter (its sign is the start value's, and ``lower`` and ``upper`` bound its
    magnitude), z = v / scale otherwise.  The one parameter type of :mod:`bondgraph.fit`
    and of the diagnosis's calibration and fits.

    Parameters
    ----------
    name : str
        The model parameter.
    start : float
        Start value, in the parameter's unit.
    lower, upper : float, optional
        Bounds, same unit (default unbounded); of the magnitude for a log parameter, which
        needs ``lower`` > 0 for a finite lower z bound.
    scale : float, optional
        Typical magnitude, same unit (used when not ``log``).
    log : bool, optional
        Fit log |v| with the start's sign (a parameter spanning decades).
    linear : bool, optional
        The output is linear in this parameter: it is solved by bounded linear least squares
        at each step of the nonlinear ones instead of being searched for.
    """

    name: str
    start: float
    lower: float = -np.inf
    upper: float = np.inf
    scale: float = 1.0
    log: bool = False
    linear: bool = False

    def to_z(self, v: float) -> float:
        """The optimiser's coordinate of a value.

        Parameters
        ----------
        v : float
            The parameter's value, in its unit (not 0 for a log parameter).

        Returns
        -------
        float
            log |v| for a log parameter, its magnitude clipped to the bounds; v / scale
            otherwise.
        """
        return math.log(min(max(abs(v), self.lower), self.upper)) if self.log else v / self.scale

    def from_z(self, z: float) -> float:
        """The value at an optimiser coordinate (the inverse of :meth:`to_z`).

        Parameters
        ----------
        z : float
            The optimiser's coordinate.

        Returns
        -------
        float
            ±exp z for a log parameter (the start's sign), z · scale otherwise, in the
            parameter's unit.
        """
        return math.copysign(math.exp(z), self.start) if self.log else z * self.scale

    def z_bounds(self) -> tuple[float, float]:
        """The bounds mapped to the optimiser's coordinate.

        Returns
        -------
        lower : float
            The lower bound in z (−inf where the value's is, or for a log parameter whose
            lower bound is not positive).
        upper : float
            The upper bound in z (inf where the value's is).
        """
        if self.log:
            return (
                math.log(self.lower) if self.lower > 0 else -np.inf,
                math.log(self.upper) if np.isfinite(self.upper) else np.inf,
            )
        return self.lower / self.scale, self.upper / self.scale


def default_spec(name: str, value: float, bounds=None, linear: bool = False) -> Spec:
    """Log scale for positive parameters (bounded to ×/÷ 1000 unless given), linear otherwise.

    Parameters
    ----------
    name : str
        The parameter.
    value : float
        Its start value, in its unit.
    bounds : tuple of float, optional
        The declared (lower, upper) bounds, if any.
    linear : bool, optional
        The output is linear in the parameter (then never log scale).

    Returns
    -------
    Spec
        How to fit it.
    """
    lo, hi = bounds if bounds is not None else (-np.inf, np.inf)
    if value > 0 and lo >= 0 and not linear:
        lo = max(lo, value / 1e3) if lo > 0 or bounds is None else value / 1e3
        hi = min(hi, value * 1e3)
        return Spec(name, value, lo, hi, log=True)
    scale = abs(value) if value != 0 else 1.0
    return Spec(name, value, lo, hi, scale=scale, linear=linear)


@dataclass
class FitResult:
    """Outcome of a fit: values, standard errors, offset, RMS errors (output units).

    Parameters
    ----------
    values : dict of str to float
        The fitted values, in the parameters' units.
    stderr : dict of str to float
        Standard errors of the nonlinearly fitted parameters, same units (conditional on the
        others; see the module docstring).
    offset : float
        The output offset solved with them, output units (measured ≈ model + offset).
    rms_fit : float
        RMS error on the fit part, output units.
    rms_validation : float
        RMS error on the validation part, output units.
    nfev : int
        Number of simulations the fit ran.
    success : bool
        The optimiser's success flag.
    message : str, optional
        The optimiser's message.
    prediction : numpy.ndarray, optional
        The fitted output at every data time, offset included.
    """

    values: dict[str, float]
    stderr: dict[str, float]
    offset: float
    rms_fit: float
    rms_validation: float
    nfev: int
    success: bool
    message: str = ""
    prediction: np.ndarray | None = field(default=None, repr=False)

    def as_json(self) -> dict:
        """The result as a JSON object (without the prediction).

        Returns
        -------
        dict
            ``params``, ``stderr``, ``offset``, ``rms_fit``, ``rms_validation``, ``nfev``,
            ``success`` and ``message``.
        """
        return {
            "params": self.values,
            "stderr": self.stderr,
            "offset": self.offset,
            "rms_fit": self.rms_fit,
            "rms_validation": self.rms_validation,
            "nfev": self.nfev,
            "success": self.success,
            "message": self.message,
        }


def split_masks(
    t: np.ndarray, validation: float = 0.3, mode: str = "blocks", blocks: int = 30, skip: float = 0.02, shift: int = 0
):
    """Boolean (fit, validation) masks over samples.

    ``blocks``: ``blocks`` equal time blocks, a share ``validation`` of them (spread evenly,
    never the first) held out, each ``shift`` blocks later for another fold; ``tail``: the last
    ``validation`` of the time span.  The first ``skip`` of the span is in neither: the model
    starts at rest, a measured device may not.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s, increasing.
    validation : float, optional
        Share held out for validation, between 0 and 1.
    mode : {"blocks", "tail"}, optional
        How it is held out.
    blocks : int, optional
        Number of equal time blocks of the ``blocks`` mode.
    skip : float, optional
        Share of the time span at the start left out of both parts.
    shift : int, optional
        Blocks by which the held-out blocks move (another fold).

    Returns
    -------
    fit : numpy.ndarray
        Boolean mask of the fit part.
    validation : numpy.ndarray
        Boolean mask of the validation part.

    Raises
    ------
    UsageError
        ``validation`` outside (0, 1), or an unknown mode.
    """
    if not 0.0 < validation < 1.0:
        raise UsageError(f"validation share must be between 0 and 1, not {validation}")
    span = t[-1] - t[0]
    if mode == "tail":
        val = t >= t[0] + (1 - validation) * span
    elif mode == "blocks":
        k = np.minimum(((t - t[0]) / span * blocks).astype(int), blocks - 1)
        n_val = max(1, round(validation * blocks))
        held = {(int(round(blocks * (i + 0.5) / n_val + 0.5)) + shift) % blocks or 1 for i in range(n_val)}
        held = sorted(held)[:n_val]
        val = np.isin(k, held)
    else:
        raise UsageError(f"unknown split mode {mode!r}; use blocks or tail")
    settled = t >= t[0] + skip * span
    return ~val & settled, val & settled


class Identification:
    """A model, a data set and the machinery to simulate, score and fit it.

    ``input``/``output`` name the model's input and output (default: its first declared
    ones); ``data_input``/``data_output`` the data columns (default: the same names);
    ``validation``, ``split``, ``blocks`` and ``shift``: the held-out part (:func:`split_masks`).

    Parameters
    ----------
    model : Model or Simulator
        The model (compiled here unless a :class:`~bondgraph.Simulator` is given).
    data : Dataset
        The measured record.
    input : str, optional
        The model input the data drive (default: its first declared one).
    output : str, optional
        The model output compared with the data (default: its first declared one).
    data_input : str, optional
        The data column of the drive (default: the same name as ``input``).
    data_output : str, optional
        The data column of the output (default: the same name as ``output``).
    validation : float, optional
        Share held out for validation, between 0 and 1.
    split : {"blocks", "tail"}, optional
        How it is held out.
    max_fit_points : int, optional
        The fit part is thinned to at most about this many samples.
    rtol : float, optional
        Relative tolerance of the integrator.
    method : str, optional
        Integrator (see :meth:`bondgraph.Simulator.run`).
    lti : LTI, optional
        The model's exact linear form, when already built.
    cut : float, optional
        Modes faster than this, rad/s, are residualised on the exact linear route.
    blocks : int, optional
        Number of time blocks of the ``blocks`` split.
    shift : int, optional
        Blocks by which the held-out blocks move (another fold).

    Raises
    ------
    UsageError
        An unknown input or output, or a bad split.
    DataError
        A missing column, or a drive that does not vary.
    """

    def __init__(
        self,
        model: Model | Simulator,
        data: Dataset,
        input: str | None = None,
        output: str | None = None,
        data_input: str | None = None,
        data_output: str | None = None,
        validation: float = 0.3,
        split: str = "blocks",
        max_fit_points: int = 20000,
        rtol: float = 1e-6,
        method: str = "auto",
        lti: LTI | None = None,
        cut: float | None = None,
        blocks: int = 30,
        shift: int = 0,
    ):
        self.sim = model if isinstance(model, Simulator) else Simulator(model)
        input = input if input is not None else first_input(self.sim.eqs)
        output = output if output is not None else first_output(self.sim.eqs)
        if input not in self.sim.input_names:
            raise UsageError(f"model input: {did_you_mean(input, self.sim.input_names, 'input')}")
        if output not in self.sim.output_names:
            raise UsageError(f"model output: {did_you_mean(output, self.sim.output_names, 'output')}")
        self.data = data
        self.input, self.output = input, output
        self.data_input, self.data_output = data_input, data_output
        self.validation, self.split_mode, self.blocks, self.shift = validation, split, blocks, shift
        self.u = data.column(data_input or input)
        self.y = data.column(data_output or output)
        check_varies(self.u, data_input or input, data.path)
        self.t = data.t
        self.signal = PiecewiseLinear(self.t, self.u, label=f"data:{data_input or input}")
        self.fit_mask, self.val_mask = split_masks(self.t, validation, split, blocks, shift=shift)
        idx = np.nonzero(self.fit_mask)[0]
        step = max(1, int(math.ceil(idx.size / max_fit_points)))
        self.fit_idx = idx[::step]
        self.rtol = rtol
        self.method = method
        self.nfev = 0
        self.max_fit_points = max_fit_points
        self.dt = uniform_step(self.t)
        if lti is None and self.dt is not None:
            lti = LTI(self.sim.eqs, input, output)
        #: the exact linear route (None when the model is not linear or the data not uniform)
        self.lti = lti if lti is not None and lti.exact and self.dt is not None else None
        #: modes faster than this (rad/s) are residualised on the linear route (None: keep all)
        self.cut = cut

    def like(self, model: Model | Simulator, **kw) -> "Identification":
        """The same data, input/output mapping and split for another (e.g. extended) model.

        Parameters
        ----------
        model : Model or Simulator
            The other model.
        **kw
            Constructor arguments to change (e.g. ``rtol``, ``method``).

        Returns
        -------
        Identification
            A new identification.
        """
        args = dict(
            input=self.input,
            output=self.output,
            data_input=self.data_input,
            data_output=self.data_output,
            validation=self.validation,
            split=self.split_mode,
            blocks=self.blocks,
            shift=self.shift,
            max_fit_points=self.max_fit_points,
            rtol=self.rtol,
            method=self.method,
            cut=self.cut,
        )
        args.update(kw)
        return Identification(model, self.data, **args)

    # ---- simulation and scores ---------------------------------------------------------------
    def predict(
        self,
        values: Mapping[str, float] | None = None,
        inputs=None,
        drive: np.ndarray | None = None,
        deadline: float | None = None,
        max_steps: int | None = None,
    ) -> np.ndarray:
        """Model output at every data time, without offset (exact LTI recursion when the model
        is linear and the data uniformly sampled, with the modes faster than ``cut``
        residualised; else the compiled integrator), from the start setting ``record.start``
        says (:func:`~bondgraph.numerics.steady.record_start`; with modes residualised, the
        steady state of every state, a declared non-zero start included).  ``drive``: other input samples
        for the exact route (one per data time, units of the input); ``deadline``: the
        integrator's (see :meth:`Simulator.run`).

        Parameters
        ----------
        values : mapping of str to float, optional
            Parameter values overriding the model's.
        inputs : mapping of str to Signal, optional
            Further input signals (forces the integrator).
        drive : numpy.ndarray, optional
            Other drive samples for the exact route.
        deadline : float, optional
            A ``time.monotonic()`` value past which the integrator stops.
        max_steps : int, optional
            Most integrator steps (default: the setting ``simulate.max_steps``).

        Returns
        -------
        numpy.ndarray
            The model output at every data time, output units, without offset.

        Raises
        ------
        SimulationError
            The integrator failed or passed ``deadline``.
        """
        self.nfev += 1
        th = self.sim.theta(values)
        if self.lti is not None and not inputs:
            ss = self.lti.state_space(th, self.cut)
            u = self.u if drive is None else np.asarray(drive, float)
            x_d = self.sim.initial_state(th)
            if starts_steady():
                if ss.fast or not np.any(x_d):  # every state at its steady state (superposition)
                    return ss.response(self.dt, u, steady=True)[:, 0]
                x0 = linear_start(ss.A, ss.B, float(u[0]), x_d, free_states(self.sim, x_d))
                return ss.response(self.dt, u, x0)[:, 0]
            return ss.response(self.dt, u, None if ss.fast else x_d)[:, 0]
        run_inputs = {self.input: self.signal, **(inputs or {})}
        res = self.sim.run(
            self.t,
            run_inputs,
            params=values,
            x0=record_start(self.sim, th, run_inputs, float(self.t[0])),
            rtol=self.rtol,
            method=self.method,
            deadline=deadline,
            max_steps=max_steps,
        )
        return res.outputs[self.output]

    def sensitivities(
        self,
        values: Mapping[str, float] | None,
        names: Sequence[str],
        inputs: np.ndarray | None = None,
        rows: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray] | None:
        """The exact linear route's output for each column of ``inputs`` (input samples, one
        per data time; default the record's input) and its derivatives with respect to the
        parameters ``names``, at the sample indices ``rows`` (every sample for None): (Y (rows,
        columns), dY (names, rows, columns)), from the output sensitivities of
        :mod:`bondgraph.linear.sensitivity` (from the start :meth:`predict` uses), or None off
        the exact linear route, for a model that declares a state other than rest, or for a
        model without a well-conditioned modal form.

        Parameters
        ----------
        values : mapping of str to float or None
            Parameter values overriding the model's.
        names : sequence of str
            The parameters to differentiate with respect to.
        inputs : numpy.ndarray, optional
            Input samples, one row per data time (one column per drive).
        rows : numpy.ndarray, optional
            Sample indices to return.

        Returns
        -------
        tuple of numpy.ndarray or None
            (Y, dY), dY per unit of each parameter; or None.
        """
        if self.lti is None:
            return None
        th = self.sim.theta(values)
        steady = starts_steady()
        if np.any(self.sim.initial_state(th)):
            return None
        modal = sensitivity(self.lti, th, names, self.cut)
        if modal is None:
            return None
        return modal.time(self.dt, self.u if inputs is None else inputs, rows, steady=steady)

    def offset(self, pred: np.ndarray) -> float:
        """The output offset that fits a prediction best on the fit part.

        Parameters
        ----------
        pred : numpy.ndarray
            Model output at every data time.

        Returns
        -------
        float
            mean(measured − pred) on the fit part, output units.
        """
        return float(np.mean(self.y[self.fit_idx] - pred[self.fit_idx]))

    def scores(self, pred: np.ndarray) -> tuple[float, float, float]:
        """(offset, rms on the fit part, rms on the validation part).

        Parameters
        ----------
        pred : numpy.ndarray
            Model output at every data time.

        Returns
        -------
        tuple of float
            The offset (:meth:`offset`) and the RMS errors after it, output units.
        """
        b = self.offset(pred)
        r = self.y - pred - b
        return b, float(np.sqrt(np.mean(r[self.fit_mask] ** 2))), float(np.sqrt(np.mean(r[self.val_mask] ** 2)))

    def evaluate(self, values: Mapping[str, float] | None = None) -> FitResult:
        """Score the model at given values without fitting.

        Parameters
        ----------
        values : mapping of str to float, optional
            Parameter values overriding the model's.

        Returns
        -------
        FitResult
            The values, offset, RMS errors and prediction (no standard errors).
        """
        pred = self.predict(values)
        b, rf, rv = self.scores(pred)
        return FitResult(dict(values or {}), {}, b, rf, rv, 1, True, "evaluated", pred + b)

    def current(self, name: str) -> float:
        """A parameter's value in the model.

        Parameters
        ----------
        name : str
            The parameter.

        Returns
        -------
        float
            Its value, in its unit.

        Raises
        ------
        ParameterError
            The model has no such parameter.
        """
        table = {p.name: v for p, v in zip(self.sim.eqs.params, self.sim.theta())}
        if name not in table:
            raise ParameterError(did_you_mean(name, table, "parameter"))
        return float(table[name])

    # ---- fitting -----------------------------------------------------------------------------
    def specs(self, names: Sequence[str], linear: Sequence[str] = ()) -> list[Spec]:
        """Default fit specifications (:func:`default_spec`) from the model's values and bounds.

        Parameters
        ----------
        names : sequence of str
            The parameters to fit.
        linear : sequence of str, optional
            Those the output depends on linearly (:func:`detect_linear`).

        Returns
        -------
        list of Spec
            One per name.

        Raises
        ------
        ParameterError
            A name is not a parameter of the model.
        """
        decl = self.sim.eqs.model.all_parameters()
        out = []
        for n in names:
            if n not in decl:
                raise ParameterError(did_you_mean(n, decl, "parameter"))
            out.append(default_spec(n, self.current(n), decl[n].bounds, linear=n in linear))
        return out

    def fit(
        self,
        specs: Sequence[Spec],
        fixed: Mapping[str, float] | None = None,
        loss: str = "linear",
        starts: int = 1,
        max_nfev: int = 60,
        rounds: int = 3,
        progress: Callable | None = None,
        seed: int = 0,
        stderr: bool = True,
    ) -> FitResult:
        """Fit ``specs`` (others at their model values, or ``fixed``); see the module docstring.

        Parameters
        ----------
        specs : sequence of Spec
            The parameters to fit.
        fixed : mapping of str to float, optional
            Values held for other parameters.
        loss : str, optional
            The loss of ``scipy.optimize.least_squares`` (``linear``, ``soft_l1``, ...).
        starts : int, optional
            Start points (the first from the specs, the others perturbed); the best is kept.
        max_nfev : int, optional
            Evaluation budget of each nonlinear round.
        rounds : int, optional
            Alternations of the nonlinear and the exact linear solves.
        progress : callable, optional
            Called as simulations run.
        seed : int, optional
            Seed of the perturbed start points.
        stderr : bool, optional
            Compute standard errors.

        Returns
        -------
        FitResult
            The best fit over the start points.

        Raises
        ------
        SimulationError
            The model cannot be simulated at the start values.
        """
        fixed = dict(fixed or {})
        lin = [s for s in specs if s.linear]
        non = [s for s in specs if not s.linear]
        best: FitResult | None = None
        rng = np.random.default_rng(seed)
        for k in range(max(1, starts)):
            z0 = np.array([s.to_z(s.start) for s in non])
            if k > 0:
                z0 = z0 + rng.normal(0.0, 0.5, z0.size) * np.array([1.0 if s.log else 0.5 for s in non])
                z0 = np.clip(z0, *np.array([s.z_bounds() for s in non]).T) if non else z0
            res = self._fit_once(non, lin, z0, fixed, loss, max_nfev, rounds, progress, stderr)
            if best is None or res.rms_fit < best.rms_fit:
                best = res
        return best

    def _values(self, non, z, lin, w, fixed):
        vals = dict(fixed)
        vals.update({s.name: s.from_z(zi) for s, zi in zip(non, z)})
        vals.update({s.name: wi for s, wi in zip(lin, w)})
        return vals

    def _solve_linear(self, non, z, lin, fixed):
        """Exact bounded LS for the linear parameters at the nonlinear ones ``z``."""
        base_vals = self._values(non, z, lin, [0.0] * len(lin), fixed)
        base = self.predict(base_vals)
        cols = []
        for s in lin:
            v = dict(base_vals)
            v[s.name] = s.scale
            cols.append((self.predict(v) - base) / s.scale)
        A = np.column_stack(cols + [np.ones_like(base)])[self.fit_idx]
        rhs = (self.y - base)[self.fit_idx]
        sol = bounded_lstsq(A, rhs, [s.lower for s in lin] + [-np.inf], [s.upper for s in lin] + [np.inf])
        return list(sol[:-1])

    def _fit_once(self, non, lin, z0, fixed, loss, max_nfev, rounds, progress, want_stderr) -> FitResult:
        w = [s.start for s in lin]
        z = z0.copy()
        y_fit = self.y[self.fit_idx]
        scale_y = max(float(np.std(y_fit)), 1e-300)
        n0 = self.nfev
        message, success = "linear least squares", True
        for _ in range(rounds if (non and lin) else 1):
            if lin:
                w = self._solve_linear(non, z, lin, fixed)
            if non:

                def resid(zz):
                    try:
                        pred = self.predict(self._values(non, zz, lin, w, fixed))
                    except SimulationError:
                        return np.full(self.fit_idx.size, 1e3)
                    r = (pred - self.y)[self.fit_idx]
                    r = r - r.mean()
                    if progress:
                        progress(self.nfev - n0)
                    return r / scale_y

                lb, ub = np.array([s.z_bounds() for s in non]).T
                sol = least_squares(
                    resid,
                    np.clip(z, lb, ub),
                    bounds=(lb, ub),
                    loss=loss,
                    max_nfev=max_nfev,
                    x_scale=1.0,
                    diff_step=1e-3,
                )
                z, message, success = sol.x, sol.message, bool(sol.success)
        vals = self._values(non, z, lin, w, fixed)
        pred = self.predict(vals)
        b, rf, rv = self.scores(pred)
        stderr = self._stderr(non, z, lin, w, fixed, pred, rf) if non and want_stderr else {}
        fitted = {s.name: vals[s.name] for s in non + lin}
        return FitResult(fitted, stderr, b, rf, rv, self.nfev - n0, success, message, pred + b)

    def _stderr(self, non, z, lin, w, fixed, pred, rms) -> dict[str, float]:
        """Standard errors of the nonlinear parameters from a finite-difference Jacobian."""
        J = []
        for i, s in enumerate(non):
            dz = 1e-4 * max(1.0, abs(z[i]))
            zz = z.copy()
            zz[i] += dz
            try:
                J.append(((self.predict(self._values(non, zz, lin, w, fixed)) - pred)[self.fit_idx]) / dz)
            except SimulationError:
                return {}
        J = np.column_stack(J)
        J = J - J.mean(axis=0)
        m, n = J.shape
        dof = max(m - n - 1, 1)
        s2 = rms**2 * m / dof
        try:
            cov = s2 * np.linalg.pinv(J.T @ J)
        except np.linalg.LinAlgError:
            return {}
        out = {}
        for i, s in enumerate(non):
            sd = math.sqrt(max(cov[i, i], 0.0))
            out[s.name] = s.from_z(z[i]) * sd if s.log else sd * s.scale
        return out


def bounded_lstsq(A: np.ndarray, b: np.ndarray, lower, upper) -> np.ndarray:
    """min ||A·x − b|| with lower ≤ x ≤ upper (scipy's bounded-variable least squares on the
    column-scaled problem, reduced by one pivoted QR of the scaled columns, A·P = Q·R, to the
    small triangular one: ||A·x − b||² = ||R·Pᵀx − Qᵀb||² + const).  Columns that these rows
    cannot tell from the others (a diagonal of R below 1e-10 of the largest, or beyond the
    number of rows; a column that vanishes here up to rounding among them) get 0: any split
    between them would fit, and elsewhere, where they differ, a huge one would be anything
    but a fit.

    Parameters
    ----------
    A : numpy.ndarray
        m × n matrix.
    b : numpy.ndarray
        m right-hand side.
    lower, upper : sequence of float
        Bounds of each x (±inf for none).

    Returns
    -------
    numpy.ndarray
        x, n values.
    """
    return bounded_lstsq_free(A, b, lower, upper)[0]


def bounded_lstsq_free(A: np.ndarray, b: np.ndarray, lower, upper) -> tuple[np.ndarray, np.ndarray]:
    """(x, free): :func:`bounded_lstsq`'s solution and a boolean mask of its free columns,
    those solved from the data: neither on a bound nor set to 0 for want of being told apart
    (what a derivative of the solution with respect to the columns moves).

    Parameters
    ----------
    A : numpy.ndarray
        m × n matrix.
    b : numpy.ndarray
        m right-hand side.
    lower, upper : sequence of float
        Bounds of each x (±inf for none).

    Returns
    -------
    x : numpy.ndarray
        The solution, n values.
    free : numpy.ndarray
        Boolean mask of the free columns.
    """
    norms = np.linalg.norm(A, axis=0)
    out = np.zeros(A.shape[1])
    free = np.zeros(A.shape[1], bool)
    live = np.nonzero(norms > 1e-60 * max(float(norms.max(initial=0.0)), 1e-300))[0]
    if live.size == 0:
        return out, free
    Q, R, piv = scipy.linalg.qr(A[:, live] / norms[live], mode="economic", pivoting=True)
    d = np.abs(np.diag(R))
    r = int(np.argmin(d > 1e-10 * d[0])) if np.any(d <= 1e-10 * d[0]) else d.size  # the told-apart columns lead
    cols = live[piv[:r]]
    R, qb = R[:r, :r], Q[:, :r].T @ b
    lower = np.asarray(lower, float)[cols] * norms[cols]
    upper = np.asarray(upper, float)[cols] * norms[cols]
    if np.all(np.isinf(lower)) and np.all(np.isinf(upper)):
        x = scipy.linalg.solve_triangular(R, qb)
        free[cols] = True
    else:
        sol = lsq_linear(R, qb, bounds=(lower, upper), method="bvls")
        x = sol.x
        free[cols] = sol.active_mask == 0
    out[cols] = x / norms[cols]
    return out, free


def check_varies(u: np.ndarray, name: str, path: str | None = None) -> None:
    """Refuse a constant drive: a model driven by it can only be compared with its own rest.

    Parameters
    ----------
    u : numpy.ndarray
        The drive's samples.
    name : str
        Its column name (for the message).
    path : str, optional
        The data file (for the message).

    Raises
    ------
    DataError
        The drive's range is below 1e-9 of its peak.
    """
    scale = max(float(np.max(np.abs(u))), 1e-300)
    if float(np.ptp(u)) <= 1e-9 * scale:
        where = f"{path}: " if path else ""
        raise DataError(
            f"{where}input column '{name}' is constant ({u[0]:g}): nothing to identify; "
            f"give a record in which the drive varies"
        )


def detect_linear(ident: Identification, names: Sequence[str], fixed: Mapping | None = None) -> list[str]:
    """Parameters the output depends on linearly (superposition checked with two extra runs each).

    Parameters
    ----------
    ident : Identification
        The model and data.
    names : sequence of str
        The candidates.
    fixed : mapping, optional
        Values held for other parameters.

    Returns
    -------
    list of str
        The names whose second difference of the output is below 1e-6 of the first.
    """
    fixed = dict(fixed or {})
    base_vals = {n: ident.current(n) for n in names}
    base_vals.update(fixed)
    y0 = ident.predict(base_vals)
    out = []
    for n in names:
        v0 = base_vals[n]
        d = abs(v0) * 0.5 if v0 != 0 else 1.0
        v1, v2 = dict(base_vals), dict(base_vals)
        v1[n], v2[n] = v0 + d, v0 + 2 * d
        try:
            y1, y2 = ident.predict(v1), ident.predict(v2)
        except SimulationError:
            continue
        second = np.max(np.abs(y2 - 2 * y1 + y0))
        first = np.max(np.abs(y1 - y0))
        if first > 0 and second < 1e-6 * first:
            out.append(n)
    return out
