"""Symbolic linearisation at an operating point: A, B, C, D, poles, zeros, frequency response.

The Jacobians come from :meth:`Equations.jacobian` (forward differentiation of the
straight-line program), symbolic in the parameters; numbers are substituted at the end.  Memory operators are replaced by their small-signal gain (slope from the virgin
state), input derivatives are held at zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import sympy as sp

from ..equations.derivation import derive
from ..equations.system import Equations
from ..model.graph import Model
from ..numerics.checks import check_linear
from ..support.errors import UsageError, did_you_mean


@dataclass
class LinearModel:
    """Numeric state-space model x' = A x + B u, y = C x + D u around an operating point.

    Single input, single output; the deviations x, u, y from the operating point are in the SI
    units of the states, the input and the output (so A is in 1/s for like states).

    Parameters
    ----------
    A : numpy.ndarray
        n × n state matrix.
    B : numpy.ndarray
        n × 1 input matrix.
    C : numpy.ndarray
        1 × n output matrix.
    D : numpy.ndarray
        1 × 1 feedthrough.
    states : list of str
        The state names, in the order of A's rows.
    input : str
        The input's name.
    output : str
        The output's name.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    input: str
    output: str

    @property
    def poles(self) -> np.ndarray:
        """Eigenvalues of A (rad/s, complex; stable when the real parts are negative), sorted."""
        return np.sort_complex(np.linalg.eigvals(self.A)) if self.A.size else np.zeros(0, complex)

    @property
    def zeros(self) -> np.ndarray:
        """Invariant (transmission) zeros of the SISO system from the Rosenbrock pencil."""
        n = self.A.shape[0]
        if n == 0:
            return np.zeros(0, complex)
        M = np.block([[self.A, self.B], [self.C, self.D]])
        N = np.zeros_like(M)
        N[:n, :n] = np.eye(n)
        scale = max(np.abs(self.A).max(), 1.0)
        ev = sla.eigvals(M / scale, N)
        ev = ev[np.isfinite(ev)] * scale
        return np.sort_complex(ev[np.abs(ev) < 1e12 * scale])

    @property
    def natural_frequencies(self) -> np.ndarray:
        """|λ| of the poles (one per conjugate pair), ascending; poles at 0 excluded."""
        p = self.poles
        p = p[p.imag >= 0]
        w = np.abs(p)
        tol = 1e-9 * (w.max() if w.size else 1.0)
        return np.sort(w[w > tol])

    def damping_ratios(self) -> np.ndarray:
        """Damping ratios ζ = −Re λ / |λ| of the poles, one per conjugate pair.

        Returns
        -------
        numpy.ndarray
            ζ (dimensionless; 1 for a real pole, < 0 for an unstable one) in the order of
            :attr:`natural_frequencies`; poles at 0 excluded.
        """
        p = self.poles
        p = p[p.imag >= 0]
        w = np.abs(p)
        keep = w > 1e-9 * (w.max() if w.size else 1.0)
        order = np.argsort(w[keep])
        return (-p[keep].real / w[keep])[order]

    def frequency_response(self, omega) -> np.ndarray:
        """H(jω) = C (jωI − A)⁻¹ B + D at angular frequencies ``omega`` (rad/s).

        Parameters
        ----------
        omega : float or array_like
            Angular frequencies, rad/s.

        Returns
        -------
        numpy.ndarray
            Complex H(jω), output unit per input unit, one per frequency.
        """
        omega = np.atleast_1d(np.asarray(omega, float))
        n = self.A.shape[0]
        out = np.empty(omega.size, complex)
        for k, w in enumerate(omega):
            out[k] = (self.C @ np.linalg.solve(1j * w * np.eye(n) - self.A, self.B) + self.D)[0, 0]
        return out

    def dc_gain(self) -> float:
        """The static gain H(0) = D − C A⁻¹ B.

        Returns
        -------
        float
            Output unit per input unit; ``inf`` when A is singular (a free integrator).
        """
        try:
            return float((self.D - self.C @ np.linalg.solve(self.A, self.B))[0, 0])
        except np.linalg.LinAlgError:
            return float("inf")

    def to_control(self, name: str = ""):
        """The model as a ``control.StateSpace`` (python-control, the optional extra
        ``control``), with its input, output and state names, for Bode plots, margins and
        controller design::

            sys = linearize(derive(model), "V", "x").to_control()
            control.bode_plot(sys)

        Parameters
        ----------
        name : str, optional
            The system's name (default: python-control's own).

        Returns
        -------
        control.StateSpace
            The same A, B, C, D with named signals.

        Raises
        ------
        UsageError
            python-control is not installed.
        """
        try:
            import control
        except ImportError:
            raise UsageError("python-control is not installed: pip install 'bondgraph[control]'") from None
        return control.ss(
            self.A,
            self.B,
            self.C,
            self.D,
            inputs=[self.input],
            outputs=[self.output],
            states=list(self.states),
            **({"name": name} if name else {}),
        )

    def python_control_script(self, name: str = "model", comment: str = "") -> str:
        """Python source that builds this model as ``control.StateSpace`` named ``model``
        (numbers written exactly), e.g. to save and import from a control-design script.

        Parameters
        ----------
        name : str, optional
            The ``name`` given to ``control.ss`` in the script.
        comment : str, optional
            The first line's comment (default: "linearised by bondgraph").

        Returns
        -------
        str
            The script's source, ending with a newline.
        """

        def arr(M):
            return "np.array(" + repr(np.asarray(M, float).tolist()) + ")"

        lines = [
            f"# {comment}" if comment else "# linearised by bondgraph",
            "import control",
            "import numpy as np",
            "",
            f"A = {arr(self.A) if self.A.size else 'np.zeros((0, 0))'}",
            f"B = {arr(self.B) if self.B.size else 'np.zeros((0, 1))'}",
            f"C = {arr(self.C) if self.C.size else 'np.zeros((1, 0))'}",
            f"D = {arr(self.D)}",
            f"model = control.ss(A, B, C, D, inputs={[self.input]!r}, outputs={[self.output]!r},",
            f"                   states={list(self.states)!r}, name={name!r})",
            "",
        ]
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        """Poles, zeros, natural frequencies and damping ratios as a table (notebook display)."""
        from .display import linear_model_html

        return linear_model_html(self)

    def summary(self) -> dict:
        """The JSON object of ``bondgraph linearize --json``.

        Returns
        -------
        dict
            ``input``, ``output``, ``states``, ``natural_frequencies_rad_s``,
            ``damping_ratios``, ``poles`` and ``zeros`` (as [re, im] pairs, rad/s),
            ``rhp_zeros`` (count), ``dc_gain`` and the matrices ``A``, ``B``, ``C``, ``D``.
        """
        z = self.zeros
        return {
            "input": self.input,
            "output": self.output,
            "states": self.states,
            "natural_frequencies_rad_s": [float(w) for w in self.natural_frequencies],
            "damping_ratios": [float(d) for d in self.damping_ratios()],
            "poles": [[float(p.real), float(p.imag)] for p in self.poles],
            "zeros": [[float(p.real), float(p.imag)] for p in z],
            "rhp_zeros": int(np.sum(z.real > 1e-9 * max(1.0, float(np.abs(z).max(initial=0.0))))),
            "dc_gain": self.dc_gain(),
            "A": self.A.tolist(),
            "B": self.B.ravel().tolist(),
            "C": self.C.ravel().tolist(),
            "D": float(self.D[0, 0]),
        }


def symbolic_matrices(eqs: Equations, input: str, output: str, op_gains: dict | None = None):
    """Symbolic (A, B, C, D) in the parameters and the operating point symbols.

    Parameters
    ----------
    eqs : Equations
        The derived model.
    input : str
        The input's name.
    output : str
        The output's name.
    op_gains : dict, optional
        Operator output symbol → its small-signal slope (0 when not given: frozen memory).

    Returns
    -------
    A : sympy.Matrix
        n × n.
    B : sympy.Matrix
        n × 1.
    C : sympy.Matrix
        1 × n.
    D : sympy.Matrix
        1 × 1.

    Raises
    ------
    UsageError
        An unknown input or output.
    """
    names = [str(u) for u in eqs.inputs]
    if input not in names:
        raise UsageError(did_you_mean(input, names, "input"))
    if output not in eqs.outputs:
        raise UsageError(did_you_mean(output, list(eqs.outputs), "output"))
    u = eqs.inputs[names.index(input)]
    xs = eqs.state_symbols
    rates = [eqs.rates[s] for s in xs]
    y = [eqs.outputs[output]]
    A = eqs.jacobian(rates, xs, op_gains)
    B = eqs.jacobian(rates, [u], op_gains)
    C = eqs.jacobian(y, xs, op_gains)
    D = eqs.jacobian(y, [u], op_gains)
    return A, B, C, D


def linearize(
    eqs: Model | Equations,
    input: str | None = None,
    output: str | None = None,
    params: dict | None = None,
    x_op: dict | None = None,
    u_op: dict | None = None,
) -> LinearModel:
    """Linearise the response of ``output`` to ``input`` around an operating point.

    Parameters
    ----------
    eqs : Model or Equations
        The model, or its derived equations (a model is derived first).
    input, output : str, optional
        Names of a declared input and output (default: the model's first of each).
    params : dict, optional
        Parameter values by name (default: the model's values).
    x_op : dict, optional
        State values by state name (default: the initial state).
    u_op : dict, optional
        Input values by name (default: 0); input rates are held at 0 and memory operators
        are replaced by their small-signal gain from rest.

    Returns
    -------
    LinearModel
        A, B, C, D in SI units of the states, input and output.

    Raises
    ------
    UsageError
        For an unknown input or output.
    ParameterError
        When the matrices are not finite at these values.
    """
    if isinstance(eqs, Model):
        eqs = derive(eqs)
    input = input if input is not None else next(iter(eqs.model.inputs), "")
    output = output if output is not None else next(iter(eqs.model.outputs), "")
    table = eqs.model.parameter_table()
    by_name = {str(k): float(v) for k, v in (params or {}).items()}
    values = {p: by_name.get(p.name, table[p]) for p in eqs.params}
    op_gains = {}
    for ob in eqs.operators:
        prm = np.array([values[s] for s in ob.params], float)
        op_gains[ob.symbol] = sp.Float(ob.operator.small_signal_gain(prm))
    A, B, C, D = symbolic_matrices(eqs, input, output, op_gains)
    point = dict(values)
    for st in eqs.states:
        point[st.symbol] = float(st.x0.xreplace(values)) if x_op is None else float(x_op.get(str(st.symbol), 0.0))
    for s in eqs.inputs:
        point[s] = float((u_op or {}).get(str(s), 0.0))
    for s in eqs.input_rates:
        point[s] = 0.0
    for ob in eqs.operators:
        point[ob.symbol] = 0.0

    def num(M):
        E = M.xreplace(point).evalf()
        try:
            return np.array(E, dtype=float).reshape(M.shape)
        except TypeError:  # zoo, nan or complex entries (a parameter at 0 in a denominator)
            return np.array([float(e) if e.is_real and e.is_finite else np.nan for e in E], float).reshape(M.shape)

    mats = num(A), num(B), num(C), num(D)
    check_linear(eqs.model, mats, {p.name: v for p, v in values.items()})
    return LinearModel(*mats, [str(s) for s in eqs.state_symbols], input, output)
