"""Component library: numerical models of piezoelectric actuators."""
