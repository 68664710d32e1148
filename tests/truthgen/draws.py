"""Random numbers the protocol draws: log-uniform values and factors that avoid 1."""

from __future__ import annotations

import math

import numpy as np


def loguniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    """A value log-uniformly distributed in [lo, hi]."""
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def factor(rng: np.random.Generator, lo: float, hi: float, gap: float = 0.02) -> float:
    """A log-uniform factor in [lo, hi] at least ``gap`` away from 1 (a drawn device is never
    the nominal one)."""
    g = math.log1p(gap)
    span_up, span_down = max(math.log(hi) - g, 0.0), max(-math.log(lo) - g, 0.0)
    r = rng.uniform(0.0, span_up + span_down)
    return math.exp(g + r) if r < span_up else math.exp(-(g + r - span_up))
