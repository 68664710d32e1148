"""``bondgraph simulate``: simulate a model file and write the result as CSV (and a plot).

Time axis: ``--t-end``/``--dt``, else the model's EXPERIMENT.  With a measured input
(``--input V=csv(file=F, column=C)``) the run follows the data instead: it starts at the
data's first time stamp, ends at its last and samples at its time stamps (``--dt`` resamples);
a ``--t-end`` beyond the data's end is refused, because the input would be held constant
after it.  An output offset from a fit file (``--params-file``) is added to its output.
"""

from __future__ import annotations

import re
import sys
import time
from pathlib import Path

from ..support.errors import UsageError
from .registry import MODEL_ARGS, PLOT_SUFFIXES, QUIET_ARG, arg, command, load, module_constant, outputs, progress

_CSV_FILE = re.compile(r"^\s*csv\s*\(.*?\bfile\s*=\s*([^,)]+)", re.S)


@command(
    "simulate",
    "simulate the model; write t, inputs and outputs as CSV (stdout or --out) and a plot (--plot)",
    MODEL_ARGS
    + [
        arg(
            "--input",
            metavar="NAME=SIGNAL",
            action="append",
            default=[],
            help="drive an input: sine(amplitude=A, frequency=F, offset=O), step(...), ramp(...), "
            "chirp(...), triangle(...), pwl(t:v, ...), csv(file=F, column=C), or a number; "
            "with csv the run spans the data's time stamps",
        ),
        arg(
            "--t-end",
            type=float,
            help="end time (s); default from the model file's EXPERIMENT, or the end of a csv input",
        ),
        arg(
            "--dt",
            type=float,
            help="output sample interval (s); default from the EXPERIMENT, or the time stamps of a csv input",
        ),
        arg(
            "--method",
            choices=module_constant("bondgraph.numerics.simulate", "METHODS"),
            help="integration method (default from the EXPERIMENT, usually auto)",
        ),
        arg("--rtol", type=float, help="relative tolerance (default from the EXPERIMENT, 1e-6 unless set)"),
        arg(
            "--atol",
            type=float,
            help="absolute tolerance floor (default 1e-20; the error is otherwise relative to each state's peak)",
        ),
        arg("--out", metavar="FILE.csv", help="write the result CSV (default: stdout)"),
        arg(
            "--plot",
            metavar="FILE" + PLOT_SUFFIXES[0],
            help="plot the inputs and outputs that vary, with units, and the outputs against a drive "
            "that revisits its values (loops; needs matplotlib; .png, .pdf or .svg)",
        ),
        arg("--states", action="store_true", help="include the states in the CSV"),
        QUIET_ARG,
    ],
)
def run(args):
    started = time.time()  # the summary's time includes compiling (the first run's most of it)
    import numpy as np

    from ..data import write_csv
    from ..model.signals import parse_signal
    from ..numerics.checks import check_start
    from ..numerics.simulate import Simulator
    from ..numerics.steady import record_start

    csv_files = [m.group(1).strip() for m in map(_CSV_FILE.match, (i.partition("=")[2] for i in args.input)) if m]
    with outputs(args, "out", "plot", inputs=csv_files) as out:
        lm = load(args)
        exp = lm.experiment
        inputs, tables, given = dict(exp.inputs), {}, set()
        for item in args.input:
            name, sep, spec = item.partition("=")
            if not sep or not name.strip():
                raise UsageError(
                    f"bad --input {item!r}: expected NAME=SIGNAL, e.g. V='sine(amplitude=10, frequency=5)'"
                )
            name = name.strip()
            if name in given:
                raise UsageError(f"--input {name} given twice; give each input once")
            given.add(name)
            inputs[name] = parse_signal(spec, base_dir=str(Path(args.model).parent))
            if _CSV_FILE.match(spec):
                tables[name] = inputs[name]
        t = _times(args, exp, tables)
        sim = Simulator(lm.model)
        check_start(sim, inputs=inputs, t0=float(t[0]))
        rtol = exp.rtol if args.rtol is None else args.rtol
        notes = []
        x0 = None
        if tables:  # a measured drive: start as fit and diagnose do on its record (record.start)
            th = sim.theta()
            x0 = record_start(sim, th, inputs, float(t[0]))
            if not np.array_equal(x0, sim.initial_state(th)):
                notes.append("started at the steady state at the drive's first value (setting record.start)")
        with progress("simulating", quiet=args.quiet) as bar:
            ran = time.time()
            res = sim.run(t, inputs, x0=x0, method=args.method or exp.method, rtol=rtol, atol=args.atol, progress=bar)
            ran = time.time() - ran
        cols = res.columns(args.states)
        meta = {"model": str(args.model), "method": res.stats["method"], "rtol": str(rtol)}
        for name, sig in inputs.items():
            meta[f"input {name}"] = str(sig)
        for name, value in lm.model.values.items():
            meta[f"param {name}"] = repr(value)
        for name, offset in output_offsets(lm, res.outputs).items():
            cols[name] = cols[name] + offset
            meta[f"offset {name}"] = repr(offset)
            notes.append(f"{name} includes the output offset {offset:.4g} from {args.params_file}")
        if args.out:
            with out.path(args.out) as tmp, progress(f"writing {args.out}", quiet=args.quiet) as bar:
                write_csv(tmp, res.t, cols, meta, progress=bar)
        else:
            _print_csv(res.t, cols)
        if args.plot:
            from ..plotting import plot_signals

            units = {n: v.unit for n, v in lm.model.inputs.items()}
            units.update({n: v.unit for n, v in lm.model.outputs.items()})
            with out.path(args.plot) as tmp:
                signals = {n: cols[n] for n in [*res.inputs, *res.outputs]}
                plot_signals(res.t, signals, units, tmp, title=lm.model.name, inputs=list(res.inputs))
    if not args.quiet:
        wrote = [p for p in (args.out, args.plot) if p]
        total = time.time() - started
        print(
            f"simulated {res.t[-1] - res.t[0]:g} s of {lm.model.name} in {total:.2f} s "
            f"({res.stats['method']}{' on the tape interpreter' if sim.compiled.route == 'tape' else ''}, "
            f"{res.stats['steps']} steps in {ran:.2f} s"
            + ("" if res.stats["reason"] == "asked for" else f"; auto: {res.stats['reason']}")
            + ")"
            + (f"; wrote {', '.join(wrote)}" if wrote else "")
            + "".join(f"; {n}" for n in notes),
            file=sys.stderr,
        )


def _times(args, exp, tables):
    """Output times: the EXPERIMENT's (or --t-end/--dt), or those of the measured inputs."""
    import numpy as np

    if not tables:
        return exp.times(args.t_end, args.dt)
    name, sig = min(tables.items(), key=lambda kv: kv[1].table_t[-1])  # the one that ends first
    stamps = np.asarray(sig.table_t)
    start = max(s.table_t[0] for s in tables.values())
    end = float(stamps[-1])
    if start >= end:
        raise UsageError(
            f"the csv inputs do not overlap in time ({', '.join(tables)}); give inputs that cover a common time span"
        )
    if args.t_end is not None:
        if not (args.t_end > start):
            raise UsageError(f"--t-end {args.t_end:g} is not after the start of the input data of {name} ({start:g} s)")
        if args.t_end > end * (1 + 1e-9) + 1e-12:
            raise UsageError(
                f"--t-end {args.t_end:g} is beyond the end of the input data of {name} ({end:g} s): "
                f"the input would be held at its last value; shorten --t-end or extend the data"
            )
        end = args.t_end
    if args.dt is None:
        t = stamps[(stamps >= start) & (stamps <= end * (1 + 1e-12))]
        if t.size < 2:
            raise UsageError(f"the input data of {name} has fewer than 2 time stamps up to {end:g} s")
        return t
    if not (args.dt > 0) or (end - start) / args.dt > 5e7:
        raise UsageError(f"need 0 < --dt with at most 5e7 samples (got dt={args.dt})")
    n = int(np.floor((end - start) / args.dt * (1 + 1e-12)))
    return start + args.dt * np.arange(n + 1)


def output_offsets(lm, outputs) -> dict:
    """The fit file's output offsets, by output name (an unnamed one is the first of ``outputs``,
    the model's output names)."""
    out = {}
    for name, offset in lm.offsets.items():
        name = name if name is not None else next(iter(outputs), None)
        if name in outputs:
            out[name] = offset
        elif name is not None:
            raise UsageError(
                f"the parameter file's offset is for output {name!r}, which the model does not have "
                f"(outputs: {', '.join(outputs)})"
            )
    return out


def _print_csv(t, cols):
    """The CSV (header t,<columns>) on stdout, numbers written exactly (repr)."""
    import numpy as np

    table = np.column_stack([t, *cols.values()])
    fmt = ",".join(["%r"] * table.shape[1]) + "\n"
    write = sys.stdout.write
    write("t," + ",".join(cols) + "\n")
    for start in range(0, table.shape[0], 65536):
        block = table[start : start + 65536]
        write((fmt * len(block)) % tuple(block.ravel().tolist()))
