"""``bondgraph causality``: each bond's causal stroke, and a drawing of the bond graph."""
from __future__ import annotations

import json
import sys

from .registry import MODEL_ARGS, arg, command, load


@command("causality", "list each bond's causal stroke; --plot draws the bond graph",
         MODEL_ARGS + [arg("--json", action="store_true", help="print JSON"),
                       arg("--plot", metavar="FILE.png", help="draw the bond graph with causal strokes")])
def run(args):
    from ..causality import assign_causality

    lm = load(args)
    caus = assign_causality(lm.model)
    rows = caus.table()
    if args.json:
        print(json.dumps({"bonds": rows, "derivative": [f"{e}.{p}" if p != "p" else e for e, p in caus.derivative],
                          "arbitrary": caus.arbitrary}, indent=1))
    else:
        for r in rows:
            print(f"bond {r['bond']:>3}: {r['from']} → {r['to']}   effort by {r['effort_by']}, "
                  f"stroke at {r['stroke_at']}")
        for e, p in caus.derivative:
            print(f"derivative causality: {e if p == 'p' else e + '.' + p}")
    if args.plot:
        from ..plotting import plot_bond_graph
        plot_bond_graph(caus, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
