"""``bondgraph fit``: fit a model file's parameters to measured data (wraps
:func:`bondgraph.fit.fitting.fit_parameters`).

The report lists every fitted quantity with its unit: the parameters (± one standard error,
"linear" when solved exactly) and the output offset; then the RMS errors on the fitted and
the held-out part.  ``--out`` writes the fit file, which ``simulate``, ``diagnose`` and
``linearize`` read with ``--params-file`` (simulate adds the offset to the output).
"""

from __future__ import annotations

import json
import sys

from .registry import DATA_ARGS, MODEL_ARGS, PLOT_SUFFIXES, QUIET_ARG, arg, command, counter, load, outputs, read_data


@command(
    "fit",
    "fit parameters to measured data (least squares, uncertainty, held-out validation); --out "
    "writes a fit file for --params-file",
    MODEL_ARGS
    + DATA_ARGS
    + [
        arg("--params", metavar="A,B,...", help="parameters to fit (see 'bondgraph params MODEL')"),
        arg(
            "--split",
            choices=("blocks", "tail"),
            default="blocks",
            help="held-out part: interleaved blocks (default) or the last part",
        ),
        arg(
            "--loss",
            choices=("linear", "soft_l1", "huber", "cauchy"),
            default="linear",
            help="robust loss (scipy least_squares)",
        ),
        arg("--starts", type=int, default=1, help="multi-start count for non-convex fits (default 1)"),
        arg(
            "--out",
            metavar="FILE.json",
            help="write the fit file: every parameter value, the output offset, "
            "settings and scores (for --params-file)",
        ),
        arg("--plot", metavar="FILE" + PLOT_SUFFIXES[0], help="measured and fitted output, and the residual"),
        QUIET_ARG,
    ],
)
def run(args):
    from ..fit.fitting import CORRELATED, fit_parameters, residual_correlation

    with outputs(args, "out", "plot") as out:
        lm = load(args)
        data = read_data(args)
        names = [n.strip() for n in (args.params or "").split(",") if n.strip()]
        with counter("fitting", quiet=args.quiet) as bar:
            fit = fit_parameters(
                lm,
                data,
                names,
                input=args.model_input,
                output=args.model_output,
                validation=args.validation,
                split=args.split,
                loss=args.loss,
                starts=args.starts,
                progress=bar,
            )
        res = fit.result
        decl = lm.model.all_parameters()
        unit_y = fit.output_unit
        rows = []
        for n in res.values:
            sd = res.stderr.get(n)
            rows.append(
                (
                    n,
                    f"{res.values[n]:.6g}",
                    f"± {sd:.2g}" if sd else "",
                    decl[n].unit if n in decl else "",
                    "solved linearly" if n in fit.linear else "",
                )
            )
        rows.append((f"offset of {fit.output}", f"{res.offset:.6g}", "", unit_y, "measured = model output + offset"))
        widths = [max(len(r[i]) for r in rows) for i in range(4)]
        for r in rows:
            print(("  ".join(c.ljust(w) for c, w in zip(r[:4], widths)) + (f"  ({r[4]})" if r[4] else "")).rstrip())
        u = f" {unit_y}" if unit_y else ""
        print(f"rms error: fit {res.rms_fit:.4g}{u}, validation {res.rms_validation:.4g}{u} ({res.nfev} simulations)")
        rho = residual_correlation(data.column(args.model_output), res.prediction)
        if rho > CORRELATED and any(res.stderr.values()):
            print(
                f"note: the residual is correlated from sample to sample (lag-1 autocorrelation {rho:.2f}): "
                "the model misses something systematic, or the noise is far slower than the sampling; "
                f"the ± assume independent residuals and understate the error (about {((1 + rho) / (1 - rho)) ** 0.5:.0f}× "
                "for such a residual); bondgraph diagnose names what the model misses"
            )
        if args.out:
            with out.open(args.out, "w") as fh:
                json.dump(fit.as_json(str(args.model), str(args.data), args.input, args.output), fh, indent=1)
                fh.write("\n")
        if args.plot:
            from ..plotting import plot_fit

            with out.path(args.plot) as tmp:
                plot_fit(
                    data.t,
                    data.column(args.model_output),
                    res.prediction,
                    tmp,
                    fit.output,
                    unit_y,
                    title=f"{lm.model.name}: fit of {', '.join(res.values)}",
                )
    if not args.quiet:
        wrote = [p for p in (args.out, args.plot) if p]
        if wrote:
            print(f"wrote {', '.join(wrote)}", file=sys.stderr)
