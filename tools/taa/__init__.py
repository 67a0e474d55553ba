"""Temporal anti-aliasing (thesis ch. 5): data sets, training, weights, evaluation."""
