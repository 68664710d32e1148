"""Simulation: derive once, compile once, run many times (new parameters, inputs, x0).

Methods: ``dopri5`` (compiled Dormand–Prince 5(4)); ``radau5``, the compiled implicit route
for stiff models (Radau IIA on the sparse analytic Jacobian, :mod:`.implicit`); and scipy's
stiff solvers ``radau``, ``bdf``, ``lsoda`` fed with the compiled right-hand side and (radau,
bdf) the same analytic Jacobian.  ``auto`` picks ``radau5`` when the model is stiff for the
run asked (:mod:`.stiffness`: the Jacobian's spectral radius at the start against the
output's band, and the explicit method's step count), ``dopri5`` otherwise; the result's
``stats["reason"]`` says why.

An integrator sees the inputs only where it evaluates them, and a step the error test allows
can stride over a feature of a tabulated input that falls between two stages (a pulse reaching
a model at rest, whose error estimate is zero): with tables, every method's step is capped at
``simulate.table_steps`` sample intervals of the tables.

Defaults (tolerances, the step cap, the stiffness threshold of ``auto``) are settings of
:mod:`bondgraph.config` (section ``simulate``), read when a run starts.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
import scipy.integrate as si

from ..equations.derivation import derive
from ..equations.system import Equations
from ..model.experiment import Experiment  # noqa: F401  (bondgraph.numerics.simulate.Experiment)
from ..model.graph import Model
from ..model.signals import Constant, Signal
from ..support import config
from ..support.errors import BondGraphError, ParameterError, SignalError, did_you_mean
from ..support.progress import waiting
from . import implicit
from .codegen import compile_equations, parameter_vector
from .model_functions import ModelFunctions
from .stiffness import DENSE_EIGEN, SparseJacobian, spectral_radius, stiffness

# numba compiles the explicit integrator as its module is imported (seconds the first time after
# an install, a fraction of a second from its cache after): said on stderr while it lasts
with waiting("compiling the integrator", status="the first run only: numba keeps it for later runs"):
    from .integrators import STATUS, Flags, compiled_input_values, dopri5, eval_inputs, reversal_at
    from .signal_bank import SignalBank

METHODS = ("auto", "dopri5", "radau5", "radau", "bdf", "lsoda")


def _signal(name: str, value) -> Signal:
    """An input's signal: a :class:`Signal` as given, a number as a constant."""
    if isinstance(value, Signal):
        return value
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool):
        return Constant(float(value))
    raise SignalError(
        f"input {name!r}: give a number or a signal (Sine(...), PiecewiseLinear(t, v), ...), not {type(value).__name__}"
    )


class SimulationError(BondGraphError, RuntimeError):
    """The integrator failed (step-size underflow, non-finite state, too many steps)."""


class SimulationTimeout(SimulationError):
    """The run passed its ``deadline`` (see :meth:`Simulator.run`)."""


def _check_deadline(deadline: float | None, t: float) -> None:
    if deadline is not None and time.monotonic() > deadline:
        raise SimulationTimeout(f"the run passed its deadline near t = {t:.6g} s")


@dataclass
class SimResult:
    """Sampled simulation result: ``t`` (s), inputs, outputs and states by name.

    The inputs are sampled when first asked for (fitting loops read only the outputs).
    ``result["name"]`` looks a name up in the outputs, then the inputs, then the states.

    Parameters
    ----------
    t : numpy.ndarray
        Sample times, s, strictly increasing.
    outputs : dict of str to numpy.ndarray
        The model's outputs at ``t``, in their own units (one array of ``len(t)`` each).
    states : dict of str to numpy.ndarray
        The state variables at ``t`` (generalised displacements and momenta, SI units).
    stats : dict, optional
        What the integrator did: ``method`` and ``reason`` (why that method ran), ``steps``,
        ``rejected``, ``rhs_calls``, ``reversal_rejections`` and, for radau5, ``jacobians``,
        ``factorizations``, ``newton_failures``.
    bank : SignalBank or None, optional
        The packed input signals of the run, sampled for :attr:`inputs`.
    _inputs : dict or None, optional
        The sampled inputs once computed (internal cache; leave it ``None``).
    """

    t: np.ndarray
    outputs: dict[str, np.ndarray]
    states: dict[str, np.ndarray]
    stats: dict = field(default_factory=dict)
    bank: SignalBank | None = field(default=None, repr=False)
    _inputs: dict | None = field(default=None, repr=False)

    @property
    def inputs(self) -> dict[str, np.ndarray]:
        """The input signals sampled at :attr:`t` (name → array, the input's unit), computed once."""
        if self._inputs is None:
            U = self.bank.sample(self.t)
            self._inputs = {n: U[:, i] for i, n in enumerate(self.bank.names)}
        return self._inputs

    def __getitem__(self, name: str) -> np.ndarray:
        for d in (self.outputs, self.inputs, self.states):
            if name in d:
                return d[name]
        raise KeyError(name)

    def columns(self, with_states: bool = False) -> dict[str, np.ndarray]:
        """The sampled columns by name, as a record would hold them.

        Parameters
        ----------
        with_states : bool, optional
            Also include the state variables (default: inputs and outputs only).

        Returns
        -------
        dict of str to numpy.ndarray
            The inputs, then the outputs (then the states), each sampled at :attr:`t`.
        """
        cols = {**self.inputs, **self.outputs}
        if with_states:
            cols.update(self.states)
        return cols


class Simulator:
    """A model derived and compiled once, ready to simulate with any parameters and inputs.

    Parameters
    ----------
    model : Model or Equations
        The model to simulate; a :class:`~bondgraph.Model` is derived first
        (:func:`~bondgraph.derive`), an :class:`~bondgraph.Equations` is used as it is.

    Raises
    ------
    BondGraphError
        The model cannot be derived (e.g. :class:`~bondgraph.CausalityError`) or compiled.
    """

    def __init__(self, model: Model | Equations):
        self.eqs = model if isinstance(model, Equations) else derive(model)
        self.compiled: ModelFunctions = compile_equations(self.eqs)
        self._sparse: SparseJacobian | Exception | None = None
        self.state_names = [str(s) for s in self.eqs.state_symbols]
        self.output_names = list(self.eqs.outputs)
        self.input_names = [str(u) for u in self.eqs.inputs]
        self._theta = parameter_vector(self.eqs)
        self._index = {p.name: i for i, p in enumerate(self.eqs.params)}
        used = self._uses([*self.eqs.rates.values(), *self.eqs.outputs.values()])
        #: laws use input rates, so slope jumps of the inputs are discontinuities to stop at
        self.uses_input_rates = bool(used & set(self.eqs.input_rates))
        signals = set(self.eqs.inputs) | set(self.eqs.input_rates)
        outs = self._uses(self.eqs.outputs.values()) & signals
        opins = self._uses(st.expr for st in self.eqs.program if st.op is not None) & signals
        self._flags = Flags(self.uses_input_rates, bool(outs), bool(opins))

    def _uses(self, exprs) -> set:
        """Symbols the given expressions depend on through the program."""
        return self.eqs.needed(list(exprs))[1]

    # ---- setup -------------------------------------------------------------------------------
    def theta(self, params: Mapping | None = None) -> np.ndarray:
        """θ, the parameter vector, from the model's values with ``params`` overriding some.

        Parameters
        ----------
        params : mapping of str to float, optional
            Parameter name → value (SI units of the parameter) for the ones to change.

        Returns
        -------
        numpy.ndarray
            θ, one value per parameter in the order of ``eqs.params``.

        Raises
        ------
        ParameterError
            A name is not a parameter of the model (the message suggests the closest).
        """
        th = self._theta.copy()
        for k, v in (params or {}).items():
            if str(k) not in self._index:
                raise ParameterError(did_you_mean(str(k), self._index, "parameter"))
            th[self._index[str(k)]] = float(v)
        return th

    def initial_state(self, th: np.ndarray) -> np.ndarray:
        """The states' initial values x0 declared by the model, evaluated at θ.

        Parameters
        ----------
        th : numpy.ndarray
            θ, the parameter vector (see :meth:`theta`).

        Returns
        -------
        numpy.ndarray
            x0, one value per state in the order of :attr:`state_names`.
        """
        values = dict(zip(self.eqs.params, th))
        return np.array([float(s.x0.xreplace(values)) for s in self.eqs.states], float)

    def signal_bank(self, inputs: Mapping[str, Signal] | None) -> SignalBank:
        """The inputs packed for the compiled integrator.

        Parameters
        ----------
        inputs : mapping of str to Signal or float, or None
            Input name → signal, or a number for a constant; an input not given is 0.

        Returns
        -------
        SignalBank
            Every input of the model, in the order of :attr:`input_names`.

        Raises
        ------
        SignalError
            A name is not an input of the model, or a value is neither a number nor a signal.
        """
        inputs = dict(inputs or {})
        unknown = set(inputs) - set(self.input_names)
        if unknown:
            raise SignalError(
                f"model has no input {sorted(unknown)[0]!r}; inputs: {', '.join(self.input_names) or 'none'}"
            )
        return SignalBank(
            {n: _signal(n, inputs.get(n, 0.0)) for n in self.input_names},
            kinks=self.uses_input_rates or bool(self.eqs.operators),
        )

    def initial_memory(self, t0, x0, th, bank: SignalBank) -> np.ndarray:
        """The operators' memory at rest at the initial state and inputs.

        Parameters
        ----------
        t0 : float
            Start time, s.
        x0 : numpy.ndarray
            Initial state.
        th : numpy.ndarray
            θ, the parameter vector (see :meth:`theta`).
        bank : SignalBank
            The packed inputs (see :meth:`signal_bank`).

        Returns
        -------
        numpy.ndarray
            The memory vector of the model's memory operators (hysteresis, creep), at rest at
            their input values at ``t0``; zeros (length at least 1) without operators.
        """
        lay = self.compiled.layout
        mem = np.zeros(max(lay.n_mem, 1))
        if not self.eqs.operators:
            return mem
        u, du = np.zeros(max(len(self.input_names), 1)), np.zeros(max(len(self.input_names), 1))
        eval_inputs(t0, *bank.args(), u, du, True)
        v = np.zeros(len(self.eqs.operators))
        for _ in range(2):  # second pass lets cascaded operators see settled upstream memory
            for k, ob in enumerate(self.eqs.operators):
                (a, b), (c, d) = lay.mem_slices[k], lay.prm_slices[k]
                mem[a:b] = ob.operator.initial_memory(float(v[k]), th[c:d])
            self.compiled.opin(t0, x0, u, du, th, mem, self.compiled.aux, v)
        return mem

    # ---- running -----------------------------------------------------------------------------
    def run(
        self,
        t,
        inputs: Mapping[str, Signal] | None = None,
        params: Mapping | None = None,
        x0=None,
        method: str = "auto",
        rtol: float | None = None,
        atol=None,
        max_step: float = np.inf,
        max_steps: int | None = None,
        progress=None,
        deadline: float | None = None,
    ) -> SimResult:
        """Simulate and sample at times ``t`` (increasing array, or a scalar end time → 1001 samples).

        ``inputs`` maps input names to signals or numbers (constants; an input not given is 0);
        ``params`` maps parameter names to values; ``progress(fraction)`` is called between
        chunks of long runs.  ``rtol``, ``atol`` and ``max_steps`` default to the settings
        ``simulate.rtol``, ``simulate.atol_floor`` and ``simulate.max_steps``.  ``deadline``
        (a ``time.monotonic()`` value): past it scipy's solvers (radau, bdf, lsoda) stop with
        :class:`SimulationTimeout` at their next step, radau5 at the start and between the
        twenty chunks it then runs in; the compiled dopri5 checks it between chunks only (one
        chunk unless ``progress`` is given).  With ``method="auto"`` (see :meth:`choose`) a
        radau5 run that fails is repeated on dopri5.  ``stats`` of the result: the method
        that ran and the reason, step and call counts.

        Parameters
        ----------
        t : array_like or float
            Output times, s, strictly increasing (at least two); a scalar is the end time of
            1001 samples from 0.
        inputs : mapping of str to Signal or float, optional
            Input name → signal or constant number; an input not given is 0.
        params : mapping of str to float, optional
            Parameter name → value, overriding the model's values.
        x0 : array_like, optional
            Initial state in the order of :attr:`state_names` (default: the model's x0).
        method : {"auto", "dopri5", "radau5", "radau", "bdf", "lsoda"}, optional
            The integrator (default ``auto``).
        rtol : float, optional
            Relative tolerance (default: setting ``simulate.rtol``).
        atol : float or array_like, optional
            Absolute tolerance, one for all states or one per state, in the states' units
            (default: setting ``simulate.atol_floor``).
        max_step : float, optional
            Largest step, s (further capped by the input tables' spacing).
        max_steps : int, optional
            Largest number of steps (default: setting ``simulate.max_steps``).
        progress : callable, optional
            ``progress(fraction)`` called between chunks, fraction in [0, 1].
        deadline : float, optional
            A ``time.monotonic()`` value past which the run stops.

        Returns
        -------
        SimResult
            The outputs and states sampled at ``t``, with the run's ``stats``.

        Raises
        ------
        SignalError
            Bad output times, an unknown method or input, or an input that is not a signal.
        ParameterError
            An unknown parameter name.
        SimulationTimeout
            The run passed ``deadline``.
        SimulationError
            The integrator failed (step-size underflow, non-finite state, too many steps).
        """
        rtol = config.get("simulate.rtol") if rtol is None else rtol
        atol = config.get("simulate.atol_floor") if atol is None else atol
        max_steps = config.get("simulate.max_steps") if max_steps is None else max_steps
        t = np.array(t, float)  # a private, writable, contiguous copy
        if t.ndim == 0:
            t = np.linspace(0.0, float(t), 1001)
        if t.size < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
            raise SignalError("output times must be finite and strictly increasing (at least two)")
        if method not in METHODS:
            raise SignalError(f"unknown method {method!r}; choose one of {', '.join(METHODS)}")
        th = self.theta(params)
        x = self.initial_state(th) if x0 is None else np.asarray(x0, float).copy()
        bank = self.signal_bank(inputs)
        mem = self.initial_memory(t[0], x, th, bank)
        atol_v = np.broadcast_to(np.asarray(atol, float), (x.size,)).copy()
        max_step = min(max_step, config.get("simulate.table_steps") * bank.table_spacing())
        args = (t, x, th, bank, rtol, atol_v, max_step, max_steps, progress, deadline)
        if method != "auto":
            return self._integrate(method, "asked for", mem, *args)
        method, reason = self.choose(t, x, th, mem, bank)
        if method == "radau5":
            try:
                return self._integrate(method, reason, mem.copy(), *args)
            except SimulationTimeout:
                raise
            except SimulationError as exc:  # auto never leaves a model without an answer
                method, reason = "dopri5", f"{reason}; radau5 failed ({exc}), so dopri5 ran"
        return self._integrate(method, reason, mem, *args)

    def _integrate(
        self, method, reason, mem, t, x, th, bank, rtol, atol_v, max_step, max_steps, progress, deadline
    ) -> SimResult:
        """The integration of :meth:`run` with ``method`` (not auto), from memory ``mem``."""
        n = x.size
        aux = self.compiled.aux.copy()  # the tape's registers are written
        X = np.empty((t.size, n))
        Y = np.empty((t.size, len(self.output_names)))
        stats: Counter = Counter()
        n_chunks = 1 if progress is None else int(min(50, max(1, t.size // 20000)))
        if method == "radau5":
            sparse = self.sparse_jacobian()
            jaux = sparse.compiled.aux.copy()
            h_io = np.zeros(1)
            if deadline is not None:  # the compiled loop cannot look at the clock: check between chunks
                _check_deadline(deadline, float(t[0]))
                n_chunks = max(n_chunks, int(min(20, t.size - 1)))
        bounds = np.linspace(0, t.size - 1, n_chunks + 1).round().astype(int)
        for a, b in zip(bounds[:-1], bounds[1:]):
            tc = t[a : b + 1]
            breaks = bank.breaks(tc[0], tc[-1])
            Xc, Yc = X[a : b + 1], Y[a : b + 1]
            if method == "dopri5":
                st = dopri5(
                    *self.compiled.integrator_functions,
                    x,
                    th,
                    mem,
                    aux,
                    len(self.eqs.operators),
                    *bank.args(),
                    np.ascontiguousarray(tc),
                    breaks,
                    float(rtol),
                    atol_v,
                    0.0,
                    float(max_step),
                    int(max_steps),
                    Xc,
                    Yc,
                    self._flags,
                )
                if st.status != 0:
                    raise SimulationError(
                        f"integration failed ({STATUS[st.status]}) near t = "
                        f"{tc[max(st.written - 1, 0)]:.6g} s; check parameters or try --method radau"
                    )
                stats.update(
                    steps=st.steps,
                    rejected=st.rejected,
                    rhs_calls=st.rhs_calls,
                    reversal_rejections=st.reversal_rejections,
                )
            elif method == "radau5":
                stats.update(
                    self._run_radau5(
                        sparse, tc, x, th, mem, aux, jaux, bank, breaks, rtol, atol_v, h_io, max_step, max_steps, Xc, Yc
                    )
                )
            else:
                stats += self._run_scipy(
                    method, tc, x, th, mem, aux, bank, breaks, rtol, atol_v, max_step, Xc, Yc, deadline
                )
            x = np.ascontiguousarray(Xc[-1])
            if b < t.size - 1:
                _check_deadline(deadline, float(t[b]))
            if progress is not None:
                progress(b / (t.size - 1))
        return SimResult(
            t,
            {n: Y[:, i] for i, n in enumerate(self.output_names)},
            {n: X[:, i] for i, n in enumerate(self.state_names)},
            {
                "method": method,
                "reason": reason,
                **{k: int(stats[k]) for k in ("steps", "rejected", "rhs_calls", "reversal_rejections")},
                **(
                    {k: int(stats[k]) for k in ("jacobians", "factorizations", "newton_failures")}
                    if method == "radau5"
                    else {}
                ),
            },
            bank,
        )

    def _run_radau5(
        self, sparse, t, x, th, mem, aux, jaux, bank, breaks, rtol, atol_v, h_io, max_step, max_steps, X, Y
    ) -> dict:
        """One chunk on the compiled implicit integrator; returns its counts."""
        p = sparse.program
        with waiting("compiling the implicit integrator", status="the first stiff run only: numba keeps it"):
            kernel, inputs = implicit.compiled_radau5(), compiled_input_values()
        st = kernel(
            *self.compiled.integrator_functions,
            sparse.compiled.jac,
            inputs,
            reversal_at,
            x,
            th,
            mem,
            aux,
            jaux,
            len(self.eqs.operators),
            *bank.args(),
            np.ascontiguousarray(t),
            breaks,
            float(rtol),
            atol_v,
            h_io,
            float(max_step),
            int(max_steps),
            X,
            Y,
            self._flags,
            p.indptr,
            p.indices,
            p.slots,
            p.diagonal,
            p.plan,
            p.n_work,
            p.first_accumulator,
            p.constant,
            sparse.column_order(),
        )
        if st.status != 0:
            raise SimulationError(
                f"integration failed ({implicit.STATUS[st.status]}) near t = "
                f"{t[max(st.written - 1, 0)]:.6g} s; check parameters or try --method dopri5"
            )
        return {k: getattr(st, k) for k in st._fields if k not in ("status", "written")}

    def sparse_jacobian(self) -> SparseJacobian:
        """The model's sparse analytic Jacobian (:mod:`.stiffness`), built and compiled once.

        Returns
        -------
        SparseJacobian
            The compiled sparse Jacobian of the right-hand side, shared by later calls.

        Raises
        ------
        SimulationError
            The Jacobian could not be built or compiled (the message says why)."""
        if self._sparse is None:
            try:
                self._sparse = SparseJacobian(self.eqs)
            except Exception as exc:  # sympy or numba refused an expression of the model
                self._sparse = exc
        if isinstance(self._sparse, Exception):
            raise SimulationError(
                f"no analytic Jacobian for this model ({type(self._sparse).__name__}: {self._sparse})"
            )
        return self._sparse

    def jacobian_at(self, t0, x, th, mem, bank, sparse: bool = False):
        """∂(dx/dt)/∂x at time t0 and state x from the sparse analytic Jacobian.

        Where the equations have a kink the entries are the derivatives from the right
        (:mod:`bondgraph.numerics.jacobian`).

        Parameters
        ----------
        t0 : float
            Time, s.
        x : array_like
            State, in the order of :attr:`state_names`.
        th : numpy.ndarray
            θ, the parameter vector (see :meth:`theta`).
        mem : numpy.ndarray
            The memory operators' memory (see :meth:`initial_memory`).
        bank : SignalBank
            The packed inputs (see :meth:`signal_bank`).
        sparse : bool, optional
            Return a scipy CSC matrix instead of a dense array.

        Returns
        -------
        numpy.ndarray or scipy.sparse.csc_matrix
            The n × n Jacobian, 1/s for rates of states of like units.

        Raises
        ------
        SimulationError
            The model has no analytic Jacobian (see :meth:`sparse_jacobian`).
        """
        sj = self.sparse_jacobian()
        nu = max(len(self.input_names), 1)
        u, du = np.zeros(nu), np.zeros(nu)
        eval_inputs(t0, *bank.args(), u, du, True)
        J = sj.reduced(sj.augmented(t0, np.ascontiguousarray(x, float), u, du, th, mem))
        return J if sparse else J.toarray()

    def choose(self, t, x, th, mem, bank) -> tuple[str, str]:
        """The method ``auto`` runs, and why: ``radau5`` when the model is stiff for the output
        times ``t`` (:func:`bondgraph.numerics.stiffness.stiffness`), ``dopri5`` otherwise.

        The spectral radius comes from a finite-difference Jacobian of the compiled right-hand
        side for small models (no compilation), from the sparse analytic one above
        ``DENSE_EIGEN`` states.

        Parameters
        ----------
        t : numpy.ndarray
            Output times of the run, s.
        x : numpy.ndarray
            Initial state.
        th : numpy.ndarray
            θ, the parameter vector (see :meth:`theta`).
        mem : numpy.ndarray
            The memory operators' initial memory (see :meth:`initial_memory`).
        bank : SignalBank
            The packed inputs (see :meth:`signal_bank`).

        Returns
        -------
        method : str
            ``"radau5"`` or ``"dopri5"``.
        reason : str
            Why, in words (stored as ``stats["reason"]`` of the result).
        """
        n = x.size
        if n == 0:
            return "dopri5", "no states"
        if n <= DENSE_EIGEN:
            J = self._finite_difference_jacobian(t[0], x, th, mem, bank)
            radius = float(np.max(np.abs(np.linalg.eigvals(J)))) if np.all(np.isfinite(J)) else 0.0
        else:
            try:
                radius = spectral_radius(self.jacobian_at(t[0], x, th, mem, bank, sparse=True))
            except SimulationError as exc:
                return "dopri5", f"stiffness unknown: {exc}"
        verdict = stiffness(radius, t)
        if not verdict.stiff:
            return "dopri5", verdict.reason()
        try:
            self.sparse_jacobian()
        except SimulationError as exc:
            return "dopri5", f"{verdict.reason()}, but {exc}"
        return "radau5", verdict.reason()

    def choose_method(self, t, x, th, mem, bank) -> str:
        """The method ``auto`` runs (see :meth:`choose`).

        Parameters
        ----------
        t : numpy.ndarray
            Output times of the run, s.
        x : numpy.ndarray
            Initial state.
        th : numpy.ndarray
            θ, the parameter vector (see :meth:`theta`).
        mem : numpy.ndarray
            The memory operators' initial memory (see :meth:`initial_memory`).
        bank : SignalBank
            The packed inputs (see :meth:`signal_bank`).

        Returns
        -------
        str
            ``"radau5"`` or ``"dopri5"``.
        """
        return self.choose(t, x, th, mem, bank)[0]

    def _finite_difference_jacobian(self, t0, x, th, mem, bank) -> np.ndarray:
        n = x.size
        nu = max(len(self.input_names), 1)
        u, du = np.zeros(nu), np.zeros(nu)
        eval_inputs(t0, *bank.args(), u, du, True)
        f0, f1 = np.zeros(n), np.zeros(n)
        aux = self.compiled.aux.copy()
        self.compiled.rhs(t0, x, u, du, th, mem, aux, f0)
        J = np.zeros((n, n))
        for j in range(n):
            xp = x.copy()
            dxj = 1e-7 * max(abs(x[j]), 1e-9)
            xp[j] += dxj
            self.compiled.rhs(t0, xp, u, du, th, mem, aux, f1)
            J[:, j] = (f1 - f0) / dxj
        return J

    def _run_scipy(
        self, method, t, x, th, mem, aux, bank, breaks, rtol, atol_v, max_step, X, Y, deadline: float | None = None
    ) -> Counter:
        """scipy's stiff solvers; returns the step and right-hand-side counts."""
        c = self.compiled
        stats: Counter = Counter()
        nu = max(len(self.input_names), 1)
        u, du = np.zeros(nu), np.zeros(nu)
        dx = np.zeros(x.size)
        y = np.zeros(max(len(self.output_names), 1))
        nv = len(self.eqs.operators)
        v = np.zeros(max(nv, 1))
        args = bank.args()

        def f(tt, xx):
            eval_inputs(tt, *args, u, du, True)
            c.rhs(tt, np.ascontiguousarray(xx), u, du, th, mem, aux, dx)
            return dx.copy()

        def jac(tt, xx):
            return self.jacobian_at(tt, np.ascontiguousarray(xx), th, mem, bank, sparse=x.size > DENSE_EIGEN)

        solver_cls = {"radau": si.Radau, "bdf": si.BDF, "lsoda": si.LSODA}[method]
        kw = {"jac": jac} if method != "lsoda" else {}
        atol_v = np.maximum(atol_v, self._scale_atol(solver_cls, f, t, x, rtol, breaks, deadline, kw))
        edges = [t[0], *breaks, t[-1]]
        k = 0

        def emit(tt, xx):
            eval_inputs(tt, *args, u, du, True)
            c.output(tt, xx, u, du, th, mem, aux, y)
            return y[: len(self.output_names)]

        X[0], Y[0] = x, emit(t[0], x)
        k = 1
        for a, b in zip(edges[:-1], edges[1:]):
            s = solver_cls(f, a, x, b, rtol=rtol, atol=atol_v, max_step=max_step, **kw)
            while s.status == "running":
                _check_deadline(deadline, s.t)
                t_old = s.t
                msg = s.step()
                if s.status == "failed":
                    raise SimulationError(f"integration failed near t = {s.t:.6g} s ({msg})")
                dense = s.dense_output()
                while k < t.size and t[k] <= s.t:
                    X[k] = dense(t[k])
                    Y[k] = emit(t[k], np.ascontiguousarray(X[k]))
                    k += 1
                if nv:  # commit along the step so reversals inside it are followed
                    for th_ in np.linspace(0.0, 1.0, 9)[1:]:
                        tt = t_old + th_ * (s.t - t_old)
                        xx = np.ascontiguousarray(dense(tt))
                        eval_inputs(tt, *args, u, du, True)
                        c.commit(tt, xx, u, du, th, mem, aux, v)
                stats["steps"] += 1
            x = np.ascontiguousarray(s.y)
            stats["rhs_calls"] += s.nfev
        return stats

    def _scale_atol(self, solver_cls, f, t, x, rtol, breaks, deadline=None, kw=None):
        """atol_i = rtol·max|x_i| from a loose first pass (scipy's solvers weigh errors by
        atol + rtol·|x|, which chases rounding noise when a state crosses zero); ``kw``: the
        solver's Jacobian."""
        peak = np.abs(x).copy()
        floor = config.get("simulate.atol_floor")
        edges = [t[0], *breaks, t[-1]]
        xx = x.copy()
        for a, b in zip(edges[:-1], edges[1:]):
            s = solver_cls(f, a, xx, b, rtol=1e-3, atol=floor, **(kw or {}))
            while s.status == "running":
                _check_deadline(deadline, s.t)
                s.step()
                if s.status == "failed":
                    break
                peak = np.maximum(peak, np.abs(s.y))
            xx = s.y
        return np.maximum(rtol * peak, floor)


def simulate(model: Model | Equations, t, inputs: Mapping[str, Signal] | None = None, **kw) -> SimResult:
    """One-shot simulation: derive, compile (cached) and run; see :meth:`Simulator.run`.

    Parameters
    ----------
    model : Model or Equations
        The model, derived here when it is a :class:`~bondgraph.Model`.
    t : array_like or float
        Output times, s, strictly increasing; a scalar is the end time of 1001 samples from 0.
    inputs : mapping of str to Signal or float, optional
        Input name → signal or constant number; an input not given is 0.
    **kw
        The other keywords of :meth:`Simulator.run` (``params``, ``x0``, ``method``,
        ``rtol``, ``atol``, ``max_step``, ``max_steps``, ``progress``, ``deadline``).

    Returns
    -------
    SimResult
        The outputs and states sampled at ``t``.

    Raises
    ------
    BondGraphError
        The model cannot be derived, or bad input (see :meth:`Simulator.run`).
    SimulationError
        The integrator failed or passed its deadline.
    """
    return Simulator(model).run(t, inputs, **kw)
