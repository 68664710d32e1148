"""``bondgraph equations``: the causal, symbolic state equations."""

from __future__ import annotations

from .registry import MODEL_ARGS, arg, command, load, module_constant, outputs, write_text


@command(
    "equations",
    "print the causal, symbolic state equations (parameters, constitutive relations, causal "
    "strokes, state equations, outputs)",
    MODEL_ARGS
    + [
        arg(
            "--format",
            choices=module_constant("bondgraph.equations.printing", "FORMATS"),
            default="text",
            help="text (default), latex or markdown",
        ),
        arg("--out", metavar="FILE", help="write to a file instead of stdout"),
    ],
)
def run(args):
    from ..equations.derivation import derive
    from ..equations.printing import render

    with outputs(args, "out") as out:
        lm = load(args)
        write_text(args.out, render(derive(lm.model), args.format), out)
