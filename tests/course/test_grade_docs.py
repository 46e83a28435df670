"""What ``robotlib grade`` says about itself (issue 28, fault 12).

``--help`` gives every default; the files a run writes beside the default
``--out`` are ignored by git (they landed in the repository's root); the
README, syllabus and instructor guide do not say grading uses nbval (it
runs each submission in two sandboxed processes of its own).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from robotlib.course.command import add_arguments

ROOT = Path(__file__).resolve().parents[2]


def test_help_gives_every_default():
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    silent = [
        a.dest
        for a in parser._actions
        if a.default not in (None, False, argparse.SUPPRESS)
        and "default" not in (a.help or "")
    ]
    assert silent == []


def test_a_run_s_outputs_are_ignored_by_git():
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    outputs = [
        "gradebook.csv",
        "gradebook-manual.csv",
        "gradebook-hand.json",
        "gradebook-report.html",
        "gradebook-canvas.csv",
        "gradebook-moodle.csv",
        "gradebook-records/ann-0123.json",
        "gradebook-feedback/ann-0123.md",
    ]
    proc = subprocess.run(
        ["git", "check-ignore", "--no-index", *outputs],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert sorted(proc.stdout.split()) == sorted(outputs)


@pytest.mark.parametrize(
    "doc", ["README.md", "course/syllabus.md", "course/instructor-guide.md"]
)
def test_no_doc_says_grading_uses_nbval(doc):
    text = (ROOT / doc).read_text(encoding="utf-8")
    for sentence in re.split(r"(?<=[.:;])\s|\n", text):
        if "nbval" in sentence:
            assert not re.search(r"\bgrad(e|es|ed|ing|er)\b", sentence, re.I), sentence
