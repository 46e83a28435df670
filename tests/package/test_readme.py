import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def readme_commands():
    return re.findall(r"```bash\n(.+?)\n```", (ROOT / "README.md").read_text())


def readme_section(title):
    text = (ROOT / "README.md").read_text()
    return text.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def test_readme_opens_with_the_main_and_the_test_command():
    main, tests = readme_commands()[:2]
    assert "pip install ." in main and "robotlib course my-course" in main
    assert main.endswith("jupyter lab my-course")
    assert "pytest" in tests and "--durations=25" in tests  # CI lists the slowest


def test_the_students_two_commands_are_the_main_command():
    commands = re.findall(r"```bash\n *(.+?)\n *```", readme_section("Students"))
    assert len(commands) == 2
    assert " && ".join(commands) == readme_commands()[0]
    windows = re.findall(r"```bat\n(.+?)\n```", readme_section("Students"), re.S)
    (windows,) = windows
    posix = [c.replace("python3 -m venv", "py -3 -m venv") for c in commands]
    posix = [c.replace(".venv/bin/", ".venv\\Scripts\\") for c in posix]
    assert windows.splitlines() == posix


def test_contributors_get_the_fast_loop_and_the_full_suite():
    section = readme_section("Contributors")
    assert '-m "not slow"' in section and "CONTRIBUTING.md" in section
    assert "robotlib bench" not in (ROOT / "README.md").read_text()
    assert "robotlib bench mcl" in (ROOT / "CONTRIBUTING.md").read_text()


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
