"""The documentation site: pages, the API reference from the docstrings, executed journeys.

:func:`build_docs` builds the HTML site (``wheelload docs --out DIR``) with warnings as
errors; the journeys' code blocks (``{run}`` directive, :mod:`.run_blocks`) run while it
builds, so every output on a page is what the installed package printed.
"""

from wheelload.studies.docs.build import build_docs

__all__ = ["build_docs"]
