"""The seed rule and the draw of one record: device, drive, cause, visibility check."""

from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_limits

from . import apa, drives, linear, measure, t215
from .nominal import MODELS
from .record import Record

FAMILIES = {"apa": apa, "t215": t215}
SALT = 0xB11D6E4
ATTEMPTS = 3
VISIBLE = 3.0  # visible size >= VISIBLE x noise RMS


class Refused(RuntimeError):
    """The seed's effect stayed invisible after every attempt."""


def plan(seed: int) -> tuple[str, str, str | None]:
    """(family, cause, mechanism) of a seed: even seeds apa, odd t215; within a family every
    fourth record is a null, the others cycle through the causes, and each cause through its
    mechanisms on its successive appearances."""
    family = ("apa", "t215")[seed % 2]
    fam = FAMILIES[family]
    j = seed // 2
    if j % 4 == 0:
        return family, "none", None
    n = j - j // 4 - 1
    cause = fam.CAUSES[n % len(fam.CAUSES)]
    mechs = fam.MECHANISMS[cause]
    return family, cause, mechs[(n // len(fam.CAUSES)) % len(mechs)]


def _rng(seed, attempt, stream):
    return np.random.default_rng(np.random.SeedSequence([SALT, seed, attempt, stream]))


def _drive(fam, cause, rng, lin):
    """The record's drive: a cause-revealing segment, and with probability 1/2 a second one of
    any kind.  t215 dynamic segments are scaled to a tip amplitude in TIP_LIMIT (the
    experimenter sets the level on the device), within +-V_RATED."""
    dt, n = 1 / fam.FS, int(round(fam.DURATION * fam.FS))
    kinds = [str(rng.choice(fam.DRIVES[cause]))]
    if rng.random() < 0.5:
        kinds.append(str(rng.choice(fam.DRIVES["none"])))
    cut = int(n * rng.uniform(0.55, 0.8)) if len(kinds) == 2 else n
    lengths = [cut, n - cut][: len(kinds)]
    segs = []
    for kind, m in zip(kinds, lengths):
        v = drives.segment(kind, rng, m, dt, fam.limits())
        if fam is t215 and kind in drives.DYNAMIC:
            tip = linear.simulate(*t215.linear_ss(lin, "tip"), v, dt)
            target = np.exp(rng.uniform(*np.log(t215.TIP_LIMIT)))
            v = v * min(target / np.abs(tip).max(), t215.V_RATED / np.abs(v).max())
        segs.append(v)
    return np.concatenate(segs), kinds


def _strengthen(fam, mech, knobs):
    """Knobs one step stronger, or None at the mechanism's limit."""
    key, step, limit = fam.STRENGTH[mech]
    old = knobs[key]
    new = min(abs(old) * step, limit) if step > 1 else max(abs(old) * step, limit)
    if np.isclose(new, abs(old)):
        return None
    return {**knobs, key: float(np.copysign(new, old))}


def _escalate(fam, lin, mech, pil, chain, step, knobs, kernel):
    """One step towards visibility, alternating a stronger effect (within its range) and less
    noise (by 1.5, down to the lower end of its range).  Returns (kernel, knobs, quieter):
    kernel None when neither is left, quieter when only the noise changed."""
    for what in (0, 1) if step % 2 == 0 else (1, 0):
        if what == 0:
            stronger = _strengthen(fam, mech, knobs)
            k = None if stronger is None else _kernel(fam, lin, mech, stronger, pil)
            if k is not None:
                return k, stronger, False
        elif chain.level > measure.NOISE_RANGE[0]:
            chain.level = max(chain.level / 1.5, measure.NOISE_RANGE[0])
            return kernel, knobs, True
    return None, knobs, False


def _kernel(fam, lin, mech, knobs, pil):
    """The simulation kernel, or None when an added APA mode leaves the band."""
    k = fam.Kernel(lin, mech, knobs, pil)
    if fam is apa and mech in apa.MECHANISMS["higher-mode"]:
        modes = [f for f, z in k.new_modes() if apa.HM_BAND[0] <= f <= apa.HM_BAND[1]]
        if not modes:
            return None
        k.info["mode_hz"] = modes[0]
    return k


def _visible(fam, lin, V, y, dt, enough=0.0):
    """RMS (m) of y minus its best linear refit, and the refit's parameters."""
    rms, theta = linear.refit(y, *fam.refit_spec(lin, V, dt), enough)
    return rms, np.exp(theta)


def generate(seed: int) -> Record:
    """The record of a seed (deterministic; single-threaded BLAS)."""
    with threadpool_limits(1):
        return _generate(seed)


def _generate(seed: int) -> Record:
    family, cause, mech = plan(seed)
    fam = FAMILIES[family]
    dt = 1 / fam.FS
    for attempt in range(ATTEMPTS):
        lin = fam.draw_linear(_rng(seed, attempt, 0))
        V, kinds = _drive(fam, cause, _rng(seed, attempt, 1), lin)
        chain = measure.draw(_rng(seed, attempt, 2))
        pil = fam.pilot(lin, V, dt)
        knobs, kernel = None, fam.Kernel(lin)
        if mech is not None:
            rng = _rng(seed, attempt, 3)
            for _ in range(20):
                knobs = fam.draw_knobs(mech, rng)
                kernel = _kernel(fam, lin, mech, knobs, pil)
                if kernel is not None:
                    break
        steps, y = 0, None
        while kernel is not None:
            if y is None:
                y = kernel.simulate(V, dt)
                stroke = chain.gain * np.ptp(y)
                floor = measure.noise_rms(measure.quietest(chain), stroke)
                rms, refit = _visible(fam, lin, V, y, dt, VISIBLE * floor / chain.gain)
            noise = measure.noise_rms(chain, stroke)
            ratio = chain.gain * rms / noise
            if mech is None or ratio >= VISIBLE:
                return _record(
                    seed,
                    family,
                    cause,
                    mech,
                    knobs,
                    kernel,
                    lin,
                    V,
                    y,
                    chain,
                    kinds,
                    dict(
                        attempt=attempt,
                        steps=steps,
                        stroke=stroke,
                        visible_rms=chain.gain * rms,
                        noise_rms=noise,
                        visible_ratio=ratio,
                        refit=refit,
                    ),
                )
            kernel, knobs, quieter = _escalate(fam, lin, mech, pil, chain, steps, knobs, kernel)
            if not quieter:
                y = None
            steps += 1
    raise Refused(f"seed {seed}: {cause}/{mech} stayed below {VISIBLE} x noise in {ATTEMPTS} attempts")


def _plain(v):
    """JSON-ready copy (arrays to lists, numpy scalars to floats)."""
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items() if k != "table"}
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, np.generic):
        return v.item()
    return v


def _record(seed, family, cause, mech, knobs, kernel, lin, V, y, chain, kinds, vis):
    rng = _rng(seed, vis["attempt"], 4)
    t, Vr, x = measure.apply(chain, rng, V, y, 1 / FAMILIES[family].FS)
    truth = {
        "family": family,
        "cause": cause,
        "mechanism": mech,
        "knobs": _plain(knobs or {}),
        "derived": _plain(kernel.info),
        "device": _plain(lin),
        "drive": kinds,
        "chain": chain.to_dict(),
        **_plain(vis),
    }
    return Record(seed=seed, family=family, model=MODELS[family], t=t, V=Vr, x=x, truth=truth)
