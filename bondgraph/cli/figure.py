"""``bondgraph figure``: draw a figure that the model file declares itself.

A model file may define ``FIGURES = {"name": function, ...}``; each function takes ``load``,
``load(**overrides)`` returning the model file built with the command line's ``--set`` and
``--params-file`` values updated by ``overrides`` (a :class:`~bondgraph.model.modelfile.LoadedModel`),
and returns a :class:`bondgraph.plotting.panels.Figure`. The first line of its docstring is the
figure's description. Without a NAME the command lists the file's figures.
"""

from __future__ import annotations

import json
import sys

from ..support.errors import ModelError, UsageError, did_you_mean
from .registry import MODEL_ARGS, PLOT_SUFFIXES, arg, command, load, outputs


@command(
    "figure",
    "draw a figure the model file declares (FIGURES), e.g. a paper's figure; without NAME, list them",
    MODEL_ARGS
    + [
        arg("name", metavar="NAME", nargs="?", help="figure name (see 'bondgraph figure MODEL')"),
        arg("--plot", metavar="FILE" + PLOT_SUFFIXES[0], help="write the figure"),
        arg("--json", action="store_true", help="print the numbers the figure shows as JSON on stdout"),
        arg("--quiet", action="store_true", help="no summary on stderr"),
    ],
)
def run(args):
    from ..model.modelfile import load_model, read_model_module
    from ..model.parameters import parse_assignments, read_fit_file
    from ..plotting.panels import Figure, render

    module, _ = read_model_module(args.model)
    figures = getattr(module, "FIGURES", None) or {}
    if not isinstance(figures, dict) or not all(callable(f) for f in figures.values()):
        raise ModelError(f"model file {args.model}: FIGURES must map names to functions that return a Figure")
    if args.name is None:
        if not figures:
            print(f"{args.model} declares no figures (FIGURES)")
        for name, fn in figures.items():
            doc = (fn.__doc__ or "").strip().splitlines()
            print(f"{name:<16}  {doc[0] if doc else ''}")
        return
    if args.name not in figures:
        raise UsageError(did_you_mean(args.name, list(figures), f"figure of {args.model}"))
    if not args.plot and not args.json:
        raise UsageError("give --plot FILE.png (the figure) or --json (its numbers)")
    with outputs(args, "plot") as out:
        load(args)  # checks --set and --params-file before the figure's work
        base = parse_assignments(args.set)
        fitted = read_fit_file(args.params_file)[0] if args.params_file else {}

        def variant(**overrides):
            return load_model(args.model, {**fitted, **base, **overrides})

        fig = figures[args.name](variant)
        if not isinstance(fig, Figure):
            raise ModelError(
                f"model file {args.model}: figure {args.name!r} returned {type(fig).__name__}, not a Figure"
            )
        if args.plot:
            with out.path(args.plot) as tmp:
                render(fig, tmp)
    if args.json:
        print(json.dumps({"figure": args.name, "title": fig.title, "numbers": fig.numbers}, indent=1))
    if not args.quiet:
        shown = "; ".join(f"{k} {v:.4g}" for k, v in fig.numbers.items())
        print(
            f"{fig.title}" + (f": {shown}" if shown else "") + (f"; wrote {args.plot}" if args.plot else ""),
            file=sys.stderr,
        )
