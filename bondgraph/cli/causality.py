"""``bondgraph causality``: each bond's causal stroke, and a drawing of the bond graph."""

from __future__ import annotations

import json
import sys

from .registry import MODEL_ARGS, PLOT_SUFFIXES, arg, command, load, outputs


@command(
    "causality",
    "list each bond's causal stroke; --plot draws the bond graph",
    MODEL_ARGS
    + [
        arg("--json", action="store_true", help="print JSON"),
        arg(
            "--plot",
            metavar="FILE" + PLOT_SUFFIXES[0],
            help="draw the bond graph with causal strokes (needs matplotlib)",
        ),
    ],
)
def run(args):
    from ..equations.causality import assign_causality

    with outputs(args, "plot") as out:
        lm = load(args)
        caus = assign_causality(lm.model)
        _report(caus, args.json)
        if args.plot:
            from ..plotting import plot_bond_graph

            with out.path(args.plot) as tmp:
                plot_bond_graph(caus, tmp)
    if args.plot:
        print(f"wrote {args.plot}", file=sys.stderr)


def _report(caus, as_json: bool):
    rows = caus.table()
    if as_json:
        print(
            json.dumps(
                {
                    "bonds": rows,
                    "derivative": [f"{e}.{p}" if p != "p" else e for e, p in caus.derivative],
                    "arbitrary": caus.arbitrary,
                },
                indent=1,
            )
        )
    else:
        for r in rows:
            print(
                f"bond {r['bond']:>3}: {r['from']} → {r['to']}   effort by {r['effort_by']}, stroke at {r['stroke_at']}"
            )
        for e, p in caus.derivative:
            print(f"derivative causality: {e if p == 'p' else e + '.' + p}")
