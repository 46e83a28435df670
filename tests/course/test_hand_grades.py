"""Hand grades of written answers are records that no grading run resets.

The sheet the guide says to edit (``<out>-manual.csv``) starts with an empty
``score`` column (ungraded is not 0), takes a ``comment`` that reaches the
feedback, may be saved by Excel (UTF-8 with a byte-order mark, semicolons),
and what was typed into it survives every later run, with or without
``--manual``. A partial hand grade is not "passed". The CLI's runs are made
beside the other tests (`tests.background`); this module's tests run last.
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import pytest

from robotlib.course.command import fold_manual
from robotlib.course.grade import UNGRADED
from robotlib.course.gradebook import (
    HandGrades,
    Result,
    export_manual,
    feedback_text,
    gradebook_rows,
    read_manual,
)
from robotlib.course.notebooks import (
    CheckCell,
    read_notebook,
    release_notebook,
    write_notebook,
)
from tests import background
from tests.course.test_course_grade import TINY
from tests.references import records_of, shared
from tests.sandboxing import need_sandbox

WHY = CheckCell("why", 2.0, "c", 8, manual=True, rubric="r")
AUTO = CheckCell("add", 1.0, "d", 4)


def _results():
    return [
        Result("ann", {"add": 1.0}, {"why": UNGRADED}, 3.0, answers={"why": "Fast."}),
        Result("bob", {"add": 0.0}, {"why": UNGRADED}, 3.0, answers={"why": "?"}),
    ]


def _rows(path, **kw):
    with open(path, newline="", encoding="utf-8-sig") as f:
        return list(csv.DictReader(f, **kw))


def test_sheet_starts_ungraded_and_keeps_what_was_typed(tmp_path):
    sheet, record = tmp_path / "gb-manual.csv", tmp_path / "gb-hand.json"
    results = _results()
    hand = HandGrades(record)
    assert fold_manual(results, [AUTO, WHY], hand) == 2
    export_manual(sheet, results, [WHY], hand)
    rows = _rows(sheet)
    assert [r["score"] for r in rows] == ["", ""] and "comment" in rows[0]
    assert [r["why"] for r in gradebook_rows(results, [AUTO, WHY])] == ["", ""]

    # the instructor grades ann 1 of 2 with a comment, in Excel (BOM, semicolons)
    rows[0].update(score="1", comment="Say why it is faster.")
    with open(sheet, "w", newline="", encoding="utf-8-sig") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]), delimiter=";")
        w.writeheader()
        w.writerows(rows)
    hand.merge(read_manual(sheet, [WHY]))
    hand.save()

    for _ in range(2):  # two later runs, neither with --manual
        results, hand = _results(), HandGrades(record)
        assert fold_manual(results, [AUTO, WHY], hand) == 1
        export_manual(sheet, results, [WHY], hand)
        hand.merge(read_manual(sheet, [WHY]))
    ann = results[0]
    assert ann.points["why"] == 1.0 and ann.total == 2.0
    assert [r["score"] for r in _rows(sheet)] == ["1", ""]
    assert [r["why"] for r in gradebook_rows(results, [AUTO, WHY])] == ["1", ""]
    text = feedback_text(ann, [AUTO, WHY], "tiny")
    line = next(ln for ln in text.splitlines() if ln.startswith("| why"))
    assert "1 / 2" in line and "Say why it is faster." in line and "passed" not in line
    bob = feedback_text(results[1], [AUTO, WHY], "tiny")
    assert "| why | - / 2 | written answer: not graded by hand yet |" in bob


def test_bad_sheets_say_what_is_wrong(tmp_path):
    sheet = tmp_path / "m.csv"
    sheet.write_text("name,score\nann,1\n", encoding="utf-8")
    with pytest.raises(ValueError, match="no column grade_id, student"):
        read_manual(sheet, [WHY])
    sheet.write_text("student,grade_id,score\nann,why,3\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not in"):
        read_manual(sheet, [WHY])
    sheet.write_text("student,grade_id,score\nann,why,good\n", encoding="utf-8")
    with pytest.raises(ValueError, match="not a number"):
        read_manual(sheet, [WHY])
    sheet.write_text('\ufeffstudent,grade_id,score\nann,why,"1,5"\n', encoding="utf-8")
    assert read_manual(sheet, [WHY]) == {"ann": {"why": {"score": 1.5}}}
    # Excel's plain "CSV" on Windows: Windows-1252, CRLF
    sheet.write_bytes(
        "student;grade_id;score;comment\r\nJosé;why;2;très bien\r\n".encode("cp1252")
    )
    assert read_manual(sheet, [WHY]) == {
        "José": {"why": {"score": 2.0, "comment": "très bien"}}
    }


def background_work(folder: Path) -> dict:
    """The CLI end to end beside the other tests (`tests.background`), if selected.

    Grade, type a score into the sheet as Excel saves it, run twice more;
    returns each run's process, gradebook rows and sheet scores.
    """
    names = {item.originalname for item in background.selected(__name__)}
    if "test_a_run_without_manual_keeps_the_hand_grades" not in names:
        return {}
    need_sandbox()
    subs = folder / "subs"
    for name, nb in (("ann", read_notebook(TINY)), ("bob", None)):
        (subs / name).mkdir(parents=True)
        nb = nb or release_notebook(read_notebook(TINY), "tiny")
        write_notebook(nb, subs / name / "tiny.ipynb")
    out = folder / "gb.csv"
    cmd = [sys.executable, "-m", "robotlib.cli", "grade", str(subs), "--lab", "tiny",
           "--solution", str(TINY), "--out", str(out), "--cell-timeout", "20",
           "--jobs", "2", "--quiet"]  # fmt: skip
    sheet = out.with_name("gb-manual.csv")

    def run():
        proc = background.run(cmd, 600)  # quiet s: tests.contention
        rows = {r["student"]: r for r in _rows(out)} if out.exists() else {}
        scores = [r["score"] for r in _rows(sheet)] if sheet.exists() else None
        return proc, rows, scores

    with shared("tiny", TINY, records_of(out)):
        runs = {"first": run()}
    if runs["first"][2] == ["", ""]:
        lines = _rows(sheet)
        lines[0].update(score="1", comment="Good.")
        with open(sheet, "w", newline="", encoding="utf-8-sig") as f:  # Excel's BOM
            w = csv.DictWriter(f, fieldnames=list(lines[0]))
            w.writeheader()
            w.writerows(lines)
        runs["second"], runs["third"] = run(), run()
    fb = next(out.with_name("gb-feedback").glob("ann-*.md"), None)
    runs["feedback"] = fb.read_text() if fb else ""
    return runs


@pytest.mark.slow
def test_a_run_without_manual_keeps_the_hand_grades():
    """The CLI end to end: grade, type a score into the sheet, run twice more."""
    runs = background.result(__name__)
    proc, rows, scores = runs["first"]
    assert proc.returncode == 0, proc.stderr
    assert rows["ann"]["why"] == "" and "written answers to grade" in proc.stderr
    assert "1 of 2 have full marks on the automatic checks" in proc.stderr
    assert scores == ["", ""]
    for again in ("second", "third"):
        proc, rows, scores = runs[again]
        assert proc.returncode == 0, proc.stderr
        assert rows["ann"]["why"] == "1" and rows["ann"]["total"] == "5", rows["ann"]
        assert scores == ["1", ""]
    assert "graded by hand: Good." in runs["feedback"]
