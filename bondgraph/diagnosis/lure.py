"""A linear model with static nonlinear terms in some elements' laws (a Lur'e system),
simulated on the exact linear route by fixed-point iteration.

The model's elements ``el_k`` get laws law_k(x) + w_k with w_k = φ_k(x_k, a_k), x_k the
element's own variable (q of a C, p of an I, f of an R) and a_k the displacement of a partner
element (or 0).  The model with the w_k as extra inputs is linear: y = G_uy[u] + Σ G_wy[w],
x_k = G_ux[u] + Σ G_wx[w] (each G exact on the sampled grid, w linear between samples).
Iterating w ← φ(x(w)) from w = 0 converges when the nonlinear terms are small against the
linear dynamics (the usual case of a weak structural nonlinearity); otherwise
:class:`NotConverged` is raised and the caller integrates the rewritten model instead.
"""
from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np

from ..elements import C, I, R
from ..equations import derive
from ..errors import BondGraphError
from ..graph import Model, Quantity
from ..lti import LTI
from .rewrite import modify_law


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
    ``partners[el]``: an element whose displacement the term of ``el`` uses, or None."""

    def __init__(self, model: Model, input: str, output: str, elements: Sequence[str],
                 partners: Mapping[str, str | None], dt: float, cut: float | None = None):
        aug = model.copy()
        self.n = len(elements)
        ws = []
        for k, el in enumerate(elements):
            w = aug.input(f"diag.w{k}")
            ws.append(f"diag.w{k}")
            modify_law(aug, el, lambda x, old, w=w: old + w)
            aug.output(f"diag.x{k}", _variable(model, el))
            if partners.get(el):
                aug.output(f"diag.a{k}", Quantity("q", partners[el]))
        eqs = derive(aug)
        self.outputs = [output] + [f"diag.x{k}" for k in range(self.n)] + \
            [f"diag.a{k}" for k, el in enumerate(elements) if partners.get(el)]
        self.inputs = [input] + ws
        self.lti = {(i, o): LTI(eqs, i, o) for i in self.inputs for o in self.outputs}
        if not all(lti.exact for lti in self.lti.values()):
            raise BondGraphError("the model is not linear in its states")
        self.partners = [bool(partners.get(el)) for el in elements]
        self.eqs, self.dt, self.cut = eqs, dt, cut
        self._last: list[np.ndarray] | None = None

    def theta(self, values: Mapping[str, float]) -> np.ndarray:
        from ..codegen import parameter_vector
        th = parameter_vector(self.eqs)
        index = {p.name: i for i, p in enumerate(self.eqs.params)}
        for k, v in values.items():
            if k in index:
                th[index[k]] = v
        return th

    def linear_responses(self, values: Mapping[str, float], u: np.ndarray) -> dict[str, np.ndarray]:
        """The element variables (``diag.x<k>``, ``diag.a<k>``) and output of the linear model."""
        return self._respond(self._systems(self.theta(values)), self.inputs[0], u)

    def _systems(self, th: np.ndarray) -> dict:
        """Per input, its discretised system with every output as a row (one state recursion for
        all, discretised once per parameter vector), or, when the outputs' systems do not share
        A and B (after residualisation), their state spaces."""
        out = {}
        for i in self.inputs:
            parts = [self.lti[(i, o)].state_space(th, self.cut) for o in self.outputs]
            first = parts[0]
            if all(p.n == first.n and np.array_equal(p.A, first.A) and np.array_equal(p.B, first.B) for p in parts):
                out[i] = first.sampled(self.dt, np.vstack([p.C for p in parts]), np.vstack([p.D for p in parts]))
            else:
                out[i] = parts
        return out

    def _respond(self, systems: dict, input: str, u: np.ndarray) -> dict[str, np.ndarray]:
        """Every output's response to ``input`` driven by the samples ``u``."""
        sys = systems[input]
        if isinstance(sys, list):
            return {o: p.response(self.dt, u)[:, 0] for o, p in zip(self.outputs, sys)}
        Y = sys.response(u)
        return {o: Y[:, r] for r, o in enumerate(self.outputs)}

    def simulate(self, values: Mapping[str, float], u: np.ndarray,
                 phi: Callable[[int, np.ndarray, np.ndarray | None], np.ndarray],
                 tol: float = 1e-7, max_iter: int = 200) -> np.ndarray:
        """Raw output for the drive samples ``u`` with w_k = phi(k, x_k, a_k), iterated from the
        last solution found for a drive of the same length (a fit moves the parameters a little
        at a time, so a few iterations then suffice)."""
        systems = self._systems(self.theta(values))
        base = self._respond(systems, self.inputs[0], u)
        last = self._last
        w = list(last) if last is not None and len(last[0]) == len(u) else [np.zeros_like(u) for _ in range(self.n)]
        x_names = [f"diag.x{k}" for k in range(self.n)]
        a_names = {k: f"diag.a{k}" for k in range(self.n) if self.partners[k]}
        self._last = None
        for _ in range(max_iter):
            resp = {o: base[o].copy() for o in self.outputs}
            for j in range(self.n):
                if np.any(w[j]):
                    Y = self._respond(systems, self.inputs[1 + j], w[j])
                    for o in self.outputs:
                        resp[o] += Y[o]
            with np.errstate(over="ignore", invalid="ignore"):
                new = [phi(k, resp[x_names[k]], resp[a_names[k]] if k in a_names else None) for k in range(self.n)]
            if not all(np.all(np.isfinite(v)) for v in new):
                raise NotConverged("the iteration diverged")
            change = max(float(np.max(np.abs(a - b))) for a, b in zip(new, w)) if self.n else 0.0
            size = max(max(float(np.max(np.abs(a))) for a in new), 1e-300)
            w = new
            if change <= tol * size:
                self._last = w
                return self._final(systems, base, w)
        raise NotConverged(f"no convergence in {max_iter} iterations (the nonlinear term is too strong "
                           f"for the fixed-point route)")

    def _final(self, systems, base, w) -> np.ndarray:
        y = base[self.outputs[0]].copy()
        for j in range(self.n):
            y += self._respond(systems, self.inputs[1 + j], w[j])[self.outputs[0]]
        return y
