"""Model files: plain Python files that declare parameters and build a :class:`Model`.

A model file defines::

    PARAMETERS = [Parameter("K", 10.77e6, "N/m", "stack stiffness (Table 1)"), ...]
    EXPERIMENT = Experiment(t_end=0.1, dt=1e-4, inputs={"V": Sine(50, 10, offset=50)})  # optional
    def build(p):             # p.K is a sympy symbol, p.layers an int, p.value("K") a float
        m = Model("name")
        ...
        return m

:func:`load_model` runs the file, applies ``--set`` overrides (unknown names are errors
listing the known ones) and returns the built model with its parameter values attached.
"""

from __future__ import annotations

import importlib.util
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from ..support.errors import BondGraphError, ModelError, ParameterError, UsageError, did_you_mean
from .experiment import Experiment
from .graph import Model
from .parameters import Parameter, ParameterValues


@dataclass
class LoadedModel:
    """A built model with its file, declared parameters, values and default experiment;
    ``offsets`` maps output names to an offset added to them (a fit file's sensor zero)."""

    path: Path
    model: Model
    params: ParameterValues
    experiment: Experiment
    declared: list[Parameter]
    module: Any
    offsets: dict = field(default_factory=dict)


def read_model_module(path: str | Path):
    """Import a model file as a fresh module; errors become one-line ModelErrors."""
    p = Path(path)
    if p.is_dir():
        raise UsageError(f"model file {path}: is a directory (give the path to a .py model file)")
    if not p.is_file():
        raise UsageError(f"model file {path}: not found (give the path to a .py model file)")
    name = f"bondgraph_model_{abs(hash(str(p.resolve())))}"
    spec = importlib.util.spec_from_file_location(name, p)
    if spec is None or spec.loader is None:
        raise UsageError(f"model file {path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except SyntaxError as exc:
        raise ModelError(f"{path}:{exc.lineno or '?'}: syntax error: {exc.msg}") from None
    except BondGraphError as exc:
        raise type(exc)(f"{path}: {exc}") from None
    except SystemExit as exc:
        raise ModelError(
            f"{path}:{_user_line(exc, p)}: the model file called sys.exit({exc.code!r}); a model file "
            f"must define PARAMETERS and build(p), not end the program"
        ) from None
    except Exception as exc:  # noqa: BLE001 - any failure of user code is reported as an input error
        raise ModelError(f"{path}:{_user_line(exc, p)}: {type(exc).__name__}: {exc}") from None
    for attr in ("PARAMETERS", "build"):
        if not hasattr(module, attr):
            raise ModelError(
                f"model file {path}: defines no {attr} (a model file needs PARAMETERS and build(p); see README)"
            )
    declared = list(module.PARAMETERS)
    if not all(isinstance(d, Parameter) for d in declared):
        raise ModelError(f"model file {path}: PARAMETERS must be a list of bondgraph.Parameter")
    names = [d.name for d in declared]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ModelError(
            f"model file {path}: parameter {', '.join(repr(n) for n in twice)} declared twice in "
            f"PARAMETERS; declare each name once"
        )
    return module, declared


def _user_line(exc: BaseException, path: Path) -> str:
    """Line number in the model file (or a library file) where the exception arose."""
    frames = traceback.extract_tb(exc.__traceback__)
    for fr in reversed(frames):
        if Path(fr.filename).resolve() == path.resolve():
            return str(fr.lineno)
    return str(frames[-1].lineno) if frames else "?"


def load_model(path: str | Path, overrides: Mapping[str, Any] | None = None) -> LoadedModel:
    """Load and build a model file with parameter ``overrides`` (name → value or string)."""
    p = Path(path)
    module, declared = read_model_module(p)
    overrides = dict(overrides or {})
    names = {d.name for d in declared}
    values = ParameterValues(declared, {k: v for k, v in overrides.items() if k in names})
    try:
        model = module.build(values)
    except BondGraphError as exc:
        raise type(exc)(f"{path}: {exc}") from None
    except SystemExit as exc:
        raise ModelError(
            f"{path}:{_user_line(exc, p)}: build(p) called sys.exit({exc.code!r}); it must return a bondgraph.Model"
        ) from None
    except Exception as exc:  # noqa: BLE001
        raise ModelError(f"{path}:{_user_line(exc, p)}: {type(exc).__name__} while building: {exc}") from None
    if not isinstance(model, Model):
        raise ModelError(f"model file {path}: build(p) must return a bondgraph.Model, got {type(model).__name__}")
    model.declared = declared
    model.values = values.as_dict()
    try:
        model.check()
    except BondGraphError as exc:
        raise type(exc)(f"{path}: {exc}") from None
    extra = {k: v for k, v in overrides.items() if k not in names}
    for k, v in extra.items():
        if k not in model.parameters:
            raise ParameterError(did_you_mean(k, list(names) + list(model.parameters), "parameter"))
        decl = model.parameters[k][0]
        model.values[k] = decl.parse(v) if isinstance(v, str) else decl.coerce(v)
    experiment = getattr(module, "EXPERIMENT", None) or Experiment()
    if not isinstance(experiment, Experiment):
        raise ModelError(f"model file {path}: EXPERIMENT must be a bondgraph.Experiment")
    return LoadedModel(p, model, values, experiment, declared, module)
