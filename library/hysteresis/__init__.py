"""Rate-independent hysteresis operators: Prandtl–Ishlinskii (play and stop forms), the modified PI
(dead zones on the absolute PI sum, eq. 12, or measured from the last reversal, Sec. 5.3) of
Rodriguez-Fortun, J.M., Orus, J., Buil, F., Castellanos, J.A. "General bond graph model for
piezoelectric actuators and methodology for experimental identification." Mechatronics 20 (2010)
303-314, with exact inverses, and the Maxwell-slip model of Wood, R.J., Steltz, E., Fearing, R.S.
"Nonlinear performance limits for high energy density piezoelectric bending actuators." Proc. IEEE
ICRA, Barcelona, 2005. The initial-memory convention follows Ghafarirad, H., Rezaei, S.M., Sarhan,
A.A.D., Zareinejad, M. "Continuous dynamic modelling of bimorph piezoelectric cantilevered
actuators considering hysteresis effect and dynamic behaviour analysis." Mathematical and
Computer Modelling of Dynamical Systems 21(2) (2015) 130-152.

Physics-free: every operator maps a scalar input v to an output y. Play/stop thresholds r_i and
Maxwell-slip yield displacements carry the units of v, dead zones d_j the units of the PI sum,
weights w_i the units of y per unit of v. Each class is a :class:`MemoryOperator` (pure
``output``/in-place ``commit`` kernels, parameters in one flat float64 array).

Memory of a play-based operator is the vector of play outputs (for Maxwell slip: the slip
positions, which are the same thing). Initial memory convention, used throughout (Ghafarirad et al. 2015
eq. 32 with y_0 = 0): at rest at v0 each play holds the value reached by a monotone approach
from the demagnetised state v = 0, h_i = max(v0 - r_i, min(v0 + r_i, 0)). With this convention
the analytic inverse of :meth:`PrandtlIshlinskii.inverse` is exact from rest: the monotone
approach 0 -> v0 maps onto the monotone approach 0 -> H[v0] of the inverse operator.
"""

from __future__ import annotations

from .identification import bouc_wen_response, fit_pi_weights, play_outputs, threshold_grid
from .play import (
    InverseModifiedPI,
    InverseRelativeModifiedPI,
    ModifiedPI,
    PIStop,
    PrandtlIshlinskii,
    RelativeModifiedPI,
)
from .slip import MaxwellSlip

__all__ = [
    "PrandtlIshlinskii",
    "PIStop",
    "ModifiedPI",
    "InverseModifiedPI",
    "RelativeModifiedPI",
    "InverseRelativeModifiedPI",
    "MaxwellSlip",
    "play_outputs",
    "threshold_grid",
    "fit_pi_weights",
    "bouc_wen_response",
]
