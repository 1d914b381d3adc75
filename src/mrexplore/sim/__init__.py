"""Ground truth, LiDAR, per-robot log-odds belief, motion, the multi-robot env and its measures."""
