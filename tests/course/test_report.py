"""The class report, LMS grade import, late penalties and similar answers."""

from __future__ import annotations

import csv
import datetime as dt

import pytest

from robotlib.course.gradebook import Result
from robotlib.course.notebooks import CheckCell
from robotlib.course.report import (
    class_report,
    export_lms,
    late_days,
    read_roster,
    similar_pairs,
)

CHECKS = [CheckCell("add", 1.0, "a", 1), CheckCell("mean", 2.0, "b", 2)]
DUE = "2026-12-01T23:59:00+00:00"
ANSWER = """
def mean(xs):
    total = 0.0
    for x in xs:  # add them up
        total += x
    count = len(xs)
    if count == 0:
        raise ValueError("no values")
    return total / count
"""


def _when(iso):
    return dt.datetime.fromisoformat(iso).timestamp()


def _class():
    copied = ANSWER.replace("# add them up", "# my own loop").replace("    ", "  ")
    return [
        Result("ann", {"add": 1.0, "mean": 2.0}, {}, 3.0, seconds=3.0,
               code={"mean": ANSWER}, submitted=_when("2026-12-01T12:00:00+00:00")),
        Result("bob", {"add": 1.0, "mean": 0.0}, {}, 3.0, seconds=9.0,
               code={"mean": copied}, submitted=_when("2026-12-03T08:00:00+00:00"),
               flags=["uses exec (call)"]),
        Result("cy", {"add": 0.0, "mean": 2.0}, {}, 3.0, seconds=1.0,
               code={"mean": "def mean(xs):\n    return sum(xs) / len(xs)\n"}),
    ]  # fmt: skip


def test_similar_answers_late_days_and_the_report(tmp_path):
    results = _class()
    pairs = similar_pairs(results)
    assert [(e, a, b) for e, a, b, _ in pairs] == [("mean", "ann", "bob")]
    assert [late_days(r, DUE) for r in results] == [0, 2, 0]
    page = tmp_path / "report.html"
    class_report(page, results, CHECKS, "tiny", DUE)
    text = page.read_text()
    assert text.count("data:image/png;base64,") == 2
    assert "uses exec" in text and "<td>bob</td><td>2</td>" in text
    assert "<td>mean</td><td>ann</td><td>bob</td>" in text
    assert "<td>add</td><td>1</td><td>67</td>" in text  # 2 of 3 pass `add`


def test_canvas_and_moodle_imports_from_a_roster(tmp_path):
    roster_csv = tmp_path / "roster.csv"
    roster_csv.write_text(
        "\ufefffolder,id,name,email,section\n"
        "ann,1001,Ann A,ann@uni.edu,S1\nbob,1002,Bob B,bob@uni.edu,S2\n",
        encoding="utf-8",
    )
    roster = read_roster(roster_csv)
    results = _class()
    canvas = tmp_path / "canvas.csv"
    missing = export_lms(canvas, results, "canvas", "Lab 0", roster, DUE, 0.1)
    assert missing == ["cy"]
    rows = list(csv.reader(canvas.open()))
    assert rows[0][-1] == "Lab 0" and rows[1][-1] == "3"
    # bob: 1 point, 2 days late at 10 % of 3 points a day -> 0.4
    assert rows[2] == ["Ann A", "1001", "1001", "ann@uni.edu", "S1", "3"]
    assert rows[3][-1] == "0.4"
    moodle = tmp_path / "moodle.csv"
    export_lms(moodle, results, "moodle", "Lab 0", roster)
    lines = list(csv.reader(moodle.open()))[1:]
    assert lines == [["ann@uni.edu", "3"], ["bob@uni.edu", "1"]]
    bad = tmp_path / "bad.csv"
    bad.write_text("name,id\nann,1\n")
    with pytest.raises(ValueError, match="'folder' column"):
        read_roster(bad)
