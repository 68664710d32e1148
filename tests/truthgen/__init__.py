"""Independent, randomized truth records for the diagnosis — and the protocol that judges it.

Usage::

    from truthgen import SEEDS, draw
    rec = draw(1003, "ci")             # a Record: t, V, x, the model file, the truth
    rec.write_csv("rec.csv")           # the project's CSV (never carries the truth)
    rec.label, rec.causes, rec.mechanisms, rec.visible_size
    # then: bondgraph diagnose <rec.model> rec.csv [--set k=v for rec.cli_sets] --json

Why
---
A diagnosis tuned on truths built like its own candidates learns nothing about data made
elsewhere.  These truths are written by hand in numpy/scipy (no bondgraph simulation, no import
of the candidates), from the physics of the papers, with mechanisms chosen to be *structurally
unlike* a simple candidate, around devices that are never the model file's device.

Protocol (fixed before any tuning; the tests' docstrings point here)
--------------------------------------------------------------------
**Design.** A seed picks its family from ``seed % 6`` through ``(apa, t215, apa, t215, stack,
t226)`` and its cause by walking that family's cause cycle in seed order
(:func:`generator.design`), so any run of consecutive seeds is balanced:

====== ======================================== ============================================
family model file (``--set``)                   causes (cycle; ``a+b`` = compound)
====== ======================================== ============================================
apa    models/apa120ml.py                       none, hysteresis, creep, saturation, none,
                                                electrical, higher-mode, hysteresis+creep
t215   models/bimorph_t215.py (25 %: modes=3)   none, hysteresis, softening, nonlinear-damping,
                                                none, higher-mode, saturation, creep,
                                                softening+nonlinear-damping
stack  models/stack.py (40 %: lumped=true)      none, hysteresis, hysteresis+creep, creep, none,
                                                saturation, electrical
t226   models/bimorph_t226.py                   none, softening, nonlinear-damping, higher-mode,
                                                softening+nonlinear-damping
====== ======================================== ============================================

Everything else is drawn from the seed (``numpy.random.SeedSequence([seed, size])``, separate
streams for model options, parameters, record shape, drive, mechanisms, noise and the
visibility rule).

**Physics** (:mod:`.stack`, :mod:`.bimorph`): stacks are the lumped three-domain stack of
Rodriguez-Fortun et al. (2010) with the electrical side (series R, source), the polarization
capacitor and the mechanics (stiffness K, damping c, mass M); bimorphs are mass-normalised
modes (Ghafarirad et al. 2015) with the sensor at 0.95 L (T215) or 23.46 mm (T226).  Simulated
by an exact discretisation of the linear part and an explicit exponential scheme for the
effects (:mod:`.system`).

**Linear parameters** are the model file's values (read with
``bondgraph.model.modelfile.load_model``) times a log-uniform factor, never within 2 % of 1:
stacks Re x[0.5, 2], polarization elastance (capacitance) x[0.75, 1.33], a x[0.8, 1.25],
K x[0.75, 1.33], damping c x[0.1, 10], mass M x[0.7, 1.4]; bimorphs omega_i x[0.92, 1.08]
(common) x[0.98, 1.02] (each), zeta_i x[0.2, 5], mp_i x[0.8, 1.25]; plus sensor gain
x[0.9, 1.1] (never within 1 %) and offset up to +-5 % of the stroke.

**Causes and mechanisms** (:mod:`.mechanisms`, strengths and their realistic ranges there):

* hysteresis — Preisach with a random density, Bouc–Wen (complement form), Duhem
  (Coleman–Hodgdon), all in the field domain (stacks: the polarization charge as a hysteretic
  function of the field; bimorphs: the equivalent drive), and Maxwell slip as friction in the
  mechanics (flexure hinges on the stack's output; clamp friction on bimorph mode 1);
* creep — log-time (a spectrum with equal weight per third of a decade), fractional (a
  t^alpha spectrum), a few Kelvin–Voigt-like cells; in the field domain;
* saturation — tanh, polynomial (cubic with an asymmetric square term), piecewise (a smoothed
  knee) in the field domain; an end stop on the stack's output;
* softening (bimorphs) — cubic, cubic+quintic on mode 1, a cubic spring at the sensor point
  coupling the modes, a drive-dependent stiffness;
* nonlinear damping (bimorphs) — quadratic in the sensed velocity, amplitude-dependent
  viscous damping of mode 1, smooth Coulomb friction;
* higher mode — stacks: an amplification-shell mode, a compliant base, a sensor bracket
  (1.5-6 kHz, below 0.42 fs); bimorphs: the next beam mode, an off-beam mode, a sensor
  bracket;
* electrical (stacks) — a series resistance 10-200 x nominal, a series inductance (with
  some extra R), an amplifier pole (the recorded V is the command);
* ``none``; compounds hysteresis+creep (stacks) and softening+nonlinear-damping (bimorphs).
  A compound's ``causes`` are ordered by visible size; ``ordered`` is False when the larger is
  less than twice the smaller (read the pair as a set).

**Drives** (:mod:`.drives`): sine, triangle, steps with holds, chirp, band-limited noise,
bursts with amplitude ramps and pauses, resonant bursts and stepped sines near resonance; each
cause draws only among the kinds that can reveal it (``Family.reveal``).

**Records** (:mod:`.families`): ``ci`` — small: APA 5-10 kHz x 1-1.5 s, T215 10-20 kHz x
0.3-0.6 s (higher-mode: 20-50 kHz x 0.2-0.35 s), stack 200 Hz x 15-25 s or 1 kHz x 3-5 s
(slow) or 2-5 kHz x 1-2 s (fast), T226 10 kHz x 0.5-0.8 s.  ``bench`` — realistic: APA
10 kHz x 18 s, T215 50 kHz x 5 s, stack 200 Hz x 70 s or 1 kHz x 30 s (slow, like real
stacks) or 5 kHz x 10 s (fast), T226 20 kHz x 3 s.

**Measurement** (:mod:`.measure`): noise 0.1-2 % of the stroke (white plus AR(1), pink or hum
coloured parts), jittered time stamps or sampling clock, a sensor delay up to 0.2 samples,
quantisation of x and V, a little noise on V.

**Visibility rule** (:data:`generator.VISIBLE` = 3): for every hidden effect, its *effect
size* is RMS(with - without it, same linear parameters) / noise RMS, and its *visible size*
RMS(with it - best plausible linear refit) / noise RMS, the refit spanning the linear
parameters within a factor 2.5 of the file's values (damping 12, natural frequencies 15 %)
(:mod:`.visibility`).  Both must reach 3 (for a compound: each effect's size against the
other alone, and its visible size alone).  Otherwise, in rounds: 1. double the strength of the
weak effects (capped at the top of their realistic range); 2. once capped, halve the noise
level (down to 0.1 % of the stroke); 3. then draw a new drive among the revealing kinds.  After
14 rounds a single effect's seed is refused; a compound gets up to 10 more rounds in which an
effect that is visible alone but masked by its partner (e.g. friction that damps a softening
resonance away) first halves its partner's strength (never raised again).  Both sizes, the
strengths and the rounds used are stored in the record.  (No seed of the three sets is refused.)

**Seed sets** (:data:`SEEDS`, disjoint, fixed before tuning): ``dev`` 0-199 (tune freely, any
size); ``ci`` 1000-1013 (14 small records: 3 null, 1 compound, all four families);
``bench`` 2000-2071 (72 realistic records: 17 null, 9 compound).  Records of the sets are looked
at while the diagnosis is built; :func:`fresh_seeds` picks seeds outside them, single-effect or
effect-free like the held-out records a user brings, for a measurement nobody has tuned on (run
an engine on them once, then move on past them).

References
----------
- Rodriguez-Fortun, J.M., Orus, J., Buil, F., Castellanos, J.A. "General bond graph model for
  piezoelectric actuators and methodology for experimental identification." Mechatronics 20
  (2010) 303–314.  [the lumped stack, the APA-120ML numbers, field-domain hysteresis]
- Ghafarirad, H., Rezaei, S.M., Sarhan, A.A.D., Zareinejad, M. "Continuous dynamic modelling of
  bimorph piezoelectric cantilevered actuators considering hysteresis effect and dynamic
  behaviour analysis." Mathematical and Computer Modelling of Dynamical Systems 21(2) (2015)
  130–152, doi:10.1080/13873954.2014.906472.  [bimorph modes, sensor point, input hysteresis]
- Shahabi, P., Ghafarirad, H., Taghvaeipour, A. "Nonlinear vibration analysis of piezoelectric
  bending actuators: theoretical and experimental studies." Comptes Rendus Mécanique 347(12)
  (2019) 953–966, doi:10.1016/j.crme.2019.10.007.  [T226, cubic/quintic softening, nonlinear
  damping near resonance]
- Wood, R.J., Steltz, E., Fearing, R.S. "Nonlinear performance limits for high energy density
  piezoelectric bending actuators." Proc. IEEE International Conference on Robotics and
  Automation (ICRA), Barcelona, 2005.  [creep cells, Maxwell slip, field-dependent stiffness
  and damping]

Timing (a loaded 2-core machine): a ``ci`` record takes 0.1-5 s to generate, a few up to
~30 s (plus ~5 s once per process to import bondgraph for the model files' values); a
``bench`` record 1-60 s, median 16 s, a few that need many rounds of the visibility rule up to
~10 min (compounds at 250 000 samples).
"""

from .families import FAMILIES
from .generator import ATTEMPTS, NOISE_FLOOR, VISIBLE, Record, design, draw
from .runner import diagnose_record

SEEDS = {
    "dev": list(range(0, 200)),
    "ci": list(range(1000, 1014)),
    "bench": list(range(2000, 2072)),
}


def fresh_seeds(start: int, n: int, families=None) -> list[int]:
    """The first ``n`` seeds from ``start`` on that no seed set holds and whose design is one
    effect or none, in ``families`` (a collection of family names; all when None)."""
    if families is not None and not set(families) <= set(FAMILIES):
        raise ValueError(f"unknown families {sorted(set(families) - set(FAMILIES))}: use {', '.join(FAMILIES)}")
    used = set().union(*map(set, SEEDS.values()))
    seeds, s = [], start
    while len(seeds) < n:
        family, causes = design(s)
        if s not in used and len(causes) <= 1 and (families is None or family in families):
            seeds.append(s)
        s += 1
    return seeds


#: the causes of the truths (a diagnosis' ``electrical-rc`` is scored as ``electrical``)
CAUSES = ("none", "hysteresis", "creep", "saturation", "softening", "nonlinear-damping", "higher-mode", "electrical")

__all__ = [
    "SEEDS",
    "CAUSES",
    "VISIBLE",
    "ATTEMPTS",
    "NOISE_FLOOR",
    "Record",
    "design",
    "draw",
    "diagnose_record",
    "fresh_seeds",
]
