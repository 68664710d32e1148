"""``bondgraph export``: the model as an FMI 2.0 FMU (Model Exchange and Co-Simulation) for
Simulink, Dymola, OpenModelica, 20-sim and other FMI tools; see docs/fmi.md."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from ..support.errors import UsageError
from .registry import MODEL_ARGS, QUIET_ARG, arg, command, load, outputs


@command(
    "export",
    "write the model as an FMI 2.0 FMU (model exchange and co-simulation, C sources and a compiled binary)",
    MODEL_ARGS
    + [
        arg("--fmu", metavar="FILE.fmu", required=True, help="the FMU to write"),
        arg(
            "--experiment",
            action="store_true",
            help="drive the inputs the model file's EXPERIMENT names inside the FMU (a self-contained FMU that "
            "reproduces 'bondgraph simulate'); without it every model input is an FMU input",
        ),
        arg(
            "--input",
            metavar="NAME=SIGNAL",
            action="append",
            default=[],
            help="drive input NAME inside the FMU by SIGNAL (as for simulate: sine(...), step(...), pwl(...), "
            "csv(file=F, column=C), a number); overrides --experiment for that input",
        ),
        QUIET_ARG,
    ],
)
def run(args):
    from ..export import export_fmu
    from ..model.signals import parse_signal
    from .simulate import output_offsets

    with outputs(args) as out:
        out.add(args.fmu, "--fmu", suffixes=(".fmu",))
        lm = load(args)
        for name, offset in output_offsets(lm, lm.model.outputs).items():
            lm.model.outputs[name].expr += offset  # a fit file's sensor zero, as simulate adds it
        signals = dict(lm.experiment.inputs) if args.experiment else {}
        given = set()
        for item in args.input:
            name, sep, spec = item.partition("=")
            name = name.strip()
            if not sep or not name:
                raise UsageError(
                    f"bad --input {item!r}: expected NAME=SIGNAL, e.g. V='sine(amplitude=10, frequency=5)'"
                )
            if name in given:
                raise UsageError(f"--input {name} given twice; give each input once")
            given.add(name)
            signals[name] = parse_signal(spec, base_dir=str(Path(args.model).parent))
        started = time.time()
        with out.path(args.fmu) as tmp:
            rep = export_fmu(lm.model, tmp, signals=signals, experiment=lm.experiment)
    if not args.quiet:
        inside = f"; driven inside: {', '.join(rep.embedded)}" if rep.embedded else ""
        print(
            f"wrote {args.fmu}: FMI 2.0 model exchange and co-simulation, {rep.n_states} states, "
            f"{len(rep.parameters)} parameters, inputs: {', '.join(rep.inputs) or 'none'}{inside}, "
            f"outputs: {', '.join(rep.outputs) or 'none'} (compiled in {rep.compile_seconds:.1f} s, "
            f"{time.time() - started:.1f} s in all)",
            file=sys.stderr,
        )
