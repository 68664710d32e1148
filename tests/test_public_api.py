"""Every top-level function of ``bondgraph`` accepts what its signature and docstring say.

The first argument's annotation names the kinds of object a function takes (a ``Model``, its
``Equations``, ...); each kind is built for a mass–spring–damper and passed, and the results
must agree whichever kind was given.
"""

from __future__ import annotations

import inspect
import typing

import numpy as np
import pytest

import bondgraph as bg

FUNCTIONS = sorted(n for n in bg.__all__ if inspect.isfunction(getattr(bg, n)))

#: the further arguments a function needs to run
EXTRA = {"simulate": (np.linspace(0.0, 0.5, 51), {"F": bg.Step(1.0)})}


def oscillator() -> bg.Model:
    g = bg.Model("msd")
    F = g.input("F", "N")
    g.add(bg.Se("f", F), bg.J1("v"), bg.I("m", 1.0), bg.C("k", 0.01), bg.R("c", 2.0))
    g.bond("f", "v")
    for e in ("m", "k", "c"):
        g.bond("v", e)
    g.output("x", g.displacement("k"), "m")
    return g


def kinds(fn) -> list[type]:
    first = next(iter(inspect.signature(fn).parameters), None)
    hint = typing.get_type_hints(fn).get(first)
    if hint is None:
        return []
    return list(typing.get_args(hint)) or [hint]


def instance(kind: type):
    model = oscillator()
    if kind is bg.Model:
        return model
    if kind is bg.Equations:
        return bg.derive(model)
    if kind is bg.Causality:
        return bg.assign_causality(model)
    raise AssertionError(f"no example of {kind.__name__}: add one to this test")


def summary(result):
    if isinstance(result, bg.Equations):
        return sorted(str(s) for s in result.state_symbols)
    if isinstance(result, bg.LinearModel):
        return np.round(result.natural_frequencies, 9).tolist()
    if isinstance(result, bg.SimResult):
        return np.round(result["x"], 12).tolist()
    if isinstance(result, bg.Causality):
        return sorted(str(b) for b in result.model.bonds)
    raise AssertionError(f"no summary of {type(result).__name__}: add one to this test")


def takes_a_model(name: str) -> bool:
    return bool(set(kinds(getattr(bg, name))) & {bg.Model, bg.Equations, bg.Causality})


def test_the_face_lists_its_functions():
    assert {n for n in FUNCTIONS if takes_a_model(n)} == {"derive", "simulate", "linearize", "assign_causality"}


@pytest.mark.parametrize("name", [n for n in FUNCTIONS if not takes_a_model(n)])
def test_signal_factories_make_signals_from_numbers(name):
    fn = getattr(bg, name)
    args = ([0.0, 1.0], [0.0, 2.0]) if name == "PiecewiseLinear" else ()
    assert isinstance(fn(*args), bg.Signal)


@pytest.mark.parametrize("name", [n for n in FUNCTIONS if takes_a_model(n)])
def test_every_accepted_kind_works_and_gives_the_same_answer(name):
    fn = getattr(bg, name)
    answers = [summary(fn(instance(kind), *EXTRA.get(name, ()))) for kind in kinds(fn)]
    assert all(a == answers[0] for a in answers[1:])


def test_linearize_takes_a_model():
    lm = bg.linearize(oscillator())
    assert lm.natural_frequencies == pytest.approx([10.0]) and lm.dc_gain() == pytest.approx(0.01)
