"""What an instructor does with a graded class: a report, LMS grades, late days.

- `class_report`: one HTML page (plots embedded) with the score histogram,
  each check's pass rate, the statuses, the slowest and the flagged
  students, late submissions and pairs of suspiciously similar answers.
- `similar_pairs`: students whose answer to one exercise is nearly the same
  text (comments and blank lines aside), answers too short to tell or left
  as released excluded.
- `read_roster` / `export_lms`: a roster CSV maps each submission (its
  folder or file name) to the student's LMS identity; the export writes a
  Canvas gradebook-import CSV or a Moodle grade-import CSV.
- `late_days`: days after the due date, from the roster's ``due`` column
  or the class's, against the notebook's modification time (or the
  roster's ``submitted`` column); `final_score` applies a penalty per day.

Imports `gradebook` and `notebooks` only (matplotlib when drawing).
"""

from __future__ import annotations

import base64
import csv
import datetime as dt
import difflib
import html
import io
import math
import re
from pathlib import Path

from .gradebook import Result, _atomic
from .notebooks import CheckCell

__all__ = [
    "class_report",
    "export_lms",
    "final_score",
    "late_days",
    "read_roster",
    "similar_pairs",
]


def _code(text: str) -> str:
    """Return an answer as compared: comments, blank lines, indentation aside."""
    lines = (re.sub(r"#.*", "", ln).strip() for ln in text.splitlines())
    return "\n".join(ln for ln in lines if ln)


def similar_pairs(
    results: list[Result], threshold: float = 0.9, shortest: int = 120
) -> list[tuple[str, str, str, float]]:
    """Return ``(exercise, student, student, similarity)``, most similar first.

    Answers shorter than ``shortest`` characters (once comments are removed)
    or still holding ``NotImplementedError`` are left out: short correct
    answers look alike for honest reasons.
    """
    by_ex: dict[str, list[tuple[str, str]]] = {}
    for r in results:
        for ex, text in r.code.items():
            code = _code(text)
            if len(code) >= shortest and "NotImplementedError" not in code:
                by_ex.setdefault(ex, []).append((r.student, code))
    out = []
    for ex, answers in by_ex.items():
        for i, (a, ca) in enumerate(answers):
            for b, cb in answers[i + 1 :]:
                m = difflib.SequenceMatcher(None, ca, cb, autojunk=False)
                if m.real_quick_ratio() < threshold or m.quick_ratio() < threshold:
                    continue
                if (ratio := m.ratio()) >= threshold:
                    out.append((ex, a, b, round(ratio, 3)))
    return sorted(out, key=lambda t: -t[3])


def read_roster(path: str | Path) -> dict[str, dict[str, str]]:
    """Read a roster CSV: ``{folder: {column: value}}``.

    Columns: ``folder`` (the submission's name in the gradebook) and any of
    ``id``, ``name``, ``email``, ``section``, ``due`` (ISO date-time),
    ``submitted``.

    Raises
    ------
    ValueError
        Without a ``folder`` column, or with one folder twice.
    """
    with open(path, newline="", encoding="utf-8-sig") as f:
        rows = list(csv.DictReader(f))
    if rows and "folder" not in rows[0]:
        raise ValueError(f"{path}: the roster needs a 'folder' column")
    out: dict[str, dict[str, str]] = {}
    for n, row in enumerate(rows, 2):
        key = (row.get("folder") or "").strip()
        if key in out:
            raise ValueError(f"{path}, line {n}: folder {key!r} twice")
        out[key] = {k: (v or "").strip() for k, v in row.items() if k}
    return out


def _when(text: str) -> float:
    t = dt.datetime.fromisoformat(text)
    if t.tzinfo is None:
        t = t.replace(tzinfo=dt.UTC)
    return t.timestamp()


def late_days(result: Result, due: str | None, roster: dict | None = None) -> int:
    """Whole days (started) after the due date; 0 when on time or unknown."""
    row = (roster or {}).get(result.student, {})
    due = row.get("due") or due
    if not due:
        return 0
    handed = _when(row["submitted"]) if row.get("submitted") else result.submitted
    if not handed:
        return 0
    return max(0, math.ceil((handed - _when(due)) / 86400.0))


def final_score(result: Result, days: int, penalty: float) -> float:
    """Return the total less ``penalty`` (of the maximum) per late day, >= 0."""
    return max(0.0, result.total - days * penalty * result.max_points)


def export_lms(
    path: str | Path,
    results: list[Result],
    kind: str,
    assignment: str,
    roster: dict[str, dict[str, str]],
    due: str | None = None,
    penalty: float = 0.0,
) -> list[str]:
    """Write a grade-import CSV for Canvas or Moodle; return the unmatched students.

    Canvas: ``Student, ID, SIS User ID, SIS Login ID, Section, <assignment>``
    (the roster's ``name``, ``id``, ``email``). Moodle: ``email, <assignment>``
    (map the email column to the user's email on import). Late penalties
    are applied. A submission missing from the roster is left out and named.
    """
    if kind not in ("canvas", "moodle"):
        raise ValueError(f"unknown LMS {kind!r}: canvas or moodle")
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    if kind == "canvas":
        w.writerow(
            ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", assignment]
        )
        w.writerow(["Points Possible", "", "", "", "", f"{_max(results):g}"])
    else:
        w.writerow(["email", assignment])
    missing = []
    for r in results:
        row = roster.get(r.student)
        if row is None:
            missing.append(r.student)
            continue
        score = f"{final_score(r, late_days(r, due, roster), penalty):g}"
        if kind == "canvas":
            who = [row.get("name", r.student), row.get("id", ""), row.get("id", "")]
            w.writerow([*who, row.get("email", ""), row.get("section", ""), score])
        else:
            w.writerow([row.get("email", ""), score])
    _atomic(Path(path), buf.getvalue())
    return missing


def _max(results: list[Result]) -> float:
    return max((r.max_points for r in results), default=0.0)


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    return base64.b64encode(buf.getvalue()).decode()


def _plots(results: list[Result], checks: list[CheckCell]) -> tuple[str, str]:
    from matplotlib.figure import Figure

    totals = [r.total for r in results]
    top = _max(results)
    fig = Figure(figsize=(6, 3))
    ax = fig.subplots()
    step = max(0.5, math.ceil(top / 20 * 2) / 2)  # at most about 20 bars
    edges = [step * (k - 0.5) for k in range(int(top / step) + 2)]
    ax.hist(totals, bins=edges, edgecolor="white")
    ax.set_xlabel("total (points)")
    ax.set_ylabel("students")
    hist = _png(fig)
    fig = Figure(figsize=(6, 0.4 * len(checks) + 1))
    ax = fig.subplots()
    rates = [_rate(results, c) for c in checks]
    ax.barh([c.grade_id for c in checks], rates)
    ax.set_xlim(0, 100)
    ax.invert_yaxis()
    ax.set_xlabel("students passing (%)")
    return hist, _png(fig)


def _rate(results: list[Result], c: CheckCell) -> float:
    graded = [r for r in results if c.grade_id in r.points]
    full = sum(r.points[c.grade_id] >= c.points for r in graded)
    return 100.0 * full / len(graded) if graded else 0.0


def _table(head: list[str], rows: list[list]) -> str:
    if not rows:
        return "<p>None.</p>"
    cells = "".join(f"<th>{html.escape(h)}</th>" for h in head)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(v))}</td>" for v in row) + "</tr>"
        for row in rows
    )
    return f"<table><tr>{cells}</tr>{body}</table>"


def class_report(
    path: str | Path,
    results: list[Result],
    items: list[CheckCell],
    lab: str,
    due: str | None = None,
    roster: dict | None = None,
) -> None:
    """Write the class's report, one self-contained HTML page."""
    checks = [c for c in items if not c.manual]
    hist, rates = _plots(results, checks) if results else ("", "")
    totals = sorted(r.total for r in results)
    median = totals[len(totals) // 2] if totals else 0.0
    statuses: dict[str, int] = {}
    for r in results:
        statuses[r.status] = statuses.get(r.status, 0) + 1
    slow = sorted(results, key=lambda r: -r.seconds)[:10]
    flagged = [r for r in results if r.flags]
    late = [(r.student, d) for r in results if (d := late_days(r, due, roster))]
    pairs = similar_pairs(results)
    parts = [
        f"<h1>{html.escape(lab)}: class report</h1>",
        f"<p>{len(results)} submissions; median {median:g} of {_max(results):g} "
        "points.</p>",
        "<h2>Scores</h2>",
        f'<img alt="score histogram" src="data:image/png;base64,{hist}">',
        "<h2>Checks</h2>",
        f'<img alt="pass rate per check" src="data:image/png;base64,{rates}">',
        _table(
            ["check", "points", "passing (%)"],
            [[c.grade_id, f"{c.points:g}", f"{_rate(results, c):.0f}"] for c in checks],
        ),
        "<h2>Statuses</h2>",
        _table(["status", "students"], sorted(statuses.items())),
        "<h2>Slowest</h2>",
        _table(
            ["student", "seconds", "status"],
            [[r.student, f"{r.seconds:.1f}", r.status] for r in slow],
        ),  # fmt: skip
        "<h2>Flagged</h2>",
        _table(
            ["student", "flags"], [[r.student, "; ".join(r.flags)] for r in flagged]
        ),
        "<h2>Late</h2>",
        _table(["student", "days late"], late),
        "<h2>Similar answers</h2>",
        "<p>Pairs whose answer to one exercise is at least 90 % the same text "
        "(comments aside): worth a look, not a verdict.</p>",
        _table(["exercise", "student", "student", "similarity"], pairs),
    ]
    style = (
        "body{font-family:sans-serif;max-width:60em;margin:2em auto}"
        "table{border-collapse:collapse;margin:1em 0}"
        "td,th{border:1px solid #bbb;padding:.2em .6em;text-align:left}"
    )
    page = (
        f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(lab)}"
        f"</title><style>{style}</style></head><body>{''.join(parts)}</body></html>\n"
    )
    _atomic(Path(path), page)
