"""Plots of a sweep (matplotlib, the ``plot`` extra): histograms and tornado plots."""

from __future__ import annotations

import numpy as np

from ..plotting import figures


def plot_sweep(result, path: str) -> None:
    """One column per metric: its histogram over the runs (mean and ±1 std marked) on top,
    the tornado plot of its sensitivity below (bars from the baseline to the output at each
    parameter's low and high value, the largest swing on top); the axes say the metric's unit,
    SI-prefixed to suit its values.

    Parameters
    ----------
    result : SweepResult
        The sweep.
    path : str
        The image to write (png, pdf or svg; written atomically).

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = figures.pyplot()
    metrics = result.metrics
    n = len(metrics)
    n_par = len(result.params)
    fig, axes = plt.subplots(2, n, figsize=(4.6 * n, 3.2 + 3.0 + 0.25 * n_par), squeeze=False)
    for k, (m, sens) in enumerate(zip(metrics, result.sensitivity())):
        y = result.table.column(m)
        y = y[np.isfinite(y)]
        label, f = figures.scaled_label(m, result.units.get(m, ""), y)
        y = f * y
        ax = axes[0, k]
        if y.size:
            ax.hist(y, bins=min(50, max(5, int(np.sqrt(y.size)))), color="#4c72b0", alpha=0.85)
            mu, sd = float(np.mean(y)), float(np.std(y))
            ax.axvline(mu, color="k", lw=1.2)
            for s in (-1, 1):
                ax.axvline(mu + s * sd, color="k", lw=0.8, ls="--")
        ax.set_title(f"{m}  ({y.size} runs)")
        ax.set_xlabel(label)
        ax.set_ylabel("runs")
        ax.grid(alpha=0.3)
        ax = axes[1, k]
        if "noise" in sens:
            ax.text(
                0.5,
                0.5,
                f"not ranked: the runs spread by {sens['noise']:.2g}\nof the value (numerical noise)"
                if sens["noise"] > 0
                else "not ranked: the same in every run",
                ha="center",
                va="center",
                transform=ax.transAxes,
            )
            ax.set_axis_off()
            continue
        ranking = list(reversed(sens["ranking"]))
        base = f * sens["baseline"]
        pos = np.arange(len(ranking))
        lows = f * np.array([r["low"] for r in ranking]) - base
        highs = f * np.array([r["high"] for r in ranking]) - base
        ax.barh(pos, lows, left=base, color="#dd8452", label="parameter low")
        ax.barh(pos, highs, left=base, color="#55a868", alpha=0.85, label="parameter high")
        ax.axvline(base, color="k", lw=1.0)
        ax.set_yticks(pos, [r["parameter"] for r in ranking])
        ax.set_xlabel(label)
        ax.set_title(f"sensitivity ({result.design})")
        ax.grid(alpha=0.3, axis="x")
        if k == 0:
            ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    figures.save(fig, path)
