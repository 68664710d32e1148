"""The five generic systems: their model files and the truth networks that match them.

Each :class:`System` knows its model file (``models/<name>.py``), the model file's parameter
values and tolerances (read from the file itself, so the two cannot drift apart), the names
of its drive and sensor columns, which elements an effect may sit at, and how to build the
truth :class:`~.network.Network` from linear parameter values - the same topology as the
model file, element for element, so that with every effect off and the model file's
parameters the two routes give the same output (``tests/test_generalgen.py``).
"""

from __future__ import annotations

import ast
import functools
from dataclasses import dataclass
from fnmatch import fnmatchcase
from pathlib import Path

import numpy as np

from .network import Link, Network

MODELS = Path(__file__).resolve().parent / "models"


@functools.cache
def _literal(path: Path, name: str):
    """The literal value assigned to ``name`` at the top of a model file (no import of it)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == name for t in node.targets):
            return ast.literal_eval(node.value)
    raise KeyError(f"{path.name} assigns no {name}")


@functools.cache
def _defaults(path: Path) -> dict[str, float]:
    """The model file's parameter defaults, read by loading its ``PARAMETERS`` (the files
    import only ``bondgraph``, whose import is cheap)."""
    namespace: dict = {}
    exec(compile(path.read_text(encoding="utf-8"), str(path), "exec"), namespace)  # noqa: S102
    return {p.name: float(p.default) for p in namespace["PARAMETERS"]}


@dataclass(frozen=True)
class System:
    """One generic system.

    Attributes
    ----------
    name : str
        Short name, also the model file's stem.
    input, output : str
        The model's input and output names (the CSV's drive and sensor columns).
    drive_level : float
        A typical drive amplitude (N or V), scaled by a drawn factor per record.
    springs, dampers, masses : tuple of str
        The model-file elements that may carry a stiffness, damping or inertia effect.
    causes : tuple of str
        The causes that make physical sense for this system.
    drive_element : str
        The model file's source element (an accepted name for a ``drive`` site).
    hysteretic_drive : bool
        Whether the drive itself may be hysteretic (a force actuator; not a voltage source).
    """

    name: str
    input: str
    output: str
    drive_level: float
    springs: tuple
    dampers: tuple
    masses: tuple
    causes: tuple
    drive_element: str
    hysteretic_drive: bool = True

    @property
    def model_file(self) -> Path:
        """Path of the model file."""
        return MODELS / f"{self.name}.py"

    def defaults(self) -> dict[str, float]:
        """The model file's parameter values (a fresh dict)."""
        return dict(_defaults(self.model_file))

    def tolerance(self, name: str) -> float:
        """The ×/÷ factor the model file's ``TOLERANCE`` declares for parameter ``name``."""
        for pattern, factor in _literal(self.model_file, "TOLERANCE").items():
            if fnmatchcase(name, pattern):
                return float(factor)
        return 2.0  # the setting diagnosis.tolerance's default

    def network(self, p: dict[str, float]) -> Network:
        """The linear truth network for parameter values ``p`` (model-file names)."""
        return _BUILDERS[self.name](p)


def _msd(p):
    return Network(
        np.array([p["m1"]]),
        [Link(0, -1, p["k1"], p["c1"], "spring1", "damper1")],
        np.array([1.0]),
        np.array([1.0]),
        nodes=("mass1",),
    )


def _chain(p, n, drive_node, out_node):
    links = [Link(0, -1, p["k1"], p["c1"], "spring1", "damper1")]
    # spring j is stretched by mass j moving out from mass j-1 (the model files' orientation)
    links += [Link(j - 1, j - 2, p[f"k{j}"], p[f"c{j}"], f"spring{j}", f"damper{j}") for j in range(2, n + 1)]
    drive = np.zeros(n)
    drive[drive_node] = 1.0
    out = np.zeros(n)
    out[out_node] = 1.0
    return Network(
        np.array([p[f"m{j}"] for j in range(1, n + 1)]),
        links,
        drive,
        out,
        nodes=tuple(f"mass{j}" for j in range(1, n + 1)),
    )


def _rlc(p):
    # charge for position: the inductor is the mass, the capacitor's elastance the spring,
    # the resistor the damper, all on the one loop current; the sensor reads the capacitor
    return Network(
        np.array([p["L"]]),
        [Link(0, -1, 1.0 / p["C"], p["R"], "capacitor", "resistor")],
        np.array([1.0]),
        np.array([0.0]),
        out_link=0,
        nodes=("inductor",),
    )


def _modes(p):
    links = [Link(i, -1, p[f"k{i + 1}"], p[f"c{i + 1}"], f"spring{i + 1}", f"damper{i + 1}") for i in range(3)]
    return Network(
        np.array([p[f"m{i}"] for i in (1, 2, 3)]), links, np.ones(3), np.ones(3), nodes=("mass1", "mass2", "mass3")
    )


_BUILDERS = {
    "msd": _msd,
    "chain2": lambda p: _chain(p, 2, drive_node=1, out_node=0),
    "chain3": lambda p: _chain(p, 3, drive_node=0, out_node=2),
    "rlc": _rlc,
    "modes3": _modes,
}

_MECH = ("hardening", "softening", "hysteresis", "friction", "nonlinear-damping", "clearance", "higher-mode", "drift")

SYSTEMS = {
    "msd": System("msd", "F", "x", 10.0, ("spring1",), ("damper1",), ("mass1",), _MECH, "force"),
    "chain2": System(
        "chain2", "F", "x1", 10.0, ("spring1", "spring2"), ("damper1", "damper2"), ("mass1", "mass2"), _MECH, "force"
    ),
    "chain3": System(
        "chain3",
        "F",
        "x3",
        10.0,
        ("spring1", "spring2", "spring3"),
        ("damper1", "damper2", "damper3"),
        ("mass1", "mass2", "mass3"),
        _MECH,
        "force",
    ),
    # no friction or clearance in a circuit; a hysteretic voltage source is not a circuit's fault
    "rlc": System(
        "rlc",
        "V",
        "vC",
        5.0,
        ("capacitor",),
        ("resistor",),
        ("inductor",),
        ("hardening", "softening", "hysteresis", "nonlinear-damping", "higher-mode", "drift"),
        "source",
        hysteretic_drive=False,
    ),
    # a modal coordinate has no clearance and no dry friction of its own
    "modes3": System(
        "modes3",
        "F",
        "x",
        1.0,
        ("spring1", "spring2", "spring3"),
        ("damper1", "damper2", "damper3"),
        ("mass1", "mass2", "mass3"),
        ("hardening", "softening", "hysteresis", "nonlinear-damping", "higher-mode", "drift"),
        "force",
    ),
}
