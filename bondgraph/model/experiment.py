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
    """A model file's default simulation (like Modelica's ``experiment`` annotation).

    Parameters
    ----------
    t_end : float, optional
        The end time, in s (the simulation starts at 0).
    dt : float, optional
        The output step, in s.
    inputs : mapping of str to Signal, optional
        Input name -> its signal.
    method : str, optional
        The integration method, ``"auto"`` by default (see :func:`bondgraph.simulate`).
    rtol : float, optional
        The relative tolerance; by default the setting ``simulate.rtol``.
    """

    t_end: float = 1.0
    dt: float = 1e-3
    inputs: Mapping[str, Signal] = field(default_factory=dict)
    method: str = "auto"
    rtol: float = field(default_factory=lambda: config.get("simulate.rtol"))

    def times(self, t_end: float | None = None, dt: float | None = None) -> np.ndarray:
        """The output times 0, dt, 2·dt, ... up to t_end.

        Parameters
        ----------
        t_end : float, optional
            The end time in s; the experiment's by default.
        dt : float, optional
            The output step in s; the experiment's by default.

        Returns
        -------
        numpy.ndarray
            The times, in s, starting at 0.

        Raises
        ------
        bondgraph.support.errors.SignalError
            If t_end or dt is not positive, or there would be more than 5e7 samples.
        """
        t_end = self.t_end if t_end is None else t_end
        dt = self.dt if dt is None else dt
        if not (t_end > 0 and dt > 0) or t_end / dt > 5e7:
            raise SignalError(f"need t_end > 0 and 0 < dt with at most 5e7 samples (got t_end={t_end}, dt={dt})")
        n = int(round(t_end / dt))
        return np.linspace(0.0, n * dt, n + 1)
