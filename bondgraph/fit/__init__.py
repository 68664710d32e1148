"""Models meet measured data: parameter identification (:mod:`.identify`), the fit of a
model file to a record (:mod:`.fitting`) and feedforward compensation of memory operators
(:mod:`.compensate`)."""

#: the stage's public modules
__all__ = ["compensate", "fitting", "identify"]
