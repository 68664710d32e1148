"""The four device families: which model file diagnoses them, how their linear parameters are
drawn around that file's values, how they are recorded and driven, and which causes they can
physically show (and which drives reveal them).

Linear parameters are drawn as the file's value times a log-uniform factor in ``[lo, hi]`` that
is never within 2 % of 1 (:func:`factor`); the sensor gain and offset are drawn with the noise
(:mod:`.measure`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from . import bimorph, stack
from .draws import factor
from .drives import DriveRange

ROOT = Path(__file__).resolve().parents[2]


@lru_cache(maxsize=None)
def _model_values(model: str, overrides: tuple) -> dict:
    from bondgraph.model.modelfile import load_model

    lm = load_model(ROOT / model, dict(overrides))
    values = {str(k): float(v) for k, v in lm.model.parameter_table().items()}
    file_values = lm.params.as_dict()
    if "layers" in file_values:  # an integer: not in the symbolic table
        values["layers"] = int(file_values["layers"])
    return values


@dataclass(frozen=True)
class Shape:
    """How a record is taken: sample rate (Hz), duration (s), integration step bound (s), and
    the regime (``slow`` / ``fast`` for stacks, ``""`` otherwise)."""

    fs: float
    T: float
    h_max: float
    regime: str = ""


class Family:
    name: str
    physics: str
    model: str
    #: the design cycle of causes (see :mod:`.design`); "a+b" is a compound draw
    causes: tuple
    #: which drive kinds reveal each cause
    reveal: dict

    def model_args(self, rng) -> dict:
        """``--set`` overrides of the model file for this record (usually none)."""
        return {}

    def nominal(self, overrides: dict) -> dict:
        raise NotImplementedError

    def perturb(self, p: dict, rng) -> dict:
        raise NotImplementedError

    def shape(self, size: str, causes: tuple, rng, overrides: dict) -> Shape:
        raise NotImplementedError

    def drive_range(self, p: dict, shape: Shape, rng) -> DriveRange:
        raise NotImplementedError

    def drive_kinds(self, causes: tuple, shape: Shape) -> list:
        kinds = None
        for cause in causes or ("none",):
            k = set(self.reveal[cause])
            kinds = k if kinds is None else kinds & k
        return sorted(kinds)

    @property
    def module(self):
        return stack if self.physics == "stack" else bimorph

    def context(self, p: dict) -> dict:
        return {}

    def refs(self, y: np.ndarray, rows: np.ndarray, V: np.ndarray) -> dict:
        """Ranges of the effect-free response that scale the effects (see :mod:`.mechanisms`)."""
        rng_ = lambda a: (float(np.min(a)), float(np.max(a)))  # noqa: E731
        if self.physics == "stack":
            return {"e": rng_(rows[0]), "x": rng_(rows[1]), "V": rng_(V)}
        return {"q1": rng_(rows[0]), "qd1": rng_(rows[1]), "vel": rng_(rows[2]), "V": rng_(V)}


class StackLike(Family):
    physics = "stack"

    def perturb(self, p, rng):
        ranges = {
            "Re": (0.5, 2.0),
            "S": (0.75, 1.33),
            "a": (0.8, 1.25),
            "K": (0.75, 1.33),
            "c": (0.1, 10.0),
            "M": (0.7, 1.4),
        }
        return {k: p[k] * factor(rng, *ranges[k]) for k in stack.LINEAR}


class Apa(StackLike):
    """Amplified stack (APA-120ML): 10 kHz x 18 s on the bench, 5-10 kHz x 1-1.5 s in CI."""

    name = "apa"
    model = "models/apa120ml.py"
    causes = ("none", "hysteresis", "creep", "saturation", "none", "electrical", "higher-mode", "hysteresis+creep")
    reveal = {
        "none": ("sine", "triangle", "steps", "chirp", "noise", "bursts"),
        "hysteresis": ("sine", "triangle", "bursts", "steps"),
        "creep": ("steps", "bursts"),
        "saturation": ("sine", "triangle", "bursts", "steps", "noise"),
        "electrical": ("chirp", "noise", "steps"),
        "higher-mode": ("chirp", "noise", "steps"),
    }

    def nominal(self, overrides):
        v = _model_values(self.model, tuple(sorted(overrides.items())))
        return {"Re": v["Re"], "S": v["kx"] * v["l"] ** 2, "a": v["a"] * v["T"], "K": v["K"], "c": v["c"], "M": v["M"]}

    def shape(self, size, causes, rng, overrides):
        if size == "bench":
            return Shape(10000.0, 18.0, 1e-4)
        return Shape(float(rng.choice([5000.0, 10000.0])), rng.uniform(1.0, 1.5), 1e-4)

    def drive_range(self, p, shape, rng):
        return DriveRange(-20.0, 150.0, False, (0.5, 100.0))


class BareStack(Apa):
    """Bare multilayer stack (models/stack.py, 20 layers or lumped): slow records (200 Hz-1 kHz,
    sines and bursts of 0.2-5 Hz, up to 70 s) like real stacks, or fast ones (2-5 kHz)."""

    name = "stack"
    model = "models/stack.py"
    causes = ("none", "hysteresis", "hysteresis+creep", "creep", "none", "saturation", "electrical")
    reveal = {
        "none": ("sine", "triangle", "steps", "bursts", "chirp", "noise"),
        "hysteresis": ("sine", "triangle", "bursts", "steps"),
        "creep": ("steps", "bursts"),
        "saturation": ("sine", "triangle", "bursts", "steps"),
        "electrical": ("chirp", "noise", "steps"),
    }

    def model_args(self, rng):
        return {"lumped": True} if rng.uniform() < 0.4 else {}

    def nominal(self, overrides):
        v = _model_values(self.model, tuple(sorted(overrides.items())))
        n = v.get("layers", 20)
        lumped = bool(overrides.get("lumped", False))
        return {
            "Re": v["Re"] + (0.0 if lumped else v["Re_layer"] / n),
            "S": v["kx"] * v["l"] ** 2,
            "a": v["a"],
            "K": v["K"],
            "c": v["c"],
            "M": (n + 1) / 2 * v["M_layer"],
        }

    def shape(self, size, causes, rng, overrides):
        fast = "electrical" in causes or rng.uniform() < 0.25
        if fast:
            if size == "bench":
                return Shape(5000.0, 10.0, 2e-4, "fast")
            return Shape(float(rng.choice([2000.0, 5000.0])), rng.uniform(1.0, 2.0), 2e-4, "fast")
        if size == "bench":
            return Shape(200.0, 70.0, 5e-4, "slow") if rng.uniform() < 0.6 else Shape(1000.0, 30.0, 5e-4, "slow")
        return (
            Shape(200.0, rng.uniform(15.0, 25.0), 5e-4, "slow")
            if rng.uniform() < 0.5
            else Shape(1000.0, rng.uniform(3.0, 5.0), 5e-4, "slow")
        )

    def drive_range(self, p, shape, rng):
        f = (0.2, 5.0) if shape.regime == "slow" else (1.0, 50.0)
        if rng.uniform() < 0.5:
            return DriveRange(-150.0, 150.0, True, f)  # a +-150 V stack test
        return DriveRange(-20.0, 120.0, False, f)  # a PICMA-like unipolar range

    def drive_kinds(self, causes, shape):
        kinds = super().drive_kinds(causes, shape)
        if shape.regime == "slow":
            kinds = [k for k in kinds if k not in ("chirp", "noise")] or ["sine"]
        return kinds


class Bimorph(Family):
    physics = "bimorph"
    target: float
    reveal = {
        "none": ("sine", "triangle", "steps", "chirp", "noise", "bursts", "resonant-bursts", "stepped-sine"),
        "hysteresis": ("sine", "triangle", "bursts", "steps"),
        "creep": ("steps", "triangle", "bursts"),
        "saturation": ("sine", "triangle", "bursts", "steps"),
        "softening": ("stepped-sine", "resonant-bursts", "chirp"),
        "nonlinear-damping": ("stepped-sine", "resonant-bursts", "chirp"),
        "higher-mode": ("chirp", "noise", "steps"),
    }

    def nominal(self, overrides):
        v = _model_values(self.model, tuple(sorted(overrides.items())))
        n = max(int(k.split("_")[1]) for k in v if k.startswith("omega_"))
        return {key: [v[f"{key}_{i}"] for i in range(1, n + 1)] for key in ("omega", "zeta", "mp", "phi")}

    def perturb(self, p, rng):
        common = factor(rng, 0.92, 1.08)
        return {
            "omega": [w * common * rng.uniform(0.98, 1.02) for w in p["omega"]],
            "zeta": [z * factor(rng, 0.2, 5.0) for z in p["zeta"]],
            "mp": [m * factor(rng, 0.8, 1.25) for m in p["mp"]],
            "phi": list(p["phi"]),
        }

    def context(self, p):
        return {"target": self.target}


class T215(Bimorph):
    """T215 bimorph, two (or three) modes, sensor at 0.95 L: 50 kHz x 5 s on the bench,
    10-20 kHz x 0.3-0.6 s in CI."""

    name = "t215"
    model = "models/bimorph_t215.py"
    target = 0.95
    causes = (
        "none",
        "hysteresis",
        "softening",
        "nonlinear-damping",
        "none",
        "higher-mode",
        "saturation",
        "creep",
        "softening+nonlinear-damping",
    )

    def model_args(self, rng):
        return {"modes": 3} if rng.uniform() < 0.25 else {}

    def shape(self, size, causes, rng, overrides):
        if size == "bench":
            return Shape(50000.0, 5.0, 2.5e-5)
        if "higher-mode" in causes:  # the next beam mode (6.3 kHz; 12.3 kHz past three) must show
            fs = 50000.0 if overrides.get("modes", 2) > 2 else 20000.0
            return Shape(fs, rng.uniform(0.2, 0.35), 2.5e-5)
        return Shape(float(rng.choice([10000.0, 20000.0])), rng.uniform(0.3, 0.6), 2.5e-5)

    def drive_range(self, p, shape, rng):
        return DriveRange(
            -60.0, 60.0, True, (0.5, 50.0), f_res=p["omega"][0] / (2 * np.pi), amp_res=(0.1, 2.0), amp_dyn=(0.3, 10.0)
        )


class T226(Bimorph):
    """T226 bimorph, first mode, near-resonance drives: 20 kHz x 3 s on the bench, 10 kHz x
    0.5-0.8 s in CI."""

    name = "t226"
    model = "models/bimorph_t226.py"
    target = 23.46 / 24.53
    causes = ("none", "softening", "nonlinear-damping", "higher-mode", "softening+nonlinear-damping")
    reveal = dict(Bimorph.reveal, none=("stepped-sine", "resonant-bursts", "chirp", "sine"))

    def shape(self, size, causes, rng, overrides):
        if size == "bench":
            return Shape(20000.0, 3.0, 5e-5)
        return Shape(10000.0, rng.uniform(0.5, 0.8), 5e-5)

    def drive_range(self, p, shape, rng):
        return DriveRange(
            -20.0, 20.0, True, (1.0, 100.0), f_res=p["omega"][0] / (2 * np.pi), amp_res=(0.3, 6.0), amp_dyn=(0.2, 3.0)
        )


FAMILIES = {f.name: f for f in (Apa(), BareStack(), T215(), T226())}
