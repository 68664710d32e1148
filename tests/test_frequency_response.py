"""The frequency response as a modal sum (one eigendecomposition of the balanced state matrix)
against a solve at every frequency, on the model files' own linear dynamics (state units from
coulombs to metres, modes from hertz to hundreds of kilohertz), and on a defective matrix,
where the modal sum does not exist and the solve is used, against the analytic 1/(s + a)².
The time-domain recursion's single-column loop gives, bit for bit, the column of the
many-column loop."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import MODELS
from scipy.linalg import matrix_balance

import bondgraph as bg
from bondgraph.linear import lti as lti_module
from bondgraph.linear.lti import LTI, StateSpace
from bondgraph.model.modelfile import load_model


@pytest.mark.parametrize("name", ["stack", "apa120ml", "bimorph_t215", "bimorph_t226", "bender_highfield"])
def test_the_modal_sum_is_the_solve_on_every_model_file(name, monkeypatch):
    lm = load_model(MODELS / f"{name}.py")
    eqs = bg.derive(lm.model)
    lin = LTI(eqs)
    table = lm.model.parameter_table()
    A, B, C, D = lin.matrices(np.array([float(table.get(p, 0)) for p in eqs.params]))
    Ab, _ = matrix_balance(A, permute=False, separate=True)
    assert np.linalg.cond(np.linalg.eig(Ab)[1]) < lti_module.MODAL_COND  # the modal route is taken
    top = np.max(np.abs(np.linalg.eigvals(A)))
    w = np.geomspace(1e-3, 10 * top, 2000)
    H = StateSpace(A, B, C, D).frequency_response(w)
    monkeypatch.setattr(lti_module, "MODAL_COND", -1.0)  # the solve at every frequency
    ref = StateSpace(A, B, C, D).frequency_response(w)
    assert np.max(np.abs(H - ref) / np.abs(ref)) < 1e-8


def test_a_defective_matrix_falls_back_to_the_solve():
    a = 30.0
    A = np.array([[-a, 1.0], [0.0, -a]])  # a Jordan block: one eigenvector
    B, C, D = np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]]), np.zeros((1, 1))
    w = np.geomspace(0.1, 1e4, 200)
    assert np.linalg.cond(np.linalg.eig(A)[1]) > lti_module.MODAL_COND
    H = StateSpace(A, B, C, D).frequency_response(w)
    assert np.allclose(H, 1 / (1j * w + a) ** 2, rtol=1e-12)


def test_one_column_gives_the_many_column_loops_column_bit_for_bit():
    """The recursion runs one input column in its own tighter loop: the same arithmetic, so
    each column of a four-column response equals its response alone exactly, at every sample
    and at a sparse set of rows, from a non-zero state."""
    rng = np.random.default_rng(3)
    A = np.array([[0.0, 1.0, 0.0], [-4e4, -40.0, 2e3], [0.0, 0.0, -300.0]])
    ss = StateSpace(A, np.array([[0.0], [0.0], [300.0]]), np.array([[1.0, 0.0, 0.5]]), np.array([[0.1]]))
    U = rng.normal(size=(5000, 4))
    x0 = np.array([1e-3, -0.2, 0.4])
    for rows in (None, np.sort(rng.choice(5000, 700, replace=False))):
        together = ss.response(1e-4, U, x0, rows)
        for j in range(4):
            alone = ss.response(1e-4, U[:, j], x0, rows)
            assert np.array_equal(alone[:, 0], together[:, j])


@pytest.mark.parametrize("second, exact", [(lambda u: 3 * u, True), (lambda u: u**2, False)])
def test_the_linear_route_is_exact_only_when_affine_in_every_input(second, exact):
    """A mass on a spring pushed by two forces: F1 = u1 (the input of the linear route) and
    F2 = 3·u2 or u2².  The slopes in x and u1 are constant either way; only the second input's
    slope tells that the dynamics are not affine in u2 (and the linear route not exact)."""
    g = bg.Model("two_forces")
    u1, u2 = g.input("u1"), g.input("u2")
    g.add(bg.Se("f1", u1), bg.Se("f2", second(u2)), bg.J1("v"), bg.I("m", 1e-3), bg.C("k", 1e-6))
    for e in ("f1", "f2"):
        g.bond(e, "v")
    g.bond("v", "m")
    g.bond("v", "k")
    g.output("x", "k.q", "m")
    assert LTI(bg.derive(g), input="u1").exact is exact
