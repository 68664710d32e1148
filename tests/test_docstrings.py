"""Every public function and class carries a numpydoc docstring that matches its signature.

The public objects are the names of the face (``bondgraph.__all__``, resolved one by one
through its lazy ``__getattr__``), the names in the ``__all__`` of each stage package that
declares one (submodules listed there are skipped), and the public methods and properties of
every public class (no leading underscore, defined in ``bondgraph`` itself rather than
inherited from outside it).  Each is checked by numpydoc's own validator
(:func:`numpydoc.validate.validate`), the reference for the format, on four codes:

* ``GL08`` the object has no docstring;
* ``PR01`` a parameter of the signature is not documented;
* ``PR02`` a documented parameter is not in the signature;
* ``RT01`` a function that returns a value has no Returns section (not asked of properties
  or of ``__init__``).

The cases are one per stage, so a failure names the stage and lists each object with its
codes.  A face name belongs to the stage of the module that defines it.
"""

from __future__ import annotations

import importlib
import inspect
import sys
import types

import numpydoc.validate
import pytest
from test_layout import MODULES, STAGES, public_modules

import bondgraph

#: the codes the suite enforces (see the module docstring)
CODES = ("GL08", "PR01", "PR02", "RT01")


def _stage_of(module: str) -> str:
    """The pipeline stage (``support``, ``data``, ...) of a dotted module name in ``bondgraph``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in STAGES else "face"


def _qualified(obj) -> str:
    """The importable dotted path of a function or class: its defining module and qualname."""
    return f"{obj.__module__}.{obj.__qualname__}"


def _public_names() -> list[tuple[str, object]]:
    """(stage, object) for every public name of the face and of each stage package's ``__all__``."""
    found = []
    for name in bondgraph.__all__:
        value = getattr(bondgraph, name)
        if not isinstance(value, types.ModuleType):
            found.append((_stage_of(value.__module__), value))
    for module in sorted(public_modules()):
        if module == "bondgraph" or not MODULES[module][1]:
            continue
        package = importlib.import_module(module)
        for name in getattr(package, "__all__", []):
            if f"{module}.{name}" in MODULES:  # a submodule, not an object
                continue
            value = getattr(package, name)
            if not isinstance(value, types.ModuleType):
                found.append((_stage_of(module), value))
    return found


#: codes not asked of a property (it returns its value by definition)
PROPERTY = frozenset({"RT01"})
#: codes not asked of a typing.Protocol class: its constructor is typing's ``(*args, **kwargs)``
#: placeholder, never called (a protocol is implemented, not instantiated)
PROTOCOL = frozenset({"PR01", "PR02"})


def _members(cls: type, package: str = "bondgraph") -> list[tuple[str, frozenset]]:
    """(qualified name, codes skipped) of the public methods and properties of ``cls`` that
    are defined in a class of ``package`` in its method resolution order."""
    out, seen = [], set()
    for klass in cls.__mro__:
        if not klass.__module__.startswith(package):
            continue
        for name, attr in vars(klass).items():
            if name.startswith("_") or name in seen:
                continue
            seen.add(name)
            if isinstance(attr, property):
                out.append((f"{_qualified(klass)}.{name}", PROPERTY))
            elif isinstance(attr, (staticmethod, classmethod)) or inspect.isfunction(attr):
                out.append((f"{_qualified(klass)}.{name}", frozenset()))
    return out


def public_objects() -> dict[str, list[tuple[str, frozenset]]]:
    """stage -> (qualified name, codes skipped) of the public objects it defines, each once."""
    by_stage: dict[str, list[tuple[str, frozenset]]] = {}
    seen = set()

    def add(stage: str, name: str, skip: frozenset) -> None:
        if name not in seen:
            seen.add(name)
            by_stage.setdefault(stage, []).append((name, skip))

    for stage, value in _public_names():
        if not (inspect.isclass(value) or callable(value)) or not hasattr(value, "__qualname__"):
            continue
        add(stage, _qualified(value), PROTOCOL if getattr(value, "_is_protocol", False) else frozenset())
        if inspect.isclass(value):
            for name, skip in _members(value):
                add(stage, name, skip)
    return by_stage


def problems(name: str, skip: frozenset = frozenset()) -> list[str]:
    """The enforced numpydoc codes that ``name`` (an importable dotted path) fails, as
    ``"CODE message"`` lines; ``skip`` lists codes not asked of this object (RT01 is never
    asked of ``__init__``)."""
    errors = numpydoc.validate.validate(name)["errors"]
    if name.endswith(".__init__"):
        skip = skip | {"RT01"}
    return [f"{code} {message}" for code, message in errors if code in CODES and code not in skip]


OBJECTS = public_objects()


@pytest.mark.parametrize("stage", sorted(OBJECTS))
def test_public_docstrings_follow_numpydoc(stage):
    failures = []
    for name, skip in OBJECTS[stage]:
        found = problems(name, skip)
        if found:
            failures.append(f"{name}: " + "; ".join(found))
    assert not failures, f"{len(failures)} public object(s) of stage {stage!r}:\n" + "\n".join(failures)


def test_every_stage_with_public_names_is_checked():
    """The collection reaches the stages that hold the face's names and declare ``__all__``."""
    for stage in ("support", "data", "model", "equations", "numerics", "linear", "export"):
        assert OBJECTS.get(stage), stage


@pytest.fixture
def scratch_module(monkeypatch):
    """An importable throw-away module holding deliberately bad and good docstrings."""
    module = types.ModuleType("_docstring_scratch")

    def undocumented(x):
        return x

    def missing_parameter(x, y):
        """Add two numbers.

        Parameters
        ----------
        x : float
            The first.

        Returns
        -------
        float
            The sum.
        """
        return x + y

    def extra_parameter(x):
        """Double a number.

        Parameters
        ----------
        x : float
            The number.
        z : float
            Not a parameter at all.

        Returns
        -------
        float
            Twice ``x``.
        """
        return 2 * x

    def no_returns(x):
        """Double a number.

        Parameters
        ----------
        x : float
            The number.
        """
        return 2 * x

    def good(x):
        """Double a number.

        Parameters
        ----------
        x : float
            The number, in V.

        Returns
        -------
        float
            Twice ``x``, in V.
        """
        return 2 * x

    class Device:
        """A device.

        Parameters
        ----------
        gain : float
            In m/V.
        """

        def __init__(self, gain):
            self.gain = gain

        @property
        def bare(self):
            return self.gain

        @property
        def stroke(self):
            """The stroke per 100 V, in m."""
            return 100 * self.gain

    for f in (undocumented, missing_parameter, extra_parameter, no_returns, good, Device):
        f.__module__, f.__qualname__ = module.__name__, f.__name__
        setattr(module, f.__name__, f)
    monkeypatch.setitem(sys.modules, module.__name__, module)
    return module.__name__


@pytest.mark.parametrize(
    "function, code",
    [("undocumented", "GL08"), ("missing_parameter", "PR01"), ("extra_parameter", "PR02"), ("no_returns", "RT01")],
)
def test_the_checker_catches_a_bad_docstring(scratch_module, function, code):
    found = problems(f"{scratch_module}.{function}")
    assert [p[:4] for p in found] == [code], found


def test_the_checker_passes_a_good_docstring(scratch_module):
    assert problems(f"{scratch_module}.good") == []
    assert problems(f"{scratch_module}.Device") == []


def test_a_property_needs_a_docstring_but_no_returns_section(scratch_module):
    members = dict(_members(sys.modules[scratch_module].Device, scratch_module))
    assert set(members) == {f"{scratch_module}.Device.bare", f"{scratch_module}.Device.stroke"}
    assert [p[:4] for p in problems(f"{scratch_module}.Device.bare", PROPERTY)] == ["GL08"]
    assert problems(f"{scratch_module}.Device.stroke", PROPERTY) == []


#: the project's own terms that public docstrings use: each is defined in docs/glossary.md
GLOSSARY_TERMS = ("null", "static twin", "reading", "strained", "plausible device", "site", "Lur'e system", "screen")


def test_the_glossary_defines_the_project_terms():
    text = (MODULES["bondgraph"][0].parents[1] / "docs" / "glossary.md").read_text(encoding="utf-8").lower()
    missing = [t for t in GLOSSARY_TERMS if f"**{t.lower()}**" not in text and f"**the {t.lower()}**" not in text]
    assert not missing, f"docs/glossary.md does not define {missing}"
