"""The moving-horizon estimator: settings, QP, per-sample state, loop over a log, windows."""
