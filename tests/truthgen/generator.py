"""``draw(seed, size) -> Record``: one randomized truth record (see the package docstring for
the protocol)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from . import drives, measure
from .draws import loguniform
from .families import FAMILIES
from .mechanisms import MECHANISMS
from .system import simulate
from .visibility import linear_refit

SIZES = ("ci", "bench")
#: a hidden effect must leave at least this many noise RMS after the best plausible linear refit
VISIBLE = 3.0
#: rounds of the visibility rule (steps 1-3) ...
ATTEMPTS = 14
#: ... and the further rounds that unmask a compound (step 4) before the seed is refused
UNMASK_ATTEMPTS = 10
#: the quietest sensor the visibility rule may fall back to (noise RMS / stroke)
NOISE_FLOOR = 0.001
#: the design: which family each seed goes to (seed mod 6) ...
FAMILY_CYCLE = ("apa", "t215", "apa", "t215", "stack", "t226")


def design(seed: int) -> tuple[str, tuple]:
    """(family, causes) of a seed: the family from ``seed % 6`` through FAMILY_CYCLE, the cause
    from that family's cycle of causes (Family.causes), walked in seed order — so that any run
    of consecutive seeds is balanced over families and causes."""
    block, pos = divmod(int(seed), len(FAMILY_CYCLE))
    name = FAMILY_CYCLE[pos]
    per_block = FAMILY_CYCLE.count(name)
    n = block * per_block + FAMILY_CYCLE[:pos].count(name)
    cycle = FAMILIES[name].causes
    cause = cycle[n % len(cycle)]
    return name, tuple(c for c in cause.split("+") if c != "none")


@dataclass
class Record:
    """A truth record: the measured data, the model file to diagnose it with, and the truth.

    ``causes`` is empty for an effect-free record, one cause, or two for a compound record, in
    the order of their visible sizes; ``ordered`` says whether that order is clear (the larger
    at least twice the smaller) or the pair should be read as a set."""

    seed: int
    size: str
    family: str
    model: str  # model file, relative to the repository root
    overrides: dict  # the model file's --set NAME=VALUE for this record
    t: np.ndarray
    V: np.ndarray
    x: np.ndarray
    causes: tuple
    ordered: bool
    mechanisms: tuple
    strengths: tuple
    params: dict  # the drawn linear parameters of the truth
    nominal: dict  # the model file's values they were drawn around
    drive: dict
    fs: float
    duration: float
    noise: dict
    noise_rms: float  # of x, in metres
    stroke: float  # effect-free peak-to-peak x (m, before the sensor gain)
    effect_size: tuple  # RMS(with - without effect) / noise RMS, per cause
    visible_size: tuple  # what the best plausible linear refit leaves / noise RMS
    attempts: int  # rounds of the visibility rule used
    clean: np.ndarray  # noise-free x (m, before the sensor) at the instants x was taken
    clean0: np.ndarray  # the same without the hidden effects
    seconds: float = 0.0  # generation time
    extra: dict = field(default_factory=dict)

    @property
    def cause(self) -> str:
        """The first cause, or ``none``."""
        return self.causes[0] if self.causes else "none"

    @property
    def label(self) -> str:
        """``none``, a cause, or ``a+b`` for a compound record."""
        return "+".join(self.causes) if self.causes else "none"

    @property
    def cli_sets(self) -> list:
        return [f"{k}={str(v).lower() if isinstance(v, bool) else v}" for k, v in self.overrides.items()]

    def metadata(self) -> dict:
        """What a lab would write in the file: the device and the sampling, never the truth."""
        return {
            "device": f"synthetic {self.family} (tests/truthgen seed {self.seed}, {self.size})",
            "sample_rate": f"{self.fs:g} Hz",
            "model": self.model,
        }

    def dataset(self):
        from bondgraph.data import Dataset

        return Dataset(self.t, {"V": self.V, "x": self.x}, self.metadata())

    def write_csv(self, path) -> None:
        """The record in the project's CSV format (bondgraph.data.write_csv)."""
        from bondgraph.data import write_csv

        write_csv(path, self.t, {"V": self.V, "x": self.x}, self.metadata())

    def truth(self) -> dict:
        """The truth as plain JSON-able values."""

        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            if isinstance(v, (list, tuple, np.ndarray)):
                return [clean(x) for x in v]
            if isinstance(v, (np.floating, np.integer)):
                return v.item()
            return v

        return clean(
            {
                "seed": self.seed,
                "size": self.size,
                "family": self.family,
                "model": self.model,
                "overrides": self.overrides,
                "label": self.label,
                "cause": self.cause,
                "causes": list(self.causes),
                "ordered": self.ordered,
                "mechanisms": list(self.mechanisms),
                "strengths": list(self.strengths),
                "params": self.params,
                "nominal": self.nominal,
                "drive": _drive_summary(self.drive),
                "fs": self.fs,
                "duration": self.duration,
                "samples": len(self.t),
                "noise": self.noise,
                "noise_rms": self.noise_rms,
                "stroke": self.stroke,
                "effect_size": list(self.effect_size),
                "visible_size": list(self.visible_size),
                "attempts": self.attempts,
                "seconds": round(self.seconds, 2),
            }
        )


def _drive_summary(spec: dict) -> dict:
    return {k: (v if not isinstance(v, list) or len(v) <= 6 else f"{len(v)} values") for k, v in spec.items()}


def _rms(a):
    return float(np.sqrt(np.mean(np.square(a))))


@dataclass
class Plan:
    """What a seed decides before anything is simulated (see :func:`plan`)."""

    family: object
    causes: tuple
    overrides: dict
    nominal: dict
    params: dict
    shape: object
    mechanisms: list
    context: dict
    streams: dict


def plan(seed: int, size: str = "ci") -> Plan:
    """The family, causes, model options, drawn parameters, record shape and mechanisms of a
    seed: the part of :func:`draw` that needs no simulation (the random streams it leaves
    are handed on to the rest of the draw)."""
    if size not in SIZES:
        raise ValueError(f"size must be one of {SIZES}, got {size!r}")
    fam_name, causes = design(seed)
    fam = FAMILIES[fam_name]
    names = ("model", "params", "shape", "drive", "mechanisms", "noise", "visibility")
    streams = dict(
        zip(
            names,
            (
                np.random.default_rng(s)
                for s in np.random.SeedSequence([int(seed), SIZES.index(size)]).spawn(len(names))
            ),
        )
    )
    overrides = fam.model_args(streams["model"])
    nominal = fam.nominal(overrides)
    p = fam.perturb(nominal, streams["params"])
    shape = fam.shape(size, causes, streams["shape"], overrides)
    ctx = {"p": p, "fs": shape.fs, "T": shape.T, **fam.context(p)}
    mechs = []
    for c in causes:
        usable = [m_ for _, m_ in sorted(MECHANISMS[fam.physics][c].items()) if m_.applies(ctx)]
        mechs.append(usable[int(streams["mechanisms"].integers(len(usable)))])
    return Plan(fam, causes, overrides, nominal, p, shape, mechs, ctx, streams)


def draw(seed: int, size: str = "ci") -> Record:
    """The truth record of ``seed`` at ``size`` (``ci``: small, ``bench``: realistic)."""
    start = time.perf_counter()
    pl = plan(seed, size)
    fam, causes, overrides, nominal, p, shape, mechs = (
        pl.family,
        pl.causes,
        pl.overrides,
        pl.nominal,
        pl.params,
        pl.shape,
        pl.mechanisms,
    )
    r_drive, r_mech, r_noise, r_vis = (pl.streams[k] for k in ("drive", "mechanisms", "noise", "visibility"))
    m = max(1, math.ceil(1.0 / (shape.fs * shape.h_max)))
    h = 1.0 / (shape.fs * m)
    n = int(round(shape.T * shape.fs))
    t_fine = np.arange((n + 2) * m + 1) * h
    phys = fam.module
    kinds = fam.drive_kinds(causes, shape)
    d_range = fam.drive_range(p, shape, r_drive)

    def new_drive(rng):
        spec = drives.draw(str(rng.choice(kinds)), d_range, shape.T, shape.fs, rng)
        V = drives.signal(spec, t_fine)
        sys0, probes = phys.system(p, probes=True)
        out = simulate(sys0, V, h, probes)
        return spec, V, out[0], fam.refs(out[0], out[1:], V)

    spec, V, y0, ref = new_drive(r_drive)
    noise = measure.draw(r_noise)
    stroke = float(np.ptp(y0[::m]))
    ctx = {**pl.context, "h": h, "ref": ref}
    shapes = [mech.shape(r_mech, ctx) for mech in mechs]
    strengths = [loguniform(r_mech, mech.lo, mech.hi) for mech in mechs]

    cache: dict = {}

    def response(active):
        """Noise-free response with the mechanisms ``active`` at their current strengths (and
        its best plausible linear refit), cached: noise changes need no new simulation."""
        key = (drive_version, tuple((i, strengths[i]) for i in active))
        if key not in cache:
            fx = phys.Effects()
            for i in active:
                mechs[i].apply(fx, strengths[i], shapes[i], ctx)
            y_ = simulate(phys.system(p, fx), V, h)[0]
            fit = linear_refit(phys, p, nominal, V, h, y_, m)[0] if len(active) == 1 else None
            cache[key] = (y_, fit)
        return cache[key]

    drive_version = 0
    effect, visible, attempts = (), (), 0
    y = y0
    lowered: set = set()
    for attempts in range(1, ATTEMPTS + UNMASK_ATTEMPTS + 1 if mechs else 1):
        sigma = noise["level"] * stroke
        y = response(range(len(mechs)))[0]
        effect, visible = [], []
        for i in range(len(mechs)):
            without = response([j for j in range(len(mechs)) if j != i])[0] if len(mechs) > 1 else y0
            alone, fit = response([i])
            effect.append(_rms((y - without)[::m]) / sigma)
            visible.append(_rms((alone - fit)[::m]) / sigma)
        weak = [i for i in range(len(mechs)) if min(effect[i], visible[i]) < VISIBLE]
        if not weak:
            break
        if attempts == ATTEMPTS + (UNMASK_ATTEMPTS if len(mechs) > 1 else 0):
            raise RuntimeError(
                f"seed {seed} ({size}): the hidden {'+'.join(causes)} stays below "
                f"{VISIBLE} noise RMS after {attempts} rounds of the visibility rule"
            )
        masked = [i for i in weak if visible[i] >= VISIBLE]  # visible alone, not beside its partner
        partners = [j for j in range(len(mechs)) if j not in weak and strengths[j] > mechs[j].lo]
        if attempts >= ATTEMPTS and masked and partners:  # 4. a weaker partner (compounds)
            for j in partners:
                strengths[j] = max(strengths[j] / 2, mechs[j].lo)
                lowered.add(j)
        elif any(strengths[i] < mechs[i].hi for i in weak if i not in lowered):  # 1. a stronger effect
            for i in weak:
                if i not in lowered:
                    strengths[i] = min(2 * strengths[i], mechs[i].hi)
        elif noise["level"] > NOISE_FLOOR:  # 2. a quieter sensor
            noise["level"] = max(noise["level"] / 2, NOISE_FLOOR)
        else:  # 3. a drive that reveals it
            spec, V, y0, ref = new_drive(r_vis)
            stroke = float(np.ptp(y0[::m]))
            ctx["ref"] = ref
            drive_version += 1
    order = sorted(range(len(mechs)), key=lambda i: -visible[i]) if mechs else []
    t, Vs, x, noise_rms, (clean, clean0) = measure.sample(t_fine, V, y, shape.fs, n, noise, stroke, [y, y0])
    return Record(
        seed=int(seed),
        size=size,
        family=fam.name,
        model=fam.model,
        overrides=overrides,
        t=t,
        V=Vs,
        x=x,
        causes=tuple(causes[i] for i in order),
        ordered=len(order) < 2 or visible[order[0]] >= 2 * visible[order[1]],
        mechanisms=tuple(mechs[i].name for i in order),
        strengths=tuple(strengths[i] for i in order),
        params=p,
        nominal=nominal,
        drive=spec,
        fs=shape.fs,
        duration=shape.T,
        noise=noise,
        noise_rms=noise_rms,
        stroke=stroke,
        effect_size=tuple(effect[i] for i in order),
        visible_size=tuple(visible[i] for i in order),
        attempts=attempts,
        clean=clean,
        clean0=clean0,
        seconds=time.perf_counter() - start,
        extra={"regime": shape.regime, "substeps": m},
    )
