"""The package's layout is its architecture: stages that import only the stages before them.

Every ``import`` inside ``bondgraph/`` is read with :mod:`ast`, at module level and inside
functions alike (a function-local import that closes a circle only hides it), and the tests
fail on an import circle between modules, on an import from a later stage, and on a module
at the package's root other than its face.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

ROOT = Path(__file__).resolve().parents[1] / "bondgraph"

#: the pipeline, first to last: a stage may import itself and the stages before it
STAGES = [
    "support",
    "data",
    "model",
    "equations",
    "numerics",
    "linear",
    "export",
    "fit",
    "diagnosis",
    "plotting",
    "batch",
    "cli",
]


def _modules() -> dict[str, tuple[Path, bool]]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
        package = parts[-1] == "__init__"
        if package:
            parts = parts[:-1]
        out[".".join(parts)] = (path, package)
    return out


MODULES = _modules()


def _targets(module: str, package: bool, node: ast.AST) -> list[str]:
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:
            base = module.split(".") if package else module.split(".")[:-1]
            base = base[: len(base) - node.level + 1]
            base = ".".join(base + ([node.module] if node.module else []))
        else:
            base = node.module or ""
        names = [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base for a in node.names]
    found = []
    for name in names:
        while name and name not in MODULES and "." in name:
            name = name.rsplit(".", 1)[0]
        if name in MODULES and name != module:
            found.append(name)
    return found


def import_graph() -> nx.DiGraph:
    """Module → module imports within ``bondgraph`` (module-level and function-local)."""
    g = nx.DiGraph()
    for module, (path, package) in MODULES.items():
        g.add_node(module)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for target in _targets(module, package, node):
                    if target != "bondgraph":  # the face imports nothing eagerly (PEP 562)
                        g.add_edge(module, target)
    return g


def stage(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in STAGES else None


def test_no_import_circle():
    g = import_graph()
    cycles = list(nx.simple_cycles(g))
    assert not cycles, "import circles: " + "; ".join(" -> ".join(c + c[:1]) for c in cycles[:5])


def test_stages_import_only_earlier_stages():
    late = []
    for a, b in import_graph().edges:
        sa, sb = stage(a), stage(b)
        if sa and sb and STAGES.index(sb) > STAGES.index(sa):
            late.append(f"{a} -> {b}")
    assert not late, "imports from a later stage: " + ", ".join(late)


def test_every_module_belongs_to_a_stage():
    loose = [m for m in MODULES if m not in ("bondgraph", "bondgraph.__main__") and stage(m) is None]
    assert not loose, f"modules outside the stage subpackages: {loose}"


def test_the_checker_sees_a_circle_hidden_in_a_function(tmp_path, monkeypatch):
    """The circle test fails when a function-local import closes a circle."""
    pkg = tmp_path / "bondgraph"
    (pkg / "support").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "support" / "__init__.py").write_text("")
    (pkg / "support" / "a.py").write_text("from .b import f\n")
    (pkg / "support" / "b.py").write_text("def f():\n    from .a import g\n")
    monkeypatch.setattr(__import__(__name__), "ROOT", pkg)
    monkeypatch.setattr(__import__(__name__), "MODULES", _modules())
    with pytest.raises(AssertionError, match="support.a"):
        test_no_import_circle()


def public_modules() -> set[str]:
    """The framework's public modules: the face, every package that declares ``__all__``, and
    the submodules a package lists in its ``__all__``."""
    public = {"bondgraph"}
    for module, (path, package) in MODULES.items():
        if not package:
            continue
        names = None
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
            ):
                try:
                    names = ast.literal_eval(node.value)
                except ValueError:  # computed (the face's lazy exports): no submodule listed
                    names = []
        if names is None:
            continue
        public.add(module)
        public.update(f"{module}.{n}" for n in names if f"{module}.{n}" in MODULES)
    return public


def test_the_library_and_models_use_the_public_api_only():
    """``library/`` and ``models/`` are built from the framework's public API: an import from
    any other module of ``bondgraph`` is a private one."""
    public = public_modules()
    private = []
    for folder in ("library", "models"):
        for path in sorted((ROOT.parent / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").startswith("bondgraph"):
                    if node.module not in public:
                        private.append(f"{path.relative_to(ROOT.parent)}: {node.module}")
                elif isinstance(node, ast.Import):
                    private += [
                        f"{path.relative_to(ROOT.parent)}: {a.name}"
                        for a in node.names
                        if a.name.startswith("bondgraph.") and a.name not in public
                    ]
    assert not private, "private imports: " + ", ".join(private)
