"""``wheelload misra``: the MISRA C:2012 report of generated C (``command``)."""
