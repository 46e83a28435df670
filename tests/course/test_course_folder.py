"""``robotlib course DIR``: the student's own folder of released labs."""

from __future__ import annotations

from pathlib import Path

import pytest

from robotlib.cli import main
from robotlib.course.folder import CourseFiles, course_files, write_course

ROOT = Path(__file__).resolve().parents[2]


def test_writes_released_labs_syllabus_and_readme(tmp_path, capsys):
    folder = tmp_path / "my course"
    assert main(["course", str(folder)]) == 0
    out = capsys.readouterr().out
    labs = sorted(p.name for p in (ROOT / "labs").glob("*.ipynb"))
    assert sorted(p.name for p in folder.glob("*.ipynb")) == labs
    for name in labs:
        assert (folder / name).read_bytes() == (ROOT / "labs" / name).read_bytes()
    syllabus = (ROOT / "course" / "syllabus.md").read_text()
    assert (folder / "syllabus.md").read_text() == syllabus
    readme = (folder / "README.md").read_text()
    # The next two commands, printed and in the README; a path with a space quoted.
    for text in (out, readme):
        assert "robotlib warmup" in text
        assert f'jupyter lab "{folder.resolve()}"' in text


def test_a_second_run_keeps_the_students_work_and_adds_new_labs(tmp_path):
    files = course_files()
    write_course(tmp_path, files)
    mine = tmp_path / files.labs[0].name
    mine.write_text("my answers")
    (tmp_path / files.labs[-1].name).unlink()
    done = write_course(tmp_path, files)
    assert done.written == [tmp_path / files.labs[-1].name]
    assert mine in done.kept and mine.read_text() == "my answers"


def test_only_released_labs_are_copied(tmp_path):
    files = CourseFiles(
        labs=sorted((ROOT / "solutions").glob("*.ipynb")),
        syllabus=ROOT / "course" / "syllabus.md",
    )
    with pytest.raises(ValueError, match="holds solutions"):
        write_course(tmp_path / "out", files)
    assert not (tmp_path / "out").exists()


def test_a_file_in_the_way_is_a_clear_error(tmp_path, capsys):
    (tmp_path / "course").write_text("")
    assert main(["course", str(tmp_path / "course")]) == 2
    assert "is a file" in capsys.readouterr().err
