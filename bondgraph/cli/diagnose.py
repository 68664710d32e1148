"""``bondgraph diagnose``: which effects does the model miss in measured data?"""

from __future__ import annotations

import json
import sys

from .registry import DATA_ARGS, MODEL_ARGS, PLOT_SUFFIXES, QUIET_ARG, arg, command, load, outputs, read_data


@command(
    "diagnose",
    "find the effects the model misses in measured data, extend it and measure the gain",
    MODEL_ARGS
    + DATA_ARGS
    + [
        arg("--json", action="store_true", help="print one JSON object (causes, gains, every candidate, equations)"),
        arg("--equations", action="store_true", help="end the readable report with the extended model's equations"),
        arg("--plot", metavar="FILE" + PLOT_SUFFIXES[0], help="measured vs calibrated vs extended, residuals"),
        arg(
            "--report",
            metavar="FILE.html",
            help="one self-contained HTML page: interactive plots (data, models, residuals, spectra against "
            "the noise floor), the chain with its gains, every candidate, the parameters with units",
        ),
        arg("--workers", type=int, default=2, help="parallel worker processes (default 2)"),
        arg("--no-chain", action="store_true", help="name one cause only (no compound effects)"),
        arg(
            "--drift",
            action="store_true",
            help="solve a linear sensor drift with the calibration and remove "
            "it before any effect is sought (thermal or sensor drift in the record)",
        ),
        QUIET_ARG,
    ],
)
def run(args):
    from ..diagnosis import diagnose, model_file_options
    from ..support.progress import Progress

    with outputs(args, "plot", "report") as out:  # checked before the work, written only if it all succeeds
        lm = load(args)
        data = read_data(args)
        with Progress("diagnosing", unit="candidates", mode="quiet" if args.quiet else "auto") as bar:
            report = diagnose(
                lm.model,
                data,
                **model_file_options(lm.module),
                input=args.model_input,
                output=args.model_output,
                validation=args.validation,
                workers=args.workers,
                chain=not args.no_chain,
                progress=bar,
                source=str(args.model),
                drift=True if args.drift else None,
            )
        if args.json:
            print(json.dumps(report.as_json()))
        else:
            sys.stdout.write(report.text(equations=args.equations, debug=getattr(args, "debug", False)))
        if args.plot:
            from ..plotting import plot_diagnosis

            with out.path(args.plot) as tmp:
                plot_diagnosis(report, tmp, lm.model)
        if args.report:
            from ..plotting.html_report import report_page

            with out.open(args.report) as fh:
                fh.write(report_page(report, lm.model))
