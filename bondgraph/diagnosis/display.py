"""The diagnosis as HTML: the chain with its gains and deciding rules, the unexplained share,
the calibrated and added parameters with their units, every candidate's verdict, the record.

Built from the report's JSON object (``Report.as_json()``, see docs/json-outputs.md) so that
it shows what the JSON says and nothing else; fields a report may or may not carry (a step's
``site``, ``rule``, ``unexplained_share``, ``unexplained_linear_share``, ``noise_rms``) are
shown when present.  The notebook display of a report (``Report._repr_html_``) is
:func:`report_html`; the HTML report file (:mod:`bondgraph.plotting.html_report`) puts the
same sections around its plots.
"""

from __future__ import annotations

import math
from html import escape

#: the page's look, scoped to the report's own elements
STYLE = """
.bondgraph-diagnosis { font-family: system-ui, sans-serif; font-size: 14px; color: #222; max-width: 1150px;
  margin: 0 auto; padding: 0 12px; }
.bondgraph-diagnosis table { border-collapse: collapse; margin: 0.4em 0 1em; }
.bondgraph-diagnosis th, .bondgraph-diagnosis td { border-bottom: 1px solid #ddd; padding: 3px 8px;
  text-align: left; vertical-align: top; }
.bondgraph-diagnosis th { background: #f3f3f3; }
.bondgraph-diagnosis td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
.bondgraph-diagnosis tr.named td { background: #eaf5ea; }
.bondgraph-diagnosis tr.stop td { background: #f7f2e6; }
.bondgraph-diagnosis .chain { font-size: 1.25em; margin: 0.3em 0; }
.bondgraph-diagnosis .note { background: #fff6e0; border-left: 4px solid #e0a800; padding: 4px 8px; }
.bondgraph-diagnosis pre { background: #f7f7f7; padding: 8px; overflow-x: auto; font-size: 12px; }
.bondgraph-diagnosis caption { text-align: left; font-weight: bold; padding: 2px 0; }
"""

#: per-step fields shown when a report carries them: (field, column heading, kind)
STEP_EXTRAS = (
    ("site", "site", "text"),
    ("rule", "deciding rule", "text"),
    ("unexplained_share", "unexplained share", "share"),
    ("unexplained_linear_share", "unexplained linear share", "share"),
    ("noise_rms", "noise floor (RMS)", "num"),
)


def num(v, digits: int = 4) -> str:
    """A number for a table: ``digits`` significant digits, "–" for none, ∞ and NaN spelled.

    Parameters
    ----------
    v : float or None
        The number.
    digits : int, optional
        Significant digits.

    Returns
    -------
    str
        The text.
    """
    if v is None:
        return "–"
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return escape(str(v))
    if math.isnan(v):
        return "NaN"
    if math.isinf(v):
        return "∞" if v > 0 else "−∞"
    return f"{v:.{digits}g}"


def share(v) -> str:
    """A share (0–1) as a percentage, "–" for none.

    Parameters
    ----------
    v : float or None
        The share.

    Returns
    -------
    str
        E.g. ``12%``.
    """
    return "–" if v is None else f"{100 * v:.3g} %"


def _cell(v, kind: str) -> str:
    if kind == "share":
        return f'<td class="num">{share(v)}</td>'
    if kind == "num":
        return f'<td class="num">{num(v)}</td>'
    return f"<td>{escape(str(v)) if v is not None else '–'}</td>"


def chain_text(j: dict) -> str:
    """The chain in one line: ``hysteresis ×8.82 → creep ×1.35`` (``none`` when nothing was named).

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).

    Returns
    -------
    str
        The line (plain text).
    """
    steps = j.get("steps") or []
    return " → ".join(f"{s['cause']} ×{num(s.get('gain'), 3)}" for s in steps) or "none"


def headline(j: dict) -> str:
    """What was diagnosed against what, the chain, its total gain and what is left unexplained.

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).

    Returns
    -------
    str
        An HTML fragment.
    """
    d = j.get("data", {})
    noise = j.get("noise_rms")
    base = "calibrated model" if j.get("baseline", "calibrated") == "calibrated" else "plausible device"
    what = " against ".join(escape(str(d[k])) for k in ("model", "file") if d.get(k))
    out = [
        f"<h2>Diagnosis{' of ' + what if what else ''}</h2>",
        f'<p class="chain" id="chain">Chain: <b>{escape(chain_text(j))}</b>'
        + (f" — total gain ×{num(j.get('gain'), 3)}" if j.get("causes") else "")
        + "</p>",
        f"<p>Validation RMS of the {base} {num(j.get('baseline_rms'))} → extended {num(j.get('extended_rms'))}"
        + (
            f"; noise floor {num(noise)} (the residual left is {num(j['extended_rms'] / noise, 3)}× it)"
            if noise and j.get("extended_rms") is not None
            else "; no noise floor estimated (the drive leaves no quiet band)"
        )
        + (f"; {num(j.get('seconds'), 3)} s" if j.get("seconds") is not None else "")
        + "</p>",
    ]
    shares = [
        f"{label} {share(j[k])}"
        for k, label in (("unexplained_share", "unexplained share"), ("unexplained_linear_share", "of it linear"))
        if j.get(k) is not None
    ]
    if shares:
        out.append(f'<p id="unexplained-share">{escape("; ".join(shares))}</p>')
    if j.get("unexplained"):
        out.append(f'<p class="note">{escape(j["unexplained"])}</p>')
    return "\n".join(out)


def chain_table(j: dict) -> str:
    """One row per named step (and the step where the chain stopped): its gain, the RMS before
    and after, the flexible linear reference, the fields a report may add, and why.

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).

    Returns
    -------
    str
        An HTML table.
    """
    steps = list(j.get("steps") or [])
    if j.get("stop"):
        steps.append(j["stop"])
    extras = [e for e in STEP_EXTRAS if any(s.get(e[0]) is not None for s in steps)]
    head = (
        "<tr><th>step</th><th>cause</th><th>gain</th><th>RMS before</th><th>RMS after</th>"
        "<th>flexible linear reference</th>" + "".join(f"<th>{h}</th>" for _, h, _ in extras) + "<th>why</th></tr>"
    )
    rows = []
    for k, s in enumerate(steps, 1):
        stop = s.get("cause") == "none"
        rows.append(
            f'<tr class="{"stop" if stop else "named"}"><td>{"stop" if stop else k}</td>'
            f"<td>{escape(str(s.get('cause')))}</td>"
            + _cell(s.get("gain"), "num")
            + _cell(s.get("rms_before"), "num")
            + _cell(s.get("rms"), "num")
            + _cell(s.get("reference_rms"), "num")
            + "".join(_cell(s.get(f), kind) for f, _, kind in extras)
            + f"<td>{escape(str(s.get('why', '')))}</td></tr>"
        )
    if not j.get("stop") and j.get("causes") and j.get("why") != steps[-1].get("why"):
        rows.append(
            f'<tr class="stop"><td>stop</td><td colspan="{6 + len(extras)}">{escape(j.get("why", ""))}</td></tr>'
        )
    return f'<table id="chain-table"><caption>The chain</caption>{head}{"".join(rows)}</table>'


def parameters_table(j: dict, units: dict | None = None) -> str:
    """The calibrated parameters (value, model's value, ratio, unit, bound and tolerance
    flags), those held at the model's value, the sensor's gain, offset, delay and drift, and
    the parameters each named cause added.

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).
    units : dict, optional
        Parameter name → unit (:func:`units_of`).

    Returns
    -------
    str
        HTML tables.
    """
    units = units or {}
    cal = j.get("calibration") or {}
    outside = cal.get("outside_tolerance") or {}
    at_bounds = set(cal.get("at_bounds") or [])
    rows = []
    for name, v in (cal.get("params") or {}).items():
        nominal = (cal.get("nominal") or {}).get(name)
        flags = [
            f for f, on in (("at a search bound", name in at_bounds), ("outside its tolerance", name in outside)) if on
        ]
        rows.append(
            f"<tr><td>{escape(name)}</td>{_cell(v, 'num')}{_cell(nominal, 'num')}"
            f"{_cell(v / nominal if nominal else None, 'num')}<td>{escape(units.get(name, ''))}</td>"
            f"<td>calibrated{'; ' + ', '.join(flags) if flags else ''}</td></tr>"
        )
    for name, why in (cal.get("held") or {}).items():
        rows.append(
            f"<tr><td>{escape(name)}</td><td></td><td></td><td></td><td>{escape(units.get(name, ''))}</td>"
            f"<td>held at the model's value: {escape(str(why))}</td></tr>"
        )
    out_unit = units.get(j.get("data", {}).get("output", ""), "")
    for name, key, unit in (
        ("sensor gain", "sensor_gain", ""),
        ("offset", "offset", out_unit),
        ("output delay", "delay", "s"),
        ("sensor drift", "drift", f"{out_unit}/s" if out_unit else "per s"),
    ):
        if cal.get(key) is not None and name not in (cal.get("held") or {}):
            rows.append(
                f"<tr><td>{name}</td>{_cell(cal[key], 'num')}<td></td><td></td><td>{escape(unit)}</td>"
                "<td>solved with the calibration</td></tr>"
            )
    for k, s in enumerate(j.get("steps") or [], 1):
        named = next((c for c in s.get("candidates", []) if c.get("named")), None)
        for name, v in ((named or {}).get("params") or {}).items():
            rows.append(
                f"<tr><td>{escape(name)}</td>{_cell(v, 'num')}<td></td><td></td><td>{escape(units.get(name, ''))}</td>"
                f"<td>added by step {k} ({escape(s['cause'])})</td></tr>"
            )
    head = "<tr><th>parameter</th><th>value</th><th>model's value</th><th>ratio</th><th>unit</th><th>how</th></tr>"
    return f'<table id="parameters"><caption>Parameters</caption>{head}{"".join(rows)}</table>'


def candidates_tables(j: dict) -> str:
    """Every candidate of every step (the step where the chain stopped too): gain, validation
    RMS, z, gain over the flexible linear reference, share, verdict; collapsed.

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).

    Returns
    -------
    str
        HTML tables, one per step.
    """
    steps = list(j.get("steps") or [])
    if j.get("stop"):
        steps.append(j["stop"])
    head = (
        "<tr><th>cause</th><th>extension</th><th>kind</th><th>gain</th><th>validation RMS</th><th>z</th>"
        "<th>gain vs reference</th><th>share</th><th>verdict</th></tr>"
    )
    out = []
    for k, s in enumerate(steps, 1):
        cands = sorted(s.get("candidates") or [], key=lambda c: (bool(c.get("skipped") or c.get("error")), -c["gain"]))
        rows = []
        for c in cands:
            named = bool(c.get("named"))
            if c.get("skipped") or c.get("error"):
                verdict = f"not tried: {c['skipped']}" if c.get("skipped") else f"failed: {c['error']}"
                cells = '<td colspan="5"></td>'
            else:
                verdict = "named" if named else c.get("verdict", "")
                cells = "".join(
                    _cell(c.get(f), kind)
                    for f, kind in (
                        ("gain", "num"),
                        ("rms_validation", "num"),
                        ("z", "num"),
                        ("gain_reference", "num"),
                        ("share", "share"),
                    )
                )
            rows.append(
                f'<tr class="{"named" if named else ""}"><td>{escape(c["cause"])}</td><td>{escape(c.get("label", ""))}</td>'
                f"<td>{escape(c.get('kind', ''))}</td>{cells}<td>{escape(verdict)}</td></tr>"
            )
        title = f"step {k}: {s['cause']}" if s.get("cause") != "none" else "where the chain stopped"
        out.append(
            f"<details><summary>Candidates, {escape(title)} ({len(cands)})</summary>"
            f'<table class="candidates">{head}{"".join(rows)}</table></details>'
        )
    return "\n".join(out)


def record_table(j: dict) -> str:
    """The record and how it was treated: samples, rate, validation split, drive band and
    reading, the notes, and the decision's thresholds.

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).

    Returns
    -------
    str
        An HTML table (and a list of the notes, if any).
    """
    d = j.get("data", {})
    rows = [
        ("samples", f"{d.get('samples')} at {num(d.get('rate_hz'), 6)} Hz"),
        ("from the file", f"{d.get('source_samples')} at {num(d.get('source_rate_hz'), 6)} Hz"),
        ("input → output", f"{d.get('input')} → {d.get('output')}"),
        ("validation", f"{share(d.get('validation_share'))} in {d.get('blocks')} interleaved time blocks held out"),
        ("drive band", f"{num(d.get('drive_band_hz'))} Hz"),
        ("drive reading", str(d.get("drive_reading", "–"))),
    ]
    crit = j.get("criterion") or {}
    if crit:
        rows.append(("thresholds", ", ".join(f"{k} {num(v)}" for k, v in crit.items())))
    body = "".join(f"<tr><th>{escape(k)}</th><td>{escape(v)}</td></tr>" for k, v in rows)
    notes = "".join(f"<li>{escape(n)}</li>" for n in j.get("notes") or [])
    return f'<table id="record"><caption>The record</caption>{body}</table>' + (f"<ul>{notes}</ul>" if notes else "")


def equations_block(j: dict) -> str:
    """The extended model's state equations (text), collapsed; '' when there are none.

    Parameters
    ----------
    j : dict
        The report's JSON object (:meth:`~bondgraph.diagnosis.Report.as_json`).

    Returns
    -------
    str
        An HTML ``<details>`` block, or ''.
    """
    if not j.get("equations"):
        return ""
    return (
        "<details><summary>State equations of the extended model</summary>"
        f"<pre>{escape(j['equations'])}</pre></details>"
    )


def units_of(model) -> dict[str, str]:
    """Parameter name → unit of a model (its declared parameters and its elements'), plus its
    inputs' and outputs' units; ``{}`` for no model.

    Parameters
    ----------
    model : Model or None
        The model.

    Returns
    -------
    dict of str to str
        Name → unit text.
    """
    if model is None:
        return {}
    out = {n: d.unit for n, d in model.all_parameters().items() if d.unit}
    out.update({n: i.unit for n, i in model.inputs.items() if i.unit})
    out.update({n: o.unit for n, o in model.outputs.items() if o.unit})
    return out


def report_html(report, model=None) -> str:
    """The diagnosis as one HTML fragment (no plots): the notebook display of a report.

    Parameters
    ----------
    report : Report
        A diagnosis (:func:`bondgraph.diagnosis.diagnose`).
    model : Model, optional
        The model diagnosed, for its parameters' units (default: the extended model's, when
        a cause was named).

    Returns
    -------
    str
    """
    j = report.as_json()
    units = units_of(report.extended_model) | units_of(model)
    return (
        f'<div class="bondgraph-diagnosis"><style>{STYLE}</style>'
        + "\n".join(
            [
                headline(j),
                chain_table(j),
                parameters_table(j, units),
                candidates_tables(j),
                record_table(j),
                equations_block(j),
            ]
        )
        + "</div>"
    )
