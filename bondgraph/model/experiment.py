"""A model file's default simulation (``EXPERIMENT``): end time, output step, inputs, method and
tolerance. Kept apart from :mod:`bondgraph.numerics.simulate` so that loading a model file does not
import the compiled integrator."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from ..support import config
from ..support.errors import SignalError
from .signals import Signal


@dataclass(frozen=True)
class Experiment:
    """A model file's default simulation (like Modelica's ``experiment`` annotation):
    end time and output step (s), input signals, integration method and tolerance."""

    t_end: float = 1.0
    dt: float = 1e-3
    inputs: Mapping[str, Signal] = field(default_factory=dict)
    method: str = "auto"
    rtol: float = field(default_factory=lambda: config.get("simulate.rtol"))

    def times(self, t_end: float | None = None, dt: float | None = None) -> np.ndarray:
        t_end = self.t_end if t_end is None else t_end
        dt = self.dt if dt is None else dt
        if not (t_end > 0 and dt > 0) or t_end / dt > 5e7:
            raise SignalError(f"need t_end > 0 and 0 < dt with at most 5e7 samples (got t_end={t_end}, dt={dt})")
        n = int(round(t_end / dt))
        return np.linspace(0.0, n * dt, n + 1)
