"""Estimate one or many logs: batch, lean path, digest, warnings, method comparison."""
