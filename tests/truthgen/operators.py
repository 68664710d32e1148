"""Rate-independent memory operators and static curves for the truth devices.

Every hysteresis operator maps a *normalised* input ``u`` (the drive range mapped onto
[-1, 1]) to an output of order one, keeps its memory between calls, and is advanced once per
accepted integration step (``op(u) -> float``; ``reset()`` restores the initial state, which is
the state reached by a sweep down from the top of the range to the first input, i.e. a device
last driven to its maximum).  They are written from their defining equations, not from any
candidate model of the diagnosis:

* :class:`Preisach` — relays ``gamma_{ab}`` (up at ``a``, down at ``b < a``) on a triangular
  threshold grid, weighted by a random density: a mixture of Gaussian bumps in (bias, half
  width) plus a smooth background (Mayergoyz, *Mathematical Models of Hysteresis*, 1991);
* :class:`BoucWen` — ``dz = du - beta |du| |z|^(n-1) z - gamma du |z|^n`` (Wen 1976), in the
  complement form ``u - lam z`` (``z`` leads ``u`` like an elastoplastic element; the
  polarization must lag the field);
* :class:`Duhem` — Coleman–Hodgdon form ``dz = alpha |du| (f(u) - z) + b du`` with a
  saturating anhysteretic curve ``f``;
* :class:`MaxwellSlip` — elasto-slide elements (spring ``k_j`` in series with a Coulomb slider
  that breaks away at a deformation ``d_j``); the friction force ``sum k_j e_j``.  Used in the
  *mechanical* domain (a friction force on a moving mass), driven by a displacement.

Static curves (:func:`saturation_curve`) give a relative *deficit* ``s(u) - u`` of a
saturating response ``s`` on the absolute normalised input ``u = value / max|value|``.
"""

from __future__ import annotations

import math

import numpy as np


class Operator:
    """Base: ``reset()``, ``__call__(u)``, and ``apply(u_array)`` from the reset state."""

    u0 = 0.0

    def start(self, u0: float) -> None:
        """Set the first input; the state becomes that after a sweep from +1 down to ``u0``."""
        self.u0 = float(u0)
        self.reset()

    def reset(self) -> None:
        raise NotImplementedError

    def __call__(self, u: float) -> float:
        raise NotImplementedError

    def apply(self, u: np.ndarray) -> np.ndarray:
        self.start(u[0])
        return np.fromiter((self(v) for v in u), float, len(u))


class Preisach(Operator):
    """Preisach operator with a random density on ``levels`` x ``levels`` thresholds in [-1.1, 1.1]."""

    def __init__(self, rng: np.random.Generator, levels: int = 22):
        grid = np.linspace(-1.1, 1.1, levels)
        a, b = np.meshgrid(grid, grid, indexing="ij")
        keep = a > b
        self.alpha, self.beta = a[keep], b[keep]
        bias, half = (self.alpha + self.beta) / 2, (self.alpha - self.beta) / 2
        density = 0.15 * rng.uniform() * np.exp(-half / rng.uniform(0.3, 1.0))
        for _ in range(rng.integers(1, 4)):
            m_bias, s_bias = rng.uniform(-0.5, 0.5), rng.uniform(0.15, 0.6)
            m_half, s_half = rng.uniform(0.05, 0.6), rng.uniform(0.08, 0.4)
            density = density + rng.uniform(0.3, 1.0) * np.exp(
                -0.5 * ((bias - m_bias) / s_bias) ** 2 - 0.5 * ((half - m_half) / s_half) ** 2
            )
        self.weight = density / density.sum()
        self.state = np.empty_like(self.alpha)

    def reset(self):
        self.state[:] = 1.0
        self.state[self.beta >= self.u0] = -1.0

    def __call__(self, u):
        s = self.state
        s[self.alpha <= u] = 1.0
        s[self.beta >= u] = -1.0
        return float(self.weight @ s)


class BoucWen(Operator):
    """Bouc–Wen hysteresis driven by the normalised input; output ``u - lam z / z_max`` (the
    complement of the leading, elastoplastic-like ``z``: it lags ``u`` and stays monotone)."""

    def __init__(self, rng: np.random.Generator):
        self.n = rng.uniform(1.0, 2.5)
        total = rng.uniform(1.0, 4.0)  # beta + gamma: how fast z saturates over [-1, 1]
        share = rng.uniform(0.55, 1.0)  # beta / (beta + gamma) > 1/2: z leads u
        self.beta, self.gamma = share * total, (1 - share) * total
        self.zmax = (1.0 / total) ** (1 / self.n)
        # complement form u - lam z/zmax lags u (like P behind E); lam keeps it monotone
        self.lam = rng.uniform(0.6, 1.0) * total / (2 * self.beta) * self.zmax
        self.z = 0.0
        self.u = 0.0

    def reset(self):
        self.z, self.u = 0.0, -1.0
        self(1.0)
        self(self.u0)

    def __call__(self, u):
        steps = max(1, int(math.ceil(abs(u - self.u) / 0.01)))
        du = (u - self.u) / steps
        z, n, b, g = self.z, self.n, self.beta, self.gamma
        for _ in range(steps):
            az = abs(z)
            z += du - b * abs(du) * az ** (n - 1) * z - g * du * az**n
        self.z, self.u = z, u
        return u - self.lam * z / self.zmax


class Duhem(Operator):
    """Coleman–Hodgdon (Duhem) hysteresis: ``dz = alpha |du| (f(u) - z) + b du``, output ~ z."""

    def __init__(self, rng: np.random.Generator):
        self.alpha = rng.uniform(1.0, 6.0)
        self.kappa = rng.uniform(0.5, 2.5)
        self.b = rng.uniform(0.05, 0.6)
        self.z = 0.0
        self.u = 0.0

    def f(self, u):
        return math.tanh(self.kappa * u) / math.tanh(self.kappa)

    def reset(self):
        self.z, self.u = -self.f(1.0), -1.0
        self(1.0)
        self(self.u0)

    def __call__(self, u):
        steps = max(1, int(math.ceil(abs(u - self.u) / 0.01)))
        du = (u - self.u) / steps
        z, v = self.z, self.u
        for _ in range(steps):
            z += self.alpha * abs(du) * (self.f(v) - z) + self.b * du
            v += du
        self.z, self.u = z, u
        return z


class MaxwellSlip(Operator):
    """Elasto-slide elements: deformation ``e_j`` clipped at the break-away ``+-d_j``;
    output ``sum k_j e_j`` with ``sum k_j = 1`` (scale it by the total stiffness)."""

    def __init__(self, rng: np.random.Generator, count: int | None = None):
        count = count or int(rng.integers(4, 16))
        self.d = np.sort(np.exp(rng.uniform(np.log(0.02), np.log(0.8), count)))
        k = rng.lognormal(0.0, 0.6, count)
        self.k = k / k.sum()
        self.e = np.zeros(count)
        self.u = 0.0

    def reset(self):
        self.e[:] = 0.0
        self.u = -1.0
        self(1.0)
        self(self.u0)

    def __call__(self, u):
        self.e = np.clip(self.e + (u - self.u), -self.d, self.d)
        self.u = u
        return float(self.k @ self.e)


HYSTERESIS = {"preisach": Preisach, "bouc-wen": BoucWen, "duhem": Duhem}


def loop_stats(op: Operator) -> tuple[float, float]:
    """(largest vertical gap between the descending and the ascending branch, output range) of
    the operator's major loop over full-range cycles (the second cycle)."""
    up = np.linspace(-1, 1, 201)
    u = np.concatenate([up[::-1], up[1:], up[::-1][1:], up[1:]])
    y = op.apply(u)
    last = y[-401:]
    down_branch, up_branch = last[:201], last[200:]
    return float(np.max(down_branch[::-1] - up_branch)), float(np.ptp(last))


def saturation_curve(kind: str, rng: np.random.Generator):
    """A saturating static curve as a deficit function ``u -> s(u) - u`` (relative, odd or
    mildly asymmetric) whose deficit at |u| = 1 is 1; multiply by the strength."""
    if kind == "tanh":
        k = rng.uniform(0.6, 2.0)
        ref = 1 - math.tanh(k) / k

        def deficit(u):
            return (np.tanh(k * u) / k - u) / ref
    elif kind == "polynomial":
        c2 = rng.uniform(-0.4, 0.4)  # asymmetry: an even u^2 term beside the cubic one

        def deficit(u):
            return -(u**3 + c2 * u**2) / (1 + abs(c2))
    elif kind == "piecewise":
        knee = rng.uniform(0.35, 0.75)
        width = 0.03

        def deficit(u):
            over = width * np.logaddexp(0.0, (np.abs(u) - knee) / width)
            return -np.sign(u) * over / (width * np.logaddexp(0.0, (1 - knee) / width))
    else:
        raise ValueError(f"unknown saturation curve {kind!r}")
    return deficit
