"""A third, blind truth generator for ``bondgraph diagnose`` on general (non-piezo) systems.

One seed is one record: a generic linear model file (``models/``: a mass-spring-damper, two-
and three-mass chains, a series RLC circuit, a three-mode structure), a measured record of a
truth simulated by our own physics (``network``, not bondgraph's simulator) with an effect the
model file lacks at a named site, or none, and the truth label kept apart from the record.
``PROTOCOL.md`` fixes the seed sets; ``benchmarks/README.md`` ("General-systems generator")
describes the vocabulary, the visibility rule and the scoring.

Command line: ``python -m benchmarks.generalgen SEED [SEED...] --out DIR``.
"""

from .effects import CAUSES, VOCABULARY
from .record import DEVELOPMENT, HELD_OUT, Draw, Record, draw, generate, realize, seed_set, write
from .scoring import score
from .systems import SYSTEMS

__all__ = [
    "CAUSES",
    "VOCABULARY",
    "DEVELOPMENT",
    "HELD_OUT",
    "SYSTEMS",
    "Draw",
    "Record",
    "draw",
    "generate",
    "realize",
    "score",
    "seed_set",
    "write",
]
