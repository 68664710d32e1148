"""Diagnosis: what does the model miss in measured data, and which element fixes it?

    from bondgraph.diagnosis import diagnose
    report = diagnose(model, dataset)          # candidates from the installed entry points
    report.causes, report.gain, report.as_json()

The engine, in order:

1. **Prepare** (:mod:`.context`): resample irregular time stamps; find the drive's band;
   when every mode of the (linear) model is far above the data's Nyquist frequency, replace
   it by its quasi-static contribution and its lag at the data's frequencies (time-scale
   separation, :func:`bondgraph.linear.lti.residualise`; with none left, the static route);
   decimate while the drive's band and the band where the output stands above its noise
   floor stay well below the new Nyquist frequency; estimate
   the noise floor where the drive has no power; read the drive as the band-limited signal it
   was sampled from (its linear interpolation compensated); split into fit and validation
   blocks.  When reading it as linear between its samples instead (a DAC that interpolates,
   a simulation with a first-order hold) changes the calibrated model's output by more than
   ``diagnosis.reading_gap`` of the noise floor, the first step runs under both readings and
   the chain goes on under the one whose first step fits better (the one naming no cause
   when they fit alike).
2. **Calibrate** (:mod:`.calibration`): the null is the best *linear* explanation: every
   identifiable linear parameter, the sensor gain and offset, and the output's delay behind
   the drive when the data separate it.  When that needs values outside the parameters'
   tolerance, the plausible device (within tolerance) is calibrated too.
3. **Try every candidate** (:mod:`.candidate`, run in a :mod:`.pool` of workers): each
   extends the current model through a read-only :class:`View` and returns an
   :class:`Extension`; linear structural candidates start from the plausible device.
4. **Decide** (:mod:`.decision`): paired comparisons of validation errors with the
   residuals' autocorrelation (the effective number of independent batches), against the
   current model refitted from where the candidate left its linear parameters (so that only
   the effect is credited) and against a flexible linear reference, with the thresholds of
   the diagnosis's :class:`Settings` (frozen, read once from ``bondgraph.config``, section
   ``diagnosis``, a keyword beating the default); of equivalent passing candidates the one
   with the fewest parameters is named.
5. **Chain** (:mod:`.engine`): the named cause extends the model; the others are tried
   again on it until none passes (compound effects: e.g. hysteresis, then creep).  Drive-side
   effects that act side by side are kept as one sum whose earlier weights are refitted with
   every later effect (:mod:`.additive`), so a step is credited only with what it adds.
   Time is bounded: a candidate's fits stop at ``diagnosis.candidate_seconds``, its
   simulations at ``diagnosis.candidate_limit``, and no step starts past
   ``diagnosis.chain_seconds``.
6. **Report** (:mod:`.report`): every step, every candidate's verdict, why ``none``.

Candidates are the framework's effect kinds at the model's sites (:mod:`.laws`,
:mod:`.restoring`, :mod:`.modes`, :mod:`.sites`), those of the entry point group
``bondgraph.diagnosis`` (``library`` provides the piezoelectric ones), or passed as
``candidates=``; they use only this package's public names (``__all__``: :class:`Candidate`,
:class:`Extension`, :class:`View`, :class:`LawTerm`, :class:`Spec`, :mod:`.filters`,
:mod:`.rewrite`, ...) and the framework's public API (``tests/test_layout.py`` checks the
library).
"""

from ..fit.identify import Spec
from . import filters, laws, modes, rewrite, sites
from .additive import AdditiveDrive, Term
from .candidate import LINEAR, NONLINEAR, NOT_A_DRIVE, Candidate, Extension
from .engine import diagnose, load_candidates, model_file_options
from .laws import LawTerm
from .lure import DRIVE
from .report import CandidateResult, Report, Step
from .settings import Settings
from .sites import Site
from .view import Current, DriveFit, Record, View

__all__ = [
    "AdditiveDrive",
    "Term",
    "diagnose",
    "load_candidates",
    "model_file_options",
    "Candidate",
    "Extension",
    "LawTerm",
    "Site",
    "View",
    "Record",
    "Current",
    "DriveFit",
    "Report",
    "Settings",
    "Step",
    "CandidateResult",
    "LINEAR",
    "NONLINEAR",
    "NOT_A_DRIVE",
    "DRIVE",
    "Spec",
    "filters",
    "laws",
    "modes",
    "rewrite",
    "sites",
]
