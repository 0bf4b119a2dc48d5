"""Logs in and out: readers and channel maps, validated signals, checks, output files."""
