"""Defaults in one place: the tolerances, thresholds and limits the framework reads at call time.

    from bondgraph import config
    config.get("simulate.rtol")                       # 1e-06
    config.set("diagnosis.min_gain", 1.5)             # until reset
    with config.override({"simulate.rtol": 1e-9}):    # for a block only
        ...
    config.reset()                                    # every value back to its default
    config.describe()                                 # name, value, default, meaning of each

Names are ``section.key``; each section belongs to one module, which reads its values with
:func:`get` when it needs them (never at import), so a change takes effect on the next call.
Worker processes receive a :func:`snapshot` and :func:`restore` it.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any, Iterator, Mapping

from .errors import UsageError, did_you_mean


@dataclass(frozen=True)
class Default:
    """A documented default value."""

    value: Any
    doc: str


DEFAULTS: dict[str, Default] = {
    "simulate.rtol": Default(1e-6, "relative tolerance of the integrators"),
    "simulate.atol_floor": Default(
        1e-20, "absolute tolerance floor; the error is otherwise relative to each state's peak"
    ),
    "simulate.table_steps": Default(10, "no step spans more than this many sample intervals of a tabulated input"),
    "simulate.max_steps": Default(50_000_000, "a run stops with an error after this many integrator steps"),
    "simulate.explicit_step_limit": Default(
        3e6,
        "method 'auto' picks the implicit route when the explicit method would need more "
        "steps than this (from the start-point Jacobian's spectral radius), whatever the output's band",
    ),
    "simulate.stiff_ratio": Default(
        10.0,
        "method 'auto' takes a model as stiff when the start-point Jacobian's spectral radius "
        "exceeds the output's Nyquist frequency (pi/dt, rad/s) by this factor ...",
    ),
    "simulate.stiff_min_steps": Default(
        1e5,
        "... and the explicit method would need more steps than this at its stability limit "
        "(below, the explicit method is quick anyway)",
    ),
    "record.start": Default(
        "steady",
        "where a model run against a measured record (fit, diagnose, compensate, simulate "
        "with a csv drive) starts: "
        "'steady', the equilibrium with the drive held at the record's first value (memory "
        "operators at rest), or 'rest', the model's declared initial state x0",
    ),
    "jacobian.hub_support": Default(
        16,
        "a program variable whose gradient reaches more states than this (a node shared by many "
        "parts) stays an unknown of the sparse Jacobian instead of being substituted",
    ),
    "batch.connect_timeout": Default(10.0, "seconds to wait for the Dask scheduler named by --scheduler"),
    "batch.tasks_per_worker": Default(
        4, "short jobs (simulations) are grouped into about this many Dask tasks per worker"
    ),
    "batch.max_jobs_per_task": Default(32, "at most this many short jobs in one Dask task"),
    "causality.max_attempts": Default(
        100_000,
        "causality assignment gives up after this many revised choices "
        "in one part of the graph (reported as an error naming its elements)",
    ),
    "units.check": Default(
        True,
        "check the units of every equation when equations are derived (an inconsistency is an "
        "error naming the element); bondgraph check prints the result",
    ),
    "codegen.tape_threshold": Default(
        300,
        "programs with more statements run on the tape interpreter instead of being compiled by numba per model "
        "(numba takes about 7.6 ms per statement, 2.3 s here, once per model structure; the tape is 7-8 times "
        "slower per call, which matters to long explicit runs, not to the implicit route's few thousand calls)",
    ),
    "data.uniform_rtol": Default(
        1e-2,
        "sampling is uniform when every time step is within this fraction of the "
        "mean step (absorbs time stamps printed with few digits)",
    ),
    "data.suspicious_time_span": Default(
        1e4,
        "a record with steps of 1 s or more spanning this many seconds "
        "draws a warning that 't' may be in ms or sample numbers",
    ),
    # diagnosis (bondgraph.diagnosis): what counts as evidence; see that package's docstring
    "diagnosis.spread": Default(
        10.0,
        "linear parameters are calibrated within x/÷ this factor of the model's "
        "values (and their declared bounds); the sensor gain is free",
    ),
    "diagnosis.tolerance": Default(
        2.0,
        "a plausible device has its linear parameters within x/÷ this factor of the "
        "model's values (a model file's TOLERANCE may set others per parameter); "
        "linear structural causes are fitted within it and must beat it",
    ),
    "diagnosis.identifiable": Default(
        1e-3,
        "a linear parameter is calibrated only if its pivot in the normalised "
        "sensitivity matrix (pivoted QR) is at least this share of the largest",
    ),
    "diagnosis.tolerance_z": Default(
        3.0,
        "a parameter held by that rule is calibrated after all when a change "
        "across its tolerance moves the output, beyond "
        "what the calibrated ones can, by this many times the calibrated model's "
        "residual RMS (at least the noise floor's)",
    ),
    "diagnosis.residual_share": Default(
        0.2,
        "a parameter held by that rule is calibrated after all when its "
        "sensitivity alone explains this share of the calibrated model's residual "
        "energy (with a step within the spread)",
    ),
    "diagnosis.fast_factor": Default(
        10.0,
        "modes faster than this many times the data's Nyquist frequency are "
        "residualised (replaced by their static contribution and the lag term)",
    ),
    "diagnosis.decimate_margin": Default(
        8.0,
        "records are decimated while the new Nyquist frequency stays this many "
        "times above the drive's band (and 1.25 times above the band where the "
        "output stands above its noise floor)",
    ),
    "diagnosis.min_z": Default(
        3.0,
        "a cause must lower the squared validation error by this many standard errors "
        "(effective sample size from the residuals' autocorrelation)",
    ),
    "diagnosis.min_gain": Default(1.1, "a cause must lower the validation RMS by at least this factor"),
    "diagnosis.min_gain_chain": Default(
        1.2,
        "... and by this factor in a chain step after the first (what the named "
        "extension left holds its own imperfection)",
    ),
    "diagnosis.min_gain_reference": Default(
        1.05,
        "a nonlinear or memory cause must beat the flexible linear "
        "reference by this factor (both with the reference's freedom)",
    ),
    "diagnosis.min_z_reference": Default(
        2.0, "... and by this many standard errors (a second-stage test, after min_z against the calibrated model)"
    ),
    "diagnosis.linear_share": Default(
        0.7,
        "a linear structural cause must explain this share of what the flexible "
        "linear reference explains over the calibrated model",
    ),
    "diagnosis.equivalent": Default(
        1.05,
        "passing candidates whose validation RMS is within this factor of the "
        "best's, and their gain over the flexible linear "
        "reference too, are equivalent: the one with the fewest new parameters is named",
    ),
    "diagnosis.reference_poles": Default(
        6, "real poles of the flexible linear reference, spread over the record's time scales"
    ),
    "diagnosis.max_chain": Default(3, "most causes named in one diagnosis (compound effects)"),
    "diagnosis.check_max_steps": Default(
        2_000_000,
        "integrator steps allowed to the second route (the extended "
        "model integrated as a check); beyond, the check is skipped",
    ),
    "diagnosis.candidate_seconds": Default(
        60.0,
        "a candidate's fits stop at their best point after this many seconds "
        "(reported as not converged), within a simulation on the stiff "
        "integrators too",
    ),
    "diagnosis.chain_seconds": Default(
        180.0,
        "no further chain step is started once the diagnosis has run this "
        "many seconds (the report says so): every record is answered in "
        "minutes",
    ),
    "diagnosis.candidate_limit": Default(
        180.0,
        "every simulation of a candidate stops after this many seconds from "
        "its start, its first optimiser evaluation and final prediction "
        "included: the candidate is then reported as failed",
    ),
    "diagnosis.max_fit_points": Default(20000, "samples of the fit part used by the optimisers (evenly thinned)"),
    "diagnosis.confirm_margin": Default(
        1.0,
        "a candidate whose gain passes but whose z falls short of min_z by less "
        "than this is fitted on a second fold (other validation blocks) and "
        "judged on the two folds' combined z",
    ),
    "diagnosis.confirm_max": Default(2, "most candidates per chain step fitted on the second fold"),
    "diagnosis.polish_margin": Default(
        1.5,
        "passing candidates within this factor of the best's gain over the "
        "flexible linear reference, when one of them stopped before its optimiser "
        "converged, are fitted again with polish_effort times the evaluations "
        "before one is named (a race decided by converged fits, not by which "
        "optimiser got further)",
    ),
    "diagnosis.min_coherence": Default(
        0.05,
        "a record whose output has less coherence with the drive than this, where the drive "
        "has power (bias removed), is refused: the output does not follow the drive",
    ),
    "diagnosis.screen_keep": Default(
        6,
        "when more candidates than this can say what they explain to first order (a "
        "law term at a site), only this many, those explaining most, are fitted in full",
    ),
    "diagnosis.screen_chance": Default(
        0.05,
        "a candidate whose first-order share of the residual unrelated columns reach "
        "with more than this probability (the residual's and the columns' "
        "autocorrelation taken into account) is not fitted in full",
    ),
    "diagnosis.drift_noise": Default(
        3.0,
        "when no cause is named, a slow drift of the output (a smooth curve in time, with "
        "the sensor drift the calibration solved) is named when it passes the rules a cause "
        "must and its RMS is at least this many times the noise floor",
    ),
    "diagnosis.screen_effort": Default(
        0.3,
        "factor on the optimisers' budgets of the chain's later steps "
        "(after the first cause): candidates are screened with it, and those "
        "gaining screen_gain or more are fitted again with the full budget "
        "(1: every candidate with the full budget)",
    ),
    "diagnosis.screen_gain": Default(
        1.05,
        "a screened candidate gaining at least this much is fitted again with "
        "the full budget before its step is judged",
    ),
    "diagnosis.polish_effort": Default(
        10.0,
        "factor on every optimiser's evaluation budget when a race is polished, and on the "
        "calibration's when it stops before converging",
    ),
    "diagnosis.reading_gap": Default(
        0.5,
        "when the two readings of the drive between its samples (band-limited, "
        "linear) change the calibrated model's output by more than this share "
        "of the noise floor (RMS; where the drive leaves no quiet band, the "
        "floor of the calibrated model's residual spectrum), its first step is taken under both and "
        "the better one's chain goes on",
    ),
    "diagnosis.drift": Default(
        False,
        "solve a linear sensor drift (output units per second) with the calibration and "
        "remove it from the record before any effect is sought: a thermal or "
        "sensor drift must not pass for creep or an opening loop (off: a drift is "
        "still solved when a straight line explains the record as well as the "
        "first cause found)",
    ),
    "diagnosis.blocks": Default(
        30,
        "equal time blocks of the record; the validation share of them, spread evenly, "
        "is held out (each is at least one batch of the significance test)",
    ),
    "diagnosis.sweep_blocks": Default(
        60,
        "blocks instead when the drive sweeps its frequency (a chirp): shorter "
        "blocks, so that the fit part brackets every frequency the validation "
        "part holds and a resonance passage is neither fitted only nor held out "
        "only",
    ),
    "diagnosis.sweep_ratio": Default(
        8.0,
        "the drive sweeps when the mean frequency of its blocks rises (or falls) "
        "steadily over the record by at least this factor",
    ),
}

_values: dict[str, Any] = {k: d.value for k, d in DEFAULTS.items()}


def _check(name: str) -> None:
    if name not in DEFAULTS:
        raise UsageError(f"config: {did_you_mean(name, DEFAULTS, 'setting')}")


def get(name: str) -> Any:
    """The current value of setting ``name``."""
    _check(name)
    return _values[name]


def set(name: str, value: Any) -> None:  # noqa: A001 - the natural verb here
    """Change setting ``name`` until :func:`reset`; the type must match the default's."""
    _check(name)
    default = DEFAULTS[name].value
    if isinstance(default, (int, float)) and not isinstance(default, bool):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise UsageError(f"config: {name} must be a number, got {value!r}")
        value = type(default)(value) if isinstance(default, float) else value
    elif not isinstance(value, type(default)):
        raise UsageError(f"config: {name} must be a {type(default).__name__}, got {value!r}")
    _values[name] = value


def reset(name: str | None = None) -> None:
    """Back to the default: one setting, or all of them."""
    if name is None:
        _values.clear()
        _values.update({k: d.value for k, d in DEFAULTS.items()})
    else:
        _check(name)
        _values[name] = DEFAULTS[name].value


@contextlib.contextmanager
def override(values: Mapping[str, Any]) -> Iterator[None]:
    """Set ``values`` for the duration of a ``with`` block."""
    saved = snapshot()
    try:
        for k, v in values.items():
            set(k, v)
        yield
    finally:
        restore(saved)


def snapshot() -> dict[str, Any]:
    """Every current value (to hand to a worker process)."""
    return dict(_values)


def restore(values: Mapping[str, Any]) -> None:
    """Install values taken by :func:`snapshot`."""
    for k in values:
        _check(k)
    _values.clear()
    _values.update({k: d.value for k, d in DEFAULTS.items()})
    _values.update(values)


def describe() -> list[dict]:
    """name, value, default and meaning of every setting."""
    return [{"name": k, "value": _values[k], "default": d.value, "doc": d.doc} for k, d in DEFAULTS.items()]
