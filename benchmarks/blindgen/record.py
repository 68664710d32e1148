"""A generated record and its CSV file (the project's format: ``# key: value`` metadata,
one ``t,V,x`` header, SI units).  The metadata never reveal the truth."""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

DESCRIPTION = {
    "apa": ("APA-120ML-like amplified piezo actuator", "capacitive displacement probe at the output"),
    "t215": ("T215-A4-103X-like bimorph bender, clamped-free", "laser triangulation near the tip"),
}


@dataclass
class Record:
    """t (s), V (V), x (m) as recorded; model: the model file to diagnose with; truth: cause,
    mechanism, parameters, visible size and the rest of the draw (see blindgen.generate)."""

    seed: int
    family: str
    model: str
    t: np.ndarray
    V: np.ndarray
    x: np.ndarray
    truth: dict = field(default_factory=dict)

    @property
    def record_id(self) -> str:
        return hashlib.sha256(f"blindgen/{self.seed}".encode()).hexdigest()[:12]

    def write_csv(self, path) -> None:
        actuator, sensor = DESCRIPTION[self.family]
        rate = 1.0 / np.median(np.diff(self.t))
        head = [
            f"# actuator: {actuator}",
            f"# sensor: {sensor}",
            f"# sample_rate_hz: {rate:.0f}",
            f"# record: {self.record_id}",
            "# source: benchmarks/blindgen",
            "t,V,x",
        ]
        body = np.column_stack([self.t, self.V, self.x])
        with open(path, "w", encoding="utf-8", newline="\n") as f:
            f.write("\n".join(head) + "\n")
            np.savetxt(f, body, fmt=("%.10g", "%.7g", "%.9g"), delimiter=",")
