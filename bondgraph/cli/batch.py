"""``bondgraph batch``: many diagnoses, fits or simulations, sweeps and Monte Carlo runs on Dask
(wraps :mod:`bondgraph.batch`)."""
from __future__ import annotations

import json
import sys

from ..errors import UsageError
from .registry import DATA_ARGS, MODEL_ARGS, arg, command, load, progress, write_text

ACTIONS = ("diagnose", "fit", "simulate", "sweep")
_ONLY = {"--params": ("fit",), "--split": ("fit",), "--loss": ("fit",), "--starts": ("fit",),
         "--vary": ("sweep",), "--design": ("sweep",), "--draws": ("sweep",), "--seed": ("sweep",),
         "--summary": ("sweep",), "--plot": ("sweep",), "--json": ("sweep",),
         "--metric": ("simulate", "sweep"), "--t-end": ("simulate", "sweep"), "--dt": ("simulate", "sweep"),
         "--method": ("simulate", "sweep"), "--rtol": ("simulate", "sweep")}


@command("batch", "run many diagnoses, fits or simulations, or a parameter sweep / Monte Carlo study, on Dask "
                  "(a local cluster, or --scheduler ADDRESS); one table row per job",
         [arg("action", choices=ACTIONS, metavar="{diagnose,fit,simulate,sweep}",
              help="diagnose/fit/simulate each DATA file (× each --sets row); sweep: vary parameters (--vary)")]
         + MODEL_ARGS + [
             arg("data", metavar="DATA", nargs="*", help="data files (CSV: t, V, x)"),
             arg("--out", metavar="TABLE", help="write the table: .csv (header line first) or .parquet "
                                                "(needs pyarrow); default: CSV on stdout (diagnose/fit/simulate)"),
             arg("--scheduler", metavar="ADDRESS", help="run on an existing Dask cluster, e.g. tcp://head:8786 "
                                                        "(default: a local cluster started for this command)"),
             arg("--workers", type=int, help="worker processes of the local cluster (default: one per CPU core)"),
             arg("--sets", metavar="FILE.csv", help="parameter sets: a header of parameter names, one set per row"),
             arg("--input", metavar="COL|NAME=SIGNAL", action="append", default=[],
                 help="COL: the data column that drives the model; NAME=SIGNAL: a drive for runs without data "
                      "(as for 'bondgraph simulate', repeatable)"),
         ] + [a for a in DATA_ARGS if a[0][0] not in ("data", "--input")] + [
             arg("--params", metavar="A,B,...", help="(fit) parameters to fit"),
             arg("--split", choices=("blocks", "tail"), help="(fit) held-out part (default blocks)"),
             arg("--loss", choices=("linear", "soft_l1", "huber", "cauchy"), help="(fit) robust loss (default linear)"),
             arg("--starts", type=int, help="(fit) multi-start count (default 1)"),
             arg("--metric", metavar="SPEC", action="append", default=[],
                 help="(simulate, sweep) scalar output: peak(x), rms(x), mean(x), min(x), max(x), p2p(x), "
                      "final(x), steady(x), resonance[(k)] (Hz), damping[(k)]; repeatable"),
             arg("--t-end", type=float, help="(simulate, sweep) end time (s); default from the model's EXPERIMENT"),
             arg("--dt", type=float, help="(simulate, sweep) output sample interval (s)"),
             arg("--method", choices=("auto", "dopri5", "radau", "bdf", "lsoda"), help="(simulate, sweep) integrator"),
             arg("--rtol", type=float, help="(simulate, sweep) relative tolerance"),
             arg("--vary", metavar="NAME=SPEC", action="append", default=[],
                 help="(sweep) uniform(lo, hi), normal(mean, sd[, lo, hi]) (sd may be 5%%), loguniform(lo, hi), "
                      "linspace(lo, hi, n), logspace(lo, hi, n), values(a, b, ...); repeatable"),
             arg("--design", choices=("random", "lhs", "grid", "oat"),
                 help="(sweep) Monte Carlo, Latin hypercube, full grid, one-at-a-time (tornado); default: grid "
                      "if every --vary has levels, else random"),
             arg("--draws", type=int, help="(sweep) number of random / lhs draws"),
             arg("--seed", type=int, help="(sweep) random seed (the same seed gives the same draws)"),
             arg("--summary", metavar="FILE.json", help="(sweep) write statistics and sensitivities as JSON"),
             arg("--json", action="store_true", help="(sweep) print statistics and sensitivities as JSON"),
             arg("--plot", metavar="FILE.png", help="(sweep) histograms and tornado plots (needs matplotlib)"),
             arg("--quiet", action="store_true", help="no progress on stderr"),
         ])
def run(args):
    _check_options(args)
    load(args)  # the model file builds, and names its input and output where the options do not
    from ..batch import cluster

    cluster.require_dask()
    from .. import batch
    from ..parameters import parse_assignments, read_params_file

    params = dict(read_params_file(args.params_file)) if args.params_file else {}
    params.update(parse_assignments(args.set))
    column, signals = _inputs(args)
    common = dict(params=params, scheduler=args.scheduler, workers=args.workers,
                  progress=None if args.quiet else _progress(f"batch {args.action}"),
                  say=None if args.quiet else (lambda s: print(f"batch: {s}", file=sys.stderr, flush=True)))
    data_io = dict(input=args.model_input, output=args.model_output, data_input=column, data_output=args.output)
    sets = batch.read_sets(args.sets) if args.sets else None
    sim = dict(metrics=args.metric, inputs=signals, t_end=args.t_end, dt=args.dt, method=args.method, rtol=args.rtol)
    if args.action == "sweep":
        res = batch.sweep(args.model, batch.parse_space(args.vary), design=args.design, draws=args.draws,
                          seed=args.seed, input=args.model_input, output=args.model_output, **sim, **common)
        _finish(args, res.table)
        if args.json:
            print(json.dumps(res.as_json()))
        else:
            sys.stdout.write(res.text())
        if args.summary:
            write_text(args.summary, json.dumps(res.as_json(), indent=1) + "\n")
        if args.plot:
            res.plot(args.plot)
        return
    if args.action == "diagnose":
        table = batch.diagnose(args.model, args.data, sets=sets, validation=args.validation, **data_io, **common)
    elif args.action == "fit":
        names = [n.strip() for n in (args.params or "").split(",") if n.strip()]
        table = batch.fit(args.model, args.data, names, sets=sets, validation=args.validation,
                          split=args.split or "blocks", loss=args.loss or "linear", starts=args.starts or 1,
                          **data_io, **common)
    else:
        table = batch.simulate(args.model, args.data, sets=sets, **sim, **data_io, **common)
    _finish(args, table)


def _check_options(args):
    """Options that do not apply to the action, and missing data files, are usage errors."""
    given = {flag for flag in _ONLY if _is_set(args, flag)}
    for flag in sorted(given):
        if args.action not in _ONLY[flag]:
            raise UsageError(f"batch {args.action}: {flag} applies to batch {' / '.join(_ONLY[flag])} only")
    if args.action in ("diagnose", "fit") and not args.data:
        raise UsageError(f"batch {args.action}: give the data files, e.g. bondgraph batch {args.action} MODEL a.csv b.csv")
    if args.action == "sweep" and args.data:
        raise UsageError("batch sweep: takes no data files (use batch simulate to run on data)")


def _is_set(args, flag: str) -> bool:
    return getattr(args, flag.lstrip("-").replace("-", "_")) not in (None, False, [])


def _inputs(args):
    """(data column driving the model, {input: signal}) from the --input items."""
    from pathlib import Path

    from ..signals import parse_signal

    columns = [item for item in args.input if "=" not in item]
    if len(columns) > 1:
        raise UsageError(f"--input: one data column drives the model, got {', '.join(columns)}")
    if columns and not args.data:
        raise UsageError(f"--input {columns[0]}: a data column, but no data files are given; drive runs without "
                         f"data with --input NAME=SIGNAL, e.g. --input 'V=sine(amplitude=50, frequency=5)'")
    if len(columns) < len(args.input) and args.action in ("diagnose", "fit"):
        raise UsageError(f"batch {args.action}: the data drive the model; --input NAME=SIGNAL is for batch "
                         f"simulate and sweep")
    signals = {}
    for item in args.input:
        if "=" in item:
            name, _, spec = item.partition("=")
            signals[name.strip()] = parse_signal(spec, base_dir=str(Path(args.model).parent))
    return (columns[0] if columns else None), signals


def _progress(label: str):
    report = progress(label)
    return lambda done, total: report(done / total)


def _finish(args, table):
    """Write the table (or print it when no --out) and say how many jobs failed."""
    if args.out:
        table.write(args.out)
    elif args.action != "sweep":
        write_text(None, table.csv_text())
    failed = len(table.failed)
    if not args.quiet or failed:
        print(f"batch {args.action}: {len(table)} jobs, {failed} failed"
              + (" (see the error column)" if failed else "") + (f"; wrote {args.out}" if args.out else ""),
              file=sys.stderr)

