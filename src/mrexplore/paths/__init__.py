"""Geodesic distance fields and A* on the belief grid, shared by every layer."""
