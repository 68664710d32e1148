"""From an acausal model to explicit state equations: causality by SCAP (:mod:`.causality`),
the derivation of a straight-line program (:mod:`.derivation`), its records
(:mod:`.system`) and how engineers read them (:mod:`.printing`)."""
