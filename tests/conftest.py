"""Shared test fixtures: repository paths and small reference models."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture
def models_dir() -> Path:
    return MODELS


def two_level_chirp(t: np.ndarray, duration: float, f0: float, f1: float, low: float, high: float) -> np.ndarray:
    """A unipolar chirp f0 → f1 (Hz, linear in time) in each half of ``duration`` (s), starting
    at rest: peak 2·``low`` in the first half, 2·``high`` in the second."""
    half = duration / 2
    tau = np.mod(t, half)
    level = np.where(t < half, low, high)
    return level * (1 - np.cos(2 * np.pi * (f0 * tau + (f1 - f0) / (2 * half) * tau ** 2)))
