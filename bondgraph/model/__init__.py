"""The acausal model: elements (:mod:`.elements`), the bond graph and its components
(:mod:`.graph`), parameters with units (:mod:`.parameters`), memory operators
(:mod:`.memory`), input signals (:mod:`.signals`), experiments (:mod:`.experiment`) and the
loading of model files (:mod:`.modelfile`)."""
