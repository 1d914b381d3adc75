"""Loading real map formats into a ground-truth grid; the procedural floor-plan generator."""
