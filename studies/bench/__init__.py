"""Benchmarks' workloads and baselines (``wheelload bench``)."""
