"""The paper's experiments and their extensions, one module per study (``wheelload study``)."""
