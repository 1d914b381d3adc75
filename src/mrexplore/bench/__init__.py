"""Benchmarks: scenario suites, the episode runner, reports."""
