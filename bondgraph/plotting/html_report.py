"""The diagnosis as one self-contained HTML page with interactive plots (Bokeh, the optional
extra ``report``).

The page holds the diagnosis' tables (:mod:`bondgraph.diagnosis.display`: the chain with its
gains and deciding rules, the unexplained share, the parameters with their units, every
candidate) around five linked plots: measured vs calibrated vs extended output, the
residual before and after each step against the noise floor, the residuals' spectra against
the noise floor's, the residual against the drive (loops), and the validation RMS along the
chain.  Bokeh's JavaScript is written into the page (inline resources), so it opens with no
network.

The report's ``predictions`` give the curves: ``t``, ``u`` (the drive), ``y`` (measured),
``baseline`` (the calibrated model, or the plausible device), and ``extended`` (the model
extended by the whole chain); when they also hold ``steps``, a list with the output of the
model after each named step, every step is drawn.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import welch

from ..diagnosis.display import (
    STYLE,
    candidates_tables,
    chain_table,
    chain_text,
    equations_block,
    headline,
    parameters_table,
    record_table,
    units_of,
)
from ..model.drawing import MAX_ELEMENTS, svg
from ..support.atomic import atomic_write
from ..support.errors import UsageError
from .figures import axis_label, envelope, robust_limits, scaled_label, si_scale

#: colours of the curves: measured, the calibrated model, then the steps
PALETTE = ("#444444", "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2")

TEMPLATE = """{% extends base %}
{% block postamble %}<style>{{ style }}
.bondgraph-diagnosis .plots { margin: 1em 0; }
</style>{% endblock %}
{% block contents %}
<div class="bondgraph-diagnosis">
{{ headline }}
{{ chain }}
<div class="plots" id="plots">{{ embed(roots.plots) }}</div>
{{ parameters }}
{{ candidates }}
{{ graph }}
{{ record }}
{{ equations }}
</div>
{% endblock %}
"""


def need_bokeh() -> None:
    """Raise a one-line :class:`UsageError` unless bokeh (the optional extra ``report``) is
    installed."""
    import importlib.util

    if importlib.util.find_spec("bokeh") is None:
        raise UsageError("the HTML report needs bokeh: pip install 'bondgraph[report]'")


def curves(report) -> list[tuple[str, np.ndarray]]:
    """The model outputs to draw, in order: the calibrated model (or plausible device), then
    the model after each named step (or, when the report does not keep them, after the whole
    chain), each with its legend.

    Parameters
    ----------
    report : Report
        A diagnosis report with its ``predictions``.

    Returns
    -------
    list of tuple of (str, numpy.ndarray)
        (legend, prediction on the report's time grid, output units).
    """
    p = report.predictions
    base = "calibrated model" if report.baseline == "calibrated" else "plausible device"
    out = [(base, np.asarray(p["baseline"], float))]
    causes = list(report.causes)
    steps = p.get("steps")
    if steps is not None and len(steps) == len(causes):
        out += [(" + ".join(["calibrated"] + causes[: k + 1]), np.asarray(s, float)) for k, s in enumerate(steps)]
    elif p.get("extended") is not None:
        out.append((f"extended ({' → '.join(causes)})", np.asarray(p["extended"], float)))
    return out


def noise_psd(noise: float, fs: float) -> float:
    """The one-sided power spectral density of white noise of RMS ``noise`` sampled at ``fs``
    (its integral from 0 to fs/2 is noise²), in output units² per Hz.

    Parameters
    ----------
    noise : float
        The noise's RMS, output units.
    fs : float
        Sample rate, Hz.

    Returns
    -------
    float
        2·noise²/fs, output units² per Hz.
    """
    return 2.0 * noise**2 / fs


def _figures(report, units: dict, limit: int):
    from bokeh.layouts import column, row
    from bokeh.models import BoxAnnotation, FactorRange, Label, Range1d, Span
    from bokeh.plotting import figure

    p = report.predictions
    t, u, y = (np.asarray(p[k], float) for k in ("t", "u", "y"))
    inp, out = report.data.get("input", "input"), report.data.get("output", "output")
    models = curves(report)
    y_label, fy = scaled_label(out, units.get(out, ""), y, *(m for _, m in models))
    u_label, fu = scaled_label(inp, units.get(inp, ""), u)
    residuals = [y - m for _, m in models]
    fr, r_unit = si_scale(units.get(out, ""), *residuals)
    r_label = axis_label(f"{out} residual", r_unit)
    lo, hi, start, clipped = robust_limits(t, [fr * r for r in residuals], fr * (report.noise or 0.0))
    scale = f" (scale from t ≥ {t[start]:.3g} s: start-up transient off scale)" if clipped else ""
    noise = report.noise
    tools = "pan,box_zoom,wheel_zoom,reset,save"

    def fig(title, **kw):
        f = figure(title=title, tools=tools, sizing_mode="stretch_width", height=300, **kw)
        f.toolbar.logo = None
        return f

    fit = fig("Measured vs calibrated vs extended output", x_axis_label="t (s)", y_axis_label=y_label)
    fit.line(*envelope(t, fy * y, limit), color=PALETTE[0], line_width=1.2, legend_label="measured")
    for k, (label, m) in enumerate(models, 1):
        fit.line(*envelope(t, fy * m, limit), color=PALETTE[k % len(PALETTE)], line_width=1.0, legend_label=label)

    res = fig(
        "Residual (measured − model) before and after each step" + scale,
        x_axis_label="t (s)",
        y_axis_label=r_label,
        x_range=fit.x_range,
        y_range=Range1d(lo, hi),
    )
    for k, ((label, _), r) in enumerate(zip(models, residuals), 1):
        res.line(*envelope(t, fr * r, limit), color=PALETTE[k % len(PALETTE)], line_width=0.8, legend_label=label)
    if noise:
        res.add_layout(BoxAnnotation(bottom=-fr * noise, top=fr * noise, fill_color="#999999", fill_alpha=0.25))
        res.line(
            [t[0], t[-1]], [fr * noise, fr * noise], color="#999999", line_dash="dashed", legend_label="noise floor ±1σ"
        )

    fs = float(report.data.get("rate_hz") or 1.0 / np.median(np.diff(t)))
    spec = fig(
        "Residual spectra against the noise floor",
        x_axis_label="f (Hz)",
        y_axis_label=f"PSD ({units.get(out, 'unit')}²/Hz)" if units.get(out) else "PSD (unit²/Hz)",
        x_axis_type="log",
        y_axis_type="log",
    )
    nperseg = int(min(len(t), max(256, 2 ** int(np.log2(max(len(t) // 8, 1))))))
    for k, (label, m) in enumerate(models, 1):
        f, pxx = welch(y - m, fs=fs, nperseg=nperseg)
        keep = (f > 0) & (pxx > 0)
        spec.line(f[keep], pxx[keep], color=PALETTE[k % len(PALETTE)], line_width=1.0, legend_label=label)
    if noise:
        level = noise_psd(noise, fs)
        spec.line(
            [fs / nperseg, fs / 2], [level, level], color="#999999", line_dash="dashed", legend_label="noise floor"
        )
    band = report.data.get("drive_band_hz")
    if band:
        spec.add_layout(Span(location=band, dimension="height", line_color="#888888", line_dash="dotted"))

    loops = fig(
        "Residual against the drive" + scale, x_axis_label=u_label, y_axis_label=r_label, y_range=Range1d(lo, hi)
    )
    every = slice(None, None, max(1, -(-len(t) // limit)))  # a loop plot of every k-th sample
    for k, (label, m) in enumerate(models, 1):
        loops.line(
            fu * u[every],
            fr * (y - m)[every],
            color=PALETTE[k % len(PALETTE)],
            line_width=0.6,
            alpha=0.8,
            legend_label=label,
        )

    rms = [report.baseline_rms] + [s.rms for s in report.steps if s.cause != "none"]
    names = ["calibrated" if report.baseline == "calibrated" else "plausible"] + [
        f"+ {s.cause}" for s in report.steps if s.cause != "none"
    ]
    chain = fig(
        "Validation RMS along the chain",
        x_range=FactorRange(*names),
        y_axis_label=axis_label(f"{out} RMS", units.get(out, "")),
        y_axis_type="log",
    )
    named = [s for s in report.steps if s.cause != "none"]
    floor = min(rms + [s.reference_rms for s in named]) / 10
    chain.vbar(x=names, top=rms, bottom=floor, width=0.6, color=PALETTE[1], legend_label="validation RMS")
    if named:
        chain.scatter(
            names[1:],
            [s.reference_rms for s in named],
            size=10,
            marker="diamond",
            color=PALETTE[5],
            legend_label="flexible linear reference of the step",
        )
    if noise:
        chain.add_layout(Span(location=noise, dimension="width", line_color="#999999", line_dash="dashed"))
        chain.add_layout(Label(x=4, y=noise, x_units="screen", text="noise floor", text_font_size="9pt"))
    for f in (fit, res, spec, loops, chain):
        f.legend.click_policy = "hide"
        f.legend.label_text_font_size = "9pt"
    grid = column(fit, res, row(spec, loops, sizing_mode="stretch_width"), chain, sizing_mode="stretch_width")
    grid.name = "plots"
    return grid


def report_page(report, model=None, max_points: int = 20_000) -> str:
    """The diagnosis as one self-contained HTML page.

    Parameters
    ----------
    report : Report
        A diagnosis (:func:`bondgraph.diagnosis.diagnose`) with its ``predictions``.
    model : Model, optional
        The model diagnosed, for its parameters' and signals' units (default: the extended
        model's, when a cause was named).
    max_points : int
        At most about this many points per time curve (each bucket's minimum and maximum are
        kept) and per loop (every k-th sample); spectra use every sample.

    Returns
    -------
    str
        The page (HTML with Bokeh's JavaScript inline).

    Raises
    ------
    UsageError
        When bokeh is not installed, or the report keeps no predictions.
    """
    need_bokeh()
    from bokeh.embed import file_html
    from bokeh.resources import INLINE
    from jinja2 import Template

    if not report.predictions:
        raise UsageError("the report keeps no predictions to plot: run the diagnosis again")
    from ..equations.causality import assign_causality

    j = report.as_json()
    units = units_of(report.extended_model) | units_of(model)
    graph, ext = "", report.extended_model
    if ext is not None:
        if len(ext.elements) <= MAX_ELEMENTS:
            c = assign_causality(ext)
            drawing = svg(ext, c.stroke_end, {e for e, _ in c.derivative})
        else:
            drawing = svg(ext)  # says it is too big to draw
        graph = f"<details><summary>Bond graph of the extended model</summary>{drawing}</details>"
    return file_html(
        _figures(report, units, max_points),
        resources=INLINE,
        title=f"Diagnosis: {chain_text(j)}",
        template=Template(TEMPLATE),
        template_variables={
            "style": STYLE,
            "headline": headline(j),
            "chain": chain_table(j),
            "parameters": parameters_table(j, units),
            "candidates": candidates_tables(j),
            "graph": graph,
            "record": record_table(j),
            "equations": equations_block(j),
        },
    )


def write_report(report, path, model=None) -> None:
    """Write :func:`report_page` to ``path`` atomically (the file appears whole or not at all).

    Parameters
    ----------
    report : Report
        The diagnosis.
    path : str or os.PathLike
        The HTML file to write.
    model : Model, optional
        The model diagnosed, for units.

    Raises
    ------
    UsageError
        As :func:`report_page`.
    """
    page = report_page(report, model)
    with atomic_write(path, "w") as fh:
        fh.write(page)
