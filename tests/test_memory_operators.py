"""Memory operators defined outside the framework: kernels are compiled, not copied as text, so
helpers, ``staticmethod(f)`` and ready numba functions work, and broken kernels are errors that
name the operator and the rule."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import bondgraph as bg
from bondgraph.model.memory import MemoryOperator

CLIP = 0.25


def play(v, h, r):
    """One play of half-width r from state h (a helper called by the kernels below)."""
    return max(v - r, min(v + r, h))


def clipped(y):
    return max(-CLIP, min(CLIP, y))


class _OnePlay(MemoryOperator):
    parameter_names = ("r",)

    def __init__(self, r):
        self.r = r

    def parameter_values(self):
        return np.array([self.r])

    @property
    def n_memory(self):
        return 1

    def initial_memory(self, v0, prm):
        return np.array([play(v0, 0.0, prm[0])])

    def small_signal_gain(self, prm):
        return 0.0

    @staticmethod
    def commit(v, mem, prm):
        mem[0] = play(v, mem[0], prm[0])


class HelperBacklash(_OnePlay):
    """Backlash whose output calls a helper that calls another helper and reads a constant."""

    kind = "helper_backlash"

    @staticmethod
    def output(v, mem, prm):
        return clipped(play(v, mem[0], prm[0]))


def _output_of(v, mem, prm):
    return play(v, mem[0], prm[0])


class StaticBacklash(_OnePlay):
    kind = "static_backlash"
    output = staticmethod(_output_of)


class JittedBacklash(_OnePlay):
    kind = "jitted_backlash"
    output = staticmethod(numba.njit(_output_of))


def reference(v, r, clip=np.inf):
    h, y = play(v[0], 0.0, r), []
    for vk in v:
        y.append(max(-clip, min(clip, play(vk, h, r))))
        h = play(vk, h, r)
    return np.array(y)


V = np.sin(np.linspace(0, 4 * np.pi, 200)) * np.linspace(0.2, 1.0, 200)


@pytest.mark.parametrize(
    "op, clip", [(HelperBacklash(0.3), CLIP), (StaticBacklash(0.3), np.inf), (JittedBacklash(0.3), np.inf)]
)
def test_operators_with_helpers_static_functions_and_numba_functions_run(op, clip):
    np.testing.assert_array_equal(op.run(V), reference(V, 0.3, clip))


def test_operator_calling_a_helper_simulates_end_to_end():
    """The helper operator in a model: the integrator calls the same kernels run() does."""
    g = bg.Model("gap")
    V_in = g.input("V")
    h = g.operator("H", HelperBacklash(0.3), V_in)
    g.add(bg.Se("s", h), bg.J1("j"), bg.R("r", 1e-3), bg.C("c", 1.0))
    g.chain("s", "j", "r")
    g.bond("j", "c")
    g.output("y", h)
    t = np.linspace(0.0, 2.0, 401)
    res = bg.simulate(g, t, {"V": bg.Sine(0.8, 1.0)}, rtol=1e-9)
    v = 0.8 * np.sin(2 * np.pi * t)
    np.testing.assert_allclose(res["y"], reference(v, 0.3, CLIP), atol=1e-6)
    assert res["y"].max() == pytest.approx(CLIP)


class InstanceMethodOutput(_OnePlay):
    kind = "instance"

    def output(self, v, mem, prm):  # noqa: D102 - deliberately not static
        return v


class TwoArgumentOutput(_OnePlay):
    kind = "two_args"

    @staticmethod
    def output(v, mem):
        return v


class UncompilableOutput(_OnePlay):
    kind = "uncompilable"

    @staticmethod
    def output(v, mem, prm):
        return np.frompyfunc(play, 3, 1)(v, mem[0], prm[0])  # numpy ufunc factory: Python objects


@pytest.mark.parametrize(
    "op, rule",
    [
        (InstanceMethodOutput(0.1), r"output must be a static function output\(v, mem, prm\)"),
        (TwoArgumentOutput(0.1), r"output must take exactly three arguments \(v, mem, prm\), it takes \(v, mem\)"),
        (
            UncompilableOutput(0.1),
            r"output\(v, mem, prm\) cannot be compiled by numba in nopython mode \(.+"
            r"test_memory_operators.py:\d+\)",
        ),
    ],
)
def test_broken_kernels_are_model_errors_naming_operator_and_rule(op, rule):
    g = bg.Model("m")
    with pytest.raises(bg.ModelError, match=rule) as exc:
        g.operator("H", op, g.input("V"))
    msg = str(exc.value)
    assert "\n" not in msg and type(op).__qualname__ in msg and f"kind '{op.kind}'" in msg


def test_broken_kernel_in_a_model_file_is_a_one_line_error(tmp_path, capsys):
    """Through the CLI the same rule is a one-line input error (exit status 2), not an internal error."""
    from bondgraph.cli import main

    model = tmp_path / "bad.py"
    model.write_text(
        "import numpy as np\n"
        "from bondgraph import Model, Parameter, Se, J1, R, C, MemoryOperator\n"
        "PARAMETERS = [Parameter('k', 1.0)]\n"
        "class Op(MemoryOperator):\n"
        "    kind = 'bad'\n"
        "    parameter_names = ()\n"
        "    def parameter_values(self):\n"
        "        return np.zeros(0)\n"
        "    n_memory = 1\n"
        "    def initial_memory(self, v0, prm):\n"
        "        return np.zeros(1)\n"
        "    def small_signal_gain(self, prm):\n"
        "        return 0.0\n"
        "    @staticmethod\n"
        "    def output(v, mem, prm):\n"
        "        return undefined_name(v)\n"
        "    @staticmethod\n"
        "    def commit(v, mem, prm):\n"
        "        mem[0] = v\n"
        "def build(p):\n"
        "    g = Model('bad')\n"
        "    h = g.operator('H', Op(), g.input('V'))\n"
        "    g.add(Se('s', h), J1('j'), R('r', 1.0), C('c', p.k))\n"
        "    g.chain('s', 'j', 'r')\n"
        "    g.bond('j', 'c')\n"
        "    g.output('x', g.displacement('c'))\n"
        "    return g\n"
    )
    status = main(["equations", str(model)])
    err = capsys.readouterr().err.strip()
    assert status == 2 and "internal error" not in err and len(err.splitlines()) == 1
    assert "Op (kind 'bad')" in err and "undefined_name" in err


def test_run_takes_read_only_arrays():
    """Dataset columns are read-only; run() works on a private copy."""
    v, prm = V.copy(), np.array([0.3])
    v.setflags(write=False)
    prm.setflags(write=False)
    np.testing.assert_array_equal(StaticBacklash(0.3).run(v, prm), reference(V, 0.3))
