"""The drive's own electrical loop: a series inductance (a long cable, an inductive amplifier
output) in the loop where the amplifier drives the actuator's capacitance, the loop's series
resistance refitted with it.  The loop keeps the actuator's current, so the stage feels the
actuator's electromechanical admittance: the exact form of what :class:`~.drive.InputRLC`
approximates by a stage on the drive that does not."""

from __future__ import annotations

import numpy as np

from bondgraph import I
from bondgraph.diagnosis import LINEAR, NOT_A_DRIVE, Candidate, Extension, Spec
from bondgraph.diagnosis.rewrite import drive_loop, parameters_of

#: the drive units of a voltage ("" when the model file declares none)
VOLTS = ("V", "volt", "volts", "")

#: inductances scanned for the start, and the fit's bounds (H): from bond wires to a large
#: output transformer
SCAN_H = np.geomspace(1e-9, 1e3, 25)


def not_a_voltage(view) -> str:
    """Why an electrical stage cannot sit on the drive: "" when the drive is a voltage (or its
    unit is not declared), else the reason (a force or a flow has no series resistance or
    cable capacitance to filter it).

    Parameters
    ----------
    view : View
        The read-only view of the data and the current model.

    Returns
    -------
    str
        "" or the reason.
    """
    unit = view.current.model.inputs[view.record.input].unit
    return "" if unit in VOLTS else f"the drive is not a voltage (its unit is {unit})"


class LoopInductance(Candidate):
    """A series inductance L (H) in the loop of the drive's voltage source (the 1-junction where
    source, series resistance and the actuator's electrical port share the drive current),
    u_source = R·i + L·di/dt + u_actuator, with the loop's resistances refitted within a
    device's spread (``diagnosis.tolerance``).  When the inductance adds nothing to that refit
    (the record fits as well with it at its lower bound), the extension is the model's own
    resistance recalibrated, and it must beat the flexible linear reference to be named."""

    cause = "electrical-rc"
    label = "series inductance in the drive's loop, its resistance refitted"
    kind = LINEAR

    def applies(self, view):
        if view.current.drive is None:
            return NOT_A_DRIVE
        if view.record.reduced:
            return "the model's fast states were residualised"
        if not view.record.exact:
            return "needs a model linear in its states"
        if drive_loop(view.core(), view.record.input) is None:
            return "the drive is not a voltage source in a loop of the model"
        return not_a_voltage(view) or True  # an effort source of another domain: no electrical loop

    @staticmethod
    def build(view, model, L: float):
        """``model`` with the inductance added to the drive's loop (located on the nominal model)."""
        junction, _ = drive_loop(view.core(), view.record.input)
        p = model.parameter("loop.L", L, "H", "series inductance in the drive's loop", bounds=(0, 1e12))
        model.add(I("loop.Ls", p))
        model.bond(junction, "loop.Ls")
        return model

    @staticmethod
    def _core_drive(view):
        """The drive an extension of the core sees (None when the current model is not a drive
        transform of its core)."""
        return view.current.drive if view.on_core else None

    def _base(self, view):
        return self.build(view, view.core() if view.on_core else view.rewrite(), float(SCAN_H[0]))

    def _predictor(self, view, model):
        """values -> raw prediction of ``model`` (:meth:`_base`), taking from ``values`` only the parameters
        it has: on the core, the drive transform named before (a Bouc–Wen state's ``bw.kappa``)
        is in the view's values but acts through the drive, not as a parameter of the core."""
        predict, known = view.predictor(model, self._core_drive(view))
        return lambda values: predict({k: v for k, v in values.items() if k in known})

    def fit(self, view):
        core = view.core()
        _, resistors = drive_loop(core, view.record.input)
        rs = [
            n
            for r in resistors
            for n in parameters_of(core, r)
            if n not in view.current.calibrated and view.current.values.get(n, 0.0) > 0
        ]
        model = self._base(view)
        predict = self._predictor(view, model)
        scores = []
        for L in SCAN_H:
            raw = predict({**view.current.values, "loop.L": float(L)})
            scores.append(view.score(raw)[2] if np.all(np.isfinite(raw)) else np.inf)
        L0 = float(SCAN_H[int(np.argmin(scores))])
        specs = [Spec("loop.L", L0, float(SCAN_H[0]), float(SCAN_H[-1]), log=True)]
        spread = float(view.settings.tolerance)
        specs += [
            Spec(n, view.current.values[n], view.current.values[n] / spread, view.current.values[n] * spread, log=True)
            for n in rs
        ]
        values, raw, ok, msg, at = view.fit_model(model, specs, max_nfev=30, drive=self._core_drive(view))
        model = self.build(view, view.rewrite(), values["loop.L"])
        model.values.update({n: values[n] for n in rs})
        return Extension(model, values, ["loop.L"] + rs, raw, None, None, at, ok, msg)

    def mimics_recalibration(self, view, ext):
        predict = self._predictor(view, self._base(view))
        with_l = view.score(predict(ext.values))[3]
        without = view.score(predict({**ext.values, "loop.L": float(SCAN_H[0])}))[3]
        if without <= float(view.settings.equivalent) * with_l:
            return (
                f"its inductance adds nothing to a refit of the loop's resistance (validation RMS "
                f"{without:.3g} without it, {with_l:.3g} with it)"
            )
        return ""
