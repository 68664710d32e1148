"""Shared test fixtures: repository paths and small reference models."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture
def models_dir() -> Path:
    return MODELS
