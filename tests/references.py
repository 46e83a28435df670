"""One reference run per lab and solution for the whole test session.

A grading starts with the reference run of the lab's solution, unless its
records folder holds a saved one made from the same solution and library
(`robotlib.course.cache.load_reference`). The tests grade the tiny lab and
Lab 0 in several modules and processes (the session's own and those of its
background work, `tests.background`); `shared` lets them make that run once.

The session's store is a temporary folder named by ``ROBOTLIB_TEST_REFERENCES``
(set by `start`, so every process the session starts inherits it). In
``with shared(lab, solution, records):`` the first grading of a solution makes
its reference run as usual and, once the grader has saved it in ``records``,
keeps a copy in the store; meanwhile the others wait for it (a lock per
solution), then start from that copy. A test of the reference run itself
(saving, reuse, what it costs) does not use `shared`.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import tempfile
import threading
from pathlib import Path

from robotlib.course.cache import reference_key
from robotlib.course.notebooks import notebook_text, read_notebook

ENV = "ROBOTLIB_TEST_REFERENCES"
SAVED = ".reference"
"""The grader's folder of a saved reference run, in a records folder."""


_made: list[str] = []


def start() -> None:
    """Make the session's store (unless a session that started this one has one)."""
    if not os.environ.get(ENV):
        os.environ[ENV] = tempfile.mkdtemp(prefix="robotlib-references-")
        _made.append(os.environ[ENV])


def end() -> None:
    """Remove the store `start` made, if it made one."""
    while _made:
        shutil.rmtree(_made.pop(), ignore_errors=True)
        os.environ.pop(ENV, None)


def records_of(gradebook: Path) -> Path:
    """The records folder ``robotlib grade --out GRADEBOOK`` uses."""
    return gradebook.with_name(f"{gradebook.stem}-records")


@contextlib.contextmanager
def shared(lab: str, solution: Path, records: Path):
    """Grade ``lab`` inside the block with ``records``, sharing its reference run.

    Parameters
    ----------
    lab : str
        The lab's name, as given to the grader.
    solution : pathlib.Path
        The solution notebook it grades against.
    records : pathlib.Path
        The records folder of the grading (``records=``, or `records_of` the
        CLI's gradebook); it must not hold a saved reference run yet.
    """
    store = os.environ.get(ENV)
    if not store:  # outside a session of this suite: a run of its own
        yield
        return
    key = reference_key(notebook_text(read_notebook(solution)), lab)
    saved = Path(store) / key
    lock = os.open(Path(store) / f"{key}.lock", os.O_RDWR | os.O_CREAT, 0o600)
    fcntl.flock(lock, fcntl.LOCK_EX)  # while another grading makes it
    if saved.is_dir():
        os.close(lock)
        records.mkdir(parents=True, exist_ok=True)
        shutil.copytree(saved, records / SAVED)
        yield
        return
    done = threading.Event()

    def keep() -> None:
        """Copy the reference run into the store once saved, then let the others in."""
        made = records / SAVED / "reference.json"  # renamed into place whole
        try:
            while not done.is_set() and not made.exists():
                done.wait(0.2)
            if made.exists():
                part = saved.with_name(f"{key}.part")
                shutil.copytree(records / SAVED, part)
                part.rename(saved)
        except OSError:
            pass  # the others make their own
        finally:
            os.close(lock)

    keeper = threading.Thread(target=keep, name="reference-keeper", daemon=True)
    keeper.start()
    try:
        yield
    finally:
        done.set()
        keeper.join()
