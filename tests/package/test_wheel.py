"""The package as a student installs it: a wheel in a fresh virtual environment.

The wheel is built as ``robotlib release --bundle`` builds it
(`robotlib.course.bundle.build_wheel`: ``pip wheel --no-deps`` on a copy of
the files the build reads, in a temporary folder, so the build writes nothing
into the repository). It is installed into a fresh venv in another temporary folder,
far from any checkout. The venv sees the test environment's installed
packages (numpy, numba, Jupyter, pytest, ...) through a ``.pth`` file, which
is what ``--system-site-packages`` gives when the base interpreter carries
them, so nothing is downloaded; robotlib itself comes only from the wheel
(checked). There a student's steps run: ``robotlib course DIR``, ``robotlib
warmup``, and Lab 0 headless under nbval, with the answers a student would
write (the exercise cells of ``solutions/``) pasted into the released copy.
The build, the venv and the first (cold) warm-up start with the session,
beside the other tests (`tests.background`); this module's tests run last.
"""

from __future__ import annotations

import json
import os
import re
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest

from robotlib.course.bundle import build_wheel
from tests import background, contention

ROOT = Path(__file__).resolve().parents[2]
LAB0 = "lab0_getting_started.ipynb"

pytestmark = pytest.mark.slow


def _run(cmd, cwd, env, timeout=600):
    """Run ``cmd`` (``timeout`` in quiet seconds: `tests.contention`); its output."""
    proc = contention.run(cmd, timeout, cwd=cwd, env=env)
    assert proc.returncode == 0, f"{cmd}\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
    return proc.stdout


def _student(home: Path, wheel: Path):
    """A fresh venv with the wheel installed: (its python, its scripts, env, home)."""
    home.mkdir(parents=True)
    venv = home / "venv"
    _run([sys.executable, "-m", "venv", venv], cwd=home, env=os.environ)
    scripts = venv / ("Scripts" if os.name == "nt" else "bin")
    python = scripts / ("python.exe" if os.name == "nt" else "python")
    purelib = _run(
        [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        cwd=home,
        env=os.environ,
    ).strip()
    ours = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (Path(purelib) / "_test_env_packages.pth").write_text("\n".join(sorted(ours)))
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in {"PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME", "NUMBA_CACHE_DIR"}
    }  # numba caches beside the installed sources, as on a student's machine
    env.update(
        PATH=f"{scripts}{os.pathsep}{env.get('PATH', '')}",
        MPLBACKEND="Agg",
        ROBOTLIB_TABLE_CACHE="off",
        PIP_DISABLE_PIP_VERSION_CHECK="1",
        PYTEST_DISABLE_PLUGIN_AUTOLOAD="1",
    )
    install = [python, "-m", "pip", "install", "-q", "--no-index", "--no-deps"]
    _run([*install, "--force-reinstall", wheel], cwd=home, env=env)
    return python, scripts, env, home


def background_work(folder: Path):
    """The wheel, the student's venv, and there a first, cold ``robotlib warmup``.

    Run beside the other tests (`tests.background`): the warm-up compiles every
    kernel on one core, for most of this module's time.
    """
    wheel = build_wheel(ROOT, folder / "wheel")
    student = _student(folder / "student", wheel)
    _, scripts, env, home = student
    (home / "elsewhere").mkdir()
    cmd = [scripts / "robotlib", "warmup"]
    first = background.run(cmd, cwd=home / "elsewhere", env=env, timeout=900)
    return wheel, student, first


@pytest.fixture(scope="module")
def prepared():
    return background.result(__name__)


@pytest.fixture(scope="module")
def wheel(prepared):
    return prepared[0]


@pytest.fixture(scope="module")
def student(prepared):
    return prepared[1]


def test_the_wheel_carries_worlds_labs_and_syllabus_never_solutions(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    data = [n for n in names if "/share/robotlib/" in n]
    labs = sorted(Path(n).name for n in data if "/share/robotlib/labs/" in n)
    assert labs == sorted(p.name for p in (ROOT / "labs").glob("*.ipynb"))
    assert any(n.endswith("/share/robotlib/course/syllabus.md") for n in data)
    for world in ("corridor.wld", "office.map", "clutter.pairs.json"):
        assert any(n.endswith(f"/share/robotlib/worlds/{world}") for n in data)
    assert not [n for n in names if "solution" in n.lower()]
    with zipfile.ZipFile(wheel) as zf:
        for n in data:
            if n.endswith(".ipynb"):
                assert b"BEGIN SOLUTION" not in zf.read(n), n


def test_robotlib_comes_from_the_wheel(student):
    python, _, env, home = student
    where = _run(
        [python, "-c", "import robotlib, robotlib.world as w; "
         "print(robotlib.__file__); print(w.WORLDS_DIR)"],
        cwd=home, env=env,
    ).split()  # fmt: skip
    venv = python.parent.parent
    assert all(Path(p).is_relative_to(venv) for p in where), where
    assert not any(Path(p).is_relative_to(ROOT) for p in where)


def test_course_folder_then_lab0_headless(student, prepared):
    python, scripts, env, home = student
    robotlib_cmd = scripts / "robotlib"
    out = _run([robotlib_cmd, "course", "my-course"], cwd=home, env=env)
    course = home / "my-course"
    # The next two commands: warm the kernels, open the folder.
    assert "robotlib warmup" in out and f"jupyter lab {course}" in out
    labs = sorted(p.name for p in course.glob("*.ipynb"))
    assert labs == sorted(p.name for p in (ROOT / "labs").glob("*.ipynb"))
    for name in labs:
        assert (course / name).read_text() == (ROOT / "labs" / name).read_text()
    assert (course / "syllabus.md").read_text() == (
        ROOT / "course" / "syllabus.md"
    ).read_text()
    assert "robotlib warmup" in (course / "README.md").read_text()

    # The student's work survives a second run.
    answered = _answered_lab0(course / LAB0)
    (course / LAB0).write_text(answered)
    again = _run([robotlib_cmd, "course", "my-course"], cwd=home, env=env)
    assert "wrote 0 files" in again
    assert (course / LAB0).read_text() == answered

    # Every kernel the labs use compiles from the installed package (the first
    # warm-up, run in the background in another folder), into a cache that
    # the next run (and the labs) load from.
    first = prepared[2]
    assert first.returncode == 0, first.stderr[-4000:]
    assert "compiling kernels" in first.stderr
    listing = _run([robotlib_cmd, "warmup", "--list"], cwd=course, env=env)
    parts = [line.split(":")[0] for line in listing.splitlines()]
    warm = contention.run([robotlib_cmd, "warmup"], 900, cwd=course, env=env)
    assert warm.returncode == 0 and "compiling kernels" not in warm.stderr
    timed = [line.split()[0] for line in warm.stdout.splitlines()]
    assert timed == [*parts, "all"], warm.stdout
    (course / "pytest.ini").write_text("[pytest]\n")
    nbval = [
        python, "-m", "pytest", "-p", "nbval.plugin", "-p", "no:cacheprovider",
        "--nbval-lax", "--nbval-current-env",
        f"--nbval-cell-timeout={120 * contention.factor():.0f}",  # 120 quiet s
        "-c", course / "pytest.ini", f"--rootdir={course}", "-q", LAB0,
    ]  # fmt: skip
    report = _run(nbval, cwd=course, env=env, timeout=900)
    code_cells = [c for c in json.loads(answered)["cells"] if c["cell_type"] == "code"]
    assert re.search(r"\b(\d+) passed", report)[1] == str(len(code_cells)), report
    assert "failed" not in report


def _answered_lab0(released: Path) -> str:
    """The released Lab 0 with a student's answers: the solutions' exercise cells."""
    solution = json.loads((ROOT / "solutions" / LAB0).read_text())
    answers = {
        c["id"]: c["source"]
        for c in solution["cells"]
        if c["metadata"].get("robotlib", {}).get("exercise")
    }
    nb = json.loads(released.read_text())
    for cell in nb["cells"]:
        if cell["id"] in answers:
            source = "".join(answers[cell["id"]]).splitlines(keepends=True)
            markers = ("### BEGIN SOLUTION", "### END SOLUTION")
            cell["source"] = [ln for ln in source if ln.strip() not in markers]
    assert sum(c["id"] in answers for c in nb["cells"]) == len(answers) > 0
    return json.dumps(nb, indent=1)
