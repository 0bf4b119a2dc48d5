"""Step loops over a log: compiled whole-log, fast per-sample, chunked from a file."""
