"""Layer 3 (paper IV-C): routing a robot through the sub-clusters of its assigned cluster."""
