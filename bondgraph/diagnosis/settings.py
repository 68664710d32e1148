"""The diagnosis's settings: one frozen object, read once when a diagnosis starts and passed
down with its :class:`~bondgraph.diagnosis.context.Context`.

    from bondgraph.diagnosis import Settings, diagnose
    diagnose(model, data, settings=Settings.from_config(min_gain=1.5))

A keyword beats the default, the default being the setting ``diagnosis.<name>`` of
:mod:`bondgraph.config` (``bondgraph.config.describe()`` prints each with its meaning).  Nothing
in the diagnosis rewrites a setting: a step that needs another value (a bounded integration, a
shorter fit) takes it as an argument.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..support import config
from ..support.errors import UsageError, did_you_mean


@dataclass(frozen=True)
class Settings:
    """What counts as evidence, and the diagnosis's limits (the fields below, each the setting
    ``diagnosis.<field>``; units where a value has one)."""

    # calibration
    spread: float
    tolerance: float
    identifiable: float
    tolerance_z: float
    residual_share: float
    fast_factor: float
    decimate_margin: float
    blocks: int
    sweep_blocks: int
    sweep_ratio: float
    max_fit_points: int
    # decision
    min_z: float
    min_gain: float
    min_gain_chain: float
    min_gain_reference: float
    min_z_reference: float
    linear_share: float
    equivalent: float
    reference_poles: int
    min_coherence: float
    confirm_margin: float
    confirm_max: int
    polish_margin: float
    screen_keep: int
    screen_chance: float
    screen_effort: float
    screen_gain: float
    polish_effort: float
    # chain, drift and drive reading
    max_chain: int
    drift: bool
    drift_noise: float
    reading_gap: float
    # time and effort
    check_max_steps: int
    candidate_seconds: float
    chain_seconds: float
    candidate_limit: float

    @classmethod
    def from_config(cls, **overrides) -> Settings:
        """The settings as :mod:`bondgraph.config` holds them now, with ``overrides``.

        Parameters
        ----------
        **overrides
            Attribute → value, beating the configured default.

        Returns
        -------
        Settings

        Raises
        ------
        UsageError
            An override names no setting.
        """
        names = [f.name for f in dataclasses.fields(cls)]
        for key in overrides:
            if key not in names:
                raise UsageError(f"diagnosis settings: {did_you_mean(key, names, 'setting')}")
        return cls(**{n: overrides[n] if n in overrides else config.get(f"diagnosis.{n}") for n in names})


Settings.__doc__ += "\n\n    Parameters\n    ----------\n" + "".join(
    f"    {f.name} : {f.type}\n        {config.DEFAULTS[f'diagnosis.{f.name}'].doc}.\n"
    for f in dataclasses.fields(Settings)
)
