"""``bondgraph diagnose``: which effects does the model miss in measured data?"""
from __future__ import annotations

import json
import sys

from .registry import DATA_ARGS, MODEL_ARGS, arg, command, load, read_data


@command("diagnose", "find the effects the model misses in measured data, extend it and measure the gain",
         MODEL_ARGS + DATA_ARGS + [
             arg("--json", action="store_true", help="print one JSON object (causes, gains, every candidate)"),
             arg("--plot", metavar="FILE.png", help="measured vs calibrated vs extended, residuals"),
             arg("--workers", type=int, default=2, help="parallel worker processes (default 2)"),
             arg("--no-chain", action="store_true", help="name one cause only (no compound effects)"),
             arg("--quiet", action="store_true", help="no progress on stderr"),
         ])
def run(args):
    from ..diagnosis import diagnose
    from ..diagnosis.calibration import patterns

    lm = load(args)
    data = read_data(args)
    say = (lambda s: None) if args.quiet else (lambda s: print(f"diagnose: {s}", file=sys.stderr, flush=True))
    report = diagnose(lm.model, data, calibrate_first=getattr(lm.module, "CALIBRATE", None),
                      input=args.model_input, output=args.model_output, validation=args.validation,
                      workers=args.workers, chain=not args.no_chain, progress=say, source=str(args.model))
    if args.json:
        print(json.dumps(report.as_json()))
    else:
        sys.stdout.write(report.text())
    if args.plot:
        from ..plotting import plot_diagnosis
        plot_diagnosis(report, args.plot)
