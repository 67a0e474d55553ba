"""Hybrid autotuning (thesis 3.3): the baseline database, the evaluation of the predictors,
epsilon-greedy along camera paths."""
