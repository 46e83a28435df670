"""Every lab graded in the sandbox: solution full, released zero, cheats zero.

For each ``solutions/*.ipynb`` one grading run (after the grader's reference
run of the solution; two labs graded at a time, in a process of their own
that starts with the session, beside the other tests: `tests.background`;
this module's tests run last) holds the released lab, a
partial solution (for the labs listed in `PARTIAL`), wrong answers that the
lab's strict checks must reject (`WRONG`) and two cheating submissions built
from the exercises' ``writes`` metadata: each exercise with ``writes`` has,
in one of them, the solution's cell plus a route to its first listed
function, alternately an aliased import (caught by the static scan) and a
run-time lookup by a string built at run time (caught by the tripwire when
called). A cheated exercise scores zero with a note naming the function;
every other check of that submission full marks. The exercises of one check
are cheated in the same submission, so each check also runs uncheated, in
the solution's own cells, in one of the two: that is the solution graded as
a submission (a lab with nothing to cheat grades the solution itself), and
not a third full run of it.
New labs are picked up automatically.
"""

from __future__ import annotations

import copy
import pickle
import signal
import sys
import threading
import traceback
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from robotlib.course import grade as g
from robotlib.course.notebooks import (
    exercises,
    read_notebook,
    release_notebook,
    write_notebook,
)
from robotlib.course.plan import lab_plan
from tests import background
from tests.references import shared
from tests.sandboxing import need_sandbox, orphans_adopted

pytestmark = pytest.mark.slow  # every lab graded whole in the sandbox

ROOT = Path(__file__).resolve().parents[2]
LABS = sorted(p.stem for p in (ROOT / "solutions").glob("*.ipynb"))
# graded and tested in this order, the longest gradings first (quiet CI, s:
# lab6 81, lab2 73, lab4 64, then 35 or less); a lab missing here goes after
LONGEST = ["lab6_real_robot", "lab2_avoidance", "lab4_navigation"]
ORDER = [lab for lab in LONGEST if lab in LABS]
ORDER += [lab for lab in LABS[::-1] if lab not in ORDER]

# lab -> wrong answers, each graded in the same run: the cells it replaces (cell
# id -> source), the copy it starts from ("solution" or "released"), and for
# each check the points expected and, where zero, a piece of the reason (a
# cell's new source may also be a function of its solution source)
LAB3_DEAD_RECKONING = """
def paper_step(world, particles, odo_prev, odo_now, z, lam, floor, rng):
    particles = paper.predict(particles, odo_prev, odo_now, rng=rng)
    n = len(particles)
    return particles, paper.estimate(particles, np.full(n, 1 / n))
"""
LAB3_IDENTITY = """
def low_variance_resample(weights, rng):
    return np.arange(len(weights))
"""
LAB3_UNSORTED = """
def low_variance_resample(weights, rng):
    w = np.asarray(weights, dtype=float)
    cum = np.cumsum(w / w.sum())
    cum[-1] = 1.0
    pointers = (rng.random() + np.arange(len(w))) / len(w)
    idx = np.searchsorted(cum, pointers, side="right")
    return rng.permutation(idx)
"""
LAB3_TABLE_ZEROS = """
def tempering_table(errors, by=25, tolerance=0.5):
    return np.zeros(np.shape(errors)[:2], dtype=int)
"""
LAB3_TABLE_FIRST_BELOW = """
def tempering_table(errors, by=25, tolerance=0.5):
    e = np.asarray(errors, dtype=float)
    return (e[..., :by] <= tolerance).any(axis=-1).sum(axis=-1)
"""
LAB5_CONSTANTS = (
    "L_OCC, L_FREE, THICKNESS, HALF_CONE, MAX_RANGE = "
    "0.9, -0.35, 0.1, math.radians(15), 5.0\n\n\n"
)
LAB2_NOTHING = {  # no wiring, no force, an empty histogram, straight ahead
    "l2-05": "FEAR = np.zeros((2, 8))\nEXPLORER = np.zeros((2, 8))",
    "l2-11": "def potential_force(sonar, pose, goal, k_att=1.0, k_rep=0.5, d0=1.2):\n"
    "    return np.zeros(2)",
    "l2-21": "def polar_histogram(points, certainty, pose, n_sectors=72, window=1.8,"
    " enlarge=0.3):\n    return np.zeros(n_sectors)",
    "l2-24": "def choose_direction(hist, threshold, target, wide=16):\n    return 0.0",
}
LAB2_CONSTANT = {  # symmetric wiring, pull only, and straight at the goal
    "l2-05": "FEAR = np.full((2, 8), 0.1)\nEXPLORER = np.full((2, 8), -0.1)",
    "l2-11": "def potential_force(sonar, pose, goal, k_att=1.0, k_rep=0.5, d0=1.2):\n"
    "    dx, dy = goal[0] - pose[0], goal[1] - pose[1]\n"
    "    c, s = math.cos(pose[2]), math.sin(pose[2])\n"
    "    return np.array([c * dx + s * dy, -s * dx + c * dy])",
    "l2-21": LAB2_NOTHING["l2-21"],
    "l2-24": "def choose_direction(hist, threshold, target, wide=16):\n"
    "    return float(target)",
}
LAB4_NOTHING = {
    "l4-03": "def inflate_grid(occupied, radius, resolution):\n"
    "    return np.zeros_like(np.asarray(occupied, dtype=bool))\n",
    "l4-08": "def wavefront(blocked, goal):\n"
    "    return np.full(np.shape(blocked), -1)\n",
    "l4-13": "import heapq\n\n\ndef astar_grid(blocked, start, goal, weight=1.0):\n"
    "    return [], math.inf, 0\n",
    "l4-18": "def extend(nodes, q, step):\n    return 0, np.asarray(nodes, float)[0]\n",
    "l4-23": "def steer(pose, target, v, w_max):\n    return 0.0, 0.0\n",
}


LAB7_NOTHING = {  # no frontiers, no target, no discount
    "l7-03": "def frontier_cells(state):\n"
    "    return np.zeros(np.shape(state), dtype=bool)\n",
    "l7-08": "def utility(gain, cost, beta):\n"
    "    return np.asarray(gain, dtype=float)\n\n\n"
    "def choose_target(costs, gains, beta):\n"
    "    return np.full(len(np.atleast_2d(costs)), -1)\n",
    "l7-13": "def discount(gain, targets, chosen, radius):\n"
    "    return np.asarray(gain, dtype=float)\n",
}


def _steer_sign_error(source: str) -> str:
    """Lab 4's steering law with the heading error's sign flipped."""
    wrong = source.replace(
        "pose[2], 2 * math.pi)", "pose[2], 2 * math.pi)\n    alpha = -alpha"
    )
    assert wrong != source, "the steering cell changed: update this wrong answer"
    return wrong


LAB0_NEVER_MOVED = """
def drive_square(r, side):
    x, y, th = pose(r)
    corners = [(x, y, th)]
    for _ in range(4):  # computed, never driven
        x, y, th = x + side * math.cos(th), y + side * math.sin(th), th + math.pi / 2
        corners.append((x, y, th))
    return np.array(corners)
"""
WRONG = {
    # corners computed without driving: the check asks the simulator's clock
    "lab0_getting_started": {
        "never_moved": (
            "solution",
            {"l0-05": LAB0_NEVER_MOVED},
            {"square": "did not drive"},
        ),
    },
    "lab2_avoidance": {
        # answers that do nothing, or drive at the goal regardless, fail every
        # outcome check ("" below: zero, whatever the reason says)
        "do_nothing": (
            "released",
            LAB2_NOTHING,
            {"explorer": "", "pf": "", "vfh": ""},
        ),
        "constant": (
            "released",
            LAB2_CONSTANT,
            {"explorer": "", "pf": "", "vfh": ""},
        ),
    },
    "lab4_navigation": {
        # every exercise answered with nothing: every check fails, the outcome
        # checks (tracking, navigate) included
        "do_nothing": ("released", LAB4_NOTHING, {}),
        # a sign error in steer costs steer's own checks, not navigate's (which
        # grades A* and drives with the solution's steering law)
        "steer_sign": (
            "solution",
            {"l4-23": _steer_sign_error},
            {"steer": "", "tracking": ""},
        ),
    },
    "lab7_exploration": {
        # no frontiers, no choice and no discount: every check fails, the
        # outcome checks (one robot's coverage, the team's spread) included
        "do_nothing": ("released", LAB7_NOTHING, {}),
    },
    "lab3_mcl": {
        # ignores the sonar (dead reckoning), never resamples (identity) and
        # does nothing for the 2 x 2 table (zeros); on the check's route dead
        # reckoning drifts past 0.3 m, so the first bound rejects it (within
        # it, "the sonar must help" would)
        "wrong_dr_identity": (
            "solution",
            {
                "l3-19": LAB3_DEAD_RECKONING,
                "l3-37": LAB3_IDENTITY,
                "l3-52": LAB3_TABLE_ZEROS,
            },
            {
                "tracking": "the filter loses the robot",
                "low_variance": "indexes in order",
                "global": "the resampler loses the robot",
                "table": "routes localized by step 4",
            },
        ),
        # low-variance counts right but in shuffled order: only its check
        # fails; the table counts a run from its first step within the
        # tolerance, not from the step it stays within it
        "wrong_unsorted": (
            "released",
            {"l3-37": LAB3_UNSORTED, "l3-52": LAB3_TABLE_FIRST_BELOW},
            {
                "low_variance": "indexes in order",
                "global": None,
                "table": "routes localized by step 4",
            },
        ),
    },
    "lab5_slam": {
        # every function returns zeros or its inputs: the outcome checks fail
        "do_nothing": (
            "released",
            {
                "l5-03": LAB5_CONSTANTS + "def inverse_sonar(cells, sensor_pose, z):\n"
                "    return np.zeros(np.asarray(cells).shape[:-1])\n",
                "l5-06": "def sonar_map(world, poses, scans, resolution=0.1):\n"
                "    return np.zeros(world.occupancy_grid(resolution).shape)\n",
                "l5-12": "def weigh_and_resample(maps, particles, logw, loglik, "
                "temperature, rng):\n    return maps, particles, logw\n",
                "l5-20": "def ekf_update(mu, P, z, j, R):\n    return mu, P\n",
                "l5-26": "def icp_step(reference, scan, pose, gate):\n"
                "    return np.asarray(pose, dtype=float)\n",
            },
            {
                "sonar_map": "wrong result",
                "fastslam_outcome": "wrong result",
                "ekf_outcome": "wrong result",
                "icp_step": "",
                "icp_graph": "half of odometry's RMS",
            },
        ),
    },
}

# lab -> the solution cells a "partial" student copied (and the checks they pass)
PARTIAL = {
    "lab0_getting_started": ({"l0-14"}, {"sonar": 2}),
    "lab2_avoidance": ({"l2-05"}, {"braitenberg": 2, "explorer": 2}),
    "lab3_mcl": (
        {"l3-05", "l3-10", "l3-13", "l3-37"},
        {"weights": 2, "select": 1, "resize": 2, "low_variance": 2, "global": 2},
    ),
    "lab5_slam": (
        {"l5-03", "l5-20"},
        {"inverse_sonar": 2, "ekf_update": 3, "ekf_outcome": 2},
    ),
}


REACHES = "answer reaches the library's own version"  # a cheat's flag
BUILT = "uses a name built at run time"  # the static scan's flag of a string route


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


def cheats(sol, checks) -> list[tuple[object, dict[str, tuple[str, str]]]]:
    """Two cheating notebooks: exercise id -> (listed function, route) in each.

    Exercises graded by one check go to the same notebook, so that every
    check is run uncheated in one of the two (and must score full marks
    there, as in the solution); routes alternate within each notebook.
    """
    exs = [e for e in exercises(sol) if e.writes]
    half: dict[str, int] = {}
    for e in exs:
        shared = {
            half[o]
            for c in checks
            if e.exercise_id in c.exercises
            for o in c.exercises
            if o in half
        }
        fewer = min((0, 1), key=lambda h: list(half.values()).count(h))
        half[e.exercise_id] = shared.pop() if shared else fewer
    out = []
    for h in (0, 1):
        nb = copy.deepcopy(sol)
        cheated = {}
        for k, e in enumerate(exs):
            if half[e.exercise_id] != h:
                continue
            route = "alias" if len(cheated) % 2 == h else "string"
            code = (_alias if route == "alias" else _string)(e.writes[0], k)
            nb.cells[e.index].source = nb.cells[e.index].source + "\n" + code
            cheated[e.exercise_id] = (e.writes[0], route)
        if cheated:
            out.append((nb, cheated))
    return out


def _submissions(lab: str, folder: Path) -> list[dict[str, tuple[str, str]]]:
    """Write the lab's test submissions under ``folder``; return the cheats' plans."""
    sol = read_notebook(ROOT / "solutions" / f"{lab}.ipynb")
    released = read_notebook(ROOT / "labs" / f"{lab}.ipynb")
    assert released == release_notebook(sol, lab)
    subs = {"released": released}
    if lab in PARTIAL:
        partial = copy.deepcopy(released)
        sources = {c.id: c.source for c in sol.cells}
        for cell in partial.cells:
            if cell.id in PARTIAL[lab][0]:
                cell.source = sources[cell.id]
        subs["partial"] = partial
    for name, (base, cells, _) in WRONG.get(lab, {}).items():
        nb = copy.deepcopy(sol if base == "solution" else released)
        for cell in nb.cells:
            new = cells.get(cell.id, cell.source)
            cell.source = new(cell.source) if callable(new) else new
        subs[name] = nb
    plan = cheats(sol, lab_plan(sol, lab).checks)
    for i, (nb, _) in enumerate(plan):
        subs[f"cheat{i}"] = nb
    if not plan:  # else the cheats run every check of the solution, uncheated
        subs["solution"] = sol
    for name, nb in subs.items():
        (folder / name).mkdir(parents=True)
        write_notebook(nb, folder / name / f"{lab}.ipynb")
    return [c for _, c in plan]


# at the tests' priority: Lab 6's faulty-link check drives through a wall-clock
# link (12 s for a ~1 s drive), and at +5 beside the browser its reference run
# failed (0 of 5 runs reached the goal, load ~30)
BACKGROUND_NICER = 0


def background_work(folder: Path) -> dict[str, tuple | str]:
    """Grade the selected labs beside the other tests (`tests.background`).

    One process of its own (`_grade_labs`): its sandboxes stay out of the
    process trees the other grading tests search for leftovers. Returns lab
    -> (results, checks, cheat plans), or the text of what went wrong.
    """
    need_sandbox()
    labs = {
        item.callspec.params["lab_graded"]
        for item in background.selected(__name__)
        if "lab_graded" in getattr(getattr(item, "callspec", None), "params", {})
    }
    labs = [lab for lab in ORDER if lab in labs]
    cmd = [sys.executable, "-m", __name__, folder, *labs]
    proc = background.run(cmd, cwd=ROOT, timeout=3000)
    out = {}
    for lab in labs:
        path = folder / f"{lab}.pickle"
        got = pickle.loads(path.read_bytes()) if path.exists() else None
        out[lab] = got or f"exit {proc.returncode}: {proc.stderr[-4000:]}"
    return out


def _grade_labs(folder: Path, labs: list[str]) -> None:
    """Grade ``labs`` two at a time (two submissions each), heaviest first.

    Each grading starts with its reference run, in one sandbox (or from the
    session's, `tests.references`: Lab 0's is also the class cases'); with two
    labs at once the other core grades the other lab meanwhile, and no lab's
    last submission runs alone. Each lab's outcome goes to ``folder/LAB.pickle``.
    SIGTERM (the session ended early) ends every grading's processes.
    """
    runs, ending = [], threading.Event()

    def graded(lab: str) -> None:
        opts = g.Options(cell_timeout=90, timeout=400)
        runs.append(opts)
        if ending.is_set():
            return
        try:
            plans = _submissions(lab, folder / lab / "subs")
            records = folder / lab / "records"
            with shared(lab, ROOT / "solutions" / f"{lab}.ipynb", records):
                results, items = g.grade(
                    folder / lab / "subs", lab, jobs=2, opts=opts, progress=False,
                    records=records,
                )  # fmt: skip
            out = (results, items, plans)
        except BaseException:
            out = traceback.format_exc()
        (folder / f"{lab}.pickle").write_bytes(pickle.dumps(out))

    def stop(*_):
        ending.set()
        for opts in runs:
            if opts.stop is not None:
                opts.stop.set()

    signal.signal(signal.SIGTERM, stop)
    with orphans_adopted(), ThreadPoolExecutor(max_workers=2) as pool:
        list(pool.map(graded, labs))


@pytest.fixture(scope="module", params=ORDER)
def lab_graded(request):
    got = background.result(__name__, timeout=3000)[request.param]
    if isinstance(got, str):
        pytest.fail(f"grading {request.param} failed:\n{got}")
    results, items, plans = got
    return request.param, {r.student: r for r in results}, items, plans


def test_solution_full_released_zero(lab_graded):
    """The solution scores full marks graded as a submission, twice over.

    The grader's reference run must (else `grade` raises); graded again
    against it, each check scores full marks in the solution itself (a lab
    with no cheats) or in a cheat that leaves that check's exercises alone
    (the solution's cells plus code elsewhere), with no flag but the cheats'.
    """
    lab, rows, items, plans = lab_graded
    auto = [c for c in items if not c.manual]
    uncheated = {"solution": {}} if "solution" in rows else {}
    uncheated |= {f"cheat{i}": cheated for i, cheated in enumerate(plans)}
    for c in auto:
        graded = [n for n, ch in uncheated.items() if not set(ch) & set(c.exercises)]
        assert graded, f"{c.grade_id} is cheated in every cheat"
        for name in graded:
            r = rows[name]
            assert r.points[c.grade_id] == c.points, (name, c.grade_id, r.reasons)
    for name, cheated in uncheated.items():
        r, listed = rows[name], [f for f, _ in cheated.values()]
        assert r.status == "ok", (name, r.status)
        if any(route == "string" for _, route in cheated.values()):  # the scan saw it
            listed.append(BUILT)
        other = [f for f in r.flags if f != REACHES and not any(x in f for x in listed)]
        assert not other, (name, other)
    rel = rows["released"]
    assert all(v == 0 for v in rel.points.values()), rel.points
    if lab in PARTIAL:
        got = {k: v for k, v in rows["partial"].points.items() if v}
        assert got == PARTIAL[lab][1], rows["partial"].reasons


def test_cheats_score_zero_for_their_exercise_only(lab_graded):
    lab, rows, items, plans = lab_graded
    auto = [c for c in items if not c.manual]
    for i, cheated in enumerate(plans):
        r = rows[f"cheat{i}"]
        assert r.status == "ok", (r.status, r.passes, r.details)
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
        assert REACHES in r.flags


def test_wrong_answers_fail_their_strict_checks(lab_graded):
    """Lab 3: dead reckoning fails tracking; identity and unsorted fail low-variance;
    a do-nothing table and one counting a run from its first good step fail table.
    Lab 2: doing nothing, or driving at the goal regardless, fails every outcome
    check. Lab 4: doing nothing fails every check; a sign error in steer only
    steer's and tracking's.

    A wrong answer built on the solution keeps every other check; one built
    on the released lab passes only the checks named with no reason.
    """
    lab, rows, items, _ = lab_graded
    if lab not in WRONG:
        pytest.skip(f"{lab} has no wrong answers listed")
    auto = [c for c in items if not c.manual]
    for name, (base, _, expect) in WRONG[lab].items():
        r = rows[name]
        assert r.status == "ok", (name, r.status)
        for c in auto:
            if c.grade_id in expect and expect[c.grade_id] is not None:
                assert r.points[c.grade_id] == 0, (name, c.grade_id)
                assert expect[c.grade_id] in r.reasons[c.grade_id], r.reasons
            elif base == "solution" or c.grade_id in expect:
                assert r.points[c.grade_id] == c.points, (name, c.grade_id, r.reasons)
            else:
                assert r.points[c.grade_id] == 0, (name, c.grade_id)
        assert not r.flags, (name, r.flags)


if __name__ == "__main__":  # the gradings' own process (`background_work`)
    _grade_labs(Path(sys.argv[1]), sys.argv[2:])
