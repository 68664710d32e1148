"""Hidden-effect mechanisms: for each cause several, structurally different, each with a
*strength* (one number, realistic range ``lo..hi``) and random *shape* numbers.

A mechanism is drawn once per record (``shape = mech.shape(rng, ctx)``), then applied at a
strength (``mech.apply(fx, strength, shape, ctx)``) to an :class:`Effects` of the device's
physics (:mod:`.stack` or :mod:`.bimorph`); the visibility rule may raise the strength within
its range.  ``ctx`` holds the device's linear parameters ``p``, the record's sample rate ``fs``
and duration ``T``, and the ranges of the effect-free response (``ref``): for stacks the field
``e`` (charge units) and the displacement ``x``; for bimorphs ``q1`` (mode 1), its rate and
the sensed velocity, and the drive ``V``.

Strengths (dimensionless unless stated):

=================  ==========================  ================================================
cause              mechanism                   strength
=================  ==========================  ================================================
hysteresis         preisach, bouc-wen, duhem   width of the quasi-static major loop over its
                                               range (largest vertical gap), 0.06-0.25
hysteresis         maxwell-slip                total slider stiffness over the device stiffness
                                               (stack: K; bimorph: omega_1^2), 0.05-0.6
creep              log-time                    strain gain per decade of time, 0.005-0.03
creep              fractional, kv-cells        creep at the end of the record, 0.02-0.12
saturation         tanh, polynomial, piecewise response deficit at the largest field, 0.03-0.2
saturation         stop                        end-stop stiffness over K, 0.1-0.8
softening          cubic, cubic-quintic,       stiffness drop of mode 1 at the largest
                   tip-cubic, field-stiffness  effect-free amplitude (or drive), 0.01-0.12
nonlinear-damping  quadratic, amplitude,       damping increase of mode 1 at the largest
                   friction                    effect-free amplitude or velocity, 0.2-3
electrical         series-r                    series resistance over the nominal one, 10-200
electrical         series-rl                   series inductance, 5e-5-2e-3 H
electrical         amp-pole                    amplifier time constant, 3.2e-5-1e-3 s
higher-mode        shell                       mass share before the shell spring, 0.05-0.5
higher-mode        frame                       base compliance over the stack's, 0.02-0.5
higher-mode        sensor, fixture             bracket coupling gamma, 0.1-1
higher-mode        beam                        gain of the next beam mode (1 = beam theory), 0.5-2
higher-mode        offbeam                     static compliance over mode 1's, 0.005-0.1
=================  ==========================  ================================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import bimorph as bim
from .draws import loguniform
from .operators import HYSTERESIS, MaxwellSlip, loop_stats, saturation_curve
from .terms import FieldLaw


def _always(ctx):
    return True


@dataclass(frozen=True)
class Mechanism:
    cause: str
    name: str
    lo: float
    hi: float
    shape: Callable  # (rng, ctx) -> dict
    apply: Callable  # (fx, strength, shape, ctx) -> None
    applies: Callable = _always  # (ctx) -> bool: can the record show it at all?


def _centre_half(lo_hi):
    lo, hi = lo_hi
    return (lo + hi) / 2, max((hi - lo) / 2, 1e-30)


# ----------------------------------------------------------------------------- creep kernels


def _creep_shape(kind):
    def shape(rng, ctx):
        T, h = ctx["T"], ctx["h"]
        if kind == "log-time":
            taus = 10 ** np.arange(math.log10(max(5 * h, 1e-4)), math.log10(30 * T), 1 / 3)
            return {"taus": taus, "alpha": None}
        if kind == "fractional":
            taus = 10 ** np.arange(math.log10(max(5 * h, 1e-4)), math.log10(30 * T), 1 / 3)
            return {"taus": taus, "alpha": rng.uniform(0.1, 0.4)}
        count = int(rng.integers(1, 4))
        return {
            "taus": np.sort([loguniform(rng, 0.01 * T, 0.5 * T) for _ in range(count)]),
            "share": rng.dirichlet(np.ones(count)),
        }

    return shape


def creep_cells(kind, strength, shape, T):
    """(tau_j, w_j) of a creep kernel: log-time (equal weight per third of a decade: the
    step response grows by ``strength`` per decade), fractional (weights ~ tau^alpha: a
    t^alpha law reaching ``strength`` at T), kv-cells (a few cells sharing ``strength``)."""
    taus = shape["taus"]
    if kind == "log-time":
        w = np.full(len(taus), strength / 3.0)
    elif kind == "fractional":
        w = taus ** shape["alpha"]
        w *= strength / float(np.sum(w * -np.expm1(-T / taus)))
    else:
        w = strength * shape["share"] / -np.expm1(-T / taus)
    return list(zip(taus.tolist(), w.tolist()))


# ----------------------------------------------------------------------------- stacks


def _hysteresis_shape(name):
    """A random operator of the family whose own loop is at least 0.4 of its range wide (so that
    realistic loop widths need no more hysteretic than reversible response)."""

    def shape(rng, ctx):
        for _ in range(50):
            op = HYSTERESIS[name](rng)
            gap, span = loop_stats(op)
            if gap >= 0.4 * span:
                break
        return {"op": op, "gap": gap, "span": span}

    return shape


def hysteretic_weight(width, shape):
    """Weight w of ``u + w H(u)`` whose major loop is ``width`` of its range wide:
    width = w gap / (2 + w span)."""
    return 2 * width / (shape["gap"] - width * shape["span"])


def _stack_field_hysteresis(name):
    def apply(fx, s, shape, ctx):
        c, half = _centre_half(ctx["ref"]["e"])
        fx.laws.append(FieldLaw(hysteretic_weight(s, shape), shape["op"], c, half))

    return _hysteresis_shape(name), apply


def _slip_shape(rng, ctx):
    return {"op": MaxwellSlip(rng)}


def _stack_slip_apply(fx, s, shape, ctx):
    c, half = _centre_half(ctx["ref"]["x"])
    fx.force = FieldLaw(-s * ctx["p"]["K"], shape["op"], c, half)


def _stack_saturation(name):
    def shape(rng, ctx):
        return {"deficit": saturation_curve(name, rng)}

    def apply(fx, s, shape, ctx):
        top = max(abs(v) for v in ctx["ref"]["e"])
        fx.laws.append(FieldLaw(s, deficit=shape["deficit"], top=top))

    return shape, apply


def _stop_shape(rng, ctx):
    return {"knee": rng.uniform(0.55, 0.85), "width": rng.uniform(0.01, 0.05)}


class _Stop:
    """An end stop: force -k w softplus((|x|/top - knee)/w) top, on the side(s) the drive uses."""

    def __init__(self, k, top, knee, width, both):
        self.k, self.top, self.knee, self.width, self.both = k, top, knee, width, both

    def __call__(self, x):
        u = x / self.top
        up = self.width * np.logaddexp(0.0, (u - self.knee) / self.width)
        down = self.width * np.logaddexp(0.0, (-u - self.knee) / self.width) if self.both else 0.0
        return float(-self.k * self.top * (up - down))


def _stop_apply(fx, s, shape, ctx):
    lo, hi = ctx["ref"]["x"]
    top = max(abs(lo), abs(hi))
    both = min(abs(lo), abs(hi)) > 0.5 * top
    fx.force = _Stop(s * ctx["p"]["K"], top, shape["knee"], shape["width"], both)


def _creep(kind):
    """Creep cells in the field domain (both physics keep them in ``Effects.creep``)."""

    def apply(fx, s, shape, ctx):
        fx.creep.extend(creep_cells(kind, s, shape, ctx["T"]))

    return _creep_shape(kind), apply


def _no_shape(rng, ctx):
    return {}


def _series_r_apply(fx, s, shape, ctx):
    fx.series_R = (s - 1.0) * ctx["p"]["Re"]


def _series_rl_shape(rng, ctx):
    return {"r": rng.uniform(0.0, 3.0)}


def _series_rl_apply(fx, s, shape, ctx):
    fx.L = s
    fx.series_R = shape["r"] * ctx["p"]["Re"]


def _amp_pole_apply(fx, s, shape, ctx):
    fx.amp_tau = s


def _mode_shape(rng, ctx):
    """A structural mode between 1.5 kHz (above the actuator's own) and 0.42 fs (<= 6 kHz)."""
    top = min(0.42 * ctx["fs"], 6000.0)
    return {"f": rng.uniform(min(1500.0, 0.8 * top), top), "zeta": loguniform(rng, 0.01, 0.08)}


def _shell_apply(fx, s, shape, ctx):
    M = ctx["p"]["M"]
    m1, m2 = s * M, (1 - s) * M
    k2 = (2 * np.pi * shape["f"]) ** 2 / (1 / m1 + 1 / m2)
    fx.mode = ("shell", {"mu": s, "k2": k2, "c2": 2 * shape["zeta"] * math.sqrt(k2 * m1 * m2 / M)})


def _frame_apply(fx, s, shape, ctx):
    kb = ctx["p"]["K"] / s
    mb = kb / (2 * np.pi * shape["f"]) ** 2
    fx.mode = ("frame", {"kb": kb, "mb": mb, "cb": 2 * shape["zeta"] * math.sqrt(kb * mb)})


def _sensor_apply(fx, s, shape, ctx):
    fx.mode = ("sensor", {"gamma": s, "omega": 2 * np.pi * shape["f"], "zeta": shape["zeta"]})


def _shared(field_hysteresis, slip_apply, saturation):
    """The mechanisms both physics have, with the same strength ranges."""
    out = [Mechanism("hysteresis", n, 0.06, 0.25, *field_hysteresis(n)) for n in ("preisach", "bouc-wen", "duhem")]
    out.append(Mechanism("hysteresis", "maxwell-slip", 0.05, 0.6, _slip_shape, slip_apply))
    out.append(Mechanism("creep", "log-time", 0.005, 0.03, *_creep("log-time")))
    out += [Mechanism("creep", n, 0.02, 0.12, *_creep(n)) for n in ("fractional", "kv-cells")]
    out += [Mechanism("saturation", n, 0.03, 0.2, *saturation(n)) for n in ("tanh", "polynomial", "piecewise")]
    return out


def _stack_mechanisms():
    out = _shared(_stack_field_hysteresis, _stack_slip_apply, _stack_saturation)
    out.append(Mechanism("saturation", "stop", 0.1, 0.8, _stop_shape, _stop_apply))
    out.append(Mechanism("electrical", "series-r", 10.0, 200.0, _no_shape, _series_r_apply))
    out.append(Mechanism("electrical", "series-rl", 5e-5, 2e-3, _series_rl_shape, _series_rl_apply))
    out.append(Mechanism("electrical", "amp-pole", 3.2e-5, 1e-3, _no_shape, _amp_pole_apply))
    out.append(Mechanism("higher-mode", "shell", 0.05, 0.5, _mode_shape, _shell_apply))
    out.append(Mechanism("higher-mode", "frame", 0.02, 0.5, _mode_shape, _frame_apply))
    out.append(Mechanism("higher-mode", "sensor", 0.1, 1.0, _mode_shape, _sensor_apply))
    return out


# ----------------------------------------------------------------------------- bimorphs


def _bim_input_hysteresis(name):
    def apply(fx, s, shape, ctx):
        c, half = _centre_half(ctx["ref"]["V"])
        op, w = shape["op"], hysteretic_weight(s, shape)

        def drive_map(V):
            h_ = op.apply((V - c) / half)
            return V + w * half * (h_ - h_[0])

        fx.drive_map = drive_map

    return _hysteresis_shape(name), apply


class _ModalSlip:
    """Maxwell-slip friction on mode 1 (clamp / bond-layer friction): -k half MS((q1 - c)/half)."""

    def __init__(self, k, op, centre, half, n):
        self.law = FieldLaw(-k, op, centre, half)
        self.n = n

    def reset(self):
        self.law.reset()

    def __call__(self, q, qd, v):
        f = np.zeros(self.n)
        f[0] = self.law(q[0])
        return f


def _bim_slip_apply(fx, s, shape, ctx):
    c, half = _centre_half(ctx["ref"]["q1"])
    fx.modal.append(_ModalSlip(s * ctx["p"]["omega"][0] ** 2, shape["op"], c, half, len(ctx["p"]["omega"])))


def _bim_saturation(name):
    def shape(rng, ctx):
        return {"deficit": saturation_curve(name, rng)}

    def apply(fx, s, shape, ctx):
        top = max(abs(v) for v in ctx["ref"]["V"])
        deficit = shape["deficit"]

        def drive_map(V):
            return V + s * top * deficit(V / top)

        fx.drive_map = drive_map

    return shape, apply


def _qref(ctx):
    lo, hi = ctx["ref"]["q1"]
    return max(abs(lo), abs(hi), 1e-30)


def _softening(name):
    def shape(rng, ctx):
        return {"r": rng.uniform(0.2, 0.8)}

    def apply(fx, s, shape, ctx):
        p = ctx["p"]
        n, w1, phi = len(p["omega"]), p["omega"][0], np.asarray(p["phi"])
        qr = _qref(ctx)
        vmax = max(abs(v) for v in ctx["ref"]["V"])
        r = shape["r"]

        def law(q, qd, v):
            f = np.zeros(n)
            if name == "cubic":
                f[0] = s * w1 * w1 * q[0] ** 3 / qr**2
            elif name == "cubic-quintic":
                a = q[0] / qr
                f[0] = s * w1 * w1 * qr * ((1 + r) * a**3 - r * a**5)
            elif name == "tip-cubic":
                w = float(phi @ q)
                f = phi * (s * w1 * w1 / (phi[0] ** 2 * (phi[0] * qr) ** 2)) * w**3
            else:  # field-stiffness: the stiffness drops with the drive field (k_a(E))
                f[0] = s * w1 * w1 * abs(v) / vmax * q[0]
            return f

        fx.modal.append(law)

    return shape, apply


def _damping(name):
    def shape(rng, ctx):
        return {"m": rng.uniform(1.0, 2.0)}

    def apply(fx, s, shape, ctx):
        p = ctx["p"]
        n, w1, z1, phi = len(p["omega"]), p["omega"][0], p["zeta"][0], np.asarray(p["phi"])
        qr = _qref(ctx)
        vref = max(abs(v) for v in ctx["ref"]["vel"]) or 1e-30
        c1 = 2 * z1 * w1
        m = shape["m"]

        def law(q, qd, v):
            if name == "quadratic":
                w = float(phi @ qd)
                return -phi * (s * c1 / (phi[0] ** 2 * vref)) * abs(w) * w
            if name == "friction":
                w = float(phi @ qd)
                return -phi * (s * c1 * vref / phi[0] ** 2) * math.tanh(w / (0.05 * vref))
            f = np.zeros(n)
            amp = math.sqrt(q[0] ** 2 + (qd[0] / w1) ** 2)
            f[0] = -c1 * s * (amp / qr) ** m * qd[0]
            return f

        fx.modal.append(law)

    return shape, apply


def _next_beam_mode(ctx):
    """Angular frequency of the first beam mode the device's model leaves out."""
    w_ratio, _, _ = bim.cantilever_ratios(len(ctx["p"]["omega"]) + 1, ctx["target"])
    return ctx["p"]["omega"][0] * w_ratio


def _below_nyquist(omega, ctx):
    return omega < 2 * np.pi * 0.4 * ctx["fs"]


def _beam_shape(rng, ctx):
    return {"jitter": rng.uniform(0.95, 1.05), "zeta": loguniform(rng, 0.005, 0.08)}


def _beam_apply(fx, s, shape, ctx):
    p = ctx["p"]
    k = len(p["omega"]) + 1
    w_ratio, slope, at = bim.cantilever_ratios(k, ctx["target"])
    omega = p["omega"][0] * w_ratio * shape["jitter"]
    mp = p["mp"][0] * abs(slope) * s * np.sign(slope * at)
    fx.extra_modes.append((omega, shape["zeta"], mp, p["phi"][0] * abs(at)))


def _offbeam_shape(rng, ctx):
    top = 2 * np.pi * 0.42 * ctx["fs"]
    lo = 1.3 * max(ctx["p"]["omega"])
    return {
        "omega": loguniform(rng, lo, max(top, lo * 1.1)),
        "zeta": loguniform(rng, 0.005, 0.05),
        "sign": float(rng.choice([-1.0, 1.0])),
    }


def _offbeam_apply(fx, s, shape, ctx):
    p = ctx["p"]
    g1 = p["mp"][0] * p["phi"][0] / p["omega"][0] ** 2  # mode 1 static compliance
    mp = shape["sign"] * s * g1 * shape["omega"] ** 2 / p["phi"][0]
    fx.extra_modes.append((shape["omega"], shape["zeta"], mp, p["phi"][0]))


def _fixture_shape(rng, ctx):
    top = 2 * np.pi * 0.42 * ctx["fs"]
    lo = 1.3 * ctx["p"]["omega"][0]
    return {"omega": loguniform(rng, lo, max(top, lo * 1.1)), "zeta": loguniform(rng, 0.01, 0.06)}


def _fixture_apply(fx, s, shape, ctx):
    fx.sensor_mode = {"gamma": s, "omega": shape["omega"], "zeta": shape["zeta"]}


def _bimorph_mechanisms():
    out = _shared(_bim_input_hysteresis, _bim_slip_apply, _bim_saturation)
    for name in ("cubic", "cubic-quintic", "tip-cubic", "field-stiffness"):
        out.append(Mechanism("softening", name, 0.01, 0.12, *_softening(name)))
    for name in ("quadratic", "amplitude", "friction"):
        out.append(Mechanism("nonlinear-damping", name, 0.2, 3.0, *_damping(name)))
    out.append(
        Mechanism(
            "higher-mode",
            "beam",
            0.5,
            2.0,
            _beam_shape,
            _beam_apply,
            lambda ctx: _below_nyquist(1.05 * _next_beam_mode(ctx), ctx),
        )
    )
    out.append(
        Mechanism(
            "higher-mode",
            "offbeam",
            0.005,
            0.1,
            _offbeam_shape,
            _offbeam_apply,
            lambda ctx: _below_nyquist(1.5 * max(ctx["p"]["omega"]), ctx),
        )
    )
    out.append(
        Mechanism(
            "higher-mode",
            "fixture",
            0.1,
            1.0,
            _fixture_shape,
            _fixture_apply,
            lambda ctx: _below_nyquist(1.5 * ctx["p"]["omega"][0], ctx),
        )
    )
    return out


def _index(mechs):
    out: dict = {}
    for m in mechs:
        out.setdefault(m.cause, {})[m.name] = m
    return out


#: {physics: {cause: {mechanism name: Mechanism}}}
MECHANISMS = {"stack": _index(_stack_mechanisms()), "bimorph": _index(_bimorph_mechanisms())}
