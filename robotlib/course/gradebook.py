"""Grades on disk: per-submission records, the gradebook CSV, feedback, manual points.

- `Result`: one submission's grade.
- `Records`: one JSON file per submission in ``<out>-records/``, written
  atomically (temporary file, fsync, rename) as soon as it is graded, so an
  interrupted class resumes where it stopped (`Records.done`).
- `write_gradebook`: the CSV, one row per student, rewritten atomically.
- `feedback_text` / `write_feedback`: a Markdown file per student, named by a
  slug plus a hash of the student's name (names differing by case, spaces or
  accents never collide).
- `HandGrades`: the instructor's scores and comments of written answers, a
  record of their own (``<out>-hand.json``) that no grading run resets.
- `export_manual` / `read_manual`: the written answers of every student in
  one file for the instructor (``<out>-manual.csv``: student, grade id,
  points, rubric, answer, ``score`` (empty until graded), ``comment``);
  `read_manual` reads it back (UTF-8 with or without Excel's byte-order
  mark) to merge into `HandGrades`.

Imports `notebooks` only.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import re
import unicodedata
from dataclasses import asdict, dataclass, field
from pathlib import Path

from .notebooks import CheckCell

__all__ = [
    "Result",
    "Again",
    "Records",
    "write_gradebook",
    "gradebook_rows",
    "feedback_text",
    "write_feedback",
    "HandGrades",
    "export_manual",
    "read_manual",
    "slug",
]


@dataclass
class Result:
    """The grade of one submission."""

    student: str
    points: dict[str, float]
    reasons: dict[str, str]
    max_points: float
    status: str = "ok"
    seconds: float = 0.0
    passes: int = 0
    flags: list[str] = field(default_factory=list)
    check_lines: dict[str, dict] = field(default_factory=dict)
    details: dict[str, str] = field(default_factory=dict)  # gid -> feedback text
    answers: dict[str, str] = field(default_factory=dict)  # manual gid -> answer
    code: dict[str, str] = field(default_factory=dict)  # exercise -> their cell
    submitted: float = 0.0  # the notebook's modification time (Unix time, s)
    source: str = ""

    @property
    def total(self) -> float:
        """Sum of the points earned."""
        return float(sum(self.points.values()))

    def to_json(self) -> dict:
        """Return the record written to disk."""
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict) -> Result:
        """Read a record back."""
        names = set(cls.__dataclass_fields__)
        return cls(**{k: v for k, v in data.items() if k in names})


def slug(name: str) -> str:
    """Return a file name for ``name``: readable, unique (hashes the exact name)."""
    ascii_ = unicodedata.normalize("NFKD", name).encode("ascii", "ignore").decode()
    base = re.sub(r"[^A-Za-z0-9_.@-]+", "_", ascii_).strip("._")[:60] or "student"
    digest = hashlib.sha1(name.encode("utf-8", "surrogateescape")).hexdigest()[:8]
    return f"{base}-{digest}"


def _atomic(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    tmp.replace(path)


class Records:
    """One durable JSON record per graded submission, in a folder."""

    def __init__(self, folder: str | Path, lab: str):
        self.folder = Path(folder)
        self.lab = lab
        self.folder.mkdir(parents=True, exist_ok=True)

    def path(self, student: str) -> Path:
        """Return the record file of ``student``."""
        return self.folder / f"{slug(student)}.json"

    def save(self, result: Result, fingerprint: str) -> None:
        """Write ``result`` (atomically, synced to disk)."""
        data = {"lab": self.lab, "fingerprint": fingerprint, **result.to_json()}
        _atomic(self.path(result.student), json.dumps(data, indent=1))

    def load(self, student: str) -> tuple[Result, str] | None:
        """Return the stored result of ``student`` and its fingerprint, or None."""
        try:
            data = json.loads(self.path(student).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if data.get("lab") != self.lab or data.get("student") != student:
            return None
        return Result.from_json(data), str(data.get("fingerprint", ""))

    def all(self) -> list[Result]:
        """Every stored result."""
        out = []
        for p in sorted(self.folder.glob("*.json")):
            if p.name.startswith("."):
                continue  # the grader's own lists
            try:
                data = json.loads(p.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue
            if isinstance(data, dict) and data.get("lab") == self.lab:
                out.append(Result.from_json(data))
        return out


class Again:
    """Students to grade again, kept on disk until each is graded (``--regrade``).

    An interrupted ``--regrade`` (or ``--student``) is finished by the next
    plain run: without this, the students it had not reached yet would keep
    their earlier grades silently.

    Parameters
    ----------
    store : Records or None
        Where the list is kept (``.again.json`` in the records folder).
    students : list of str, optional
        Start grading these again (None: take up the list left on disk).
    """

    def __init__(self, store: Records | None, students: list[str] | None):
        self.path = store.folder / ".again.json" if store is not None else None
        self.left: set[str] = set(students or ())
        if students is None and self.path is not None and self.path.exists():
            try:
                self.left = set(json.loads(self.path.read_text(encoding="utf-8")))
            except (OSError, ValueError):
                self.left = set()
        self.resumed = students is None and bool(self.left)
        self._write()

    def __contains__(self, student: str) -> bool:
        return student in self.left

    def done(self, student: str) -> None:
        """Strike ``student`` off the list."""
        if student in self.left:
            self.left.discard(student)
            self._write()

    def _write(self) -> None:
        if self.path is None:
            return
        if self.left:
            _atomic(self.path, json.dumps(sorted(self.left)))
        elif self.path.exists():
            self.path.unlink()


def gradebook_rows(results: list[Result], checks: list[CheckCell]) -> list[dict]:
    """Return the gradebook as a list of rows (dicts of strings)."""
    rows = []
    for r in results:
        row = {"student": r.student}
        for c in checks:  # empty: a written answer not graded yet
            got = r.points.get(c.grade_id, None if c.manual else 0.0)
            row[c.grade_id] = "" if got is None else f"{got:g}"
        row["total"] = f"{r.total:g}"
        row["max"] = f"{r.max_points:g}"
        row["status"] = r.status
        row["seconds"] = f"{r.seconds:.1f}"
        row["flags"] = "; ".join(r.flags)
        row["notes"] = "; ".join(f"{k}: {v}" for k, v in r.reasons.items())
        rows.append(row)
    return rows


def write_gradebook(
    path: str | Path, results: list[Result], checks: list[CheckCell]
) -> None:
    """Write the gradebook CSV atomically (a temporary file, then a rename)."""
    fields = ["student", *[c.grade_id for c in checks], "total", "max"]
    fields += ["status", "seconds", "flags", "notes"]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(gradebook_rows(results, checks))
    _atomic(Path(path), buf.getvalue())


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def feedback_text(result: Result, checks: list[CheckCell], lab: str) -> str:
    """Return a student's feedback, in Markdown."""
    lines = [
        f"# {lab}: feedback for {result.student}",
        "",
        f"Score: **{result.total:g} / {result.max_points:g}**",
        "",
        "| check | points | result |",
        "|---|---|---|",
    ]
    for c in checks:
        got = result.points.get(c.grade_id)
        why = result.reasons.get(c.grade_id, "passed")
        shown = "-" if got is None else f"{got:g}"
        lines.append(f"| {c.grade_id} | {shown} / {c.points:g} | {_cell(why)} |")
    if result.status != "ok":
        lines += ["", f"Status: {result.status}."]
    for gid, text in result.details.items():
        lines += ["", f"## {gid}", "", "```", text.rstrip(), "```"]
    lines += [
        "",
        "Each check was run by the instructor's own code in a separate process,"
        " calling your functions, with hidden tests added.",
        "",
    ]
    return "\n".join(lines)


def write_feedback(folder: str | Path, results: list[Result], checks, lab: str) -> None:
    """Write ``<slug>.md`` feedback files into ``folder``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for r in results:
        _atomic(folder / f"{slug(r.student)}.md", feedback_text(r, checks, lab))


MANUAL_FIELDS = [
    "student", "grade_id", "points", "rubric", "answer", "score", "comment",
]  # fmt: skip


class HandGrades:
    """The instructor's scores of written answers: a record no grading run resets.

    One JSON file (``<out>-hand.json``): ``{student: {grade_id: {"score":
    points, "comment": text}}}``, written atomically. Scores come in only
    through `merge` (from the ``<out>-manual.csv`` the instructor edits, or
    ``--manual``); a score left empty there changes nothing.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        try:
            self.grades = json.loads(self.path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            self.grades = {}
        except ValueError as exc:
            raise ValueError(f"{self.path}: not a hand-grade record ({exc})") from None

    def merge(self, entries: dict) -> int:
        """Take ``{student: {grade_id: {"score", "comment"}}}``; return the changes."""
        changed = 0
        for student, by_gid in entries.items():
            mine = self.grades.setdefault(student, {})
            for gid, entry in by_gid.items():
                new = {**mine.get(gid, {}), **entry}
                changed += new != mine.get(gid)
                mine[gid] = new
        return changed

    def save(self) -> None:
        """Write the record (atomically)."""
        _atomic(self.path, json.dumps(self.grades, indent=1, ensure_ascii=False))

    def get(self, student: str, gid: str) -> dict:
        """Return ``{"score"?, "comment"?}`` of one written answer ({}: ungraded)."""
        return self.grades.get(student, {}).get(gid, {})


def export_manual(
    path: str | Path, results: list[Result], manual: list[CheckCell], hand: HandGrades
):
    """Write every student's written answers to one CSV, ``score`` and ``comment``.

    ``score`` is empty until graded by hand (ungraded is not 0).
    """
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=MANUAL_FIELDS, lineterminator="\n")
    writer.writeheader()
    for r in results:
        for c in manual:
            got = hand.get(r.student, c.grade_id)
            writer.writerow(
                {
                    "student": r.student,
                    "grade_id": c.grade_id,
                    "points": f"{c.points:g}",
                    "rubric": c.rubric,
                    "answer": r.answers.get(c.grade_id, ""),
                    "score": f"{got['score']:g}" if "score" in got else "",
                    "comment": got.get("comment", ""),
                }
            )
    _atomic(Path(path), buf.getvalue())


def read_manual(path: str | Path, manual: list[CheckCell]) -> dict:
    """Read the instructor's scores: ``{student: {grade_id: {"score", "comment"}}}``.

    Accepts UTF-8 with or without a byte-order mark (Excel's "CSV UTF-8"),
    else Windows-1252 (Excel's plain "CSV" on Windows: ``José`` stays José),
    and a comma or semicolon as separator; rows with neither a score nor a
    comment are skipped.

    Raises
    ------
    ValueError
        On missing columns, an unknown grade id or a score outside
        ``[0, points]``.
    """
    limits = {c.grade_id: float(c.points) for c in manual}
    out: dict[str, dict[str, dict]] = {}
    raw = Path(path).read_bytes()
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    text = text.replace("\r\n", "\n")
    first = text.split("\n", 1)[0]
    delimiter = ";" if first.count(";") > first.count(",") else ","
    reader = csv.DictReader(io.StringIO(text), delimiter=delimiter)
    missing = {"student", "grade_id", "score"} - set(reader.fieldnames or [])
    if missing:
        raise ValueError(f"{path}: no column {', '.join(sorted(missing))}")
    for n, row in enumerate(reader, 2):
        gid, score = row.get("grade_id", ""), (row.get("score") or "").strip()
        comment = (row.get("comment") or "").strip()
        if not score and not comment:
            continue
        if gid not in limits:
            raise ValueError(f"{path}, line {n}: unknown written answer {gid!r}")
        entry: dict = {"comment": comment} if comment else {}
        if score:
            try:
                value = float(score.replace(",", "."))
            except ValueError:
                why = f"{path}, line {n}: score {score!r} is not a number"
                raise ValueError(why) from None
            if not 0 <= value <= limits[gid]:
                raise ValueError(
                    f"{path}, line {n}: score {value:g} of {gid!r} is not in "
                    f"[0, {limits[gid]:g}]"
                )
            entry["score"] = value
        out.setdefault(row["student"], {})[gid] = entry
    return out
