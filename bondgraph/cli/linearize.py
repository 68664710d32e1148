"""``bondgraph linearize``: poles, zeros and natural frequencies at the initial state."""
from __future__ import annotations

import json

from .registry import MODEL_ARGS, arg, command, load


@command("linearize", "linearise at the initial state: poles, zeros, natural frequencies (--json)",
         MODEL_ARGS + [
             arg("--input", default="V", help="input name (default V)"),
             arg("--output", default="x", help="output name (default x)"),
             arg("--json", action="store_true", help="print one JSON object (natural frequencies, poles, zeros, "
                                                     "right-half-plane zeros, damping, static gain)"),
             arg("--bode", metavar="FILE.csv", help="write the frequency response"),
             arg("--plot", metavar="FILE.png", help="Bode plot (needs matplotlib)"),
         ])
def run(args):
    from ..equations import derive
    from ..linearize import linearize

    lm = load(args)
    lin = linearize(derive(lm.model), args.input, args.output)
    summary = lin.summary()
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{lm.model.name}: {args.output}/{args.input}, {len(lin.states)} states")
        print("natural frequencies (rad/s): " + ", ".join(f"{w:.6g}" for w in summary["natural_frequencies_rad_s"]))
        print("damping ratios:              " + ", ".join(f"{d:.4g}" for d in summary["damping_ratios"]))
        print("poles: " + ", ".join(_complex(p) for p in summary["poles"]))
        print("zeros: " + (", ".join(_complex(z) for z in summary["zeros"]) or "none")
              + f"   ({summary['rhp_zeros']} in the right half-plane)")
        print(f"static gain: {summary['dc_gain']:.6g}")
    if args.bode or args.plot:
        import numpy as np
        w = _bode_grid(lin)
        H = lin.frequency_response(w)
        if args.bode:
            from ..data import write_csv
            write_csv(args.bode, w, {"magnitude": np.abs(H), "phase_deg": np.degrees(np.unwrap(np.angle(H)))},
                      {"model": str(args.model), "note": "first column t holds the angular frequency in rad/s"})
        if args.plot:
            from ..plotting import plot_bode
            plot_bode(w, H, args.plot, title=f"{lm.model.name}: {args.output}/{args.input}")


def _bode_grid(lin):
    import numpy as np
    wn = lin.natural_frequencies
    lo = (wn.min() if wn.size else 1.0) / 100
    hi = (wn.max() if wn.size else 1.0) * 100
    return np.logspace(np.log10(lo), np.log10(hi), 800)


def _complex(p) -> str:
    re_, im = p
    return f"{re_:.6g}" if im == 0 else f"{re_:.6g}{'+' if im > 0 else '-'}{abs(im):.6g}j"
