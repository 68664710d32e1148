"""A current-limited input stage (library.extensions.InputCurrentLimit): the stage's numerics
against its two analytic limits, and a record of the blind generator whose amplifier's output
current saturates (its own electromechanical simulation, not the stage's equations) named so."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from conftest import ROOT

from bondgraph.data import Dataset
from bondgraph.diagnosis import diagnose
from bondgraph.diagnosis.engine import model_file_options
from bondgraph.diagnosis.filters import lowpass, rate_limited
from bondgraph.model.modelfile import load_model

sys.path.insert(0, str(ROOT / "benchmarks"))
import blindgen  # noqa: E402


def test_small_steps_see_the_lag_and_large_ones_the_slew_rate():
    dt = 1e-5
    t = np.arange(0.0, 0.05, dt)
    step = np.where(t > 0.01, 1.0, 0.0)
    # unsaturated (S far above the lag's largest rate 1/τ): the RC lag, to the backward Euler
    # rule's error O(dt/τ)
    lag = rate_limited(step, 1e-3, 1e6, dt)
    assert np.max(np.abs(lag - lowpass(step, 1e-3, dt))) < 0.01
    # saturated with no lag: a ramp at S that reaches the step's height at H/S and stays there
    ramp = rate_limited(step, 1e-7, 200.0, dt)
    k0 = int(np.argmax(t > 0.01))
    assert np.max(np.diff(ramp)) / dt == pytest.approx(200.0, rel=1e-9)
    assert ramp[k0 + 249] == pytest.approx(200.0 * 250 * dt, rel=1e-9)
    assert ramp[k0 + 510 :] == pytest.approx(1.0, abs=1e-9)


def test_the_rate_never_exceeds_the_limit_on_any_drive():
    rng = np.random.default_rng(1)
    u = np.cumsum(rng.standard_normal(5000))
    for tau, S in ((1e-4, 50.0), (1e-2, 5.0), (1e-6, 500.0)):
        v = rate_limited(u, tau, S, 1e-3)
        assert np.max(np.abs(np.diff(v))) / 1e-3 <= S * (1 + 1e-12)


def test_an_amplifier_current_limit_is_named_a_current_limited_stage():
    """Blind record 102: an APA-120ML behind an amplifier whose output current saturates, under
    the generator's electrical drive; beside the linear RC and RLC stages, the current-limited
    stage is named and explains most of what the calibration leaves."""
    from library.extensions import InputCurrentLimit, InputRC, InputRLC

    rec = blindgen.draw(102)
    assert rec.truth["mechanism"] == "current-limit"
    lm = load_model(rec.model)
    data = Dataset(rec.t, {"V": rec.V, "x": rec.x})
    rep = diagnose(
        lm.model,
        data,
        **model_file_options(lm.module),
        workers=1,
        chain=False,
        candidates=[InputRC(), InputRLC(), InputCurrentLimit()],
    )
    assert rep.cause == "electrical-rc", rep.text()
    named = next(c for c in rep.steps[0].candidates if c.passed and c.cause == "electrical-rc")
    assert named.label.startswith("current-limited input stage") and rep.gain > 3
