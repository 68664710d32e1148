"""The diagnosis at a glance: measured, calibrated and extended output, residuals, loops.

Axes carry the quantity and its unit (the model's declared units, SI-prefixed to suit the
data: µm rather than 0.0001 m); the residual panels take their scale from the record after
its start-up transient (:func:`bondgraph.plotting.figures.residual_scale`), so a transient the
models cannot follow (both start from rest, the record does not) never hides the loops.
"""

from __future__ import annotations

import numpy as np

from . import figures


def plot_diagnosis(report, path: str, model=None) -> None:
    """Measured vs calibrated vs extended output (after each named cause), residuals, and
    residual-vs-input loops.

    Parameters
    ----------
    report : Report
        A diagnosis report (:func:`bondgraph.diagnosis.diagnose`) with its ``predictions``.
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).
    model : Model, optional
        The model diagnosed, for its input's and output's units (default: the extended
        model's, when a cause was named).

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    from ..diagnosis.display import units_of  # here: importing the diagnosis costs every plot ~0.7 s

    plt = figures.pyplot()
    p = report.predictions
    t, u, y, base = (np.asarray(p[k], float) for k in ("t", "u", "y", "baseline"))
    ext = p.get("extended")
    ext = None if ext is None else np.asarray(ext, float)
    chain = " → ".join(report.causes) or "none"
    inp, out = report.data.get("input", "input"), report.data.get("output", "output")
    units = units_of(report.extended_model) | units_of(model)
    y_label, fy = figures.scaled_label(out, units.get(out, ""), y)
    u_label, fu = figures.scaled_label(inp, units.get(inp, ""), u)
    residuals = [y - base] + ([] if ext is None else [y - ext])
    fr, r_unit = figures.si_scale(units.get(out, ""), *residuals)
    r_label = figures.axis_label(f"{out} residual", r_unit)
    fig, ax = plt.subplots(3, 1, figsize=(9, 9))
    ax[0].plot(t, fy * y, lw=0.8, label="measured")
    which = "calibrated" if report.baseline == "calibrated" else "plausible device"
    ax[0].plot(
        t,
        fy * base,
        lw=0.8,
        label="calibrated model" if which == "calibrated" else "plausible device (calibrated within tolerance)",
    )
    if ext is not None:
        ax[0].plot(t, fy * ext, lw=0.8, ls="--", label=f"extended ({chain})")
    ax[0].set_xlabel("t (s)")
    ax[0].set_ylabel(y_label)
    ax[0].legend(fontsize=8)
    ax[1].plot(t, fr * residuals[0], lw=0.6, label=f"residual, {which} (RMS {fr * report.baseline_rms:.3g} {r_unit})")
    if ext is not None:
        ax[1].plot(
            t, fr * residuals[1], lw=0.6, label=f"residual, extended (RMS {fr * report.extended_rms:.3g} {r_unit})"
        )
    noise = fr * (report.noise or 0.0)
    if noise:
        ax[1].axhspan(-noise, noise, color="0.85", label="noise floor (±1σ)")
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel(r_label)
    ax[1].legend(fontsize=8)
    ax[2].plot(fu * u, fr * residuals[0], lw=0.4, label="calibrated")
    if ext is not None:
        ax[2].plot(fu * u, fr * residuals[1], lw=0.4, label="extended")
    ax[2].set_xlabel(u_label)
    ax[2].set_ylabel(r_label)
    ax[2].legend(fontsize=8)
    for a in ax[1:]:
        figures.residual_scale(a, t, [fr * r for r in residuals], noise)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(f"diagnosis: {chain} (gain {report.gain:.3g})")
    fig.tight_layout()
    figures.save(fig, path)
