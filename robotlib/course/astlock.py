"""One lock for CPython's AST builder, shared by the grader's threads.

CPython 3.11 keeps one counter per interpreter while it turns parsed code
into `ast` objects. When two threads do it at once (a garbage collection in
the middle lets the other thread run), the later call fails with
``SystemError: AST constructor recursion depth mismatch`` (CPython issue
gh-106905). The grader scans submissions in a thread pool, so every parse in
`robotlib.course` goes through `parse`, and tracebacks, which Python 3.11
parses to place their ``^^^`` markers, through `format_exc`.
"""

from __future__ import annotations

import ast
import threading
import traceback

_LOCK = threading.Lock()


def parse(source: str) -> ast.Module:
    """`ast.parse` of ``source``, one thread at a time.

    Parameters
    ----------
    source : str
        Python code.

    Returns
    -------
    ast.Module

    Raises
    ------
    SyntaxError, ValueError
        As `ast.parse` does (a null byte gives ValueError).
    """
    with _LOCK:
        return ast.parse(source)


def format_exc() -> str:
    """`traceback.format_exc`, one thread at a time."""
    with _LOCK:
        return traceback.format_exc()
