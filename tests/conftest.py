"""Test-wide settings: property tests draw the same examples on every run.

CI must be deterministic: hypothesis derives its examples from each test's
own name instead of a fresh random seed, so a run passes or fails the same
way on every machine. An example that once failed stays in its test as an
``@example``.

Modules with slow subprocess work start it when the session starts, beside
the tests, and run their tests last (`tests.background`). Gradings of the
same lab share one reference run of its solution (`tests.references`).

SIGTERM (a CI runner stopping the job) ends the run as Ctrl-C does: the
session stops at once, its background work is ended and its folders are
removed (`tests.background.end`), and pytest exits with status 2. A
grading in the foreground turns SIGTERM into its own clean stop first
(`robotlib.course.grade.grade`), then the session ends the same way.
"""

import signal

import pytest
from hypothesis import settings

from tests import background, references

settings.register_profile("robotlib", derandomize=True, print_blob=True)
settings.load_profile("robotlib")


def _terminated(signum, frame):
    """SIGTERM: end the session as Ctrl-C does (once: a second one waits for it)."""
    signal.signal(signal.SIGTERM, lambda *_: None)
    raise KeyboardInterrupt(f"signal {signum}")


def pytest_configure(config):
    signal.signal(signal.SIGTERM, _terminated)
    references.start()


def pytest_unconfigure(config):
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    references.end()


@pytest.hookimpl(trylast=True)  # after the selection by -m and -k
def pytest_collection_modifyitems(session, config, items):
    """The tests of modules with background work run last (`tests.background`)."""
    items.sort(key=lambda item: hasattr(getattr(item, "module", None), background.HOOK))


def pytest_collection_finish(session):
    if session.config.option.collectonly:
        return
    modules: dict = {}
    for item in session.items:
        module = getattr(item, "module", None)
        if hasattr(module, background.HOOK):
            modules.setdefault(module, []).append(item)
    background.start(modules)


def pytest_sessionfinish(session, exitstatus):
    background.end()
