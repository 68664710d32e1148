"""Tests of library.beam: exact bimorph cantilever modes against Ghafarirad et al. 2015, closed forms and FEM."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.linalg import eigh

from library.beam import (
    T215_A4_103X,
    T226_H4_203X,
    Bimorph,
    cantilever_beta_L,
    effective_mass,
    uniform_cantilever_omegas,
)

B = T215_A4_103X
COVERAGES = [(0.1, 0.7), (0.2, 1.0), (0.0, 0.5), (0.5, 1.0)]


def covered(l1, l2, beam=B):
    return replace(beam, l1=l1 * beam.L, l2=l2 * beam.L)


def fem_matrices(beam, n_el=200):
    """Independent Hermite-cubic finite elements (element edges on l1, l2); EI, rhoA recomputed here.

    Returns stiffness and consistent mass matrices with the clamped DOFs removed, DOF order
    (w_1, h w_1', w_2, h w_2', ...) at nodes x_k = L k / n_el.
    """
    x = np.linspace(0.0, beam.L, n_el + 1)
    mid = 0.5 * (x[:-1] + x[1:])
    cov = (mid > beam.l1) & (mid < beam.l2)
    b, tb, tp = beam.b, beam.t_b, beam.t_p
    EI = beam.c_b * b * tb**3 / 12 + cov * beam.c_p * 2 * b * ((tb / 2 + tp) ** 3 - (tb / 2) ** 3) / 3
    rhoA = beam.rho_b * b * tb + cov * 2 * beam.rho_p * b * tp
    h = beam.L / n_el  # DOFs w and h*w' keep the element matrices well scaled
    k0 = np.array([[12, 6, -12, 6], [6, 4, -6, 2], [-12, -6, 12, -6], [6, 2, -6, 4]]) / h**3
    m0 = np.array([[156, 22, 54, -13], [22, 4, 13, -3], [54, 13, 156, -22], [-13, -3, -22, 4]]) * h / 420
    n = 2 * (n_el + 1)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for e in range(n_el):
        sl = slice(2 * e, 2 * e + 4)
        K[sl, sl] += EI[e] * k0
        M[sl, sl] += rhoA[e] * m0
    return K[2:, 2:], M[2:, 2:]


def fem(beam, n_el=200, n_modes=8):
    """FEM omegas and M-normalised nodal deflections w(x_k), k = 1..n_el.

    Solved as M v = mu K v (mu = 1/omega^2, largest first): the low modes then do not suffer from
    the n_el^4 condition number of K.
    """
    K, M = fem_matrices(beam, n_el)
    mu, vec = eigh(M, K, subset_by_index=[len(K) - n_modes, len(K) - 1])
    vec = vec[:, ::-1] / np.sqrt(mu[::-1])  # now vec.T M vec = I
    return 1 / np.sqrt(mu[::-1]), vec[0::2].T


def gauss_grid(beam, n=200):
    """Own quadrature: n-point Gauss–Legendre on each piece between 0, l1, l2, L."""
    xs, ws = [], []
    t, w = np.polynomial.legendre.leggauss(n)
    for a, c in zip([0.0, beam.l1, beam.l2], [beam.l1, beam.l2, beam.L]):
        if c > a:
            xs.append(0.5 * (c - a) * t + 0.5 * (a + c))
            ws.append(0.5 * (c - a) * w)
    x, w = np.concatenate(xs), np.concatenate(ws)
    cov = (x > beam.l1) & (x < beam.l2)
    return x, w, np.where(cov, beam.rhoA_covered, beam.rhoA_bare), np.where(cov, beam.EI_covered, beam.EI_bare)


def test_table2_frequencies():
    """Ghafarirad et al. 2015, Table 2 within 0.5 %, and the uniform-beam numbers 2247.4, 14084.2, 39436.2."""
    w = B.modes(3).omegas
    np.testing.assert_allclose(w, [2249.0, 14094.24, 39464.29], rtol=5e-3)
    np.testing.assert_allclose(w, [2247.4, 14084.2, 39436.2], atol=0.1)


def test_fully_covered_equals_closed_form():
    np.testing.assert_allclose(cantilever_beta_L(4), [1.8751, 4.6941, 7.8548, 10.9955], atol=1e-4)
    for beam in (B, T226_H4_203X):
        closed = uniform_cantilever_omegas(beam.EI_covered, beam.rhoA_covered, beam.L, 10)
        np.testing.assert_allclose(beam.modes(10).omegas, closed, rtol=1e-6)
    # the uniform-beam formula for T226-H4-203X gives about 2915 rad/s, 10.5 % above the measured 2637
    assert T226_H4_203X.modes(1).omegas[0] == pytest.approx(2915.5, abs=0.5)
    # bare substrate (no piezo) is uniform too
    bare = covered(0.3, 0.3)
    np.testing.assert_allclose(
        bare.modes(5).omegas, uniform_cantilever_omegas(B.EI_bare, B.rhoA_bare, B.L, 5), rtol=1e-6
    )


@pytest.mark.parametrize("l1,l2", COVERAGES)
def test_partial_coverage_matches_fem(l1, l2):
    """Frequencies and mode shapes of 8 modes agree with an independent FEM eigenproblem."""
    beam = covered(l1, l2)
    modes = beam.modes(8)
    w_fem, v_fem = fem(beam)
    np.testing.assert_allclose(modes.omegas, w_fem, rtol=1e-6)
    xn = np.linspace(0.0, beam.L, 201)[1:]
    for i in range(8):
        phi = modes.shape(i, xn)
        v = v_fem[i] * np.sign(v_fem[i][-1])
        assert np.max(np.abs(phi - v)) < 1e-5 * np.max(np.abs(phi))


def test_partial_differs_from_full_and_converges():
    """Partial coverage changes omega_1 a lot; shrinking bare ends converge to the fully covered beam."""
    full = B.modes(4).omegas
    assert covered(0.1, 0.7).modes(1).omegas[0] == pytest.approx(1136.47, abs=0.05)
    eps = (1e-2, 1e-3, 1e-4, 1e-6, 1e-9)  # bare end pieces of eps*L at both ends (1e-9: 22 pm)
    errs = [np.max(np.abs(covered(e, 1 - e).modes(4).omegas / full - 1)) for e in eps]
    assert all(a > 5 * b for a, b in zip(errs, errs[1:]))
    assert errs[0] > 0.2 and errs[-1] < 1e-7


@pytest.mark.parametrize("l1,l2", [(0.0, 1.0)] + COVERAGES)
def test_orthonormality(l1, l2):
    """int rhoA phi_i phi_j = delta_ij and int EI phi_i'' phi_j'' = omega_i^2 delta_ij (own quadrature)."""
    beam = covered(l1, l2)
    modes = beam.modes(8)
    x, w, rhoA, EI = gauss_grid(beam)
    phi = np.array([modes.shape(i, x) for i in range(8)])
    curv = np.array([modes.derivative(i, x, 2) for i in range(8)])
    np.testing.assert_allclose((phi * rhoA * w) @ phi.T, np.eye(8), atol=1e-6)
    stiff = (curv * EI * w) @ curv.T / np.outer(modes.omegas, modes.omegas)
    np.testing.assert_allclose(stiff, np.eye(8), atol=1e-6)
    assert np.all(np.diff(modes.omegas) > 0) and all(modes.shape(i, beam.L) > 0 for i in range(8))


@pytest.mark.parametrize("l1,l2", COVERAGES)
def test_boundary_and_interface_conditions(l1, l2):
    beam = covered(l1, l2)
    modes = beam.modes(8)
    for i in range(8):
        beta = modes.betas[i].max()
        scale = np.max(np.abs(modes.shape(i, np.linspace(0, beam.L, 400))))
        for d in (0, 1):
            assert abs(modes.derivative(i, 0.0, d)) < 1e-9 * scale * beta**d
        for d in (2, 3):
            assert abs(modes.derivative(i, beam.L, d)) < 1e-9 * scale * beta**d
        for xc in {beam.l1, beam.l2} - {0.0, beam.L}:
            left, right = np.nextafter(xc, 0.0), xc
            EI_left, EI_right = (beam.EI_bare, beam.EI_covered) if xc == beam.l1 else (beam.EI_covered, beam.EI_bare)
            for d in range(4):
                wl, wr = (EI_left, EI_right) if d >= 2 else (1.0, 1.0)
                jump = wl * modes.derivative(i, left, d) - wr * modes.derivative(i, right, d)
                assert abs(jump) < 1e-8 * scale * beta**d * max(wl, wr)


@pytest.mark.parametrize("l1,l2", [(0.0, 1.0)] + COVERAGES)
def test_input_gains_static_deflection(l1, l2):
    """Quasi-static tip deflection sum_i phi_i(L) m_p,i / omega_i^2 equals the exact bending solution.

    With M = EI w'' - M_p V and a free tip, w'' = M_p V / EI_covered on [l1, l2], zero elsewhere, so
    w(L)/V = M_p [(L - l1)^2 - (L - l2)^2] / (2 EI_covered). Negative for e31 < 0 (M_p < 0).
    """
    beam = covered(l1, l2)
    modes = beam.modes(20)  # the modal sum converges like 1/n^2
    assert beam.M_p == pytest.approx(3.2e-3 * -12.54 * 0.25e-3)
    exact = beam.M_p * ((beam.L - beam.l1) ** 2 - (beam.L - beam.l2) ** 2) / (2 * beam.EI_covered)
    series = sum(modes.shape(i, beam.L) * g / w**2 for i, (g, w) in enumerate(zip(modes.input_gains, modes.omegas)))
    assert exact < 0
    assert series == pytest.approx(exact, rel=2.5e-3)
    if l1 == 0.0 and l2 == 1.0:
        np.testing.assert_allclose(modes.input_gains, [beam.M_p * modes.slope(i, beam.L) for i in range(20)])
        assert modes.input_gains[0] == pytest.approx(-0.087237, rel=1e-4)


def a1(modes, xt):
    g = modes.input_gains
    return 1 + g[1] * modes.shape(1, xt) / (g[0] * modes.shape(0, xt))


def test_nonminimum_phase_boundary():
    """Ghafarirad et al. 2015, §3: two-mode w(l_t)/V has an RHP zero iff a1 < 0, boundary at 0.737 L."""
    modes = B.modes(2)
    lo, hi = 0.6, 1.0
    assert a1(modes, lo * B.L) < 0 < a1(modes, hi * B.L)
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if a1(modes, mid * B.L) < 0 else (lo, mid)
    assert lo == pytest.approx(0.737, abs=5e-3)
    zetas = modes.damping_ratios(1e-3, 1e-5)
    np.testing.assert_allclose(zetas, (1e-3 + 1e-5 * modes.omegas**2) / (2 * modes.omegas))
    for frac, n_rhp in [(0.7, 1), (0.73, 1), (0.75, 0), (0.9, 0), (0.95, 0), (1.0, 0)]:
        x = frac * B.L
        num, den = modes.transfer_function(x, zetas)
        assert len(num) == 3 and len(den) == 5
        assert num[0] == pytest.approx(a1(modes, x) * modes.shape(0, x) * modes.input_gains[0])
        assert np.sum(np.roots(num).real > 0) == n_rhp, frac
        assert np.all(np.roots(den).real < 0)


def test_effective_mass():
    """Tip effective mass of a uniform cantilever: two different, exactly known numbers.

    From the first mass-normalised mode, 1/phi_1(L)^2 = m/4 exactly (classical shapes normalised to
    int phi^2 = L have |phi(L)| = 2). The 33/140 m of Wood, Steltz & Fearing 2005, is the Rayleigh value built on the
    static tip-load deflection, so the two differ by about 6 %. With partial coverage the Rayleigh
    definition still applies but 33/140 does not (0.196 m for l1 = 0.1 L, l2 = 0.7 L).
    """
    modes = B.modes(2)
    assert modes.effective_mass() / B.mass == pytest.approx(0.25, rel=1e-9)
    assert effective_mass(B) / B.mass == pytest.approx(33 / 140, rel=1e-12)
    assert 33 / 140 == pytest.approx(0.2357, abs=1e-4)
    assert B.mass == pytest.approx(21.6e-3 * 3.2e-3 * (9000 * 0.12e-3 + 2 * 7800 * 0.13e-3))
    # partly covered: Rayleigh value from the FEM static tip-load solution (exact for Hermite cubics)
    beam = covered(0.1, 0.7)
    K, M = fem_matrices(beam, 20)
    f = np.zeros(len(K))
    f[-2] = 1.0
    u = np.linalg.solve(K, f)
    assert effective_mass(beam) == pytest.approx(u @ M @ u / u[-2] ** 2, rel=1e-9)
    assert effective_mass(beam) / beam.mass == pytest.approx(0.19614, abs=1e-5)
    assert modes.effective_mass(1, 0.5 * B.L) == pytest.approx(modes.shape(1, 0.5 * B.L) ** -2)


def test_validation():
    with pytest.raises(ValueError):
        replace(B, l1=0.8 * B.L, l2=0.5 * B.L)
    with pytest.raises(ValueError):
        replace(B, t_p=0.0)
    with pytest.raises(ValueError):
        B.modes(1).shape(0, 1.1 * B.L)
    assert Bimorph(**{**B.__dict__, "l2": None}).l2 == B.L
