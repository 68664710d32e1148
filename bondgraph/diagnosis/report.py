"""The diagnosis report: candidates and verdicts of every chain step, the named causes, and
how the data were treated (readable text and JSON)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .candidate import LINEAR
from .settings import Settings


@dataclass
class CandidateResult:
    """One candidate's outcome in one chain step (RMS in output units, on the validation part).

    A gain is an RMS ratio, before over after (> 1: the candidate explains something); a z is
    the significance of a paired comparison of validation errors
    (:func:`bondgraph.diagnosis.decision.compare`).

    Parameters
    ----------
    cause : str
        The cause it stands for (e.g. "hysteresis").
    label : str
        A short description of the extension.
    kind : {"nonlinear", "linear"}, optional
        The kind of cause (:data:`NONLINEAR`, :data:`LINEAR`).
    site : str, optional
        Where it acts: an element site, "output", or "" for the drive.
    gain : float, optional
        Validation RMS before over after the candidate.
    rms_fit : float, optional
        RMS error on the fit part, output units.
    rms_validation : float, optional
        RMS error on the validation part, output units.
    z : float, optional
        Significance of the gain.
    n_eff : float, optional
        Effective number of independent batches of the comparison.
    gain_reference : float, optional
        Gain over the flexible linear reference.
    z_reference : float, optional
        Significance of ``gain_reference``.
    share : float, optional
        Share of what the flexible linear reference explains that the candidate explains.
    n_params : int, optional
        Number of new parameters.
    params : dict, optional
        The new parameters' fitted values, by name.
    evidence : dict, optional
        Numbers that speak for the cause (:meth:`Candidate.evidence`).
    at_bounds : list, optional
        Parameters that ended on a search bound.
    success : bool, optional
        The optimiser's success flag.
    message : str, optional
        The optimiser's message.
    skipped : str, optional
        Why it was not fitted ("" when it was).
    error : str, optional
        Why its fit failed ("" when it did not).
    verdict : str, optional
        The decision in words.
    rule : str, optional
        The name of the rule that refused it ("" when it passed or was not judged).
    passed : bool, optional
        Whether it passed every rule.
    seconds : float, optional
        Wall time of its fit, s.
    against : str, optional
        "plausible" when fitted from, and compared with, the plausible device.
    implausible : str, optional
        For a linear cause, why its values are physically implausible ("" if not).
    recalibration : str, optional
        For a linear cause, why it may be a recalibration of the model's own structure.
    need_share : float, optional
        For a linear cause, the share of the reference's gain it must explain (None: the
        setting ``diagnosis.linear_share``).
    gain_static : float, optional
        For a memory effect, its gain over the same freedom without memory.
    z_second : float, optional
        z on a second fold, when the first was borderline.
    effort : float, optional
        The factor on its optimisers' evaluation budgets.
    """

    cause: str
    label: str
    kind: str = "nonlinear"
    #: where it acts: an element site (an element, a role, ``*.<local name>``), "output", or
    #: "" for the drive
    site: str = ""
    gain: float = 0.0
    rms_fit: float = math.inf
    rms_validation: float = math.inf
    z: float = 0.0
    n_eff: float = 0.0
    gain_reference: float | None = None
    z_reference: float | None = None
    share: float | None = None
    n_params: int = 0
    params: dict = field(default_factory=dict)
    evidence: dict = field(default_factory=dict)
    at_bounds: list = field(default_factory=list)
    success: bool = True
    message: str = ""
    skipped: str = ""
    error: str = ""
    verdict: str = ""
    #: the name of the rule that refused it ('' when it passed or was not judged)
    rule: str = ""
    passed: bool = False
    seconds: float = 0.0
    #: "plausible" when fitted from, and compared with, the plausible device (the calibration
    #: within tolerance) instead of the null
    against: str = ""
    #: for a linear cause, why its fitted values are physically implausible ('' if they are not)
    implausible: str = ""
    #: for a linear cause, why it may be a recalibration of the model's own structure ('' if
    #: not): it must then beat the flexible linear reference too
    recalibration: str = ""
    #: for a linear cause, the share of the reference's gain it must explain (None: the setting)
    need_share: float | None = None
    #: for a memory effect, its gain over the same freedom without memory (a static curve)
    gain_static: float | None = None
    #: z on a second fold (other validation blocks), when the first was borderline; ``z`` is
    #: then the two folds' combined z
    z_second: float | None = None
    #: the factor on its optimisers' evaluation budgets (above 1 when it was fitted again
    #: because it stopped before converging in a close race)
    effort: float = 1.0

    def as_json(self) -> dict:
        """The result as a JSON object (the ``candidates`` entries of :meth:`Report.as_json`).

        Returns
        -------
        dict
            The fields by name (``site`` "drive" for the drive; optional fields only when set,
            ``seconds`` rounded to 0.01 s).
        """
        out = {
            "cause": self.cause,
            "site": self.site or "drive",
            "label": self.label,
            "kind": self.kind,
            "gain": self.gain,
            "rms_fit": self.rms_fit,
            "rms_validation": self.rms_validation,
            "z": self.z,
            "n_eff": self.n_eff,
            "gain_reference": self.gain_reference,
            "z_reference": self.z_reference,
            "share": self.share,
            "n_params": self.n_params,
            "params": self.params,
            "evidence": self.evidence,
            "at_bounds": self.at_bounds,
            "success": self.success,
            "message": self.message,
            "passed": self.passed,
            "verdict": self.verdict,
            "rule": self.rule,
            "seconds": round(self.seconds, 2),
        }
        if self.against:
            out["against"] = self.against
        if self.gain_static is not None:
            out["gain_static"] = self.gain_static
        if self.z_second is not None:
            out["z_second"] = self.z_second
        if self.effort != 1.0:
            out["effort"] = self.effort
        if self.skipped:
            out["skipped"] = self.skipped
        if self.error:
            out["error"] = self.error
        return out


@dataclass
class Step:
    """One link of the chain: what was tried on the model so far and what (if anything) won.

    Parameters
    ----------
    cause : str
        The cause named at this step, or "none".
    gain : float
        The winner's validation RMS ratio before over after (1 for none).
    rms_before : float
        Validation RMS of the model the step starts from, output units.
    rms : float
        Validation RMS after the step, output units.
    reference_rms : float
        Validation RMS of the flexible linear reference, output units.
    candidates : list of CandidateResult
        Every candidate tried, with its verdict.
    why : str
        Why this cause was named, or why none was.
    site : str, optional
        Where the named cause acts ("" for none or the drive).
    label : str, optional
        The named candidate's label.
    rule : str, optional
        The rule that decided the step.
    winner : CandidateResult, optional
        The named candidate, one of ``candidates`` (None for none).
    """

    cause: str
    gain: float
    rms_before: float
    rms: float
    reference_rms: float
    candidates: list[CandidateResult]
    why: str
    #: where the named cause acts ("" for none)
    site: str = ""
    #: the named candidate's label ("" for none)
    label: str = ""
    #: the rule that decided the step: how the winner was chosen, or for none the rule that
    #: refused the best candidate
    rule: str = ""
    #: the named candidate, one of ``candidates`` (None for none): other passing candidates
    #: may share its cause, label and site, so only this one is marked named
    winner: CandidateResult | None = None

    def as_json(self) -> dict:
        """The step as a JSON object (the ``steps`` entries of :meth:`Report.as_json`).

        Returns
        -------
        dict
            ``cause``, ``site``, ``rule``, ``gain``, ``rms``, ``rms_before``,
            ``reference_rms``, ``why`` and ``candidates`` (:meth:`CandidateResult.as_json`).
        """
        return {
            "cause": self.cause,
            "site": (self.site or "drive") if self.cause != "none" else "",
            "rule": self.rule,
            "gain": self.gain,
            "rms": self.rms,
            "rms_before": self.rms_before,
            "reference_rms": self.reference_rms,
            "why": self.why,
            "candidates": [c.as_json() | ({"named": True} if c is self.winner else {}) for c in self.candidates],
        }


@dataclass
class Report:
    """What a diagnosis found: the causes named in order, every step, the calibration and how
    the data were treated (:meth:`text`, :meth:`as_json`; RMS in output units).

    Parameters
    ----------
    causes : list of str
        The causes named, in the order of the chain (empty: none).
    gain : float
        ``baseline_rms`` over ``extended_rms`` (1 without a cause).
    baseline_rms : float
        Validation RMS of the calibrated model (or of the plausible device, see
        ``baseline``).
    extended_rms : float
        Validation RMS of the model extended with every named cause.
    steps : list of Step
        Every step of the chain, the last one naming none unless the chain was cut.
    calibration : dict
        The calibration as JSON: ``params``, ``route``, ``sensor_gain``, ``offset``,
        ``delay`` (s), ``at_bounds``, ``held``, ``success``, ``message``, ``rms_validation``,
        ``outside_tolerance`` and, where solved, ``drift`` (output units per s).
    data : dict
        How the data were treated: ``file``, ``model``, ``samples``, ``rate_hz``,
        ``source_samples``, ``source_rate_hz``, ``validation_share``, ``blocks``, ``input``,
        ``output``, ``drive_band_hz``, ``drive_reading`` and the readings' gap.
    notes : list of str, optional
        Notes on the data and the decisions.
    equations : str, optional
        The extended model's state equations as text.
    extended_model : Model, optional
        The model extended with the named causes.
    extended_values : dict, optional
        Its parameter values, by name.
    extended_rms_integrated : float, optional
        The extended model's validation RMS from the compiled integrator (a second route).
    predictions : dict, optional
        Series on the (resampled) time grid: ``t`` (s), ``u`` (the drive), ``y`` (measured),
        ``baseline``, ``steps`` and ``extended`` (predictions), for the plots.
    noise : float, optional
        The noise floor's RMS, output units.
    seconds : float, optional
        Wall time of the diagnosis, s.
    baseline : {"calibrated", "plausible"}, optional
        What ``baseline_rms`` and ``gain`` start from.
    account : Account, optional
        What the final model leaves unexplained.
    settings : Settings, optional
        The settings the diagnosis ran with (:meth:`Settings.from_config` when not given).
    """

    causes: list[str]
    gain: float
    baseline_rms: float
    extended_rms: float
    steps: list[Step]
    calibration: dict
    data: dict
    notes: list[str] = field(default_factory=list)
    equations: str = ""
    extended_model: object = None
    extended_values: dict = field(default_factory=dict)
    #: the extended model's validation RMS from the compiled integrator (a second route), if run
    extended_rms_integrated: float | None = None
    predictions: dict = field(default_factory=dict)
    noise: float | None = None
    seconds: float = 0.0
    #: what ``baseline_rms`` and ``gain`` start from: "calibrated" (the free calibration), or
    #: "plausible" when the first cause is a linear structural one fitted on the plausible device
    #: (the calibration within tolerance), whose implausible values it replaces
    baseline: str = "calibrated"
    #: what the final model leaves unexplained (:class:`~bondgraph.diagnosis.account.Account`)
    account: object = None
    settings: Settings = field(default_factory=Settings.from_config)

    @property
    def cause(self) -> str:
        """The first cause named, or "none"."""
        return self.causes[0] if self.causes else "none"

    @property
    def candidates(self) -> list[CandidateResult]:
        """The candidates of the first step (empty without steps)."""
        return self.steps[0].candidates if self.steps else []

    @property
    def unexplained(self) -> str:
        """Why the calibrated device stays implausible: its parameters outside their tolerance
        when no linear structural cause fitted on the plausible device was named to account for
        them ('' otherwise)."""
        outside = self.calibration.get("outside_tolerance") or {}
        if not outside or any(
            s.winner is not None and s.winner.kind == LINEAR and s.winner.against == "plausible" for s in self.steps
        ):
            return ""
        return (
            "the calibration needs "
            + ", ".join(f"{k} ×{v:.3g}" for k, v in outside.items())
            + " of the model's values, beyond their tolerance, and no structural cause explains it: "
            "the model's linear structure may lack something no candidate covers (a mode, a "
            "compliance, a sensor stage), or the device is further from the model file than its "
            "tolerance says"
        )

    def _repr_html_(self) -> str:
        from .display import report_html

        return report_html(self)

    def as_json(self) -> dict:
        """The report as a JSON object (``bondgraph diagnose --json``).

        Returns
        -------
        dict
            ``cause``, ``causes``, ``gain``, ``baseline_rms``, ``baseline``, ``extended_rms``,
            ``candidates`` (first step), ``steps`` (those naming a cause), ``why``, ``stop``
            (the last step naming none), ``site``, the unexplained account (or
            ``noise_rms``), ``extended_rms_integrated``, ``calibration``, ``unexplained``,
            ``data``, ``notes``, ``criterion`` (the decision thresholds), ``seconds`` and
            ``equations``.
        """
        steps = [s for s in self.steps if s.cause != "none"]
        return {
            "cause": self.cause,
            "causes": list(self.causes),
            "gain": self.gain,
            "baseline_rms": self.baseline_rms,
            "baseline": self.baseline,
            "extended_rms": self.extended_rms,
            "candidates": self.steps[0].as_json()["candidates"] if self.steps else [],
            "steps": [s.as_json() for s in steps],
            "why": self.steps[-1].why if self.steps else "",
            "stop": self.steps[-1].as_json() if self.steps and self.steps[-1].cause == "none" else None,
            "site": (steps[0].site or "drive") if steps else "",
            **(self.account.as_json() if self.account is not None else {"noise_rms": self.noise}),
            "extended_rms_integrated": self.extended_rms_integrated,
            "calibration": self.calibration,
            "unexplained": self.unexplained,
            "data": self.data,
            "notes": self.notes,
            "criterion": {
                k: getattr(self.settings, k)
                for k in (
                    "min_z",
                    "min_gain",
                    "min_gain_chain",
                    "min_gain_reference",
                    "min_z_reference",
                    "linear_share",
                    "spread",
                )
            },
            "seconds": round(self.seconds, 1),
            "equations": self.equations,
        }

    def chain_text(self) -> str:
        """The named causes with their sites and step gains (``none`` without one).

        Returns
        -------
        str
            E.g. ``hysteresis at the drive (×2.1) → creep at the drive (×1.3)``.
        """
        named = [s for s in self.steps if s.cause != "none"]
        if not named:
            return "none"
        return " → ".join(f"{s.cause} at {s.site or 'the drive'} (×{s.gain:.3g})" for s in named)

    def summary_lines(self) -> list[str]:
        """The answer: causes, gain, what stays unexplained, why the chain stopped (a screen).

        Returns
        -------
        list of str
            The lines, without line ends.
        """
        d = self.data
        lines = [f"Diagnosis of {d.get('model', '')} against {d.get('file', '')}", f"  Causes: {self.chain_text()}"]
        base = "" if self.baseline == "calibrated" else " of the plausible device"
        if self.causes:
            lines.append(
                f"  Gain: {self.gain:.3g} (validation RMS{base} {self.baseline_rms:.4g} → {self.extended_rms:.4g})"
            )
        else:
            lines.append(f"  Calibrated model validation RMS: {self.baseline_rms:.4g}")
        if self.account is not None:
            lines.append(f"  Unexplained: {self.account.sentence(bool(self.causes))}")
        if self.steps:
            last = self.steps[-1]
            lines.append(f"  Decided by rule '{last.rule}': {last.why}" if last.rule else f"  Decided: {last.why}")
        if self.unexplained:
            lines.append(f"  NOTE: {self.unexplained}")
        lines += [f"  note: {n}" for n in self.notes]
        return [ln for ln in lines if ln]

    def text(self, equations: bool = False, debug: bool = False) -> str:
        """The readable report: the answer first (:meth:`summary_lines`), then how the data were
        treated, every chain step's candidates and verdicts, and with ``equations`` the extended
        model's state equations.  A candidate that raised an error is a defect of that
        candidate, not a verdict on the data: it is listed in one line per step, its error
        only with ``debug`` (the JSON always has it).

        Parameters
        ----------
        equations : bool, optional
            Append the extended model's state equations.
        debug : bool, optional
            Give the errors of candidates that failed.

        Returns
        -------
        str
            The report, lines joined by newlines.
        """
        d, cal = self.data, self.calibration
        lines = self.summary_lines() + [
            "",
            "Data and calibration",
            f"  {d['samples']} samples at {d['rate_hz']:.6g} Hz"
            + (
                f" (from {d['source_samples']} at {d['source_rate_hz']:.6g} Hz)"
                if d.get("source_samples") != d["samples"]
                else ""
            )
            + f", validation {d['validation_share']:.0%} of "
            + (f"{d['blocks']} " if d.get("blocks") else "")
            + "interleaved time blocks held out",
        ]
        free = ", ".join(
            f"{k} = {v:.5g}" + (" (AT BOUND)" if k in cal["at_bounds"] else "") for k, v in cal["params"].items()
        )
        lines.append(
            f"  calibrated ({cal['route']}): {free or 'no model parameter'}; sensor gain "
            f"{cal['sensor_gain']:.5g}, offset {cal['offset']:.4g}, output delay {cal.get('delay', 0.0):.3g} s"
            + (
                f"; sensor drift {cal['drift']:.4g} per s (removed from the record)"
                if cal.get("drift") is not None
                else ""
            )
        )
        if cal.get("outside_tolerance"):
            lines.append(
                "  outside their tolerance (an implausible device unless a structural cause explains it): "
                + ", ".join(f"{k} ×{v:.3g}" for k, v in cal["outside_tolerance"].items())
                + (
                    f"; the plausible device's validation RMS {cal['rms_plausible']:.4g}"
                    if cal.get("rms_plausible") is not None
                    else ""
                )
            )
        for k, why in cal["held"].items():
            lines.append(f"  held at the model's value: {k} ({why})")
        if cal["at_bounds"]:
            lines.append(
                f"  WARNING: {', '.join(cal['at_bounds'])} ended on the search bound "
                f"(×/÷{self.settings.spread:g} of the model's value): the device is "
                f"further from the model file than calibration allows"
            )
        if not cal["success"]:
            lines.append(f"  WARNING: calibration did not converge ({cal['message']})")
        if self.account is not None:
            lines.append(
                f"  noise floor {self.account.noise_rms:.3g} ({self.account.noise_source}); calibrated model "
                f"validation RMS {cal['rms_validation']:.4g}"
            )
        named: list[str] = []
        for k, s in enumerate(self.steps, 1):
            lines += [
                "",
                f"Step {k}: on the model "
                + (" + ".join(["calibrated"] + named))
                + f" (validation RMS {s.rms_before:.4g}; flexible linear reference {s.reference_rms:.4g})",
                f"  {'cause':<18} {'site':<12} {'gain':>7} {'val. RMS':>10} {'z':>6} {'vs ref':>7}  verdict / extension",
            ]
            tried = [c for c in s.candidates if not c.skipped and not c.error]
            for c in sorted(tried, key=lambda c: -c.gain):
                site = c.site or "drive"
                vr = f"{c.gain_reference:.3g}" if c.gain_reference is not None else "-"
                flag = ("" if c.success else " [optimiser: not converged]") + (
                    f" [fitted again, {c.effort:g}× the evaluations]"
                    if c.effort > 1.0
                    else f" [screened, {c.effort:g}× the evaluations]"
                    if c.effort < 1.0
                    else ""
                )
                won = c is s.winner
                lines.append(
                    f"  {c.cause:<18} {site:<12} {c.gain:>7.3g} {c.rms_validation:>10.4g} {c.z:>6.1f} {vr:>7}  "
                    f"{'NAMED' if won else c.verdict}; {c.label}{flag}"
                )
            skipped = [c for c in s.candidates if c.skipped]
            if skipped:
                lines.append(f"  not fitted: {len(skipped)} (" + "; ".join(_grouped(skipped)) + ")")
            failed = [c for c in s.candidates if c.error and not c.skipped]
            if failed:
                lines.append(
                    "  failed (a defect of the candidate, not a verdict on the data): "
                    + (
                        "; ".join(f"{c.cause} at {c.site or 'drive'}: {c.error}" for c in failed)
                        if debug
                        else ", ".join(f"{c.cause} at {c.site or 'drive'}" for c in failed) + " (--debug: the errors)"
                    )
                )
            lines.append(f"  → {s.cause}" + (f" (rule '{s.rule}')" if s.rule else "") + f": {s.why}")
            if s.cause != "none":
                named.append(s.cause)
        if self.extended_rms_integrated is not None:
            lines += ["", f"Extended model integrated: validation RMS {self.extended_rms_integrated:.4g}"]
        if equations and self.equations:
            lines += ["", "Equations of the extended model:", self.equations]
        return "\n".join(lines) + "\n"


def _grouped(skipped: list[CandidateResult]) -> list[str]:
    """Skipped candidates grouped by reason: 'reason: cause at site, ...'."""
    by: dict[str, list[str]] = {}
    for c in skipped:
        reason = c.skipped.split(": explains")[0] if c.skipped.startswith("screened out") else c.skipped
        by.setdefault(reason, []).append(f"{c.cause} at {c.site or 'drive'}")
    return [f"{why}: {', '.join(names)}" for why, names in by.items()]
