"""The diagnosis' serial stages on both cores give the serial results, bit for bit.

``fork_map`` shares independent calls between this process and forked children (the
calibration's frequency-response starts); ``projected_fit(threads=2)`` evaluates the
finite-difference Jacobian's columns in threads (fits without analytic derivatives: the
compiled kernels release the GIL).  Truths: an exponentially decaying sine (amplitude and
offset solved, decay rate and frequency fitted), and the tone record of
test_diagnosis_strained (a lightly damped resonator whose calibration ends on a bound and is
retried from random starts: the frequency-response starts in forked children).
"""

import math
import os

import numpy as np
import pytest
from test_diagnosis_strained import record, resonator

from bondgraph.diagnosis.calibration import calibrate
from bondgraph.diagnosis.context import Context
from bondgraph.diagnosis.pool import fork_map
from bondgraph.diagnosis.projection import projected_fit


def _square_or_fail(x):
    if x == 5:
        raise ValueError("item 5 refused")
    return x * x, os.getpid()


def test_fork_map_keeps_the_order_and_the_serial_results():
    out = fork_map(_square_or_fail, [1, 2, 3, 4], 2)
    assert [v for v, _ in out] == [1, 4, 9, 16]
    assert len({pid for _, pid in out}) == 2  # this process and one child
    assert [v for v, _ in fork_map(_square_or_fail, [1, 2, 3], 1)] == [1, 4, 9]


def test_fork_map_raises_a_childs_exception_here():
    with pytest.raises(ValueError, match="item 5 refused"):
        fork_map(_square_or_fail, [1, 5, 2, 3], 2)  # item 5 is the child's


def decaying_sine():
    """(t, y, fit rows, columns(z, rows)): 0.7·e^(−1.3t)·sin(2π·3.1t) + 0.05 with noise of 1e-3;
    the columns of z = (log decay rate, log frequency): the sine and a constant."""
    t = np.linspace(0.0, 2.0, 4000)
    y = 0.7 * np.exp(-1.3 * t) * np.sin(2 * math.pi * 3.1 * t) + 0.05
    y = y + 1e-3 * np.random.default_rng(3).standard_normal(t.size)

    def columns(z, rows):
        a, f = math.exp(z[0]), math.exp(z[1])
        tt = t if rows is None else t[rows]
        return np.column_stack([np.exp(-a * tt) * np.sin(2 * math.pi * f * tt), np.ones(tt.size)])

    return t, y, np.arange(0, t.size, 2), columns


def test_threaded_jacobians_give_the_serial_fit():
    t, y, idx, columns = decaying_sine()
    fits = [
        projected_fit(columns, y, idx, [0.0, math.log(2.5)], [-3, 0], [3, 2], [-np.inf] * 2, [np.inf] * 2, threads=n)
        for n in (1, 2)
    ]
    assert np.array_equal(fits[0].z, fits[1].z) and fits[0].cost == fits[1].cost and fits[0].nfev == fits[1].nfev
    assert math.exp(fits[1].z[0]) == pytest.approx(1.3, rel=0.02)
    assert math.exp(fits[1].z[1]) == pytest.approx(3.1, rel=0.01)


def test_a_calibration_on_two_cores_is_the_one_on_one():
    cals = [calibrate(Context(resonator(38.0, 0.01), record()), workers=n)[1] for n in (1, 2)]
    assert cals[0].values == cals[1].values
    assert cals[0].rms_validation == cals[1].rms_validation and cals[0].gain == cals[1].gain
