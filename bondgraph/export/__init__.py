"""Export of derived models to other tools: FMI 2.0 FMUs (:func:`export_fmu`, ``docs/fmi.md``)."""

from .fmu import FMUReport, export_fmu

__all__ = ["export_fmu", "FMUReport"]
