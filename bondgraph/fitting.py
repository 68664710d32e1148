"""Fit a model file's parameters to measured data: the workflow behind ``bondgraph fit``.

    from bondgraph.modelfile import load_model
    from bondgraph.data import read_csv
    from bondgraph.fitting import fit_parameters

    fit = fit_parameters(load_model("models/apa120ml.py"), read_csv("data.csv"), ["a", "c", "K"])
    fit.result.values, fit.result.stderr, fit.result.rms_validation

The model file's optional ``seed(p, data)`` hook gives start values; parameters the output
depends on linearly are detected and solved exactly (see :mod:`bondgraph.identify`).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from .data import Dataset
from .errors import UsageError
from .identify import FitResult, Identification, detect_linear
from .modelfile import LoadedModel


@dataclass
class ModelFit:
    """A fit of a model file to data: the result and which parameters were solved linearly."""

    result: FitResult
    linear: list[str]

    def as_json(self, model: str = "", data: str = "") -> dict:
        return {"model": model, "data": data, "linear": self.linear, **self.result.as_json()}


def fit_parameters(loaded: LoadedModel, data: Dataset, names: Sequence[str], *, input: str = "V",
                   output: str = "x", validation: float = 0.3, split: str = "blocks", loss: str = "linear",
                   starts: int = 1, progress: Callable[[int], None] | None = None) -> ModelFit:
    """Least-squares fit of ``names`` of the loaded model file to ``data`` (model input
    ``input`` driven by the data column of that name, compared with output ``output``)."""
    names = list(names)
    if not names:
        raise UsageError("fit: give the parameters to fit, e.g. --params a,c,K")
    seed = getattr(loaded.module, "seed", None)
    if seed is not None:  # the model file's seeding procedure (start values read off the data)
        start = seed(loaded.params, data)
        loaded.model.values.update({k: v for k, v in start.items() if k in names})
    ident = Identification(loaded.model, data, input, output, validation=validation, split=split)
    linear = detect_linear(ident, names)
    res = ident.fit(ident.specs(names, linear), loss=loss, starts=starts, progress=progress)
    return ModelFit(res, linear)
