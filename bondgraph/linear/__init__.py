"""Linear views of a model: symbolic linearisation (:mod:`.linearize`) and exact discrete
linear filters, modal sums and residualisation (:mod:`.lti`)."""
