"""Parameter tuning (thesis 3.2): analysis of tuning databases, convergence, gains,
sweeps."""
