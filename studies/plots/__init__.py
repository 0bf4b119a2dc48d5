"""Figures of the command line: estimates, comparisons, scenarios, identification."""
