"""``bondgraph fit``: fit a model file's parameters to measured data (wraps
:func:`bondgraph.fitting.fit_parameters`)."""
from __future__ import annotations

import json
import sys

from .registry import DATA_ARGS, MODEL_ARGS, arg, command, counter, load, read_data


@command("fit", "fit parameters to measured data (least squares, uncertainty, validation split)",
         MODEL_ARGS + DATA_ARGS + [
             arg("--params", metavar="A,B,...", help="parameters to fit"),
             arg("--split", choices=("blocks", "tail"), default="blocks",
                 help="held-out part: interleaved blocks (default) or the last part"),
             arg("--loss", choices=("linear", "soft_l1", "huber", "cauchy"), default="linear",
                 help="robust loss (scipy least_squares)"),
             arg("--starts", type=int, default=1, help="multi-start count for non-convex fits"),
             arg("--out", metavar="FILE.json", help="write the fitted parameters (for --params-file)"),
         ])
def run(args):
    from ..atomic import atomic_write
    from ..fitting import fit_parameters

    lm = load(args)
    data = read_data(args)
    names = [n.strip() for n in (args.params or "").split(",") if n.strip()]
    fit = fit_parameters(lm, data, names, input=args.model_input, output=args.model_output,
                         validation=args.validation, split=args.split, loss=args.loss, starts=args.starts,
                         progress=counter("fitting"))
    res = fit.result
    for n in names:
        sd = res.stderr.get(n)
        print(f"{n:<14} = {res.values[n]:.6g}" + (f" ± {sd:.2g}" if sd else "")
              + ("  (linear)" if n in fit.linear else ""))
    print(f"rms: fit {res.rms_fit:.4g}, validation {res.rms_validation:.4g} ({res.nfev} simulations)")
    if args.out:
        with atomic_write(args.out, "w", encoding="utf-8") as fh:
            json.dump(fit.as_json(str(args.model), str(args.data)), fh, indent=1)
        print(f"wrote {args.out}", file=sys.stderr)
