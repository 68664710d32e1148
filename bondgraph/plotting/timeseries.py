"""Signals against time (and against a periodic drive: loops), fits and Bode diagrams.

Axes carry the quantity and its unit (taken from the model's declared inputs and outputs,
SI-prefixed to suit the data: µm rather than 0.0001 m);
signals that never change are left out (and listed in the title); curves that share a unit
share a panel, with a legend.
"""

from __future__ import annotations

import numpy as np

from . import figures


def plot_signals(t, signals: dict, units: dict, path: str, title: str = "", inputs=()) -> None:
    """Signals against time, one panel per unit: signals that share a unit share the panel
    (with a legend), the y axis says the unit; signals that never change are left out and
    listed in the title.  When one of ``inputs`` comes back over its values (a periodic or
    reversing drive, :func:`~bondgraph.plotting.figures.revisits`), every other signal is
    also drawn against it, in a second column beside its time panel: the loop of a
    hysteretic output, with units on both axes.

    Parameters
    ----------
    t : array_like
        Sample times, s.
    signals : dict of str to array_like
        Signal name → samples at ``t``.
    units : dict of str to str
        Signal name → unit text (a signal without one gets a panel of its own).
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).
    title : str, optional
        The figure's title.
    inputs : sequence of str, optional
        The names among ``signals`` that are drives: the first that revisits its values is
        the loops' x axis (no loops without one).

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = figures.pyplot()
    panels: dict = {}
    constant = []
    for name, y in signals.items():
        if not figures.varies(y):
            constant.append(
                f"{name} = {float(np.asarray(y)[0]):.4g}" + (f" {units.get(name)}" if units.get(name) else "")
            )
            continue
        unit = units.get(name, "")
        panels.setdefault(unit if unit else ("", name), []).append(name)  # unitless: a panel each
    drive = next((n for n in inputs if n in signals and figures.revisits(signals[n])), None)
    n = max(len(panels), 1)
    if drive is None:
        fig, axes = plt.subplots(n, 1, figsize=(8, 1.9 * n + 0.8), sharex=True, squeeze=False)
    else:
        fig, axes = plt.subplots(
            n, 2, figsize=(11.5, 2.1 * n + 0.8), sharex="col", squeeze=False, gridspec_kw={"width_ratios": [2.2, 1]}
        )
    labels = {}
    for ax, (key, names) in zip(axes[:, 0], panels.items()):
        factor, unit = figures.si_scale(units.get(names[0], ""), *(signals[n] for n in names))
        for name in names:
            ax.plot(*figures.envelope(np.asarray(t), factor * np.asarray(signals[name], float)), lw=1.0, label=name)
        joined = ", ".join(names)
        labels[key] = (
            factor,
            figures.axis_label(joined if len(joined) <= 24 else "", unit).strip() if unit else joined,
        )
        ax.set_ylabel(labels[key][1])
        if len(names) > 1:
            ax.legend(fontsize=8, loc="best")
        ax.grid(alpha=0.3)
    if not panels:
        axes[0, 0].text(0.5, 0.5, "every signal is constant", ha="center", va="center", transform=axes[0, 0].transAxes)
    axes[-1, 0].set_xlabel("t (s)")
    if drive is not None:
        _loops(axes[:, 1], panels, labels, signals, units, drive)
    head = title + (": " if title and constant else "") + ("constant " + ", ".join(constant) if constant else "")
    if head:
        axes[0, 0].set_title(head, fontsize=9)
    figures.save(fig, path)


def _loops(axes, panels: dict, labels: dict, signals: dict, units: dict, drive: str, limit: int = 20000) -> None:
    """Beside each time panel, its signals (but ``drive``) against ``drive``: the loops; at
    most about ``limit`` points each (evenly thinned); a panel of drives only stays empty."""
    u = np.asarray(signals[drive], float)
    step = max(1, int(np.ceil(u.size / limit)))
    xlabel, xf = figures.scaled_label(drive, units.get(drive, ""), u)
    drawn = []
    for ax, (key, names) in zip(axes, panels.items()):
        others = [n for n in names if n != drive]
        if not others:
            ax.set_axis_off()
            continue
        factor, label = labels[key]
        for name in others:
            ax.plot(xf * u[::step], factor * np.asarray(signals[name], float)[::step], lw=0.8, label=name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
        drawn.append(ax)
    for ax in drawn:  # the column shares its x axis: the drive, labelled under the lowest loop
        ax.tick_params(labelbottom=ax is drawn[-1])
    if drawn:
        drawn[-1].set_xlabel(xlabel)
        drawn[0].set_title(f"against {drive}", fontsize=9)


def plot_simulation(res, path: str, title: str = "", units: dict | None = None, columns: dict | None = None) -> None:
    """Inputs and outputs of a :class:`~bondgraph.numerics.simulate.SimResult` against time,
    and against a drive that revisits its values (see :func:`plot_signals`); ``units`` name → unit (e.g. from the model's inputs and outputs),
    ``columns`` replaces the result's signals (e.g. outputs with a fit's offset added).

    Parameters
    ----------
    res : SimResult
        The simulation result (its ``t``, inputs and outputs are drawn).
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).
    title : str, optional
        The figure's title.
    units : dict of str to str, optional
        Signal name → unit text.
    columns : dict of str to array_like, optional
        Signals to draw instead of the result's inputs and outputs, sampled at ``res.t``.

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    signals = columns if columns is not None else {**res.inputs, **res.outputs}
    plot_signals(res.t, signals, units or {}, path, title, inputs=list(res.inputs))


def plot_fit(t, measured, fitted, path: str, name: str = "y", unit: str = "", title: str = "") -> None:
    """Measured and fitted output (offset included) on one panel, the residual below (its
    scale set after the start-up transient, :func:`~bondgraph.plotting.figures.residual_scale`).

    Parameters
    ----------
    t : array_like
        Sample times, s.
    measured : array_like
        The measured output at ``t``.
    fitted : array_like
        The fitted model's output at ``t``, same unit; the residual drawn is measured − fitted.
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).
    name : str, optional
        The output's name (y axis).
    unit : str, optional
        The output's unit (shown SI-prefixed to suit the data).
    title : str, optional
        The figure's title.

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = figures.pyplot()
    t, measured, fitted = (np.asarray(v, float) for v in (t, measured, fitted))
    residual = measured - fitted
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    label, f = figures.scaled_label(name, unit, measured, fitted)
    a1.plot(*figures.envelope(t, f * measured), lw=0.8, label="measured")
    a1.plot(*figures.envelope(t, f * fitted), lw=0.8, label="fitted model")
    a1.set_ylabel(label)
    a1.legend(fontsize=8, loc="best")
    label, f = figures.scaled_label(f"{name} residual", unit, residual)
    a2.plot(*figures.envelope(t, f * residual), lw=0.6, color="tab:red")
    a2.set_ylabel(label)
    figures.residual_scale(a2, t, [f * residual])
    a2.set_xlabel("t (s)")
    for a in (a1, a2):
        a.grid(alpha=0.3)
    if title:
        a1.set_title(title, fontsize=9)
    figures.save(fig, path)


def plot_bode(
    w, H, path: str, title: str = "", input: tuple[str, str] = ("u", ""), output: tuple[str, str] = ("y", "")
) -> None:
    """Magnitude and phase of the frequency response H(jω) of ``output`` to ``input``
    (each a (name, unit) pair; the magnitude's unit is theirs divided).

    Parameters
    ----------
    w : array_like
        Angular frequencies, rad/s (log axis).
    H : array_like
        Complex H(jω) at ``w``, output unit per input unit; the phase is drawn unwrapped, in
        degrees.
    path : str or path-like
        The image to write (png, pdf or svg; written atomically).
    title : str, optional
        The figure's title.
    input : tuple of (str, str), optional
        The input's name and unit.
    output : tuple of (str, str), optional
        The output's name and unit.

    Raises
    ------
    UsageError
        matplotlib is not installed.
    """
    plt = figures.pyplot()
    (u, uu), (y, yu) = input, output
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    a1.loglog(w, np.abs(H))
    unit = f"{yu or '1'}/{uu}" if uu else yu
    a1.set_ylabel(figures.axis_label(f"|{y}/{u}|", unit))
    a2.semilogx(w, np.degrees(np.unwrap(np.angle(H))))
    a2.set_ylabel("phase (deg)")
    a2.set_xlabel("ω (rad/s)")
    for a in (a1, a2):
        a.grid(alpha=0.3, which="both")
    if title:
        a1.set_title(title)
    figures.save(fig, path)
