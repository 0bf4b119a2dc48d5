"""The moving-horizon estimator: settings, QP, per-sample state, ring buffers, windows, terms."""
