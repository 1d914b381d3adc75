"""Predicting the unseen part of a map from the team's belief: predictors and how to score them."""
