"""``bondgraph linearize``: poles, zeros and natural frequencies at the initial state; the
state-space model as JSON or as a python-control script."""

from __future__ import annotations

import json

from ..support.errors import UsageError
from .registry import MODEL_ARGS, PLOT_SUFFIXES, arg, command, load, outputs, write_text

FORMATS = ("text", "json", "python-control")


@command(
    "linearize",
    "linearise at the initial state: poles, zeros, natural frequencies; the state-space "
    "model as JSON or for python-control",
    MODEL_ARGS
    + [
        arg("--input", metavar="NAME", help="model input (default: the model's first input)"),
        arg("--output", metavar="NAME", help="model output (default: the model's first output)"),
        arg(
            "--format",
            choices=FORMATS,
            default="text",
            help="text (default); json: one object with natural frequencies, poles, zeros, right-half-plane "
            "zeros, damping, static gain and A, B, C, D; python-control: a Python script that builds "
            "the model as control.StateSpace named 'model' (needs the 'control' extra)",
        ),
        arg("--json", action="store_true", help="same as --format json"),
        arg("--out", metavar="FILE", help="write the result to a file instead of stdout"),
        arg(
            "--bode",
            metavar="FILE.csv",
            help="write the frequency response: columns omega_rad_s (rad/s), magnitude, phase_deg",
        ),
        arg("--plot", metavar="FILE" + PLOT_SUFFIXES[0], help="Bode plot (needs matplotlib)"),
    ],
)
def run(args):
    from ..equations.derivation import derive
    from ..linear.linearize import linearize

    fmt = "json" if args.json else args.format
    if args.json and args.format not in ("text", "json"):
        raise UsageError(f"--json and --format {args.format} contradict each other; give one")
    if fmt == "python-control":
        import importlib.util

        if importlib.util.find_spec("control") is None:
            raise UsageError("--format python-control needs python-control: pip install 'bondgraph[control]'")
    with outputs(args, "out", "bode", "plot") as out:
        lm = load(args)
        model = lm.model
        inp = args.input or next(iter(model.inputs), None)
        outp = args.output or next(iter(model.outputs), None)
        if inp is None or outp is None:
            raise UsageError(
                f"model {args.model} declares no {'input' if inp is None else 'output'}; linearize needs one of each"
            )
        lin = linearize(derive(model), inp, outp)
        summary = lin.summary()
        if fmt == "json":
            text = json.dumps(summary) + "\n"
        elif fmt == "python-control":
            lin.to_control(model.name)  # the script's model, built once here so a problem shows now
            text = lin.python_control_script(
                model.name, f"{model.name}: {outp}/{inp} linearised at the initial state by bondgraph from {args.model}"
            )
        else:
            text = _text(model, lin, summary, inp, outp)
        write_text(args.out, text, out)
        if args.bode or args.plot:
            import numpy as np

            w = _bode_grid(lin)
            H = lin.frequency_response(w)
            if args.bode:
                from ..data import write_csv

                with out.path(args.bode) as tmp:
                    unit = _gain_unit(model, inp, outp).strip()
                    write_csv(
                        tmp,
                        w,
                        {"magnitude": np.abs(H), "phase_deg": np.degrees(np.unwrap(np.angle(H)))},
                        {
                            "model": str(args.model),
                            "input": inp,
                            "output": outp,
                            "omega_rad_s": "angular frequency (rad/s)",
                            "magnitude": f"|{outp}/{inp}| ({unit or '1'})",
                            "phase_deg": "phase of the response (degrees)",
                        },
                        index="omega_rad_s",
                    )
            if args.plot:
                from ..plotting import plot_bode

                with out.path(args.plot) as tmp:
                    plot_bode(
                        w,
                        H,
                        tmp,
                        title=f"{model.name}: {outp}/{inp}",
                        input=(inp, model.inputs[inp].unit),
                        output=(outp, model.outputs[outp].unit),
                    )


def _gain_unit(model, inp, outp) -> str:
    """ " m/V": the unit of the output per unit of the input, with a leading blank ("" for none)."""
    yu, uu = model.outputs[outp].unit, model.inputs[inp].unit
    return f" {yu or '1'}/{uu}" if uu else (f" {yu}" if yu else "")


def _text(model, lin, summary, inp, outp) -> str:
    gain_unit = _gain_unit(model, inp, outp)
    return "\n".join(
        [
            f"{model.name}: {outp}/{inp}, {len(lin.states)} states",
            "natural frequencies (rad/s): " + ", ".join(f"{w:.6g}" for w in summary["natural_frequencies_rad_s"]),
            "damping ratios:              " + ", ".join(f"{d:.4g}" for d in summary["damping_ratios"]),
            "poles (rad/s): " + ", ".join(_complex(p) for p in summary["poles"]),
            "zeros (rad/s): "
            + (", ".join(_complex(z) for z in summary["zeros"]) or "none")
            + f"   ({summary['rhp_zeros']} in the right half-plane)",
            f"static gain: {summary['dc_gain']:.6g}{gain_unit}",
            "",
        ]
    )


def _bode_grid(lin):
    import numpy as np

    wn = lin.natural_frequencies
    lo = (wn.min() if wn.size else 1.0) / 100
    hi = (wn.max() if wn.size else 1.0) * 100
    return np.logspace(np.log10(lo), np.log10(hi), 800)


def _complex(p) -> str:
    re_, im = p
    return f"{re_:.6g}" if im == 0 else f"{re_:.6g}{'+' if im > 0 else '-'}{abs(im):.6g}j"
