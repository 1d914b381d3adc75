"""Training of the learned planners (the mGNN of ``hier`` and NeuralCoMapping's network): the lookahead
expert, the policy search, DAgger, PPO and the loop that runs them. It sits above the mission it drives;
inference stays in :mod:`mrexplore.global_planning.learned`."""
