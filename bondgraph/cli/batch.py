"""``bondgraph batch``: many diagnoses, fits or simulations, sweeps and Monte Carlo runs on Dask
(wraps :mod:`bondgraph.batch`)."""

from __future__ import annotations

import json
import sys

from ..support.errors import UsageError
from .registry import DATA_ARGS, MODEL_ARGS, PLOT_SUFFIXES, arg, command, module_constant, outputs, write_text

ACTIONS = ("diagnose", "fit", "simulate", "sweep")
_ONLY = {
    "--params": ("fit",),
    "--split": ("fit",),
    "--loss": ("fit",),
    "--starts": ("fit",),
    "--vary": ("sweep",),
    "--design": ("sweep",),
    "--draws": ("sweep",),
    "--seed": ("sweep",),
    "--summary": ("sweep",),
    "--plot": ("sweep",),
    "--json": ("sweep",),
    "--metric": ("simulate", "sweep"),
    "--t-end": ("simulate", "sweep"),
    "--dt": ("simulate", "sweep"),
    "--method": ("simulate", "sweep"),
    "--rtol": ("simulate", "sweep"),
}


@command(
    "batch",
    "run many diagnoses, fits or simulations, or a parameter sweep / Monte Carlo study, on Dask "
    "(a local cluster, or --scheduler ADDRESS); one table row per job",
    [
        arg(
            "action",
            choices=ACTIONS,
            metavar="{diagnose,fit,simulate,sweep}",
            help="diagnose/fit/simulate each DATA file (× each --sets row); sweep: vary parameters (--vary)",
        )
    ]
    + MODEL_ARGS
    + [
        arg("data", metavar="DATA", nargs="*", help="data files (CSV: t, V, x)"),
        arg(
            "--out",
            metavar="TABLE",
            help="write the table: .csv (header line first) or .parquet "
            "(needs pyarrow); default: CSV on stdout (diagnose/fit/simulate)",
        ),
        arg(
            "--scheduler",
            metavar="ADDRESS",
            help="run on an existing Dask cluster, e.g. tcp://head:8786 "
            "(default: a local cluster started for this command)",
        ),
        arg("--workers", type=int, help="worker processes of the local cluster (default: one per CPU core)"),
        arg("--sets", metavar="FILE.csv", help="parameter sets: a header of parameter names, one set per row"),
        arg(
            "--input",
            metavar="COL|NAME=SIGNAL",
            action="append",
            default=[],
            help="COL: the data column that drives the model; NAME=SIGNAL: a drive for runs without data "
            "(as for 'bondgraph simulate', repeatable)",
        ),
    ]
    + [a for a in DATA_ARGS if a[0][0] not in ("data", "--input")]
    + [
        arg("--params", metavar="A,B,...", help="(fit) parameters to fit"),
        arg("--split", choices=("blocks", "tail"), help="(fit) held-out part (default blocks)"),
        arg("--loss", choices=("linear", "soft_l1", "huber", "cauchy"), help="(fit) robust loss (default linear)"),
        arg("--starts", type=int, help="(fit) multi-start count (default 1)"),
        arg(
            "--metric",
            metavar="SPEC",
            action="append",
            default=[],
            help="(simulate, sweep) scalar output: peak(x), rms(x), mean(x), min(x), max(x), p2p(x), "
            "final(x), steady(x), resonance[(k)] (Hz), damping[(k)]; repeatable",
        ),
        arg("--t-end", type=float, help="(simulate, sweep) end time (s); default from the model's EXPERIMENT"),
        arg("--dt", type=float, help="(simulate, sweep) output sample interval (s)"),
        arg(
            "--method",
            choices=module_constant("bondgraph.numerics.simulate", "METHODS"),
            help="(simulate, sweep) integrator",
        ),
        arg("--rtol", type=float, help="(simulate, sweep) relative tolerance"),
        arg(
            "--vary",
            metavar="NAME=SPEC",
            action="append",
            default=[],
            help="(sweep) uniform(lo, hi), normal(mean, sd[, lo, hi]) (sd may be 5%%), loguniform(lo, hi), "
            "linspace(lo, hi, n), logspace(lo, hi, n), values(a, b, ...); repeatable",
        ),
        arg(
            "--design",
            choices=("random", "lhs", "grid", "oat"),
            help="(sweep) Monte Carlo, Latin hypercube, full grid, one-at-a-time (tornado); default: grid "
            "if every --vary has levels, else random",
        ),
        arg("--draws", type=int, help="(sweep) number of random / lhs draws"),
        arg("--seed", type=int, help="(sweep) random seed (the same seed gives the same draws)"),
        arg("--summary", metavar="FILE.json", help="(sweep) write statistics and sensitivities as JSON"),
        arg("--json", action="store_true", help="(sweep) print statistics and sensitivities as JSON"),
        arg(
            "--plot",
            metavar="FILE" + PLOT_SUFFIXES[0],
            help="(sweep) histograms and tornado plots (needs matplotlib; .png, .pdf or .svg)",
        ),
        arg("--quiet", action="store_true", help="no progress on stderr"),
    ],
)
def run(args):
    _check_options(args)
    from ..batch import cluster

    cluster.require_dask()
    from .. import batch
    from ..model.parameters import parse_assignments, read_params_file
    from ..support.progress import Progress

    params = dict(read_params_file(args.params_file)) if args.params_file else {}
    params.update(parse_assignments(args.set))
    column, signals = _inputs(args)
    sets = batch.read_sets(args.sets) if args.sets else None
    bar = Progress(f"batch {args.action}", unit="jobs", mode="quiet" if args.quiet else "auto")

    def report(done: int, total: int):
        bar.total = total
        bar.update(done)

    common = dict(params=params, scheduler=args.scheduler, workers=args.workers, progress=report, say=bar.note)
    data_io = dict(input=args.model_input, output=args.model_output, data_input=column, data_output=args.output)
    sim = dict(metrics=args.metric, inputs=signals, t_end=args.t_end, dt=args.dt, method=args.method, rtol=args.rtol)
    with outputs(args, "out", "plot", "summary", inputs=[args.sets]) as out, bar:
        if args.action == "sweep":
            res = batch.sweep(
                args.model,
                batch.parse_space(args.vary),
                design=args.design,
                draws=args.draws,
                seed=args.seed,
                input=args.model_input,
                output=args.model_output,
                **sim,
                **common,
            )
            table = res.table
        elif args.action == "diagnose":
            table = batch.diagnose(args.model, args.data, sets=sets, validation=args.validation, **data_io, **common)
        elif args.action == "fit":
            names = [n.strip() for n in (args.params or "").split(",") if n.strip()]
            table = batch.fit(
                args.model,
                args.data,
                names,
                sets=sets,
                validation=args.validation,
                split=args.split or "blocks",
                loss=args.loss or "linear",
                starts=args.starts or 1,
                **data_io,
                **common,
            )
        else:
            table = batch.simulate(args.model, args.data, sets=sets, **sim, **data_io, **common)
        bar.close(f"{len(table)} jobs, {len(table.failed)} failed")
        if args.out:
            with out.path(args.out) as tmp:
                table.write(tmp)
        if args.action != "sweep":
            if not args.out:
                write_text(None, table.csv_text())
        else:
            summary = json.dumps(res.as_json(), indent=None if args.json else 1)
            sys.stdout.write(summary + "\n" if args.json else res.text())
            if args.summary:
                write_text(args.summary, summary + "\n", out)
            if args.plot:
                with out.path(args.plot) as tmp:
                    res.plot(tmp)
    failed = len(table.failed)
    if failed or not args.quiet:
        wrote = [p for p in (args.out, args.summary, args.plot) if p]
        print(
            f"batch {args.action}: {len(table)} jobs, {failed} failed"
            + (" (see the error column)" if failed else "")
            + (f"; wrote {', '.join(wrote)}" if wrote else ""),
            file=sys.stderr,
        )


def _check_options(args):
    """Options that do not apply to the action, and missing data files, are usage errors."""
    given = {flag for flag in _ONLY if _is_set(args, flag)}
    for flag in sorted(given):
        if args.action not in _ONLY[flag]:
            raise UsageError(f"batch {args.action}: {flag} applies to batch {' / '.join(_ONLY[flag])} only")
    if args.action in ("diagnose", "fit") and not args.data:
        raise UsageError(
            f"batch {args.action}: give the data files, e.g. bondgraph batch {args.action} MODEL a.csv b.csv"
        )
    if args.out and not args.out.lower().endswith((".csv", ".parquet")):
        raise UsageError(f"--out {args.out}: the table is written as .csv or .parquet; name the file so")
    if args.action == "sweep" and args.data:
        raise UsageError("batch sweep: takes no data files (use batch simulate to run on data)")


def _is_set(args, flag: str) -> bool:
    return getattr(args, flag.lstrip("-").replace("-", "_")) not in (None, False, [])


def _inputs(args):
    """(data column driving the model, {input: signal}) from the --input items."""
    from pathlib import Path

    from ..model.signals import parse_signal

    columns = [item for item in args.input if "=" not in item]
    if len(columns) > 1:
        raise UsageError(f"--input: one data column drives the model, got {', '.join(columns)}")
    if columns and not args.data:
        raise UsageError(
            f"--input {columns[0]}: a data column, but no data files are given; drive runs without "
            f"data with --input NAME=SIGNAL, e.g. --input 'V=sine(amplitude=50, frequency=5)'"
        )
    if len(columns) < len(args.input) and args.action in ("diagnose", "fit"):
        raise UsageError(
            f"batch {args.action}: the data drive the model; --input NAME=SIGNAL is for batch simulate and sweep"
        )
    signals = {}
    for item in args.input:
        if "=" in item:
            name, _, spec = item.partition("=")
            signals[name.strip()] = parse_signal(spec, base_dir=str(Path(args.model).parent))
    return (columns[0] if columns else None), signals
