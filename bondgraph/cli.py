"""Command-line interface: ``bondgraph COMMAND MODEL ...`` (see ``bondgraph --help``).

Exit status: 0 success, 2 usage or input error (one line on stderr, no traceback),
1 internal failure (``--debug`` shows the traceback), 130 interrupted.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
import warnings
from pathlib import Path

from .errors import BondGraphError, UsageError

_COMMANDS = {}


def command(name: str, help: str):
    def deco(fn):
        _COMMANDS[name] = (fn, help)
        return fn
    return deco


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(f"{self.prog}: {message} (see {self.prog} --help)")


def _model_args(p: argparse.ArgumentParser):
    p.add_argument("model", metavar="MODEL", help="model file (.py)")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[],
                   help="override a parameter (repeatable)")
    p.add_argument("--params-file", metavar="FILE.json", help="parameter values, e.g. from 'bondgraph fit'")


def _load(args):
    from .modelfile import load_model
    from .parameters import parse_assignments, read_params_file

    overrides = {}
    if args.params_file:
        overrides.update(read_params_file(args.params_file))
    overrides.update(parse_assignments(args.set))
    return load_model(args.model, overrides)


def _write_text(path: str | None, text: str):
    if path:
        from .atomic import atomic_write
        with atomic_write(path, "w", encoding="utf-8") as fh:
            fh.write(text)
    else:
        sys.stdout.write(text)


# ---- commands -----------------------------------------------------------------------------
@command("params", "list a model's parameters with defaults, units and meaning")
def _params(args):
    lm = _load(args)
    rows = []
    for name, decl in lm.model.all_parameters().items():
        value = lm.model.values.get(name, decl.default)
        rows.append({"name": name, "value": value, "default": decl.default, "unit": decl.unit,
                     "kind": decl.kind, "choices": list(decl.choices or []), "meaning": decl.doc})
    if args.json:
        print(json.dumps(rows, indent=1))
        return
    w = max(len(r["name"]) for r in rows) if rows else 4
    for r in rows:
        val = f"{r['value']:.6g}" if isinstance(r["value"], float) else str(r["value"])
        extra = f" (one of {', '.join(r['choices'])})" if r["choices"] else ""
        print(f"{r['name']:<{w}}  {val:>12}  {r['unit']:<8}  {r['meaning']}{extra}")


@command("equations", "print the causal, symbolic state equations")
def _equations(args):
    from .equations import derive
    from .printing import render

    lm = _load(args)
    _write_text(args.out, render(derive(lm.model), args.format))


@command("causality", "list each bond's causal stroke; --plot draws the bond graph")
def _causality(args):
    from .causality import assign_causality

    lm = _load(args)
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
        from .plotting import plot_bond_graph
        plot_bond_graph(caus, args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)


@command("simulate", "simulate the model and write the CONTRACT CSV (and a PNG with --plot)")
def _simulate(args):
    from .data import write_csv
    from .signals import parse_signal
    from .simulate import ATOL_FLOOR, Simulator

    lm = _load(args)
    exp = lm.experiment
    inputs = dict(exp.inputs)
    for item in args.input:
        name, sep, spec = item.partition("=")
        if not sep:
            raise UsageError(f"bad --input {item!r}: expected NAME=SIGNAL, e.g. V='sine(amplitude=10, frequency=5)'")
        inputs[name.strip()] = parse_signal(spec, base_dir=str(Path(args.model).parent))
    t = exp.times(args.t_end, args.dt)
    started = time.time()
    sim = Simulator(lm.model)
    rtol = exp.rtol if args.rtol is None else args.rtol
    res = sim.run(t, inputs, method=args.method or exp.method, rtol=rtol,
                  atol=ATOL_FLOOR if args.atol is None else args.atol, progress=_progress("simulating") if not args.quiet else None)
    meta = {"model": str(args.model), "method": res.stats["method"], "rtol": str(rtol)}
    for name, sig in inputs.items():
        meta[f"input {name}"] = str(sig)
    for name, value in lm.model.values.items():
        meta[f"param {name}"] = repr(value)
    if args.out:
        write_csv(args.out, res.t, res.columns(args.states), meta)
    else:
        cols = res.columns(args.states)
        print("t," + ",".join(cols))
        for k in range(res.t.size):
            print(",".join(repr(float(v)) for v in [res.t[k], *(c[k] for c in cols.values())]))
    if args.plot:
        from .plotting import plot_simulation
        plot_simulation(res, args.plot, title=lm.model.name)
    if not args.quiet:
        print(f"simulated {res.t[-1]:g} s of {lm.model.name} in {time.time() - started:.2f} s "
              f"({res.stats['method']}, {res.stats['steps']} steps)"
              + (f"; wrote {args.out}" if args.out else "") + (f", {args.plot}" if args.plot else ""),
              file=sys.stderr)


@command("linearize", "linearise at the initial state: poles, zeros, natural frequencies (--json)")
def _linearize(args):
    from .equations import derive
    from .linearize import linearize

    lm = _load(args)
    lin = linearize(derive(lm.model), args.input, args.output)
    summary = lin.summary()
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{lm.model.name}: {args.output}/{args.input}, {len(lin.states)} states")
        print("natural frequencies (rad/s): " + ", ".join(f"{w:.6g}" for w in summary["natural_frequencies_rad_s"]))
        print("damping ratios:              " + ", ".join(f"{d:.4g}" for d in summary["damping_ratios"]))
        print("poles: " + ", ".join(_c(p) for p in summary["poles"]))
        print("zeros: " + (", ".join(_c(z) for z in summary["zeros"]) or "none")
              + f"   ({summary['rhp_zeros']} in the right half-plane)")
        print(f"static gain: {summary['dc_gain']:.6g}")
    if args.bode or args.plot:
        import numpy as np
        w = _bode_grid(lin)
        H = lin.frequency_response(w)
        if args.bode:
            from .data import write_csv
            write_csv(args.bode, w, {"magnitude": np.abs(H), "phase_deg": np.degrees(np.unwrap(np.angle(H)))},
                      {"model": str(args.model), "note": "first column t holds the angular frequency in rad/s"})
        if args.plot:
            from .plotting import plot_bode
            plot_bode(w, H, args.plot, title=f"{lm.model.name}: {args.output}/{args.input}")


def _read_data(args):
    from .data import read_csv

    rename = {}
    if args.input:
        rename[args.input] = args.model_input
    if args.output:
        rename[args.output] = args.model_output
    return read_csv(args.data, required=("t", args.model_input, args.model_output), rename=rename or None)


@command("fit", "fit parameters to measured data (least squares, uncertainty, validation split)")
def _fit(args):
    from .atomic import atomic_write
    from .identify import Identification, detect_linear

    lm = _load(args)
    data = _read_data(args)
    names = [n.strip() for n in (args.params or "").split(",") if n.strip()]
    if not names:
        raise UsageError("fit: give the parameters to fit, e.g. --params a,c,K")
    seed = getattr(lm.module, "seed", None)
    if seed is not None:  # the model file's seeding procedure (e.g. Bouc–Wen, seed 002 §5.2)
        start = seed(lm.params, data)
        lm.model.values.update({k: v for k, v in start.items() if k in names})
    ident = Identification(lm.model, data, args.model_input, args.model_output, validation=args.validation,
                           split=args.split)
    linear = detect_linear(ident, names)
    res = ident.fit(ident.specs(names, linear), loss=args.loss, starts=args.starts, progress=_counter("fitting"))
    out = {"model": str(args.model), "data": str(args.data), "linear": linear, **res.as_json()}
    for n in names:
        sd = res.stderr.get(n)
        print(f"{n:<14} = {res.values[n]:.6g}" + (f" ± {sd:.2g}" if sd else "") + ("  (linear)" if n in linear else ""))
    print(f"rms: fit {res.rms_fit:.4g}, validation {res.rms_validation:.4g} ({res.nfev} simulations)")
    if args.out:
        with atomic_write(args.out, "w", encoding="utf-8") as fh:
            json.dump(out, fh, indent=1)
        print(f"wrote {args.out}", file=sys.stderr)


@command("diagnose", "find the effect the model misses in measured data, extend it and measure the gain")
def _diagnose(args):
    from .diagnose import calibration_names, diagnose, load_candidates

    lm = _load(args)
    data = _read_data(args)
    say = (lambda s: None) if args.quiet else (lambda s: print(f"diagnose: {s}", file=sys.stderr, flush=True))
    report = diagnose(lm.model, data, calibration_names(lm.module, lm.model), load_candidates(),
                      args.model_input, args.model_output, validation=args.validation,
                      workers=args.workers, progress=say, source=str(args.model))
    if args.json:
        print(json.dumps(report.as_json()))
    else:
        sys.stdout.write(report.text())
    if args.plot:
        from .plotting import plot_diagnosis
        plot_diagnosis(report, data, args.model_input, args.model_output, args.plot)


def _bode_grid(lin):
    import numpy as np
    wn = lin.natural_frequencies
    lo = (wn.min() if wn.size else 1.0) / 100
    hi = (wn.max() if wn.size else 1.0) * 100
    return np.logspace(np.log10(lo), np.log10(hi), 800)


def _c(p) -> str:
    re_, im = p
    return f"{re_:.6g}" if im == 0 else f"{re_:.6g}{'+' if im > 0 else '-'}{abs(im):.6g}j"


def _progress(label: str):
    """A progress callback printing to stderr once a run has taken more than 2 s."""
    state = {"t0": time.time(), "last": 0.0, "shown": False}

    def report(fraction: float):
        now = time.time()
        if fraction < 1.0 and (now - state["last"] < 0.5 or now - state["t0"] < 2.0):
            return
        if fraction >= 1.0 and not state["shown"]:
            return
        state["last"], state["shown"] = now, True
        end = "\n" if fraction >= 1.0 else "\r"
        print(f"{label}: {100 * fraction:5.1f} %  ({now - state['t0']:.1f} s)", end=end, file=sys.stderr, flush=True)
    return report


def _counter(label: str):
    """A progress callback for iterative work: prints the evaluation count every 2 s."""
    state = {"t0": time.time(), "last": time.time()}

    def report(count: int):
        now = time.time()
        if now - state["last"] >= 2.0:
            state["last"] = now
            print(f"{label}: {count} simulations ({now - state['t0']:.0f} s)", file=sys.stderr, flush=True)
    return report


# ---- entry point ----------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="bondgraph", description="Bond-graph modelling of piezoelectric actuators.")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name, (_, help_) in _COMMANDS.items():
        p = sub.add_parser(name, help=help_, description=help_)
        _model_args(p)
        if name == "params":
            p.add_argument("--json", action="store_true", help="print JSON")
        elif name == "equations":
            p.add_argument("--format", choices=("text", "latex", "markdown"), default="text")
            p.add_argument("--out", metavar="FILE", help="write to a file instead of stdout")
        elif name == "causality":
            p.add_argument("--json", action="store_true", help="print JSON")
            p.add_argument("--plot", metavar="FILE.png", help="draw the bond graph with causal strokes")
        elif name == "simulate":
            p.add_argument("--input", metavar="NAME=SIGNAL", action="append", default=[],
                           help="drive an input: sine(amplitude=A, frequency=F, offset=O), step(...), ramp(...), "
                                "chirp(...), triangle(...), pwl(t:v, ...), csv(file=F, column=C), or a number")
            p.add_argument("--t-end", type=float, help="end time (s); default from the model's EXPERIMENT")
            p.add_argument("--dt", type=float, help="output sample interval (s)")
            p.add_argument("--method", choices=("auto", "dopri5", "radau", "bdf", "lsoda"))
            p.add_argument("--rtol", type=float, help="relative tolerance (default 1e-6)")
            p.add_argument("--atol", type=float, help="absolute tolerance floor (default 1e-20; the error is otherwise relative to each state's peak)")
            p.add_argument("--out", metavar="FILE.csv", help="write the result CSV (default: stdout)")
            p.add_argument("--plot", metavar="FILE.png", help="plot inputs and outputs (needs matplotlib)")
            p.add_argument("--states", action="store_true", help="include the states in the CSV")
            p.add_argument("--quiet", action="store_true", help="no progress or summary on stderr")
        elif name in ("fit", "diagnose"):
            p.add_argument("data", metavar="DATA", help="measured data (CSV: t, V, x)")
            p.add_argument("--input", metavar="COL", help="data column that drives the model (default: the model input name)")
            p.add_argument("--output", metavar="COL", help="data column to compare with the model output")
            p.add_argument("--model-input", default="V", help="model input (default V)")
            p.add_argument("--model-output", default="x", help="model output (default x)")
            p.add_argument("--validation", type=float, default=0.3, help="share of the data held out (default 0.3)")
            if name == "fit":
                p.add_argument("--params", metavar="A,B,...", help="parameters to fit")
                p.add_argument("--split", choices=("blocks", "tail"), default="blocks",
                               help="held-out part: interleaved blocks (default) or the last part")
                p.add_argument("--loss", choices=("linear", "soft_l1", "huber", "cauchy"), default="linear",
                               help="robust loss (scipy least_squares)")
                p.add_argument("--starts", type=int, default=1, help="multi-start count for non-convex fits")
                p.add_argument("--out", metavar="FILE.json", help="write the fitted parameters (for --params-file)")
            else:
                p.add_argument("--json", action="store_true", help="print the CONTRACT JSON object")
                p.add_argument("--plot", metavar="FILE.png", help="measured vs baseline vs extended, residuals")
                p.add_argument("--workers", type=int, default=2, help="parallel worker processes (default 2)")
                p.add_argument("--quiet", action="store_true", help="no progress on stderr")
        elif name == "linearize":
            p.add_argument("--input", default="V", help="input name (default V)")
            p.add_argument("--output", default="x", help="output name (default x)")
            p.add_argument("--json", action="store_true", help="print the CONTRACT JSON object")
            p.add_argument("--bode", metavar="FILE.csv", help="write the frequency response")
            p.add_argument("--plot", metavar="FILE.png", help="Bode plot (needs matplotlib)")
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    debug = "--debug" in argv
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if not args.command:
            raise UsageError(f"no command given; choose one of {', '.join(_COMMANDS)} (see bondgraph --help)")
        _check_numbers(args)
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = _show_warning
            _COMMANDS[args.command][0](args)
        return 0
    except BondGraphError as exc:
        if debug:
            traceback.print_exc()
        print(f"bondgraph: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bondgraph: interrupted; no output file was written partially", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:  # noqa: BLE001 - internal failure: one line unless --debug
        if debug:
            traceback.print_exc()
        print(f"bondgraph: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)",
              file=sys.stderr)
        return 1


def _check_numbers(args):
    """Refuse nonsensical numeric options with a one-line message."""
    import math
    for name in ("rtol", "atol"):
        v = getattr(args, name, None)
        if v is None:
            continue
        if not math.isfinite(v) or v <= 0 or (name == "rtol" and v >= 1):
            bound = "between 0 and 1" if name == "rtol" else "a positive number"
            raise UsageError(f"--{name.replace('_', '-')} must be {bound}, got {v}")


def _show_warning(message, category, filename, lineno, file=None, line=None):
    print(f"bondgraph: warning: {message}", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
