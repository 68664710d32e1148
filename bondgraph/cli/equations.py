"""``bondgraph equations``: the causal, symbolic state equations."""
from __future__ import annotations

from .registry import MODEL_ARGS, arg, command, load, write_text


@command("equations", "print the causal, symbolic state equations",
         MODEL_ARGS + [arg("--format", choices=("text", "latex", "markdown"), default="text"),
                       arg("--out", metavar="FILE", help="write to a file instead of stdout")])
def run(args):
    from ..equations import derive
    from ..printing import render

    lm = load(args)
    write_text(args.out, render(derive(lm.model), args.format))
