"""The moving-horizon estimator: settings, QP window, ring buffers, per-sample terms."""
