"""The two-stage KF (method A): its step, guards, offsets, smoother, projection KF, step cache."""
