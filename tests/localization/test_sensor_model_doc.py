"""ARCHITECTURE.md's example: a sensor model in NumPy alone plugs into `MCL`."""

import re
from pathlib import Path

import pytest

from robotlib.experiments.routes import drive_route
from robotlib.world import load_world

DOC = Path(__file__).resolve().parents[2] / "ARCHITECTURE.md"


def _example() -> dict:
    text = DOC.read_text()
    section = text[text.index("## Adding a sensor model") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    namespace: dict = {}
    exec(compile(code, str(DOC), "exec"), namespace)  # noqa: S102
    return namespace


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_numpy_model_localizes_in_the_corridor(seed):
    example = _example()
    world = load_world("corridor")
    route = drive_route(world, seed, 40)
    run = [
        (route.odometry[k - 1], route.odometry[k], route.sonar[k], route.truth[k])
        for k in range(1, len(route))
    ]
    assert example["localize"](world, run, seed) < 0.5


def test_the_example_model_has_only_log_likelihood():
    model = _example()["GaussianSonarModel"]
    public = [n for n in vars(model) if not n.startswith("_")]
    assert public == ["log_likelihood"]
