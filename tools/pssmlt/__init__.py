"""PSSMLT and sigma-binning (thesis ch. 4): comparisons, tuning and sweeps against
references."""
