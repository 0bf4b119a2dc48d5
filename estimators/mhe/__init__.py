"""The moving-horizon estimator: settings, QP, per-sample state, the loop over a log, windows, terms."""
