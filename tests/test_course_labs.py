"""Every lab graded in the sandbox: solution full, released zero, cheats zero.

For each ``solutions/*.ipynb`` one grading run holds the solution, the
released lab, a partial solution (for the labs listed in `PARTIAL`) and two
cheating submissions built from the exercises' ``writes`` metadata: each
exercise with ``writes`` has, in one of them, the solution's cell plus a
route to its first listed function, alternately an aliased import (caught by
the static scan) and a run-time lookup by a string built at run time
(caught by the tripwire when called). A cheated exercise scores zero with a
note naming the function; every other check of that submission full marks.
New labs are picked up automatically.
"""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from robotlib.course import grade as g
from robotlib.course import sandbox as sb
from robotlib.course.notebooks import (
    exercises,
    read_notebook,
    release_notebook,
    write_notebook,
)

ROOT = Path(__file__).resolve().parents[1]
LABS = sorted(p.stem for p in (ROOT / "solutions").glob("*.ipynb"))

# lab -> the solution cells a "partial" student copied (and the checks they pass)
PARTIAL = {
    "lab0_getting_started": ({"l0-14"}, {"sonar": 2}),
    "lab2_avoidance": ({"l2-05"}, {"braitenberg": 2, "explorer": 2}),
    "lab3_mcl": (
        {"l3-05", "l3-10", "l3-13", "l3-37"},
        {"weights": 2, "select": 1, "resize": 2, "low_variance": 2, "global": 2},
    ),
}


def _alias(listed: str, k: int) -> str:
    mod, _, attr = listed.rpartition(".")
    try:
        import importlib

        importlib.import_module(mod)
    except ImportError:  # a method: module.Class.attr
        mod, _, cls = mod.rpartition(".")
        return f"\nfrom {mod} import {cls} as _cheat{k}\n_cheat{k}.{attr}\n"
    return f"\nfrom {mod} import {attr} as _cheat{k}\n_cheat{k}\n"


def _string(listed: str, k: int) -> str:
    import importlib

    parts = listed.split(".")
    for i in range(len(parts) - 1, 0, -1):
        try:
            importlib.import_module(".".join(parts[:i]))
            break
        except ImportError:
            continue
    mod, attrs = ".".join(parts[:i]), parts[i:]
    code = f"\nimport {mod} as _m{k}\n_f{k} = _m{k}\n"
    for a in attrs:
        pieces = [a[: len(a) // 2], a[len(a) // 2 :]]
        code += f"_f{k} = getattr(_f{k}, ''.join({pieces!r}))\n"
    return code + f"try:\n    _f{k}()\nexcept Exception:\n    pass\n"


def cheats(sol) -> list[tuple[object, dict[str, tuple[str, str]]]]:
    """Two cheating notebooks: exercise id -> (listed function, route) in each."""
    exs = [e for e in exercises(sol) if e.writes]
    out = []
    for half in (0, 1):
        nb = copy.deepcopy(sol)
        cheated = {}
        for k, e in enumerate(exs):
            if k % 2 != half:
                continue
            route = "alias" if (k // 2 + half) % 2 == 0 else "string"
            code = (_alias if route == "alias" else _string)(e.writes[0], k)
            nb.cells[e.index].source = nb.cells[e.index].source + "\n" + code
            cheated[e.exercise_id] = (e.writes[0], route)
        if cheated:
            out.append((nb, cheated))
    return out


@pytest.fixture(scope="module", params=LABS)
def lab_graded(request, tmp_path_factory):
    if sb.available():
        pytest.skip(f"no sandbox here: {sb.available()}")
    lab = request.param
    tmp = tmp_path_factory.mktemp(lab)
    sol = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
    released = read_notebook(ROOT / "labs" / f"{lab}.ipynb")
    assert released == release_notebook(sol, lab)
    subs = {"solution": sol, "released": released}
    if lab in PARTIAL:
        partial = copy.deepcopy(released)
        sources = {c.id: c.source for c in sol.cells}
        for cell in partial.cells:
            if cell.id in PARTIAL[lab][0]:
                cell.source = sources[cell.id]
        subs["partial"] = partial
    plan = cheats(sol)
    for i, (nb, _) in enumerate(plan):
        subs[f"cheat{i}"] = nb
    for name, nb in subs.items():
        (tmp / "subs" / name).mkdir(parents=True)
        write_notebook(nb, tmp / "subs" / name / f"{lab}.ipynb")
    opts = g.Options(cell_timeout=90, timeout=400)
    results, items = g.grade(tmp / "subs", lab, jobs=2, opts=opts, progress=False)
    return lab, {r.student: r for r in results}, items, [c for _, c in plan]


def test_solution_full_released_zero(lab_graded):
    lab, rows, items, _ = lab_graded
    auto = [c for c in items if not c.manual]
    sol, rel = rows["solution"], rows["released"]
    assert all(sol.points[c.grade_id] == c.points for c in auto), sol.reasons
    assert all(v == 0 for v in rel.points.values()), rel.points
    assert sol.status == "ok" and not sol.flags, (sol.status, sol.flags)
    if lab in PARTIAL:
        got = {k: v for k, v in rows["partial"].points.items() if v}
        assert got == PARTIAL[lab][1], rows["partial"].reasons


def test_cheats_score_zero_for_their_exercise_only(lab_graded):
    lab, rows, items, plans = lab_graded
    auto = [c for c in items if not c.manual]
    for i, cheated in enumerate(plans):
        r = rows[f"cheat{i}"]
        for c in auto:
            hit = [e for e in c.exercises if e in cheated]
            if not hit:
                assert r.points[c.grade_id] == c.points, (c.grade_id, r.reasons)
                continue
            assert r.points[c.grade_id] == 0, (c.grade_id, cheated)
            listed, route = cheated[hit[0]]
            assert listed in r.reasons[c.grade_id], r.reasons[c.grade_id]
            if route == "string":  # only the run-time tripwire can see this one
                assert "called" in r.reasons[c.grade_id], r.reasons[c.grade_id]
        assert "answer reaches the library's own version" in r.flags
