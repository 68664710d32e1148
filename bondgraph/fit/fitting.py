"""Fit a model file's parameters to measured data: the workflow behind ``bondgraph fit``.

    from bondgraph.model.modelfile import load_model
    from bondgraph.data import read_csv
    from bondgraph.fit.fitting import fit_parameters

    fit = fit_parameters(load_model("models/apa120ml.py"), read_csv("data.csv"), ["a", "c", "K"])
    fit.result.values, fit.result.stderr, fit.result.offset, fit.result.rms_validation
    fit.as_json("models/apa120ml.py", "data.csv")   # the fit file (bondgraph fit --out)

The model file's optional ``seed(p, data)`` hook gives start values; parameters the output
depends on linearly are detected and solved exactly (see :mod:`bondgraph.fit.identify`).  The
fit also solves an output offset (the sensor's zero): measured ≈ model output + offset.

The fit file holds everything needed to reproduce the fit: every parameter value of the
fitted model (``params``, what ``--params-file`` applies), the output ``offset`` and the
``output`` it belongs to (``simulate --params-file`` adds it), the model input and the data
columns, the settings (validation share, split, loss, starts) and the scores.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from ..data import Dataset
from ..model.modelfile import LoadedModel
from ..model.parameters import FIT_FORMAT
from ..support.errors import UsageError
from .identify import FitResult, Identification, detect_linear

#: the ``format`` entry of fit files
FORMAT = FIT_FORMAT

#: lag-1 autocorrelation of the residual above which ``bondgraph fit`` warns that its
#: standard errors, which assume independent residuals, understate the parameters' error
CORRELATED = 0.5


def residual_correlation(measured, predicted) -> float:
    """The lag-1 autocorrelation of the residual measured − predicted (its mean removed).

    Near 0 for a model that leaves only white noise; near 1 for a residual that is a smooth
    curve (a systematic model error such as a hysteresis loop the model lacks, or noise far
    slower than the sampling).  The standard errors of a least-squares fit assume independent
    residuals: with a correlated one they understate the parameters' error, by about
    sqrt((1 + ρ)/(1 − ρ)) for a first-order autoregressive residual.

    Parameters
    ----------
    measured, predicted : array_like
        The measured output and the model's prediction on the same samples (same unit).

    Returns
    -------
    float
        ρ in [−1, 1]; 0 when the residual is constant or has fewer than three samples.
    """
    r = np.asarray(measured, float) - np.asarray(predicted, float)
    r = r[np.isfinite(r)]
    if r.size < 3:
        return 0.0
    r = r - r.mean()
    energy = float(r @ r)
    return float(r[1:] @ r[:-1]) / energy if energy > 0 else 0.0


@dataclass
class ModelFit:
    """A fit of a model file to data: the result, the parameters solved linearly, every
    parameter value of the fitted model, the model input/output and the fit's settings.

    Parameters
    ----------
    result : FitResult
        Values, standard errors, offset and RMS errors of the fit.
    linear : list of str
        The fitted parameters solved by linear least squares.
    params : dict, optional
        Every parameter value of the fitted model, by name.
    input : str, optional
        The model input the data drove.
    output : str, optional
        The model output compared with the data.
    output_unit : str, optional
        The output's unit (that of the offset and the RMS errors).
    settings : dict, optional
        ``validation``, ``split``, ``loss`` and ``starts`` of the fit.
    """

    result: FitResult
    linear: list[str]
    params: dict = field(default_factory=dict)
    input: str = ""
    output: str = ""
    output_unit: str = ""
    settings: dict = field(default_factory=dict)

    def as_json(
        self, model: str = "", data: str = "", data_input: str | None = None, data_output: str | None = None
    ) -> dict:
        """The fit file: see the module docstring.

        Parameters
        ----------
        model : str, optional
            The model file's path, as recorded.
        data : str, optional
            The data file's path, as recorded.
        data_input : str, optional
            The data column of the drive (default: the model input's name).
        data_output : str, optional
            The data column of the output (default: the model output's name).

        Returns
        -------
        dict
            ``format``, ``model``, ``data``, ``input``, ``output``, ``data_input``,
            ``data_output``, ``params``, ``fitted``, ``linear``, ``stderr``, ``offset``,
            ``offset_unit``, ``rms_fit``, ``rms_validation``, ``nfev``, ``success``,
            ``message`` and ``settings``.
        """
        res = self.result.as_json()
        return {
            "format": FORMAT,
            "model": model,
            "data": data,
            "input": self.input,
            "output": self.output,
            "data_input": data_input or self.input,
            "data_output": data_output or self.output,
            "params": self.params,
            "fitted": list(self.result.values),
            "linear": self.linear,
            "stderr": res["stderr"],
            "offset": res["offset"],
            "offset_unit": self.output_unit,
            "rms_fit": res["rms_fit"],
            "rms_validation": res["rms_validation"],
            "nfev": res["nfev"],
            "success": res["success"],
            "message": res["message"],
            "settings": self.settings,
        }


def fit_parameters(
    loaded: LoadedModel,
    data: Dataset,
    names: Sequence[str],
    *,
    input: str | None = None,
    output: str | None = None,
    validation: float = 0.3,
    split: str = "blocks",
    loss: str = "linear",
    starts: int = 1,
    progress: Callable[[int], None] | None = None,
) -> ModelFit:
    """Least-squares fit of ``names`` of the loaded model file to ``data`` (model input
    ``input`` driven by the data column of that name, compared with output ``output``; both
    default to the model's first declared input and output).

    Parameters
    ----------
    loaded : LoadedModel
        The model file, loaded (:func:`bondgraph.model.modelfile.load_model`).
    data : Dataset
        The measured record.
    names : sequence of str
        The real-valued parameters to fit, each once.
    input : str, optional
        The model input (and data column) driving the model.
    output : str, optional
        The model output (and data column) compared.
    validation : float, optional
        Share of the record held out for validation, between 0 and 1.
    split : {"blocks", "tail"}, optional
        How it is held out (:func:`~bondgraph.fit.identify.split_masks`).
    loss : str, optional
        The loss of ``scipy.optimize.least_squares``.
    starts : int, optional
        Start points of the fit (the best is kept).
    progress : callable, optional
        ``progress(n)`` as simulations run.

    Returns
    -------
    ModelFit
        The fit, with every parameter value of the fitted model.

    Raises
    ------
    UsageError
        No name, a name listed twice, a parameter that is not real-valued, or a bad split.
    ParameterError
        A name is not a parameter of the model.
    DataError
        A missing column, or a drive that does not vary.
    SimulationError
        The model cannot be simulated from its start values.
    """
    from ..numerics.checks import check_start

    names = list(names)
    if not names:
        raise UsageError("fit: give the parameters to fit, e.g. --params a,c,K")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise UsageError(f"fit: {', '.join(twice)} listed twice in the parameters to fit; list each once")
    model = loaded.model
    decl = model.all_parameters()
    for n in names:
        if n in decl and decl[n].kind != "real":
            raise UsageError(
                f"fit: '{n}' is {decl[n].expected()}, not a real number; only real-valued parameters "
                f"can be fitted (set it with --set {n}=...)"
            )
    input = input or next(iter(model.inputs), "")
    output = output or next(iter(model.outputs), "")
    seed = getattr(loaded.module, "seed", None)
    if seed is not None:  # the model file's seeding procedure (start values read off the data)
        start = seed(loaded.params, data)
        model.values.update({k: v for k, v in start.items() if k in names})
    ident = Identification(model, data, input, output, validation=validation, split=split)
    check_start(ident.sim, inputs={input: ident.signal}, t0=float(data.t[0]))
    linear = detect_linear(ident, names)
    res = ident.fit(ident.specs(names, linear), loss=loss, starts=starts, progress=progress)
    params = {**model.values, **res.values}
    unit = model.outputs[output].unit if output in model.outputs else ""
    settings = {"validation": validation, "split": split, "loss": loss, "starts": starts}
    return ModelFit(res, linear, params, input, output, unit, settings)
