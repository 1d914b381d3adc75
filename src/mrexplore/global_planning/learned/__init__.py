"""Layer 2, learned (paper IV-B): the mGNN and NeuralCoMapping networks, their policies and checkpoints.

Inference only; training lives in :mod:`mrexplore.training`.
"""
