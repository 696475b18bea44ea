"""The chaos soak (``make soak``): the keyed fleet on the testbed through a seeded schedule
of faults, its invariants checked over the whole history from the bags."""
