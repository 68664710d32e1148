"""``bondgraph simulate``: simulate a model file and write the result as CSV (and a plot)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from ..errors import UsageError
from .registry import MODEL_ARGS, arg, command, load, progress


@command("simulate", "simulate the model and write the result as CSV (t, inputs, outputs; a PNG with --plot)",
         MODEL_ARGS + [
             arg("--input", metavar="NAME=SIGNAL", action="append", default=[],
                 help="drive an input: sine(amplitude=A, frequency=F, offset=O), step(...), ramp(...), "
                      "chirp(...), triangle(...), pwl(t:v, ...), csv(file=F, column=C), or a number"),
             arg("--t-end", type=float, help="end time (s); default from the model's EXPERIMENT"),
             arg("--dt", type=float, help="output sample interval (s)"),
             arg("--method", choices=("auto", "dopri5", "radau", "bdf", "lsoda")),
             arg("--rtol", type=float, help="relative tolerance (default 1e-6)"),
             arg("--atol", type=float, help="absolute tolerance floor (default 1e-20; the error is otherwise "
                                             "relative to each state's peak)"),
             arg("--out", metavar="FILE.csv", help="write the result CSV (default: stdout)"),
             arg("--plot", metavar="FILE.png", help="plot inputs and outputs (needs matplotlib)"),
             arg("--states", action="store_true", help="include the states in the CSV"),
             arg("--quiet", action="store_true", help="no progress or summary on stderr"),
         ])
def run(args):
    from ..data import write_csv
    from ..signals import parse_signal
    from ..simulate import Simulator

    lm = load(args)
    exp = lm.experiment
    inputs = dict(exp.inputs)
    for item in args.input:
        name, sep, spec = item.partition("=")
        if not sep:
            raise UsageError(f"bad --input {item!r}: expected NAME=SIGNAL, e.g. V='sine(amplitude=10, frequency=5)'")
        inputs[name.strip()] = parse_signal(spec, base_dir=str(Path(args.model).parent))
    t = exp.times(args.t_end, args.dt)
    started = time.time()
    sim = Simulator(lm.model)
    rtol = exp.rtol if args.rtol is None else args.rtol
    res = sim.run(t, inputs, method=args.method or exp.method, rtol=rtol,
                  atol=args.atol,
                  progress=progress("simulating") if not args.quiet else None)
    meta = {"model": str(args.model), "method": res.stats["method"], "rtol": str(rtol)}
    for name, sig in inputs.items():
        meta[f"input {name}"] = str(sig)
    for name, value in lm.model.values.items():
        meta[f"param {name}"] = repr(value)
    if args.out:
        write_csv(args.out, res.t, res.columns(args.states), meta)
    else:
        cols = res.columns(args.states)
        print("t," + ",".join(cols))
        for k in range(res.t.size):
            print(",".join(repr(float(v)) for v in [res.t[k], *(c[k] for c in cols.values())]))
    if args.plot:
        from ..plotting import plot_simulation
        plot_simulation(res, args.plot, title=lm.model.name)
    if not args.quiet:
        print(f"simulated {res.t[-1]:g} s of {lm.model.name} in {time.time() - started:.2f} s "
              f"({res.stats['method']}, {res.stats['steps']} steps)"
              + (f"; wrote {args.out}" if args.out else "") + (f", {args.plot}" if args.plot else ""),
              file=sys.stderr)
