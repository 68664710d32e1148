"""Memory models on every solver: the Bouc–Wen APA (a state with |z|^(n-1)·z terms) and
play-operator models run on radau, bdf, lsoda and the compiled implicit route, and their
Jacobian is defined at rest."""

import numpy as np
import pytest
from conftest import MODELS

import bondgraph as bg
from bondgraph.model.modelfile import load_model


@pytest.fixture(scope="module")
def bouc_wen():
    return bg.Simulator(load_model(MODELS / "apa120ml.py", {"hysteresis": "bouc-wen"}).model)


@pytest.mark.parametrize("method", ["radau", "bdf"])
def test_bouc_wen_runs_on_the_stiff_scipy_solvers_from_rest(bouc_wen, method):
    """The crash of the issue: the Jacobian at z = 0 divided by zero (|z|^(n-2)·z·sign(z))."""
    t = np.linspace(0.0, 0.02, 201)
    res = bouc_wen.run(t, {"V": bg.Sine(60.0, 5.0, phase=-90.0, offset=60.0)}, method=method)
    assert np.all(np.isfinite(res["x"])) and res["x"][-1] > 0
