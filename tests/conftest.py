"""Shared test fixtures: repository paths and small reference models."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
sys.path.insert(0, str(Path(__file__).resolve().parent))


def pytest_configure(config):
    """Compile (or load) the integrator once per test process before any test runs: its
    "compiling the integrator" progress line would otherwise land in the captured stderr of
    whichever test imports the simulator first on a fresh checkout."""
    import bondgraph.numerics.simulate  # noqa: F401


def _shares_a_module_fixture(path: Path) -> bool:
    """Whether the test module at ``path`` defines a fixture of module scope."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        for dec in getattr(node, "decorator_list", ()):
            if isinstance(dec, ast.Call) and any(
                k.arg == "scope" and getattr(k.value, "value", None) == "module" for k in dec.keywords
            ):
                return True
    return False


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """Under ``pytest -n``: the tests of a module that defines a module-scoped fixture (a
    diagnosed seed set, a diagnosed real record) go to one worker together, so the fixture is
    computed once and not on each worker that runs one of its tests; every other test is
    scheduled on its own.  Groups are sent first, the largest first (pytest-xdist's
    load-scope ordering), so the long ones do not end the run alone."""
    from xdist.scheduler import LoadScopeScheduling

    here = Path(__file__).resolve().parent
    shared = {f"{here.name}/{p.name}" for p in here.glob("test_*.py") if _shares_a_module_fixture(p)}

    class SharedFixtureScheduling(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = nodeid.split("::", 1)[0]
            return module if module in shared else nodeid

    return SharedFixtureScheduling(config, log)


@pytest.fixture
def models_dir() -> Path:
    return MODELS


def two_level_chirp(t: np.ndarray, duration: float, f0: float, f1: float, low: float, high: float) -> np.ndarray:
    """A unipolar chirp f0 → f1 (Hz, linear in time) in each half of ``duration`` (s), starting
    at rest: peak 2·``low`` in the first half, 2·``high`` in the second."""
    half = duration / 2
    tau = np.mod(t, half)
    level = np.where(t < half, low, high)
    return level * (1 - np.cos(2 * np.pi * (f0 * tau + (f1 - f0) / (2 * half) * tau**2)))
