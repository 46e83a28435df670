"""Course machinery: release labs from solutions, grade submissions with nbval.

One source: ``solutions/NAME.ipynb`` holds each lab with its solutions
between ``### BEGIN SOLUTION`` / ``### END SOLUTION`` markers and its graded
check cells, tagged in their metadata::

    {"robotlib": {"grade_id": "weights", "points": 2}}

`robotlib.course.release` writes the student notebooks in ``labs/`` from it;
`robotlib.course.grade` grades a folder of submissions with nbval, after
putting the instructor's check cells (hidden tests included) back into each
submission. See ``course/instructor-guide.md``.
"""

from .notebooks import (
    CheckCell,
    check_cells,
    check_meta,
    read_notebook,
    release_notebook,
    write_notebook,
)

__all__ = [
    "CheckCell",
    "check_cells",
    "check_meta",
    "read_notebook",
    "release_notebook",
    "write_notebook",
]
