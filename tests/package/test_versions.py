"""The version: one number, ``robotlib --version``, and the labs' check against it."""

from __future__ import annotations

import builtins
import json
import re
import warnings
from importlib.metadata import version
from pathlib import Path

import numpy as np
import pytest

import robotlib
from robotlib._versions import lab_version, version_mismatch
from robotlib.cli import main
from robotlib.notebook import setup

ROOT = Path(__file__).resolve().parents[2]
LABS = sorted((ROOT / "labs").glob("*.ipynb"))
SOLUTIONS = sorted((ROOT / "solutions").glob("*.ipynb"))


def test_one_version_everywhere(capsys):
    assert version("robotlib") == robotlib.__version__
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"robotlib {robotlib.__version__}"
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## {robotlib.__version__}" in changelog


@pytest.mark.parametrize(
    "requires, installed, fits",
    [
        ("0.2", "0.1.0", False),  # a lab released for 0.2 warns on 0.1
        ("0.1", "0.1.7", True),  # patch releases never matter
        ("0.1", "0.2.0", True),  # a newer minor keeps what the lab uses
        ("0.1", "1.0.0", False),  # another major may not
        ("1.2", "0.9.0", False),
    ],
)
def test_version_mismatch(requires, installed, fits):
    message = version_mismatch(requires, installed)
    assert (message is None) == fits
    if not fits:
        assert requires in message and installed in message


@pytest.mark.parametrize("bad", ["", "1", "one.two", "1.x"])
def test_a_malformed_version_is_a_clear_error(bad):
    with pytest.raises(ValueError, match="MAJOR.MINOR"):
        version_mismatch(bad, "0.1.0")


def test_setup_warns_when_the_lab_is_newer_than_robotlib():
    newer = f"{int(lab_version().split('.')[0]) + 1}.0"
    with np.printoptions():  # (setup sets the labs' print options)
        with pytest.warns(RuntimeWarning, match=f"released for robotlib {newer}"):
            setup(warm=(), style=False, requires=newer)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            setup(warm=(), style=False, requires=lab_version())


def _first_code_cell(path):
    cells = json.loads(path.read_text())["cells"]
    return "".join(next(c["source"] for c in cells if c["cell_type"] == "code"))


@pytest.mark.parametrize("lab", SOLUTIONS, ids=[p.stem for p in SOLUTIONS])
def test_each_lab_names_the_version_it_is_released_for(lab):
    found = re.findall(r'setup\(requires="([^"]+)"', _first_code_cell(lab))
    assert found == [lab_version()], "bump the labs' requires= with the version"


@pytest.mark.parametrize("lab", LABS, ids=[p.stem for p in LABS])
def test_a_kernel_without_robotlib_is_told_how_to_install_it(lab):
    cell = _first_code_cell(lab)
    guard = cell.split("\n\n", 1)[0]

    def no_robotlib(name, *args, **kwargs):
        if name.split(".")[0] == "robotlib":
            raise ModuleNotFoundError(f"No module named {name!r}")
        return builtins.__import__(name, *args, **kwargs)

    scope = {"__builtins__": {**vars(builtins), "__import__": no_robotlib}}
    with pytest.raises(SystemExit, match=r"%pip install robotlib"):
        exec(compile(guard, lab.name, "exec"), scope)
    exec(compile(guard, lab.name, "exec"), {})  # with robotlib: nothing happens
