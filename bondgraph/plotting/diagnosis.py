"""The diagnosis at a glance: measured, calibrated and extended output, residuals, loops."""

from __future__ import annotations

from . import figures


def plot_diagnosis(report, path: str) -> None:
    """Measured vs calibrated vs extended output (after each named cause), residuals, and
    residual-vs-input loops.

    Parameters
    ----------
    report : Report
        A diagnosis report (:func:`bondgraph.diagnosis.diagnose`) with its ``predictions``.
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = figures.pyplot()
    p = report.predictions
    t, u, y, base = p["t"], p["u"], p["y"], p["baseline"]
    ext = p.get("extended")
    chain = " → ".join(report.causes) or "none"
    inp, out = report.data.get("input", "input"), report.data.get("output", "output")
    fig, ax = plt.subplots(3, 1, figsize=(9, 9))
    ax[0].plot(t, y, lw=0.8, label="measured")
    which = "calibrated" if report.baseline == "calibrated" else "plausible device"
    ax[0].plot(
        t,
        base,
        lw=0.8,
        label="calibrated model" if which == "calibrated" else "plausible device (calibrated within tolerance)",
    )
    if ext is not None:
        ax[0].plot(t, ext, lw=0.8, ls="--", label=f"extended ({chain})")
    ax[0].set_xlabel("t (s)")
    ax[0].set_ylabel(out)
    ax[0].legend(fontsize=8)
    ax[1].plot(t, y - base, lw=0.6, label=f"residual, {which} (RMS {report.baseline_rms:.3g})")
    if ext is not None:
        ax[1].plot(t, y - ext, lw=0.6, label=f"residual, extended (RMS {report.extended_rms:.3g})")
    if report.noise:
        ax[1].axhspan(-report.noise, report.noise, color="0.85", label="noise floor (±1σ)")
    ax[1].set_xlabel("t (s)")
    ax[1].set_ylabel(f"{out} residual")
    ax[1].legend(fontsize=8)
    ax[2].plot(u, y - base, lw=0.4, label="calibrated")
    if ext is not None:
        ax[2].plot(u, y - ext, lw=0.4, label="extended")
    ax[2].set_xlabel(inp)
    ax[2].set_ylabel(f"{out} residual")
    ax[2].legend(fontsize=8)
    for a in ax:
        a.grid(alpha=0.3)
    fig.suptitle(f"diagnosis: {chain} (gain {report.gain:.3g})")
    fig.tight_layout()
    figures.save(fig, path)
