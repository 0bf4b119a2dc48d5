"""Fixtures of the studies' tests."""

import logging

import pytest


@pytest.fixture
def library_caplog(caplog):
    """The library's records straight from its logger (the console command stops them
    propagating to the root, where pytest listens, once it has run in this process)."""
    library = logging.getLogger("wheelload")
    propagate = library.propagate
    library.addHandler(caplog.handler)
    library.propagate = False
    yield caplog
    library.removeHandler(caplog.handler)
    library.propagate = propagate
