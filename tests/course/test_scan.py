# ruff: noqa: E501
"""The static pass zeroes routes to the library's own answers, and nothing else.

Honest cells that merely look like routes (``__import__('time')``, importlib
of the standard library, ``re.compile``, ``model.eval()``, a dictionary
looked up by a listed function's own name, a message naming it) give no
finding at all, so they are neither zeroed nor flagged; every cheating cell
gives one, naming the listed function when the code names it.
"""

from __future__ import annotations

import pytest
from nbformat.v4 import new_code_cell

from robotlib.course.answers import aliases
from robotlib.course.notebooks import read_notebook
from robotlib.course.plan import lab_plan, scan_submission, student_cells
from robotlib.course.scan import scan_code
from tests.course.test_course_grade import MEAN, SCALE, TINY, by_id, with_cell

ASTAR, UPDATE, STEP = (
    "robotlib.planning.astar",
    "robotlib.localization.histogram.update",
    "robotlib.localization.mcl.MCL.step",
)

HONEST = {
    "dunder_import_time": "t0 = __import__('time').perf_counter()",
    "dunder_import_fromlist": "p = __import__('os.path', fromlist=['join']).join('a', 'b')",
    "importlib_math": "import importlib\nm = importlib.import_module('math')\nm.hypot(3, 4)",
    "getattr_numpy": "import numpy as np\nf = getattr(np, 'hypot')\ng = getattr(np, name)",
    "re_compile": "import re\npattern = re.compile(r'\\d+')",
    "method_eval": "model.eval()\nnet.compile()",
    "platform_system": "import platform\nplatform.system()",
    "machinery_names": "system, modules, reload, popen = 1, [], False, None\nprint(system, modules)",
    "eval_constant": "x = eval('1 + 2')",
    "dict_get_listed_name": "cfg = {}\nu = cfg.get('update', 1)\ns = params.pop('step', 0.1)",
    "getattr_own_method": "class A:\n    def astar(self):\n        pass\n\nf = getattr(A(), 'astar')",
    "message_names_function": "print('mine is slower than robotlib.planning.astar')",
    "message_solutions": "raise ValueError('no solutions / no path; see lab4_navigation.ipynb')",
    "own_decorator": "import functools\n\ndef deco(f):\n    @functools.wraps(f)\n    def g(*a):\n        return f(*a)\n    return g\n\nh = deco(len)\nh.__wrapped__\nh.__code__",
    "sys_modules_read": "import sys\nhave_numba = 'numba' in sys.modules",
    "sys_path": "import sys\nsys.path.insert(0, '..')",
    "timeit_own_code": "import timeit\nt = timeit.timeit('astar(grid, s, g)', globals=globals(), number=3)",
    "module_of_library": "import robotlib.planning as p\ngrid = p.OccupancyGrid\nq = getattr(p, 'OccupancyGrid')",
}

CHEATS = {
    # the listed function named, however indirectly: the finding names it
    "alias": ("from robotlib.planning import astar as f", ASTAR),
    "attribute": ("import robotlib.planning as p\nf = p.astar", ASTAR),
    "getattr_constant": (
        "import robotlib.planning as p\nf = getattr(p, 'as' + 'tar')",
        ASTAR,
    ),
    "vars_subscript": ("import robotlib.planning as p\nf = vars(p)['astar']", ASTAR),
    "dict_alias": (
        "import robotlib.planning as p\nd = p.__dict__\nf = d['astar']",
        ASTAR,
    ),
    "vars_get": ("import robotlib.planning as p\nf = vars(p).get('astar')", ASTAR),
    "attrgetter": (
        "import operator, robotlib.planning as p\nf = operator.attrgetter('astar')(p)",
        ASTAR,
    ),
    "import_module": (
        "import importlib\nm = importlib.import_module('robotlib.planning')\nm.astar",
        ASTAR,
    ),
    "dunder_import_top": ("f = __import__('robotlib.planning').planning.astar", ASTAR),
    "dunder_import_fromlist": (
        "f = vars(__import__('robotlib.planning', fromlist=['x']))['astar']",
        ASTAR,
    ),
    "dunder_import_computed": ("m = __import__(name)\nf = m.astar", ASTAR),
    "sys_modules": ("import sys\nf = sys.modules['robotlib.planning'].astar", ASTAR),
    "exec_constant": ("exec('from robotlib.planning import astar as f')", ASTAR),
    "string_of_code": (
        "code = 'from robotlib.planning import astar as f'\nrun(code)",
        ASTAR,
    ),
    "subprocess_code": (
        "import subprocess, sys\nsubprocess.run([sys.executable, '-c', 'import robotlib.planning as p; print(p.astar)'])",
        ASTAR,
    ),
    "pydoc_locate": (
        "import pydoc\nf = pydoc.locate('robotlib.planning.astar')",
        ASTAR,
    ),
    "star": ("from robotlib.planning import *", ASTAR),
    "listed_name_via_getattr": (
        "from robotlib.localization import histogram as h\nf = getattr(h, 'update')",
        UPDATE,
    ),
    "method": ("from robotlib.localization.mcl import MCL\nf = MCL.step", STEP),
    # machinery that reaches the library where no name shows it
    "computed_lookup": (
        "import importlib\nf = getattr(importlib.import_module('robotlib.planning'), ''.join(['as', 'tar']))",
        "a name built at run time",
    ),
    "computed_both": (
        "import importlib\nm = importlib.import_module(n)\nf = getattr(m, k)",
        "a name built at run time",
    ),
    "exec_variable": ("code = open(path).read()\nexec(code)", "exec"),
    "exec_passed_around": ("run = exec\nrun(code)", "exec"),
    "compile_variable": ("c = compile(src, 'x', 'exec')", "compile"),
    "subprocess": (
        "import subprocess\nsubprocess.run(['python', '-c', code])",
        "a subprocess",
    ),
    "subprocess_imported_name": (
        "from subprocess import check_output as co\nco(cmd)",
        "a subprocess",
    ),
    "os_system": ("import os\nos.system(cmd)", "os.system"),
    "os_system_dunder": ("__import__('os').system(cmd)", "os.system"),
    "reload": (
        "import importlib, robotlib.planning as p\nimportlib.reload(p)",
        "importlib.reload",
    ),
    "module_from_file": (
        "import importlib.util as u\nspec = u.spec_from_file_location('m', path)",
        "importlib.util",
    ),
    "sys_modules_deleted": (
        "import sys\ndel sys.modules['robotlib.planning']",
        "sys.modules",
    ),
    "sys_modules_popped": ("import sys\nsys.modules.pop(name)", "sys.modules"),
    "meta_path": ("import sys\nsys.meta_path.insert(0, Finder())", "sys.meta_path"),
    "getsource": (
        "import inspect, robotlib.planning as p\nsrc = inspect.getsource(p)",
        "inspect.getsource",
    ),
    "library_file": (
        "import robotlib.planning as p\nsrc = open(p.__file__).read()",
        "robotlib.planning.__file__",
    ),
    "library_closure": (
        "import robotlib.planning as p\nc = p.plan.__wrapped__",
        "robotlib.planning.plan.__wrapped__",
    ),
    "gc": ("import gc\nobjects = gc.get_objects()", "gc.get_objects"),
    "ctypes": ("import ctypes\nctypes.CDLL(None)", "ctypes"),
    "process_pool": (
        "from concurrent.futures import ProcessPoolExecutor\nProcessPoolExecutor(2)",
        "a process pool",
    ),
    "multiprocessing": ("import multiprocessing as mp\nmp.Pool(2)", "multiprocessing"),
    "solutions_path": (
        "open('../solutions/lab4_navigation.ipynb').read()",
        "solutions/",
    ),
    "notebook_glob": ("import glob\nglob.glob('**/*.ipynb')", "solutions/"),
}


@pytest.fixture(scope="module")
def names():
    return aliases([ASTAR, UPDATE, STEP])


@pytest.mark.parametrize("case", HONEST)
def test_honest_code_finds_nothing(names, case):
    assert scan_code(HONEST[case], names) == []


@pytest.mark.parametrize("case", CHEATS)
def test_every_route_is_found(names, case):
    source, what = CHEATS[case]
    found = scan_code(source, names)
    assert what in [f.function for f in found], found
    for f in found:
        assert f.listed == (f.function in (ASTAR, UPDATE, STEP)), f


def test_a_cell_that_does_not_parse_finds_nothing(names):
    assert scan_code("def f(:\n", names) == []
    assert scan_code("%timeit f()\nimport robotlib.planning as p\np.astar", names)


def test_in_an_exercise_cell_honest_imports_cost_nothing_and_routes_zero():
    """The case of the last session: ``__import__('time')`` zeroed an exercise."""
    plan = lab_plan(read_notebook(TINY), "tiny")
    answer = by_id(read_notebook(TINY), MEAN).source
    honest = with_cell(
        read_notebook(TINY),
        MEAN,
        "import importlib\n_t = __import__('time').perf_counter()\n"
        "_m = importlib.import_module('math')\n" + answer,
    )
    assert scan_submission(plan, student_cells(plan, honest)) == ({}, [])
    # a cell of one's own naming the listed function: its tripwire refuses it
    # if it runs (an answer calling it is zeroed then), the scan says nothing
    compared = read_notebook(TINY)
    compared.cells.append(new_code_cell("from numpy import mean as m\nm([1.0])"))
    assert scan_submission(plan, student_cells(plan, compared)) == ({}, [])
    # another exercise's library version (``scale`` does not list numpy.mean)
    scale = by_id(read_notebook(TINY), SCALE).source
    other = with_cell(read_notebook(TINY), SCALE, "from numpy import mean\n" + scale)
    assert scan_submission(plan, student_cells(plan, other)) == ({}, [])
    assert plan.lists("mean", "numpy.mean") and not plan.lists("scale", "numpy.mean")
    for route in ("m = __import__('numpy').mean", "exec(text)", "__import__('os').system(c)"):  # fmt: skip
        cheat = with_cell(read_notebook(TINY), MEAN, route + "\n" + answer)
        zero, flags = scan_submission(plan, student_cells(plan, cheat))
        assert list(zero) == ["mean"] and flags, route
