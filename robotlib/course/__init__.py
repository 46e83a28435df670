"""Course machinery: release labs from solutions, grade submissions in a sandbox.

One source: ``solutions/NAME.ipynb`` holds each lab with its solutions
between ``### BEGIN SOLUTION`` / ``### END SOLUTION`` markers and its graded
check cells, tagged in their metadata::

    {"robotlib": {"grade_id": "weights", "points": 2}}

`robotlib.course.release` writes the student notebooks in ``labs/`` from it;
`robotlib.course.grade` grades a folder of submissions in a sandbox: the
student's cells in one process, the instructor's checks (hidden tests
included) in another. See ``course/instructor-guide.md``.
"""

__all__ = [
    "CheckCell",
    "check_cells",
    "check_meta",
    "read_notebook",
    "release_notebook",
    "write_notebook",
]


def __getattr__(name):  # lazy: the sandboxed workers never import nbformat
    if name in __all__:
        from . import notebooks

        return getattr(notebooks, name)
    raise AttributeError(name)
