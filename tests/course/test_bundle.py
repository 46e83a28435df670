"""``robotlib release --bundle``: the students' wheel, labs and INSTALL.md.

The bundle must hold no solution code: the wheel's file names, its text
(every solution region of every lab looked for), and the labs' exercise
cells, which must be the released stubs. The bundle is made beside the
other tests (`tests.background`); this module's tests run last.
"""

from __future__ import annotations

import json
import shutil
import sys
import zipfile
from pathlib import Path

import pytest

from robotlib.cli import main
from robotlib.course.bundle import leaks, make_bundle, solution_regions
from robotlib.course.notebooks import CODE_STUB, exercises, read_notebook
from robotlib.course.release import release
from tests import background

ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = ROOT / "solutions"
LAB4 = "lab4_navigation.ipynb"
DIST = "robotlib-0.1.0.data/data/share/robotlib/labs/"


def _zip(path: Path, files: dict[str, str]) -> Path:
    with zipfile.ZipFile(path, "w") as zf:
        for name, text in files.items():
            zf.writestr(name, text)
    return path


RELEASED = release(SOLUTIONS, ROOT / "labs")


def _released_labs() -> dict[str, str]:
    return {DIST + name: text for name, text in RELEASED.items()}


def test_a_clean_wheel_has_no_leaks(tmp_path):
    assert leaks(_zip(tmp_path / "w.whl", _released_labs()), SOLUTIONS, RELEASED) == []


def test_every_way_an_answer_can_leak_is_reported(tmp_path):
    files = _released_labs()
    solution = (SOLUTIONS / LAB4).read_text()
    region = solution_regions(SOLUTIONS / LAB4)[0][1]
    files[DIST + LAB4] = solution  # the solution shipped as the lab
    del files[DIST + "lab0_getting_started.ipynb"]
    files["robotlib/solutions/lab1.ipynb"] = "{}"
    files["robotlib/notes.md"] = "### BEGIN HIDDEN TESTS\nassert x\n"
    files["robotlib/planning/answers.py"] = "def f():\n" + region.replace("\n", "\n ")
    found = "\n".join(leaks(_zip(tmp_path / "w.whl", files), SOLUTIONS, RELEASED))
    assert f"{DIST}{LAB4}: differs from a fresh release" in found
    assert f"{DIST}{LAB4}: holds '### BEGIN SOLUTION'" in found
    assert "lab0_getting_started.ipynb: not in the wheel" in found
    assert "robotlib/solutions/lab1.ipynb: a file named after solutions" in found
    assert "robotlib/notes.md: holds '### BEGIN HIDDEN TESTS'" in found
    # found whatever the indentation, and in the shipped notebook's JSON too
    assert "robotlib/planning/answers.py: holds solution region 1 of lab4" in found
    assert f"{DIST}{LAB4}: holds solution region 1 of lab4" in found


def test_the_library_s_own_listed_version_is_no_leak(tmp_path):
    """Lab 3's ``resize`` lists ``robotlib.localization.paper.resize``.

    The library ships it, and its formula is the solution's one line; the
    same line in any other module is a leak.
    """
    nb = SOLUTIONS / "lab3_mcl.ipynb"
    (ex,) = [e for e in exercises(read_notebook(nb)) if e.exercise_id == "resize"]
    assert "robotlib.localization.paper.resize" in ex.writes
    regions = [t for cell, t in solution_regions(nb) if cell == ex.index]
    (line,) = [t for t in regions if "math.exp" in t]  # the paper's resize
    files = _released_labs()
    files["robotlib/localization/paper.py"] = f"def resize():\n    {line}\n"
    assert leaks(_zip(tmp_path / "ok.whl", files), SOLUTIONS, RELEASED) == []
    files["robotlib/localization/mcl.py"] = f"def other():\n    {line}\n"
    found = leaks(_zip(tmp_path / "bad.whl", files), SOLUTIONS, RELEASED)
    where = "robotlib/localization/mcl.py"
    assert found == [f"{where}: holds solution region 5 of lab3_mcl"]


def test_a_stale_release_or_a_used_folder_is_refused(tmp_path, monkeypatch, capsys):
    root = tmp_path / "course"
    (root / "solutions").mkdir(parents=True)
    (root / "labs").mkdir()
    shutil.copy2(ROOT / "tests" / "data" / "course" / "tiny.ipynb", root / "solutions")
    monkeypatch.chdir(root)  # the course folder: the one holding solutions/
    assert main(["release", "--bundle", "out", "--warmup-seconds", "1"]) == 1
    assert "stale: tiny.ipynb (run `robotlib release` first)" in capsys.readouterr().err
    assert not (root / "out").exists()
    (root / "out").mkdir()
    (root / "out" / "old.whl").write_text("")
    with pytest.raises(ValueError, match="is not empty"):
        make_bundle(root, root / "out", {}, warmup=1.0)
    assert main(["release", "--warmup-seconds", "3"]) == 2
    assert main(["release", "tiny", "--bundle", "x"]) == 2


def background_work(folder: Path):
    """Make the bundle beside the other tests (`tests.background`), if selected.

    The CLI in the repository whose labs are bundled; it builds the wheel.
    """
    names = {item.originalname for item in background.selected(__name__)}
    if "test_the_bundle_holds_no_solution_code" not in names:
        return None
    out = folder / "bundle"
    cmd = [sys.executable, "-m", "robotlib.cli", "release", "--bundle", out,
           "--warmup-seconds", "150"]  # fmt: skip
    return background.run(cmd, timeout=900, cwd=ROOT), out


@pytest.mark.slow
def test_the_bundle_holds_no_solution_code():
    proc, out = background.result(__name__)
    assert proc.returncode == 0, proc.stderr[-3000:]
    (wheel,) = out.glob("robotlib-*.whl")
    assert sorted(p.name for p in out.iterdir()) == ["INSTALL.md", "labs", wheel.name]
    assert leaks(wheel, SOLUTIONS, RELEASED) == []
    with zipfile.ZipFile(wheel) as zf:
        names = zf.namelist()
        assert not [n for n in names if "solution" in n.lower()]
        shipped = {n.rsplit("/", 1)[1]: zf.read(n).decode() for n in names
                   if "/share/robotlib/labs/" in n}  # fmt: skip
    assert any(n.startswith("robotlib/course/grade") for n in names)  # the library
    bundled = {p.name: p.read_text() for p in (out / "labs").glob("*.ipynb")}
    assert shipped == bundled == RELEASED
    for name, text in bundled.items():
        lab = json.loads(text)
        solution = read_notebook(SOLUTIONS / name)
        answers = [t for _, t in solution_regions(SOLUTIONS / name)]
        assert answers, name
        for ex in exercises(solution, name):
            body = "".join(lab["cells"][ex.index]["source"])
            assert lab["cells"][ex.index]["id"] == ex.cell_id
            assert CODE_STUB[1] in body, (name, ex.exercise_id)
            assert not [a for a in answers if a in body], (name, ex.exercise_id)
    install = (out / "INSTALL.md").read_text()
    for command in (f"pip install {wheel.name}", "robotlib course my-course",
                    "robotlib warmup", "jupyter lab my-course"):  # fmt: skip
        assert f".venv/bin/{command}" in install
    assert "It takes about 2 minutes**\n  (150 s as measured by" in install
