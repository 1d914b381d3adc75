"""mrexplore: hierarchical multi-robot exploration (frontier preprocessing, global assignment, local routing)."""

__version__ = "0.1.0"
