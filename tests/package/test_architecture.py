"""The house rules of ARCHITECTURE.md, read off the source with ast.

Every import between robotlib's modules (at the top of a module or inside a
function) goes down the layers or stays inside its package; the imports,
counting those inside functions, form no circle; kernels import nothing of
ours but the JIT options and other kernels; no module is long; every module
says what it holds.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2] / "robotlib"

LAYERS = {
    "robotlib._config": 0,
    "robotlib._kernel_cache": -1,  # below _config, which runs it once
    "robotlib._random": 0,
    "robotlib.p3dx": 0,
    "robotlib.world": 1,
    "robotlib.sensing": 2,
    "robotlib.robot": 2,
    "robotlib.sim": 3,
    "robotlib.pioneer": 3,
    "robotlib.localization": 4,
    "robotlib.avoidance": 4,
    "robotlib.planning": 4,
    "robotlib.mapping": 4,
    "robotlib.logs": 4,
    "robotlib.exploration": 4,
    "robotlib.experiments": 5,
    "robotlib.plotting": 6,
    "robotlib.widgets": 7,
    "robotlib.notebook": 7,
    "robotlib.warmups": 6,  # what `robotlib warmup` runs: the layers below, once
    "robotlib._unsolved": 0,  # a leaf: the notebook set-up's IPython handler
    "robotlib._ipython": 0,  # a leaf: which shell runs us (notebook, widgets)
    "robotlib._loading": 0,  # a leaf: the first cell's status line (notebook)
    "robotlib._versions": 0,  # a leaf: the version, and a lab's check against it
    "robotlib._shipped": 0,  # a leaf: where the worlds, labs and syllabus are
    "robotlib.course": 7,
    "robotlib.cli": 8,
    "robotlib": 8,
}
"""Package (or leaf module) to its layer; see ARCHITECTURE.md."""

ALLOWED_SIDEWAYS = {
    # The sim-server serves the simulator: the protocol's server side sits on it.
    ("robotlib.pioneer", "robotlib.sim"),
    # Navigation localizes, plans, follows and avoids.
    ("robotlib.planning", "robotlib.localization"),
    ("robotlib.planning", "robotlib.avoidance"),
    # Grid FastSLAM resamples its map-carrying particles with MCL's resamplers.
    ("robotlib.mapping", "robotlib.localization"),
    # Exploration maps (occupancy grids, FastSLAM) and plans (A*, pursuit).
    ("robotlib.exploration", "robotlib.mapping"),
    ("robotlib.exploration", "robotlib.planning"),
}
"""Imports between packages of one layer that the design allows."""

MAX_LINES = 600


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


MODULES = _modules()


def _package(module: str) -> str:
    best = max(
        (p for p in LAYERS if module == p or module.startswith(p + ".")), key=len
    )
    return best


def _resolve(name: str) -> str:
    """The longest prefix of ``name`` that is one of our modules ('' if none)."""
    while name and name not in MODULES:
        name = name.rpartition(".")[0]
    return name


def _imports(
    module: str, path: Path, top_only: bool, parents: bool = True, source: str = ""
) -> set[str]:
    """Our modules that ``module`` imports, with the packages whose ``__init__`` runs.

    Importing ``a.b.c`` runs ``a`` and ``a.b`` first, unless they are
    packages ``module`` itself lives in (those are already running).
    ``source``: read instead of the file.
    """
    tree = ast.parse(source or path.read_text(encoding="utf-8"))
    is_pkg = path.name == "__init__.py"
    base = module.split(".") if is_pkg else module.split(".")[:-1]
    mine = {".".join(base[:k]) for k in range(1, len(base) + 1)}
    found = set()
    for node in tree.body if top_only else ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [_resolve(a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = base[: len(base) - node.level + 1]
                stem = ".".join(anchor + ([node.module] if node.module else []))
            else:
                stem = node.module or ""
            names = [
                f"{stem}.{a.name}" if f"{stem}.{a.name}" in MODULES else _resolve(stem)
                for a in node.names
            ]
        else:
            continue
        for name in names:
            if not name.startswith("robotlib") or name == module:
                continue
            found.add(name)
            if parents:
                parts = name.split(".")
                found |= {".".join(parts[:k]) for k in range(1, len(parts))} - mine
    found.discard(module)
    return found


def test_every_package_has_a_layer():
    for module in MODULES:
        assert _package(module) in LAYERS, module


@pytest.mark.parametrize("module", sorted(MODULES))
def test_imports_go_down_the_layers(module):
    here = _package(module)
    for target in _imports(module, MODULES[module], top_only=False):
        there = _package(target)
        if there == here:
            continue
        down = LAYERS[there] < LAYERS[here] or (here, there) in ALLOWED_SIDEWAYS
        assert down, (
            f"{module} imports {target} (layer {LAYERS[there]} >= {LAYERS[here]})"
        )


@pytest.mark.parametrize("module", sorted(m for m in MODULES if "_kernels" in m))
def test_kernels_import_only_config_and_kernels(module):
    for target in _imports(module, MODULES[module], top_only=False, parents=False):
        assert target == "robotlib._config" or "_kernels" in target, (module, target)


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    out = []

    def visit(m):
        index[m] = low[m] = len(index)
        stack.append(m)
        for t in sorted(graph.get(m, ())):
            if t not in index:
                visit(t)
                low[m] = min(low[m], low[t])
            elif t in stack:
                low[m] = min(low[m], index[t])
        if low[m] == index[m]:
            group = []
            while True:
                t = stack.pop()
                group.append(t)
                if t == m:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for m in sorted(graph):
        if m not in index:
            visit(m)
    return sorted(out)


def _loop_in(group: list[str], graph: dict[str, set[str]]) -> list[str]:
    """One import loop through ``group``'s first module (for the message)."""
    start, inside = group[0], set(group)
    trail, seen = [start], {start}
    while True:
        nxt = sorted(t for t in graph[trail[-1]] if t in inside)
        if start in nxt:
            return trail + [start]
        step = next((t for t in nxt if t not in seen), nxt[0])
        if step in seen:
            return trail[trail.index(step) :] + [step]
        trail.append(step)
        seen.add(step)


def test_no_import_circles():
    """No circle, counting imports inside functions and TYPE_CHECKING blocks."""
    graph = {m: _imports(m, p, top_only=False) for m, p in MODULES.items()}
    bad = _circles(graph)
    assert not bad, "import circles:\n" + "\n".join(
        " -> ".join(_loop_in(g, graph)) for g in bad
    )


def test_the_circle_check_sees_function_level_imports():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _circles(graph) == [["a", "b", "c"]]
    assert _loop_in(["a", "b", "c"], graph) == ["a", "b", "c", "a"]
    src = "import robotlib.world\ndef f():\n    from robotlib import sim\n"
    tmp = ROOT.parent / "robotlib" / "world" / "geometry.py"
    found = _imports("robotlib.world.geometry", tmp, top_only=False, source=src)
    assert "robotlib.sim" in found


@pytest.mark.parametrize("module", sorted(MODULES))
def test_modules_are_short_and_documented(module):
    text = MODULES[module].read_text(encoding="utf-8")
    assert text.count("\n") <= MAX_LINES, f"{module}: {text.count(chr(10))} lines"
    assert ast.get_docstring(ast.parse(text)), f"{module} has no docstring"


def test_import_robotlib_loads_no_algorithm():
    import subprocess
    import sys

    code = (
        "import sys, robotlib; "
        "print(sorted(m for m in sys.modules if m.startswith('robotlib.')))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    for heavy in ("localization", "sim", "pioneer", "plotting", "widgets", "course"):
        assert f"'robotlib.{heavy}" not in out, out
