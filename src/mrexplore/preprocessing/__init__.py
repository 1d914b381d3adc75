"""Layer 1 (paper IV-A): closing, frontier detection and Mean-Shift clustering."""
