"""The report: the paper's numbers, tables, figures and the words on their shape."""
