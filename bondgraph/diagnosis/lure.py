"""A linear model with static nonlinear terms in some elements' laws (a Lur'e system),
simulated on the exact linear route.

The model's elements ``el_k`` get laws law_k(x) + w_k with w_k = term(c_k, r2_k, x_k, a_k),
c_k one coefficient or a tuple of them (a term with an even and an odd part, say),
x_k the element's own variable (q of a C, p of an I, f of an R) and a_k the displacement of a
partner element, or the drive itself (partner :data:`DRIVE`: a law that moves with the field),
or None.  The model with the w_k as extra inputs is linear; its
first-order-hold discretisation (every input linear between samples, exact for the linear
part) is stepped sample by sample in compiled code, and at each sample the small implicit
equation w = term(x(w)) (x depends on w only through the hold's direct term) is solved by
Newton's method from the previous sample's w; the term, a polynomial in x and a plus at most
one smooth saturation h·tanh(g·x) of the element's own variable (Coulomb friction smoothed,
say), is passed as its coefficients, so the stepping kernel is compiled once.  Unlike iterating on whole trajectories, this converges however strong the
nonlinearity (a softening resonance that jumps between branches included); when a step does
not (a term that makes the model unstable), :class:`NotConverged` is raised and the caller
takes the term's values as predicting nothing.  (The callers once integrated the rewritten
model instead: on two records of the general-systems generator none of 454 such integrations
predicted better than 62 % of the output left unexplained, and they took 85 s of one record's
348 s.)
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np
import scipy.optimize
import sympy as sp
from numba import njit

from ..equations.derivation import derive
from ..linear.lti import StateSpace, foh, linear_matrices
from ..model.elements import C, I, R
from ..model.graph import Model, Quantity
from ..numerics.steady import starts_steady
from ..support.errors import BondGraphError
from .rewrite import modify_law

#: the partner that names the drive (the Lur'e model's input) instead of an element
DRIVE = "<drive>"


class NotConverged(BondGraphError, RuntimeError):
    """The fixed-point iteration of a Lur'e system did not converge."""


def _variable(model: Model, element: str) -> Quantity:
    el = model.elements[element]
    what = "q" if isinstance(el, C) else "p" if isinstance(el, I) else "f" if isinstance(el, R) else None
    if what is None:
        raise BondGraphError(f"'{element}' is not a C, I or R element")
    return Quantity(what, element)


class Lure:
    """``model`` (linear) with nonlinear terms on ``elements`` (see the module docstring);
    ``partners[el]``: an element whose displacement the term of ``el`` uses, :data:`DRIVE`
    for the drive, or None.
    ``fixed``: terms already part of the model being extended, one (element, partner, term,
    c, r2) each (c a number or a tuple of numbers), held as they are while the new elements'
    terms are fitted.  A new term may act on an element that holds one (a hardening after a
    softening of the same spring, friction beside a nonlinear damping): the terms on an element
    add up in its law, sharing its partner, with at most one saturation h·tanh(g·x) among them.

    Parameters
    ----------
    model : Model
        The linear model the terms extend.
    input : str
        The drive input.
    output : str
        The compared output.
    elements : sequence of str
        The elements that get new terms.
    partners : mapping of str to str or None
        Element → its partner, :data:`DRIVE` or None.
    dt : float
        The record's sample interval, s.
    fixed : sequence of tuple, optional
        Terms held as they are: (element, partner, term, c, r2) each.

    Raises
    ------
    BondGraphError
        Two new terms on one element, terms on one element with different partners, or a
        model that is not linear in its states.
    """

    def __init__(
        self,
        model: Model,
        input: str,
        output: str,
        elements: Sequence[str],
        partners: Mapping[str, str | None],
        dt: float,
        fixed: Sequence[tuple] = (),
    ):
        self.fixed = [(el, p, term, _coefficient(c), float(r2)) for el, p, term, c, r2 in fixed]
        #: the elements of the new terms, one term each
        self.new = list(elements)
        if len(set(self.new)) < len(self.new):
            raise BondGraphError("two new nonlinear terms on one element")
        # one slot per element: the terms on an element (held ones, a new one) add up in its law
        elements = list(dict.fromkeys([el for el, *_ in self.fixed] + self.new))
        own = [p for _, p, *_ in self.fixed] + [partners.get(el) for el in self.new]
        partners = {}
        for el, p in zip([el for el, *_ in self.fixed] + self.new, own):
            if p and partners.get(el) and partners[el] != p:
                raise BondGraphError(f"the nonlinear terms on '{el}' use different partners")
            partners[el] = partners.get(el) or p
        self._slot = [elements.index(el) for el, *_ in self.fixed] + [elements.index(el) for el in self.new]
        self._own_partner = [bool(p) for p in own]
        aug = model.copy()
        self.n = len(elements)
        self.elements = elements
        ws = []
        for k, el in enumerate(elements):
            w = aug.input(f"diag.w{k}")
            ws.append(f"diag.w{k}")
            modify_law(aug, el, lambda x, old, w=w: old + w)
            aug.output(f"diag.x:{el}", _variable(model, el))
            if partners.get(el):
                aug.output(
                    f"diag.a:{el}", model.inputs[input].symbol if partners[el] == DRIVE else Quantity("q", partners[el])
                )
        eqs = derive(aug)
        self.outputs = (
            [output] + [f"diag.x:{el}" for el in elements] + [f"diag.a:{el}" for el in elements if partners.get(el)]
        )
        self.inputs = [input] + ws
        mats, exact, _ = linear_matrices(eqs, self.inputs, self.outputs)
        if not exact:
            raise BondGraphError("the model is not linear in its states")
        n, m, p = len(eqs.state_symbols), len(self.inputs), len(self.outputs)
        self._fn = sp.lambdify([eqs.params], mats, modules="numpy", cse=True)
        self._shapes = [(n, n), (n, m), (p, n), (p, m)]
        self.partners = [bool(partners.get(el)) for el in elements]
        self.eqs, self.dt = eqs, dt

    def theta(self, values: Mapping[str, float]) -> np.ndarray:
        """θ of the augmented model with ``values`` over the model's.

        Parameters
        ----------
        values : mapping of str to float
            Parameter values by name (others at the model's).

        Returns
        -------
        numpy.ndarray
            θ in the order of the augmented equations' parameters.
        """
        from ..numerics.codegen import parameter_vector

        th = parameter_vector(self.eqs)
        index = {p.name: i for i, p in enumerate(self.eqs.params)}
        for k, v in values.items():
            if k in index:
                th[index[k]] = v
        return th

    def linear_responses(self, values: Mapping[str, float], u: np.ndarray, term: Callable) -> dict[str, np.ndarray]:
        """The element variables (``diag.x:<element>``, ``diag.a:<element>``: the partner's
        displacement) and the output, with the fixed terms but none of the new ones (``term``:
        the one :meth:`simulate` will use).

        Parameters
        ----------
        values : mapping of str to float
            Parameter values by name (others at the model's).
        u : numpy.ndarray
            The drive's samples (drive units).
        term : callable
            The new terms' function ``term(c, r2, x, a)``.

        Returns
        -------
        dict of str to numpy.ndarray
            Output name → series on every sample.

        Raises
        ------
        NotConverged
            The fixed terms make the model diverge.
        """
        Y, ok = self._run(values, u, term, [(0.0, 0.0)] * len(self.new), len(self.fixed) > 0, active_new=False)
        if not ok:
            raise NotConverged("the model's own nonlinear terms make it diverge")
        return {o: Y[:, r] for r, o in enumerate(self.outputs)}

    def simulate(
        self, values: Mapping[str, float], u: np.ndarray, term: Callable, coefs: Sequence[tuple]
    ) -> np.ndarray:
        """Raw output for the drive samples ``u`` with w_k = term(c_k, r2_k, x_k, a_k),
        ``coefs[k] = (c_k, r2_k)`` (c_k a number, or a tuple for a term of several
        coefficients); ``term`` is written in arithmetic that works on sympy
        symbols and is a polynomial in x and a, plus at most one h·tanh(g·x) (see
        :func:`polynomial_term`).

        Parameters
        ----------
        values : mapping of str to float
            Parameter values by name (others at the model's).
        u : numpy.ndarray
            The drive's samples (drive units).
        term : callable
            ``term(c, r2, x, a)``.
        coefs : sequence of tuple
            (c_k, r2_k) per new element: c_k a float or a tuple of floats, r2_k a float.

        Returns
        -------
        numpy.ndarray
            The raw output on every sample (sensor gain 1, no offset).

        Raises
        ------
        NotConverged
            The terms make the model diverge, or ``term`` is not of the supported form.
        """
        coefs = [(_coefficient(c), float(r2)) for c, r2 in coefs]
        if len(coefs) != len(self.new):
            raise ValueError(f"{len(coefs)} coefficients for {len(self.new)} new terms")
        Y, ok = self._run(values, u, term, coefs, True)
        if not ok:
            raise NotConverged("the nonlinear term makes the model diverge (an implicit step did not converge)")
        return Y[:, 0]

    def site_response(self, values: Mapping[str, float], w: np.ndarray, element: str) -> np.ndarray:
        """The output's response to a series ``w`` added to the law of ``element`` (one of
        :attr:`elements`), the drive at zero and the nonlinear terms left out: the linear
        transfer from that site to the output (raw, sensor gain 1).

        Parameters
        ----------
        values : mapping
            Parameter values by name.
        w : ndarray
            The series added to the element's law, on the record's samples (the law's units:
            force for a spring); the response starts where setting ``record.start`` says
            (its steady state at ``w[0]`` by default, as the model's runs start).
        element : str
            The element.

        Returns
        -------
        ndarray
        """
        k = self.elements.index(element)
        A, B, C, D = self._matrices(self.theta(values))
        ss = StateSpace(A, B[:, [1 + k]], C[[0]], D[[0]][:, [1 + k]])
        return ss.response(self.dt, np.asarray(w, float), steady=starts_steady())[:, 0]

    def hysteretic(
        self, values: Mapping[str, float], u: np.ndarray, element: str, kh: float, zmax: float
    ) -> np.ndarray:
        """Raw output with w = k_h·z in the law of ``element``, z the Bouc–Wen state of the
        element's own variable (n = 1, β = γ = 1/(2·z_max): see
        :mod:`bondgraph.diagnosis.restoring`), exact per increment of that variable between
        samples; the implicit sample equation (x depends on w through the hold's direct term)
        solved by fixed-point iteration.  Only for a Lur'e system without other terms.

        Parameters
        ----------
        values : mapping of str to float
            Parameter values by name (others at the model's).
        u : numpy.ndarray
            The drive's samples (drive units).
        element : str
            The element whose law gets the term.
        kh : float
            k_h, force per unit z (N/m for a spring).
        zmax : float
            z_max, the saturation level of z (displacement, m).

        Returns
        -------
        numpy.ndarray
            The raw output on every sample.

        Raises
        ------
        NotConverged
            When the fixed point is not reached (a term that makes the model unstable).
        """
        if self.n != 1 or self.fixed:
            raise NotConverged("the hysteretic term is stepped alone")
        th = self.theta(values)
        A, B, C, D = self._matrices(th)
        Phi, Gam, G1 = foh(A, B, self.dt)
        Dd = D + C @ G1
        u = np.ascontiguousarray(u, float)
        Y = np.empty(u.size)
        row = self.outputs.index(f"diag.x:{element}")
        # z at rest (0), so w = 0: the start is the linear model's (steady or rest)
        x_s, _ = self._start(A, B, C, D, float(u[0]), None, None, False)
        xi0 = x_s - G1[:, 0] * u[0]
        x_prev = float(C[row] @ x_s + D[row, 0] * u[0]) if starts_steady() else 0.0
        ok = _step_bouc_wen(
            np.ascontiguousarray(Phi),
            np.ascontiguousarray(Gam),
            np.ascontiguousarray(C),
            np.ascontiguousarray(Dd),
            np.ascontiguousarray(G1),
            u,
            xi0,
            x_prev,
            row,
            float(kh),
            float(zmax),
            Y,
        )
        if not ok:
            raise NotConverged("the hysteretic term makes the model diverge")
        return Y

    def _matrices(self, th: np.ndarray):
        """A, B (inputs: drive, w_0..), C (rows: self.outputs), D of the augmented model."""
        return tuple(np.array(M, dtype=float).reshape(shape) for M, shape in zip(self._fn(th), self._shapes))

    def _run(self, values, u, term, coefs, active, active_new=True):
        th = self.theta(values)
        A, B, C, D = self._matrices(th)
        Phi, Gam, G1 = foh(A, B, self.dt)
        Dd = D + C @ G1
        u = np.ascontiguousarray(u, float)
        Y = np.empty((u.size, len(self.outputs)))
        a_rows = np.array(
            [self.outputs.index(f"diag.a:{el}") if self.partners[k] else -1 for k, el in enumerate(self.elements)],
            np.int64,
        )
        terms = [(t, c, r2) for _, _, t, c, r2 in self.fixed] + [
            (term if active_new else None, c, r2) for c, r2 in coefs
        ]
        laws = [
            polynomial_term(t, self._own_partner[k], _arity(c))(c, r2)
            if t is not None
            else (np.zeros((1, 1)), np.zeros(2))
            for k, (t, c, r2) in enumerate(terms)
        ]
        P = np.zeros((self.n, max(m.shape[0] for m, _ in laws), max(m.shape[1] for m, _ in laws)))
        HG = np.zeros((self.n, 2))
        for k, (m, hg) in enumerate(laws):  # the terms on one element add up
            j = self._slot[k]
            P[j, : m.shape[0], : m.shape[1]] += m
            if hg[0] != 0.0:
                if HG[j, 0] != 0.0:
                    raise NotConverged(f"two saturations in the law of '{self.elements[j]}'")
                HG[j] = hg
        x_s, w_s = self._start(A, B, C, D, float(u[0]), P, HG, active)
        xi0 = x_s - G1[:, 0] * u[0] - G1[:, 1:] @ w_s
        ok = _step(
            np.ascontiguousarray(Phi),
            np.ascontiguousarray(Gam),
            np.ascontiguousarray(C),
            np.ascontiguousarray(Dd),
            np.ascontiguousarray(G1),
            u,
            xi0,
            w_s,
            self.n,
            a_rows,
            P,
            HG,
            active,
            Y,
        )
        return Y, ok

    def _start(self, A, B, C, D, u0: float, P, HG, active: bool) -> tuple[np.ndarray, np.ndarray]:
        """(x, w) at the start of a run: rest (zeros), or with ``record.start = "steady"`` the
        equilibrium A·x + B·(u0, w) = 0 with w = term(x) (``active``; else w = 0), w solved by
        :func:`scipy.optimize.root` from 0; rest when A is singular, the linear equilibrium
        (w = 0) when the root is not found.  Rest is the equilibrium when u0 = 0 and no term
        has a constant part, and is returned as it is then."""
        n, n_el = A.shape[0], B.shape[1] - 1
        rest = (np.zeros(n), np.zeros(n_el))
        constant = active and P is not None and bool(np.any(P[:, 0, 0]))
        if not starts_steady() or (u0 == 0.0 and not constant):
            return rest
        try:
            A_inv = np.linalg.inv(A)
        except np.linalg.LinAlgError:
            return rest
        if not np.all(np.isfinite(A_inv)):
            return rest

        def state(w):
            return -A_inv @ (B[:, 0] * u0 + B[:, 1:] @ w)

        if not active:
            return state(rest[1]), rest[1]
        a_rows = [self.outputs.index(f"diag.a:{el}") if self.partners[k] else -1 for k, el in enumerate(self.elements)]

        def residual(w):
            rows = C @ state(w) + D[:, 0] * u0 + D[:, 1:] @ w
            g = np.empty(n_el)
            for j in range(n_el):
                x, a = rows[1 + j], (rows[a_rows[j]] if a_rows[j] >= 0 else 0.0)
                f = HG[j, 0] * np.tanh(HG[j, 1] * x)
                f += sum(P[j, i, m] * x**i * a**m for i in range(P.shape[1]) for m in range(P.shape[2]))
                g[j] = w[j] - f
            return g

        sol = scipy.optimize.root(residual, np.zeros(n_el), method="hybr")
        w = sol.x if sol.success and np.all(np.isfinite(sol.x)) else rest[1]
        return state(w), w


_TERMS: dict = {}


def _coefficient(c):
    """A term's coefficient as a float, or a tuple of floats for a term of several."""
    return tuple(float(v) for v in c) if isinstance(c, (tuple, list, np.ndarray)) else float(c)


def _arity(c) -> int:
    """How many coefficients ``c`` holds."""
    return len(c) if isinstance(c, tuple) else 1


def polynomial_term(term: Callable, partner: bool, arity: int = 1):
    """``term(c, r2, x, a)`` (``a`` None without a partner; ``c`` a tuple of ``arity``
    coefficients when ``arity`` > 1) as a polynomial in x and a plus at
    most one smooth saturation h·tanh(g·x) of the element's own variable, the coefficients
    functions of (c, r2): a function (c, r2) → (P, (h, g)) with
    term = Σ P[i, j]·x^i·a^j + h·tanh(g·x), made once per process and formula (and looked up
    by the function itself after its first call).  Any other
    term raises :class:`NotConverged` (the caller then integrates).

    Parameters
    ----------
    term : callable
        ``term(c, r2, x, a)``.
    partner : bool
        Whether the term has a partner variable a.
    arity : int, optional
        How many coefficients ``c`` holds (1: a number).

    Returns
    -------
    callable
        (c, r2) → (P, (h, g)); a scalar c of 0 is every coefficient at 0.

    Raises
    ------
    NotConverged
        The term is not of that form.
    """
    try:
        return _TERMS[(term, partner, arity)]  # the same function again: no sympy
    except (KeyError, TypeError):
        pass
    r2, x, a = sp.symbols("r2 x a", real=True)
    cs = sp.symbols(f"c0:{arity}", real=True)
    expr = sp.expand(sp.sympify(term(cs[0] if arity == 1 else cs, r2, x, a if partner else None)))
    key = (sp.srepr(expr), arity)
    if key not in _TERMS:
        refuse = NotConverged(f"the term {expr} is not a polynomial in the element's variables plus one h·tanh(g·x)")
        h, g = sp.Integer(0), sp.Integer(0)
        sats = list(expr.atoms(sp.tanh))
        if len(sats) > 1:
            raise refuse
        if sats:
            g = sp.simplify(sats[0].args[0] / x)
            h = expr.coeff(sats[0])
            if g.free_symbols & {x, a} or h.free_symbols & {x, a} or g == 0:
                raise refuse
            expr = sp.expand(expr - h * sats[0])
        try:
            poly = sp.Poly(expr, x, a)
        except sp.PolynomialError as exc:
            raise refuse from exc
        if any(v.free_symbols & {x, a} for v in poly.coeffs()):
            raise refuse
        I, J = poly.degree(x) + 1, poly.degree(a) + 1
        I, J = max(I, 1), max(J, 1)
        entries = [[poly.coeff_monomial(x**i * a**j) for j in range(J)] for i in range(I)]
        f = sp.lambdify((*cs, r2), [entries, [h, g]], modules="numpy")

        def coefficients(cv, r2v, f=f):
            cv = np.broadcast_to(np.asarray(cv, np.float64), (arity,))
            with np.errstate(divide="ignore", invalid="ignore"):
                P, hg = f(*cv, np.float64(r2v))
            hg = np.array(hg, float)
            return np.array(P, float), (hg if hg[0] != 0.0 and np.all(np.isfinite(hg)) else np.zeros(2))

        _TERMS[key] = coefficients
    try:
        _TERMS[(term, partner, arity)] = _TERMS[key]
    except TypeError:  # an unhashable callable: its formula's key only
        pass
    return _TERMS[key]


@njit(cache=True, nogil=True)
def _step(Phi, Gam, C, Dd, G1, u, xi0, w0, n_el, a_rows, P, HG, active, Y):
    """Sample-by-sample first-order-hold stepping of the augmented model (inputs: drive, then
    the n_el nonlinear terms; output rows: output, element variables, partners); at each
    sample Newton's method (with a backtracking line search) on w − term(x(w), a(w)) = 0 from
    the linear extrapolation of the last two samples' w (w = 0 throughout unless ``active``),
    the term of element j being
    Σ P[j, i, l]·x^i·a^l + HG[j, 0]·tanh(HG[j, 1]·x), from the discrete state ``xi0`` (ξ = x −
    Γ1·(u, w) at the first sample) and the terms ``w0``.  False when a step does not converge.
    One function without array-passing helpers: numba's reference counting of the arrays
    handed to inlined helpers cost more than the arithmetic (1.35-1.6x on the whole step).
    The powers are kept as running products, the elimination is skipped for terms that do not
    move each other within a sample, and such terms stop after one Newton step when its own
    quadratic error estimate is far below the tolerance: 1.6x (33 → 20 ms a run) on the law
    fits' runs of a three-spring site (138 456 samples), the same output to 1e-15."""
    n = Phi.shape[0]
    N = u.shape[0]
    R = C.shape[0]
    nx, na = P.shape[1], P.shape[2]  # powers of x and of a in the terms
    xi = np.zeros(n)
    xn = np.zeros(n)
    w = w0.copy()
    g = np.zeros(n_el)
    J = np.zeros((n_el, n_el))
    step = np.zeros(n_el)
    curve = np.zeros(n_el)  # each term's second derivative along its own w
    trial = np.zeros(n_el)
    wprev = w0.copy()
    row = np.zeros(R)
    scale = 1e-300  # largest |w| so far: the convergence test's scale
    coupled = False  # does a term's variable move with another term within the sample?
    for j in range(n_el):
        for l in range(n_el):
            if l != j and (Dd[1 + j, 1 + l] != 0.0 or (a_rows[j] >= 0 and Dd[a_rows[j], 1 + l] != 0.0)):
                coupled = True
    for i in range(n):
        xi[i] = xi0[i]
    for k in range(N):
        for r in range(R):  # every row without the terms' direct part
            acc = Dd[r, 0] * u[k]
            for i in range(n):
                acc += C[r, i] * xi[i]
            row[r] = acc
        converged = not active
        if active:
            full, last, change = False, 0.0, 0.0  # was the last step a full Newton step, its size
            lam, norm0, halvings, newton = 1.0, -1.0, 0, 0  # norm0 < 0: not in a line search
            for j in range(n_el):  # from the linear extrapolation of the last two samples
                wp = w[j]
                w[j] = 2.0 * wp - wprev[j]
                wprev[j] = wp
                trial[j] = w[j]
            while True:
                # g = trial - term(x(trial), a(trial)) and its Jacobian J
                norm, big = 0.0, 0.0
                for j in range(n_el):
                    x = row[1 + j]
                    for l in range(n_el):
                        x += Dd[1 + j, 1 + l] * trial[l]
                    ar = a_rows[j]
                    a = 0.0
                    if ar >= 0:
                        a = row[ar]
                        for l in range(n_el):
                            a += Dd[ar, 1 + l] * trial[l]
                    f = fx = fa = fxx = fxa = faa = 0.0
                    if HG[j, 0] != 0.0:
                        th = np.tanh(HG[j, 1] * x)
                        f += HG[j, 0] * th
                        fx += HG[j, 0] * HG[j, 1] * (1.0 - th * th)
                        fxx -= 2.0 * HG[j, 0] * HG[j, 1] * HG[j, 1] * th * (1.0 - th * th)
                    xp, xq, xr = 1.0, 0.0, 0.0  # x^i, x^(i-1) and x^(i-2), kept as products (no pow)
                    for i in range(nx):
                        aj, aq, ar2 = 1.0, 0.0, 0.0  # a^m, a^(m-1) and a^(m-2)
                        for m in range(na):
                            p = P[j, i, m]
                            if p != 0.0:
                                f += p * xp * aj
                                fx += i * p * xq * aj
                                fa += m * p * xp * aq
                                fxx += i * (i - 1) * p * xr * aj
                                fxa += i * m * p * xq * aq
                                faa += m * (m - 1) * p * xp * ar2
                            ar2 = aq
                            aq = aj
                            aj *= a
                        xr = xq
                        xq = xp
                        xp *= x
                    s2 = Dd[1 + j, 1 + j]
                    t2 = Dd[ar, 1 + j] if ar >= 0 else 0.0
                    curve[j] = fxx * s2 * s2 + 2.0 * fxa * s2 * t2 + faa * t2 * t2
                    g[j] = trial[j] - f
                    norm += g[j] * g[j]
                    big = max(big, abs(f))
                    for l in range(n_el):
                        J[j, l] = (
                            (1.0 if j == l else 0.0) - fx * Dd[1 + j, 1 + l] - (fa * Dd[ar, 1 + l] if ar >= 0 else 0.0)
                        )
                if norm0 >= 0.0:  # a trial of the line search (backtracking: a saturating
                    #                              term can send a full Newton step far past the root)
                    if norm > (1.0 - 1e-4 * lam) * norm0:
                        halvings += 1
                        if halvings >= 40:
                            break
                        lam *= 0.5
                        for j in range(n_el):
                            trial[j] = w[j] - lam * step[j]
                        continue
                    for j in range(n_el):
                        w[j] = trial[j]
                    full, last = lam == 1.0, change
                    scale = max(scale, big)
                    if lam * change <= 1e-12 * scale:
                        converged = True
                        break
                else:
                    scale = max(scale, big)
                if newton >= 60:
                    break
                newton += 1
                # step = J⁻¹ g (Gaussian elimination with partial pivoting; J overwritten;
                # a diagonal J, terms not coupled within the sample, needs the division only)
                for j in range(n_el):
                    step[j] = g[j]
                for c in range(n_el if coupled else 0):
                    pv = c
                    for r in range(c + 1, n_el):
                        if abs(J[r, c]) > abs(J[pv, c]):
                            pv = r
                    if pv != c:
                        for l in range(n_el):
                            J[c, l], J[pv, l] = J[pv, l], J[c, l]
                        step[c], step[pv] = step[pv], step[c]
                    for r in range(c + 1, n_el):
                        fq = J[r, c] / J[c, c]
                        for l in range(c, n_el):
                            J[r, l] -= fq * J[c, l]
                        step[r] -= fq * step[c]
                for c in range(n_el - 1, -1, -1):
                    acc = step[c]
                    for l in range(c + 1, n_el):
                        acc -= J[c, l] * step[l]
                    step[c] = acc / J[c, c]
                change = 0.0
                for j in range(n_el):
                    change = max(change, abs(step[j]))
                if not np.isfinite(change):
                    return False
                # converged: the step is below the tolerance, or, after a full step, quadratic
                # convergence (next ≈ change³/last²) puts the step after this one below it
                # or, terms not coupled, the step's own quadratic error estimate
                # (|φ''|·step²/(2|1 − φ'|) per term, φ the term along its w) is far below it
                quad = not coupled
                if quad:
                    for j in range(n_el):
                        if abs(curve[j]) * step[j] * step[j] > 2e-14 * scale * abs(J[j, j]):
                            quad = False
                if change <= 1e-12 * scale or (full and change**3 <= 1e-12 * scale * last * last) or quad:
                    for j in range(n_el):
                        w[j] -= step[j]
                    converged = True
                    break
                norm0, lam, halvings = norm, 1.0, 0
                for j in range(n_el):
                    trial[j] = w[j] - step[j]
        if not converged:
            return False
        for r in range(R):
            acc = row[r]
            for l in range(n_el):
                acc += Dd[r, 1 + l] * w[l]
            Y[k, r] = acc
        for i in range(n):  # ξ[k+1] = Φ ξ[k] + Γ u_all[k]
            acc = Gam[i, 0] * u[k]
            for l in range(n_el):
                acc += Gam[i, 1 + l] * w[l]
            for l2 in range(n):
                acc += Phi[i, l2] * xi[l2]
            xn[i] = acc
        for i in range(n):
            xi[i] = xn[i]
    return True


@njit(cache=True)
def _bouc_wen_increment(z: float, dx: float, zmax: float) -> float:
    """The Bouc–Wen state after an increment ``dx`` of its input from ``z`` (n = 1,
    β = γ = 1/(2·z_max)): slope 1 back toward 0, then an exponential approach to ±z_max."""
    if dx == 0.0:
        return z
    s = 1.0 if dx > 0 else -1.0
    if s * z < 0.0:
        nz = z + dx
        if s * nz <= 0.0:
            return nz
        dx, z = nz, 0.0
    return s * zmax - (s * zmax - z) * np.exp(-abs(dx) / zmax)


@njit(cache=True)
def _step_bouc_wen(Phi, Gam, C, Dd, G1, u, xi0, x_prev, row, kh, zmax, Y):
    """The Lur'e stepping of :meth:`Lure.hysteretic`: one term w = k_h·z(x) on input 1, x the
    output row ``row``, from the discrete state ``xi0`` with z at rest (0) at the element
    variable ``x_prev``; False when a sample's fixed point is not reached.  |dz/dx| ≤ 1, so the
    sample's map w → k_h·z(x(w)) contracts by L ≤ |k_h·D| (D the direct term of w in x) and an
    iterate that moved by δ is within L·δ/(1 − L) of the fixed point: the iteration stops when
    that bound (or δ itself) is below the tolerance."""
    n = Phi.shape[0]
    xi = np.zeros(n)
    xn = np.zeros(n)
    for i in range(n):
        xi[i] = xi0[i]
    z, xprev, w = 0.0, x_prev, 0.0
    lip = abs(kh * Dd[row, 1])
    reach = lip / (1.0 - lip) if lip < 1.0 else 1.0  # distance to the fixed point per δ
    for k in range(u.shape[0]):
        y0 = Dd[0, 0] * u[k]
        x0 = Dd[row, 0] * u[k]
        for i in range(n):
            y0 += C[0, i] * xi[i]
            x0 += C[row, i] * xi[i]
        zk = z
        ok = False
        for _ in range(50):
            x = x0 + Dd[row, 1] * w
            zk = _bouc_wen_increment(z, x - xprev, zmax)
            wn = kh * zk
            if abs(wn - w) * min(reach, 1.0) <= 1e-12 * (abs(wn) + kh * zmax):
                w = wn
                ok = True
                break
            w = wn
        if not ok or not np.isfinite(w):
            return False
        x = x0 + Dd[row, 1] * w
        z, xprev = zk, x
        Y[k] = y0 + Dd[0, 1] * w
        for i in range(n):
            acc = Gam[i, 0] * u[k] + Gam[i, 1] * w
            for l in range(n):
                acc += Phi[i, l] * xi[l]
            xn[i] = acc
        for i in range(n):
            xi[i] = xn[i]
    return True
