"""Layer 2, learned (paper IV-B): the mGNN, its policy, PPO and imitation, the trainer; the only place torch lives."""
