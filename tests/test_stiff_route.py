"""The compiled implicit route (radau5) for stiff models: its sparse analytic Jacobian equals the
symbolic one, its sparse LU solves, its results equal an exact reference, and ``auto`` takes it
for a stiff stack and not for a non-stiff actuator."""

import re

import numpy as np
import pytest
import scipy.sparse as sps
from conftest import MODELS, ROOT
from test_tape import nonlinear_oscillator
from truth import exact_step_response

import bondgraph as bg
from bondgraph import config
from bondgraph.cli import main
from bondgraph.model.modelfile import load_model
from bondgraph.numerics.implicit import lu_factor, lu_solve


def stack(layers: int):
    return load_model(MODELS / "stack.py", {"layers": layers})


@pytest.mark.parametrize("hub_support,tape", [(16, False), (1, False), (16, True)])
@pytest.mark.parametrize("build", [nonlinear_oscillator, lambda: stack(4).model])
def test_sparse_jacobian_equals_the_symbolic_one(build, hub_support, tape):
    """Through hubs (hub_support = 1 makes nearly every program variable one) or substituted,
    compiled by numba or on the tape, the Schur complement of the augmented matrix is the
    dense symbolic Jacobian."""
    with config.override({"jacobian.hub_support": hub_support, "codegen.tape_threshold": 0 if tape else 300}):
        sim = bg.Simulator(build())
        sj = sim.sparse_jacobian()
    eqs = sim.eqs
    assert sj.route == ("tape" if tape else "numba")
    if hub_support == 1:
        assert sj.program.hubs
    rng = np.random.default_rng(4)
    th = sim.theta()
    x = rng.uniform(-1, 1, len(eqs.states)) * np.maximum(1e-9, np.abs(rng.normal(size=len(eqs.states))))
    bank = sim.signal_bank({})
    J = sim.jacobian_at(0.0, x, th, np.zeros(1), bank)
    xs = eqs.state_symbols
    dense = eqs.jacobian([eqs.rates[s] for s in xs], xs)
    values = {**dict(zip(eqs.params, th)), **dict(zip(xs, x)), **{u: 0.0 for u in eqs.inputs}}
    ref = np.array(dense.xreplace(values).evalf(), float)
    assert np.allclose(J, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("dtype", [float, complex])
def test_sparse_lu_is_backward_stable_on_badly_scaled_rows(dtype):
    n = 60
    rng = np.random.default_rng(2)
    A = sps.random(n, n, density=0.08, random_state=3) + sps.diags(rng.uniform(1e-3, 1e3, n))
    if dtype is complex:
        A = A + 1j * sps.random(n, n, density=0.05, random_state=5)
    A = sps.csc_matrix(sps.diags(10.0 ** rng.uniform(-8, 8, n)) @ A)  # rows in wildly different units
    A.sort_indices()
    q = np.arange(n, dtype=np.int64)[::-1].copy()
    cap = 40 * A.nnz
    ints = [np.empty(k, np.int64) for k in (n + 1, cap, n + 1, cap, n, n, n, n, n)]
    Lp, Li, Up, Ui, pinv, xi, stack_, pstack, mark = ints
    Lx, Ux, x = np.empty(cap, A.dtype), np.empty(cap, A.dtype), np.zeros(n, A.dtype)
    rs = np.empty(n)
    ip, ii = A.indptr.astype(np.int64), A.indices.astype(np.int64)
    assert lu_factor(ip, ii, A.data, q, 0.1, rs, Lp, Li, Lx, Up, Ui, Ux, pinv, x, xi, stack_, pstack, mark) == 0
    b = (rng.standard_normal(n) + (1j * rng.standard_normal(n) if dtype is complex else 0)).astype(A.dtype)
    y = b.copy()
    lu_solve(q, rs, Lp, Li, Lx, Up, Ui, Ux, pinv, y, x)
    backward = np.abs(A @ y - b) / (abs(A) @ np.abs(y) + np.abs(b))  # componentwise (Oettli-Prager)
    assert backward.max() < 1e-12


def test_radau5_equals_the_exact_step_response_of_a_stiff_stack():
    """10 layers (30 states, modes up to 1 MHz), 0.1 s of the model file's experiment: the
    default picks radau5, which takes a few hundred steps where dopri5 takes about 200 000,
    and both stay within 1e-6 of the peak of the exact response (rtol 1e-6)."""
    lm = stack(10)
    sim = bg.Simulator(lm.model)
    t = lm.experiment.times(0.1, None)
    ref = exact_step_response(sim, t, lm.experiment.inputs)
    auto = sim.run(t, lm.experiment.inputs)
    explicit = sim.run(t, lm.experiment.inputs, method="dopri5")
    assert auto.stats["method"] == "radau5" and auto.stats["reason"].startswith("stiff")
    assert auto.stats["jacobians"] == 1  # a linear model: one Jacobian for the run
    assert 20 * auto.stats["steps"] < explicit.stats["steps"]
    for res in (auto, explicit):
        assert np.max(np.abs(res["x"] - ref)) <= 1e-6 * np.max(np.abs(ref))


def test_radau5_equals_the_exact_step_response_at_fifty_layers():
    """50 layers (150 states, spectral radius 4.9e7 1/s, on the tape interpreter): the default is radau5
    and stays within 1e-6 of the exact response's peak, in under 2 000 steps."""
    lm = stack(50)
    sim = bg.Simulator(lm.model)
    t = lm.experiment.times(0.1, None)
    ref = exact_step_response(sim, t, lm.experiment.inputs)
    res = sim.run(t, lm.experiment.inputs)
    assert res.stats["method"] == "radau5" and res.stats["steps"] < 2000
    assert np.max(np.abs(res["x"] - ref)) <= 1e-6 * np.max(np.abs(ref))


def test_auto_keeps_the_explicit_route_for_a_non_stiff_model():
    lm = load_model(MODELS / "apa120ml.py")
    res = bg.Simulator(lm.model).run(lm.experiment.times(0.05, None), lm.experiment.inputs)
    assert res.stats["method"] == "dopri5" and res.stats["reason"].startswith("not stiff")


def test_the_summary_line_names_the_route_and_why(tmp_path, capsys):
    """The line docs/stiff-models.md shows (all but the time)."""
    argv = ["simulate", MODELS / "stack.py", "--set", "layers=10", "--t-end", "0.1", "--out", tmp_path / "r.csv"]
    rc = main([str(a) for a in argv])
    err = capsys.readouterr().err
    assert rc == 0
    shown = " ".join((ROOT / "docs" / "stiff-models.md").read_text().split())
    said = re.sub(r"steps in [0-9.]+ s", "steps in T s", err)
    line = "(radau5, 517 steps in T s; auto: stiff: spectral radius 6.6e+06 1/s, 21 × the output's Nyquist frequency; "
    assert line in said
    assert line in re.sub(r"steps in [0-9.]+ s", "steps in T s", shown)
    assert "dopri5 would need ~2e+05 steps)" in err


def test_the_docs_example_runs_the_stack_on_radau5(monkeypatch, capsys):
    block = re.findall(r"```python\n(.*?)```", (ROOT / "docs" / "stiff-models.md").read_text(), re.S)[0]
    monkeypatch.chdir(ROOT)
    exec(compile(block, "docs/stiff-models.md", "exec"), {})
    method, steps = capsys.readouterr().out.split()
    assert method == "radau5" and 100 < int(steps) < 1000
