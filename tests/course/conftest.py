"""Fixtures of the grading tests."""

import pytest

from tests.sandboxing import orphans_adopted


@pytest.fixture
def adopting():
    """The test adopts its escaped processes (`tests.sandboxing.orphans_adopted`)."""
    with orphans_adopted():
        yield
