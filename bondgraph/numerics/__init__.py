"""Equations made fast: code generation for numba (:mod:`.codegen`, :mod:`.tape`), the
compiled integrator with its memory contract (:mod:`.integrators`), inputs packed for it
(:mod:`.signal_bank`), simulation (:mod:`.simulate`) and start-up checks (:mod:`.checks`)."""
