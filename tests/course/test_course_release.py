"""robotlib release: labs/ is generated from solutions/, deterministically."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest

from robotlib.cli import main
from robotlib.course import release as rel
from robotlib.course.notebooks import (
    NotebookError,
    check_cells,
    notebook_text,
    read_notebook,
    release_notebook,
    strip_region,
)

ROOT = Path(__file__).resolve().parents[2]
TINY = Path(__file__).parents[1] / "data" / "course" / "tiny.ipynb"


def test_labs_are_fresh():
    """labs/ equals a fresh release of solutions/ (run `robotlib release`)."""
    assert rel.stale_labs(ROOT / "solutions", ROOT / "labs") == []


def test_release_check_cli(tmp_path):
    out = tmp_path / "labs"
    cmd = ["release", "--solutions", str(TINY.parent), "--labs", str(out)]
    assert main([*cmd, "--check"]) == 1
    assert main(cmd) == 0
    first = (out / "tiny.ipynb").read_bytes()
    assert main([*cmd, "--check"]) == 0
    assert main(cmd) == 0
    assert (out / "tiny.ipynb").read_bytes() == first  # no churn


def test_release_replaces_solutions_and_hides_tests():
    sol = read_notebook(TINY)
    lab = release_notebook(sol, "tiny")
    text = notebook_text(lab)
    assert "BEGIN SOLUTION" not in text and "HIDDEN" not in text
    assert "return a + b" not in text and "Vectorised" not in text
    assert "assert add(-1, 1) == 0" not in text  # the hidden test is gone
    assert "assert add(1, 2) == 3" in text  # the visible check stays
    code = [c for c in lab.cells if c.cell_type == "code"]
    assert "    # YOUR CODE HERE\n    raise NotImplementedError()" in code[1].source
    assert "YOUR ANSWER HERE" in lab.cells[8].source
    assert all(c.outputs == [] and c.execution_count is None for c in code)
    assert [c.id for c in lab.cells] == [c.id for c in sol.cells]
    assert [c.grade_id for c in check_cells(lab)] == ["add", "mean", "why", "scale"]
    assert "rubric" not in text and "writes" not in text  # answers' keys stay home
    assert lab.cells[8].metadata["robotlib"]["manual"] is True
    checks = [
        c for c in lab.cells if "robotlib" in c.metadata and c.cell_type == "code"
    ]
    assert all(c.metadata["editable"] is False for c in checks)
    # checks fail until solved: JupyterLab's Run All goes past them, not the rest
    auto = [c for c in checks if not c.metadata["robotlib"].get("manual")]
    assert all("raises-exception" in c.metadata["tags"] for c in auto)
    stub = code[1]  # its stub raises inside a function: the cell itself runs
    assert "tags" not in stub.metadata
    nbformat.validate(lab)


def test_release_of_every_lab_is_well_formed():
    for path in sorted((ROOT / "solutions").glob("*.ipynb")):
        sol = read_notebook(path)
        lab = release_notebook(sol, path.stem)
        assert check_cells(lab, path.stem), f"{path.name} has no graded checks"
        first = next(c for c in sol.cells if c.cell_type == "code")
        assert "robotlib.notebook.setup(" in first.source
        loads = first.source.index("robotlib.notebook.loading()")  # a line that moves
        assert loads < first.source.index("import matplotlib"), path.name
        assert "NotImplementedError" in notebook_text(lab)


def test_strip_region_keeps_indentation():
    src = (
        "def f():\n    x = 1\n    ### BEGIN SOLUTION\n    return x\n"
        "    ### END SOLUTION"
    )
    out = strip_region(src, ("### BEGIN SOLUTION", "### END SOLUTION"),
                       ("# YOUR CODE HERE", "raise NotImplementedError()"))  # fmt: skip
    assert (
        out
        == "def f():\n    x = 1\n    # YOUR CODE HERE\n    raise NotImplementedError()"
    )


@pytest.mark.parametrize(
    "source, message",
    [
        ("### BEGIN SOLUTION\nx = 1", "never closed"),
        ("x = 1\n### END SOLUTION", "without"),
        ("### BEGIN SOLUTION\n### BEGIN SOLUTION\n### END SOLUTION", "nested"),
    ],
)
def test_bad_markers_are_reported(source, message):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(source)])
    with pytest.raises(NotebookError, match=message):
        release_notebook(nb, "bad")


def test_bad_check_metadata_is_reported():
    a = nbformat.v4.new_code_cell("pass", metadata={"robotlib": {"grade_id": "x"}})
    b = nbformat.v4.new_code_cell("pass", metadata={"robotlib": {"grade_id": "x"}})
    with pytest.raises(NotebookError, match="used twice"):
        release_notebook(nbformat.v4.new_notebook(cells=[a, b]), "bad")
    c = nbformat.v4.new_code_cell(
        "pass", metadata={"robotlib": {"grade_id": "y", "points": -1}}
    )
    with pytest.raises(NotebookError, match="points"):
        release_notebook(nbformat.v4.new_notebook(cells=[c]), "bad")
    d = nbformat.v4.new_code_cell("### BEGIN SOLUTION\n### END SOLUTION",
                                  metadata={"robotlib": {"grade_id": "z"}})  # fmt: skip
    with pytest.raises(NotebookError, match="cannot hold a solution"):
        release_notebook(nbformat.v4.new_notebook(cells=[d]), "bad")


@pytest.mark.parametrize("folder", ["solutions", "labs"])
def test_every_graded_check_cell_says_so(folder):
    """Every lab's graded checks open with '# CHECK (graded, N points)', tagged."""
    import json

    from robotlib.course.marking import unmarked

    found = {}
    for path in sorted((ROOT / folder).glob("*.ipynb")):
        nb = json.loads(path.read_text())
        checks = [
            c for c in nb["cells"]
            if "grade_id" in c["metadata"].get("robotlib", {})
            and not c["metadata"]["robotlib"].get("manual")
        ]  # fmt: skip
        missing = unmarked(nb) if checks else ["no graded check cell"]
        if missing:
            found[path.name] = missing
    assert not found, found


def test_marking_adds_header_and_tag_once_and_fixes_wrong_points():
    from robotlib.course.marking import check_header, mark_checks, unmarked

    def cell(source, points=2, **meta):
        robotlib_meta = {"grade_id": "g", "points": points, **meta}
        return {"cell_type": "code", "metadata": {"robotlib": robotlib_meta},
                "source": source}  # fmt: skip

    nb = {"cells": [
        cell("assert f(1) == 2\n", points=1),
        cell(["# CHECK (graded, 5 points): old\n", "assert g()\n"], points=3),
        cell("answer", manual=True),
        {"cell_type": "code", "metadata": {}, "source": "x = 1"},
    ]}  # fmt: skip
    assert len(unmarked(nb)) == 4  # two headers (one missing, one wrong), two tags
    assert mark_checks(nb) == 2
    assert unmarked(nb) == []
    assert nb["cells"][0]["source"] == check_header(1) + "\nassert f(1) == 2\n"
    assert "(graded, 1 point)" in check_header(1)
    assert nb["cells"][1]["source"] == [check_header(3) + "\n", "assert g()\n"]
    assert nb["cells"][1]["metadata"]["tags"] == ["graded"]
    assert "tags" not in nb["cells"][2]["metadata"]  # written answers: not checks
    assert nb["cells"][3] == {"cell_type": "code", "metadata": {}, "source": "x = 1"}
    assert mark_checks(nb) == 0  # re-running changes nothing


def _demo_block(node) -> bool:
    """Whether a statement is ``with robotlib.notebook.demo():``."""
    import ast

    return isinstance(node, ast.With) and any(
        ast.unparse(item.context_expr).endswith("demo()") for item in node.items
    )


def test_every_demonstration_of_student_code_is_a_demo_block():
    """A cell that runs an exercise's code does it in ``with ...demo():``.

    Else, in the released lab, the cell fails while the exercise is not done
    (a traceback, and JupyterLab's Run All stops there). Names an exercise
    writes taint the functions that use them; a top-level statement outside
    a demo block that reads a tainted name is reported. Static, so a new lab
    is checked in milliseconds.
    """
    import ast

    from robotlib.course.notebooks import check_meta, exercises, setup_cell

    found = []
    for path in sorted((ROOT / "solutions").glob("*.ipynb")):
        nb = read_notebook(path)
        own = {e.index for e in exercises(nb, path.stem)}
        tainted = {n for e in exercises(nb, path.stem) for n in e.names}
        trees = {}
        for i, cell in enumerate(nb.cells):
            skip = i in own or i == setup_cell(nb) or check_meta(cell) is not None
            if cell.cell_type == "code" and not skip:
                trees[i] = ast.parse(cell.source)
        grew = True
        while grew:  # functions (and classes) that call tainted code are tainted
            grew = False
            for tree in trees.values():
                for node in tree.body:
                    defines = isinstance(node, ast.FunctionDef | ast.ClassDef)
                    if defines and node.name not in tainted:
                        used = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
                        if used & tainted:
                            tainted.add(node.name)
                            grew = True
        for i, tree in trees.items():
            for node in tree.body:
                if _demo_block(node) or isinstance(
                    node, ast.FunctionDef | ast.ClassDef
                ):
                    continue
                used = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
                if used & tainted:
                    names = sorted(used & tainted)
                    found.append(f"{path.stem} cell {i} line {node.lineno}: {names}")
    assert not found, "outside `with robotlib.notebook.demo():`\n" + "\n".join(found)
