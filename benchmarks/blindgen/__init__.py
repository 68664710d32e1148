"""blindgen: an independent, blind generator of measured records for ``bondgraph diagnose``
(run by benchmarks/blind_accuracy.py).  Written from the physics of the papers below, without
the diagnosis or the project's own test generator; ``draw(seed)`` gives a :class:`Record`.

Protocol
--------
Families.  ``apa``: an amplified piezo stack like the APA-120ML [1]: the source V through a
series resistance Re into the stack's polarization capacitance C0, coupling a, stiffness K,
damping c, moving mass M (apa.py); 10 kHz, 18 s; diagnosed with models/apa120ml.py.
``t215``: a T215-geometry bimorph [2]: the first two exact clamped-free bending modes,
mass-normalised, sensor at 0.92-0.98 L (t215.py); 50 kHz, 5 s; models/bimorph_t215.py.

Linear device (every record), drawn around the model file's values and at least 2 % away:
apa Re x/÷2 (log-uniform), C0 +-25 %, a +-25 %, K +-30 %, c x/÷8 (log), M +-30 %; t215
omega_i +-6 %, zeta_i x/÷4 (log) around the file's 2 zeta omega = alpha + beta omega^2, coupling
+-25 % (common) and +-3 % (per mode).  An effect-free device has the model file's structure
exactly: no nonlinearity, no further mode below Nyquist.

Causes, one per record; mechanisms with their initial range [and the limit the visibility rule
may strengthen them to]:

apa
  hysteresis   Bouc-Wen in the polarization law, E2 += h kx p_ref z ([1] eq. 9 form, h 0.06-0.14
               [0.25] of the rated field); Maxwell slip, 8-12 elasto-slide elements on the dipole
               [3], same h; Duhem (Coleman-Hodgdon [4]), h 0.03-0.08 [0.15].  Loops about
               5-30 % of the stroke wide at full range.
  creep        polarization Kelvin-Voigt cells [5]: 2-4 cells, tau 0.05-8 s; log-time creep [6]
               (two cells a decade, 10 ms-1000 s); power-law (fractional) creep t^alpha,
               alpha 0.15-0.45, as a Prony series; creep over the record 4-12 % [25 %].
  saturation   tanh polarization law (peak dipole 0.45-0.7 [0.8] of saturation); polynomial law
               (cubic 6-20 % [35 %], quadratic +-8 %); end stop of 1-5 K, 8-30 % [45 %] below the
               linear peak.
  electrical   series resistance x50-250 [600]; series inductance, LC at 350-1200 Hz [200 Hz];
               second-order amplifier, 150-700 Hz [60 Hz], zeta 0.3-0.7; amplifier current limit
               0.05-0.5 A [0.01 A] (the recorded V is the command).
  higher-mode  shell (output part 10-30 % [50 %] of M on a frame flexure); base (fixture mass
               2-12 [1] M on a spring); sensor bracket driven by the reaction force (coupling
               0.05-0.25 [0.6]); the added mode at 1.5-4 kHz (= 0.4 fs), zeta 1-5 % (bracket 0.5-3 %).
t215
  hysteresis   Preisach [7] with a random density (2-3 Gaussian bumps on the threshold
               half-plane), passing a fraction h 0.2-0.45 [0.7] of the drive; Bouc-Wen at the
               input [8], H 0.05-0.12 [0.2].  Loops 5-15 % wide.
  creep        as apa, on the drive (tau 0.02-2 s; log 3 ms-300 s); 5-15 % [30 %] over 5 s.
  saturation   tanh on the drive (peak V 0.5-0.8 [1.0] V_s); polynomial (cubic 5-18 % [30 %],
               quadratic +-6 %); tip end stop of 2-10 x the tip stiffness, 8-30 % [45 %] below
               the linear peak.
  softening    cubic stiffness of mode 1 [9]; cubic + quintic [9] (the quintic undoing 20-60 %
               at the peak); amplitude-dependent modulus omega_1^2 (1 - kappa A^2 / q_ref^2);
               backbone drop 1-4 % [8 %] at the record's peak amplitude.
  nonlinear-   mu1 q^2 q' on mode 1 [9]; quadratic air drag at the tip; Coulomb friction at the
  damping      tip (tanh-smoothed); added damping at the peak amplitude 0.3-1.5 [3] x the linear
               one (friction 0.1-0.5 [1]).
  higher-mode  bending mode 3 (omega_3 +-6 %, zeta 1-6 % [0.4 %]); a torsional (thin strip,
               ~5 kHz) or lateral (in-plane, ~3 kHz) mode seen through a small sensor offset,
               static gain 0.3-2 % [6 %] of mode 1's, zeta 0.5-3 %.

Drives (drives.py): one segment of a kind that reveals the cause (hysteresis: sine, triangle;
saturation: the same, apa also steps; creep: steps, ramp-hold; electrical: chirp, noise, bursts, steps;
higher-mode: high-band chirp or noise, bursts, apa stepped sine, t215 steps; softening: stepped
sine near the nominal resonance; nonlinear damping: the same or ring-down bursts), and with
probability 1/2 a second segment of any kind (55-80 % / rest); nulls draw both from all kinds.
Levels: apa 0-150 V (70 %) or +-75 V, at 0.6-1 of the range, small-signal 3-20 V about 0 V or
a small bias; t215 +-54-90 V, dynamic segments scaled to a 50-400 um tip amplitude (<= 90 V).

Measurement (measure.py): sensor gain +-10 %, offset +-20 % of the stroke; noise RMS 0.2-2 %
of the stroke (log-uniform), 30-90 % of its variance white, the rest AR(1) with a 0.5-50 Hz
corner; sampling jitter 0.01-0.15 % of dt (|jitter| <= 0.4 % dt; the time column holds the
true instants); 16-18-bit quantisation over twice the stroke; voltage noise 0.01-0.1 % of its
range, 16 bits over 400 V.

Visibility: the RMS of (noise-free sensor with the effect - its best linear refit) must reach
3 x the noise RMS.  The refit is the family's linear model with its parameters free around the
model file's values (apa Re x/÷3, C0, a, K, M x/÷1.6, c x/÷15; t215 omega_i x/÷1.3, zeta_i
x/÷15, mode-2/mode-1 gain ratio x/÷2), gain and offset free.  Until visible, the effect is
strengthened (x1.1-1.5 a step, up to its limit) and the noise lowered (/1.5 a step, down to
0.2 %) in turn; then the device, drive and effect are redrawn (3 attempts); then the seed is
refused (:class:`Refused`).  The truth keeps the visible size, the noise and the steps taken.

Seeds: even seeds apa, odd t215.  Within a family record j = seed // 2 is a null when j % 4 == 0;
otherwise, with n = j - j // 4 - 1, its cause is number n % (causes) and its mechanism number
(n // causes) % (mechanisms) of the lists above.  All numbers come from
numpy.random.SeedSequence([SALT, seed, attempt, stream]): a seed always gives the same record.

Numerics: classical RK4 with fixed substeps (|lambda| h <= 0.5 including the cause's
stiffening), the drive linear between samples; pilot runs and refits use the exact first-order
hold discretisation; the two agree to better than 1e-5 of the stroke on an effect-free
device, and halving the substeps changes a record by less than 1e-4 of its stroke.
Signs: apa x > 0 is extension (V > 0 extends); t215 as the model file (m_p < 0, V > 0 gives w < 0).
The CSV metadata (record.py) name the device and the sensor only.

References
  [1] Rodriguez-Fortun, J.M., Orus, J., Buil, F., Castellanos, J.A., "General bond graph model
      for piezoelectric actuators and methodology for experimental identification",
      Mechatronics 20 (2010) 303-314.
  [2] Ghafarirad, H., Rezaei, S.M., Sarhan, A.A.D., Zareinejad, M., "Continuous dynamic
      modelling of bimorph piezoelectric cantilevered actuators considering hysteresis effect
      and dynamic behaviour analysis", Mathematical and Computer Modelling of Dynamical
      Systems 21(2) (2015) 130-152.
  [3] Goldfarb, M., Celanovic, N., "Modeling piezoelectric stack actuators for control of
      micromanipulation", IEEE Control Systems Magazine 17(3) (1997) 69-79.
  [4] Coleman, B.D., Hodgdon, M.L., "A constitutive relation for rate-independent hysteresis
      in ferromagnetically soft materials", International Journal of Engineering Science
      24(6) (1986) 897-919.
  [5] Wood, R.J., Steltz, E., Fearing, R.S., "Nonlinear performance limits for high energy
      density piezoelectric bending actuators", Proc. IEEE International Conference on
      Robotics and Automation (2005).
  [6] Jung, H., Gweon, D.-G., "Creep characteristics of piezoelectric actuators", Review of
      Scientific Instruments 71(4) (2000) 1896-1900.
  [7] Mayergoyz, I.D., "Mathematical Models of Hysteresis", Springer, New York (1991).
  [8] Low, T.S., Guo, W., "Modeling of a three-layer piezoelectric bimorph beam with
      hysteresis", Journal of Microelectromechanical Systems 4(4) (1995) 230-237.
  [9] Shahabi, P., Ghafarirad, H., Taghvaeipour, A., "Nonlinear vibration analysis of
      piezoelectric bending actuators: theoretical and experimental studies", Comptes Rendus
      Mecanique 347(12) (2019) 953-966.
"""

from .generate import FAMILIES, Refused, plan
from .generate import generate as draw
from .record import Record

__all__ = ["FAMILIES", "Record", "Refused", "draw", "plan"]
