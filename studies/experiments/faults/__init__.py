"""Faulty and hostile logs: sensor faults, spikes, corruptions, and their studies."""
