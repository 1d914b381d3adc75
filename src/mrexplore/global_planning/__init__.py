"""Layer 2 (paper IV-B): the GlobalPlanner protocol and the classical assigners."""
