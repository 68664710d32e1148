"""``bondgraph params``: a model's parameters with values, defaults, units and meaning."""

from __future__ import annotations

import json

from .registry import MODEL_ARGS, arg, command, load


@command(
    "params",
    "list a model's parameters with defaults, units and meaning",
    MODEL_ARGS + [arg("--json", action="store_true", help="print JSON")],
)
def run(args):
    lm = load(args)
    rows = []
    for name, decl in lm.model.all_parameters().items():
        value = lm.model.values.get(name, decl.default)
        rows.append(
            {
                "name": name,
                "value": value,
                "default": decl.default,
                "unit": decl.unit,
                "kind": decl.kind,
                "choices": list(decl.choices or []),
                "meaning": decl.doc,
            }
        )
    if args.json:
        print(json.dumps(rows, indent=1))
        return
    w = max(len(r["name"]) for r in rows) if rows else 4
    for r in rows:
        val = f"{r['value']:.6g}" if isinstance(r["value"], float) else str(r["value"])
        extra = f" (one of {', '.join(r['choices'])})" if r["choices"] else ""
        print(f"{r['name']:<{w}}  {val:>12}  {r['unit']:<8}  {r['meaning']}{extra}")
