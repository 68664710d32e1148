"""``bondgraph compensate``: the feedforward drive that makes a model follow a desired output
(wraps :func:`bondgraph.fit.compensate.feedforward`)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from ..support.errors import UsageError
from .registry import MODEL_ARGS, PLOT_SUFFIXES, arg, command, counter, load, outputs


@command(
    "compensate",
    "feedforward drive that makes the model's output follow a desired trajectory "
    "(hysteresis inverted), with the predicted tracking error with and without compensation",
    MODEL_ARGS
    + [
        arg("reference", metavar="REFERENCE", help="desired trajectory (CSV with t and the output column)"),
        arg("--column", metavar="COL", help="reference column (default: the model output name)"),
        arg("--model-input", metavar="NAME", help="model input to compute (default: the model's first input)"),
        arg("--model-output", metavar="NAME", help="model output to follow (default: the model's first output)"),
        arg(
            "--input",
            metavar="NAME=SIGNAL",
            action="append",
            default=[],
            help="drive another model input during the run, as for simulate (default 0)",
        ),
        arg(
            "--iterations",
            type=int,
            default=10,
            help="at most this many model simulations refining the drive (default 10)",
        ),
        arg(
            "--tol",
            type=float,
            default=1e-4,
            help="stop when the largest error is below this fraction of the reference's range",
        ),
        arg(
            "--out",
            metavar="FILE.csv",
            help="write t, the compensated drive, the reference, the "
            "predicted output, the linear-inverse drive and its predicted output (default: stdout)",
        ),
        arg(
            "--drive-range",
            metavar="LO,HI",
            help="the drive the device accepts, e.g. 0,120 for a unipolar 120 V amplifier, --drive-range=-30,150 for a negative end (default: the "
            "range the model file declares for the input, if any); a drive beyond it is clipped, with a note",
        ),
        arg("--plot", metavar="FILE" + PLOT_SUFFIXES[0], help="plot reference, predicted outputs and drives"),
        arg("--json", action="store_true", help="print the summary as JSON on stdout"),
        arg("--quiet", action="store_true", help="no progress or summary on stderr"),
    ],
)
def run(args):
    from ..data import read_csv, write_csv
    from ..fit.compensate import feedforward
    from ..model.signals import parse_signal

    if args.iterations < 1:
        raise UsageError(f"--iterations must be at least 1, got {args.iterations}")
    if not 0.0 < args.tol < 1.0:
        raise UsageError(f"--tol must be between 0 and 1, got {args.tol}")
    drive_range = _drive_range(args.drive_range)
    with outputs(args, "out", "plot", inputs=[args.reference]) as out:  # checked before the work
        lm = load(args)
        col = args.column or args.model_output
        ref = read_csv(args.reference, required=("t", col))
        others = {}
        for item in args.input:
            name, sep, spec = item.partition("=")
            if not sep:
                raise UsageError(f"bad --input {item!r}: expected NAME=SIGNAL, e.g. F=0")
            others[name.strip()] = parse_signal(spec, base_dir=str(Path(args.model).parent))
        # a fit file's sensor zero: the model follows reference - offset (measured = model + offset)
        offset = lm.offsets.get(args.model_output, lm.offsets.get(None, 0.0))
        res = feedforward(
            lm.model,
            ref.t,
            ref.columns[col] - offset,
            input=args.model_input,
            output=args.model_output,
            inputs=others,
            iterations=args.iterations,
            tol=args.tol,
            progress=None if args.quiet else counter("compensating"),
            drive_range=drive_range,
        )
        u, y = args.model_input, args.model_output
        columns = {
            u: res.drive,
            f"{y}_ref": res.reference + offset,
            f"{y}_pred": res.predicted + offset,
            f"{u}_linear": res.linear_drive,
            f"{y}_pred_linear": res.linear_predicted + offset,
        }
        summary = res.summary()
        meta = {
            "model": str(args.model),
            "reference": str(args.reference),
            "method": summary["method"],
            "max_error": repr(summary["max_error"]),
            "max_error_uncompensated": repr(summary["max_error_uncompensated"]),
        }
        if args.out:
            with out.path(args.out) as tmp:
                write_csv(tmp, res.t, columns, meta)
        elif not args.json:
            print("t," + ",".join(columns))
            for k in range(res.t.size):
                print(",".join(repr(float(v)) for v in [res.t[k], *(c[k] for c in columns.values())]))
        if args.plot:
            with out.path(args.plot) as tmp:
                unit = {n: s.unit for n, s in {**lm.model.inputs, **lm.model.outputs}.items()}
                _plot(res, tmp, (u, unit.get(u, "")), (y, unit.get(y, "")), lm.model.name)
    if args.json:
        print(json.dumps(summary, indent=1))
    for note in res.notes:  # said even with --quiet: the drive is not what the numbers suggest
        print(f"bondgraph: note: {note}", file=sys.stderr)
    if not args.quiet:
        print(
            f"{summary['method']}: largest tracking error {summary['max_error']:.4g} "
            f"({100 * summary['relative_error']:.3g} % of the reference's range) with compensation, "
            f"{summary['max_error_uncompensated']:.4g} ({100 * summary['relative_error_uncompensated']:.3g} %) "
            f"with the linear inverse: {summary['improvement']:.3g}x less"
            + (f"; wrote {args.out}" if args.out else "")
            + (f", {args.plot}" if args.plot else ""),
            file=sys.stderr,
        )


def _drive_range(text: str | None) -> tuple[float, float] | None:
    """``--drive-range LO,HI`` as (lo, hi), or None."""
    if text is None:
        return None
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise UsageError(f"--drive-range {text!r}: give the lowest and highest drive as LO,HI, e.g. 0,120") from None
    if not lo < hi:
        raise UsageError(f"--drive-range {text!r}: the lowest drive must be below the highest")
    return lo, hi


def _plot(res, path: str, u: tuple[str, str], y: tuple[str, str], title: str) -> None:
    """Reference and predicted outputs, their tracking errors and the drives against time;
    ``u`` and ``y`` are (name, unit) of the drive and the output."""
    from ..plotting import figures

    plt = figures.pyplot()
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    label, f = figures.scaled_label(y[0], y[1], res.reference, res.predicted, res.linear_predicted)
    a1.plot(res.t, f * res.reference, "k", lw=1.6, label="reference")
    a1.plot(res.t, f * res.linear_predicted, lw=1.0, label="linear inverse")
    a1.plot(res.t, f * res.predicted, "--", lw=1.0, label="compensated")
    a1.set_ylabel(label)
    a1.legend(fontsize=8)
    errors = [res.linear_predicted - res.reference, res.predicted - res.reference]
    label, f = figures.scaled_label(f"{y[0]} error", y[1], *errors)
    a2.plot(res.t, f * errors[0], lw=1.0, label="linear inverse")
    a2.plot(res.t, f * errors[1], lw=1.0, label="compensated")
    a2.set_ylabel(label)
    a2.legend(fontsize=8)
    figures.residual_scale(a2, res.t, [f * e for e in errors])
    label, f = figures.scaled_label(u[0], u[1], res.linear_drive, res.drive)
    a3.plot(res.t, f * res.linear_drive, lw=1.0, label="linear inverse")
    a3.plot(res.t, f * res.drive, lw=1.0, label="compensated")
    a3.set_ylabel(label)
    a3.set_xlabel("t (s)")
    a3.legend(fontsize=8)
    for a in (a1, a2, a3):
        a.grid(alpha=0.3)
    a1.set_title(f"{title}: feedforward compensation")
    figures.save(fig, path)
