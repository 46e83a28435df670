import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def readme_commands():
    return re.findall(r"```bash\n(.+?)\n```", (ROOT / "README.md").read_text())


def test_readme_opens_with_the_main_and_the_test_command():
    main, tests = readme_commands()[:2]
    assert "pip install -e ." in main and "jupyter lab labs/" in main
    assert "pytest" in tests and "--durations=25" in tests  # CI lists the slowest


def test_ci_runs_the_readmes_test_command_verbatim():
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert readme_commands()[1] in ci


def test_readme_robot_example_runs():
    import robotlib

    example = re.findall(
        r"```python\n(.+?)\n```", (ROOT / "README.md").read_text(), re.S
    )
    scope = {}
    exec(compile(example[0], "README.md", "exec"), scope)
    assert isinstance(scope["r"], robotlib.Robot)
