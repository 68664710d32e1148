"""``bondgraph diagnose``: which effect does the model miss in measured data?"""
from __future__ import annotations

import json
import sys

from .registry import DATA_ARGS, MODEL_ARGS, arg, command, load, outputs, read_data


@command("diagnose", "find the effect the model misses in measured data, extend it and measure the gain",
         MODEL_ARGS + DATA_ARGS + [
             arg("--json", action="store_true", help="print one JSON object (cause, gain, RMS, every candidate)"),
             arg("--plot", metavar="FILE.png", help="measured vs baseline vs extended, residuals"),
             arg("--workers", type=int, default=2, help="parallel worker processes (default 2)"),
             arg("--quiet", action="store_true", help="no progress on stderr"),
         ])
def run(args):
    from ..diagnose import calibration_names, diagnose, load_candidates

    with outputs(args, "plot") as out:  # checked before the work, written only if it all succeeds
        lm = load(args)
        data = read_data(args)
        say = (lambda s: None) if args.quiet else (lambda s: print(f"diagnose: {s}", file=sys.stderr, flush=True))
        report = diagnose(lm.model, data, calibration_names(lm.module, lm.model), load_candidates(),
                          args.model_input, args.model_output, validation=args.validation,
                          workers=args.workers, progress=say, source=str(args.model))
        if args.json:
            print(json.dumps(report.as_json()))
        else:
            sys.stdout.write(report.text())
        if args.plot:
            from ..plotting import plot_diagnosis
            with out.path(args.plot) as tmp:
                plot_diagnosis(report, data, args.model_input, args.model_output, tmp)
