"""The grader parses Python safely from several threads at once."""

import gc
import re
import threading
import time
from pathlib import Path

import pytest

from robotlib.course import astlock

COURSE = Path(__file__).parents[2] / "robotlib" / "course"
SOURCE = (COURSE / "plan.py").read_text()


class _Cycle:
    """Garbage only the collector frees; its finaliser lets other threads run."""

    def __init__(self):
        self.me = self

    def __del__(self):
        time.sleep(0)


def _in_threads(work, n_threads=4, repeats=50):
    errors = []

    def loop():
        for _ in range(repeats):
            [_Cycle() for _ in range(20)]
            try:
                work()
            except SystemError as exc:  # the AST builder's shared counter
                errors.append(exc)
                return

    old = gc.get_threshold()
    gc.set_threshold(30)
    try:
        threads = [threading.Thread(target=loop) for _ in range(n_threads)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=120)
    finally:
        gc.set_threshold(*old)
    assert not any(t.is_alive() for t in threads)
    return errors


@pytest.mark.slow
def test_parse_in_threads_never_raises_system_error():
    # plain ast.parse fails here on CPython 3.11 within a few calls
    assert _in_threads(lambda: astlock.parse(SOURCE)) == []


@pytest.mark.slow
def test_tracebacks_in_threads_never_raise_system_error():
    def fail_and_format():
        try:
            {}["missing"] + SOURCE[0]
        except KeyError:
            assert "KeyError" in astlock.format_exc()
        astlock.parse(SOURCE)

    assert _in_threads(fail_and_format) == []


def test_the_course_parses_only_through_the_lock():
    direct = re.compile(r"\bast\.parse\(|\btraceback\.format_exc\(")
    users = [
        p.name
        for p in COURSE.glob("*.py")
        if p.name != "astlock.py" and direct.search(p.read_text())
    ]
    assert users == []
