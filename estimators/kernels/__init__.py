"""Numeric kernels: Kalman updates, discretisation, first-order and zero-phase filters."""
