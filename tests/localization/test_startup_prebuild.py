"""`MCL.best` on an empty numba cache compiles its step in a helper process.

`robotlib.localization._prebuild`: the helper compiles the first step's
kernels into numba's cache while the filter is built; the first step then
compiles nothing, gives the numbers a process without the helper gives, the
made-up table of the helper's room never reaches the table cache, and the
helper ends with its parent.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from robotlib.localization import _prebuild, _prebuild_run

pytestmark = pytest.mark.skipif(
    os.name != "posix" or len(os.sched_getaffinity(0)) < 2,
    reason="the helper runs on POSIX with two cores or more",
)

FIRST_STEP = textwrap.dedent("""
    import json, sys
    import numpy as np
    from robotlib.localization import MCL, expected_readings, _prebuild
    from robotlib.world import load_world
    from numba.core import event

    compiled = []

    class Count(event.Listener):
        def on_start(self, ev):
            pass

        def on_end(self, ev):
            f = getattr(ev.data.get("dispatcher"), "py_func", None)
            name = getattr(f, "__name__", "")
            compiled.append(getattr(f, "__module__", "") + "." + name)

    if "threads" in sys.argv:  # numba's thread pool up: no fork, a fresh helper
        from numba.np.ufunc import parallel
        parallel._launch_threads()
    if "pythread" in sys.argv:  # another thread, as in a Jupyter kernel: no fork
        import threading
        threading.Thread(target=threading.Event().wait, daemon=True).start()
    world = load_world("corridor")
    mcl = MCL.best(world, rng=0)
    helper = mcl._prebuild
    odo = np.array(world.start)
    z = expected_readings(world, np.array([odo + [0.5, 0.0, 0.05]]))[0]
    event.register("numba:compile", Count())
    ests = [mcl.step(odo, odo + [0.5, 0.0, 0.05], z).tolist()]
    first = [c for c in compiled if c.startswith("robotlib.")]
    ests.append(mcl.step(odo + [0.5, 0.0, 0.05], odo + [0.8, 0.0, 0.05], z).tolist())
    if helper is not None:
        helper.proc.wait(timeout=120)
    print(json.dumps({"helper": helper is not None,
                      "ready": helper is not None and helper.ready,
                      "exit": None if helper is None else helper.proc.returncode,
                      "forked": helper is not None and helper.forked,
                      "first": first, "ests": ests}))
""")


def _first_step(cache, prebuild: bool, mode: str | None = None) -> dict:
    env = dict(
        os.environ, NUMBA_CACHE_DIR=str(cache), ROBOTLIB_PREBUILD=str(int(prebuild))
    )
    env.pop("ROBOTLIB_TABLE_CACHE", None)
    args = [mode] if mode else []
    out = subprocess.run(
        [sys.executable, "-c", FIRST_STEP, *args], env=env, capture_output=True,
        text=True, timeout=600, check=True,
    )  # fmt: skip
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_the_first_step_compiles_nothing_and_gives_the_same_numbers(tmp_path):
    """With the helper: the step compiles at most its tail; same numbers, tables."""
    helped = _first_step(tmp_path / "helped", True)
    assert helped["helper"] and helped["ready"] and helped["exit"] == 0
    assert helped["forked"]  # no thread pool yet: a fork of the process
    # nothing but what this process compiles while it waits (`compile_tail`)
    assert set(helped["first"]) <= {
        f"robotlib.localization._kernels.resample.{name}"
        for name in ("gather", "kld_resample", "cumulative", "outside")
    }
    alone = _first_step(tmp_path / "alone", False)
    assert not alone["helper"]
    assert alone["first"]  # without the helper the first step compiles (else: no test)
    assert helped["ests"] == alone["ests"]  # bit for bit (floats through JSON)
    tables = sorted(p.name for p in (tmp_path / "helped" / "robotlib-tables").glob("*"))
    assert tables == sorted(
        p.name for p in (tmp_path / "alone" / "robotlib-tables").glob("*")
    )
    # a warm cache starts no helper
    assert not _first_step(tmp_path / "helped", True)["helper"]


@pytest.mark.parametrize("mode", ["threads", "pythread"])
def test_a_spawned_helper_gives_the_same_numbers(tmp_path, mode):
    """With numba's thread pool or another thread running (no fork), a fresh
    interpreter helps."""
    spawned = _first_step(tmp_path / "spawned", True, mode)
    assert spawned["helper"] and spawned["ready"] and spawned["exit"] == 0
    assert not spawned["forked"]
    assert set(spawned["first"]) <= {
        f"robotlib.localization._kernels.resample.{name}"
        for name in ("gather", "kld_resample", "cumulative", "outside")
    }
    alone = _first_step(tmp_path / "alone", False)
    assert spawned["ests"] == alone["ests"]


def test_no_helper_when_switched_off_or_busy(monkeypatch):
    monkeypatch.setenv(_prebuild.ENV, "0")
    assert _prebuild.start() is None
    monkeypatch.setenv(_prebuild.ENV, "auto")
    monkeypatch.setattr(_prebuild.os, "getloadavg", lambda: (64.0, 64.0, 64.0))
    assert not _prebuild._core_to_spare()
    assert _prebuild.start() is None  # every core busy: the helper would not help
    monkeypatch.setattr(_prebuild.os, "getloadavg", lambda: (0.0, 0.0, 0.0))
    assert _prebuild._core_to_spare()
    monkeypatch.setenv(_prebuild.ENV, "1")
    assert _prebuild.start(fast=False) is None  # cone casts: not these kernels


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_the_helper_ends_with_its_parent(tmp_path):
    """A parent that ends at once (or is killed) leaves no helper behind."""
    script = textwrap.dedent("""
        import os
        from robotlib.localization import _prebuild, _prebuild_run
        helper = _prebuild.start()
        print(helper.proc.pid, flush=True)
        os._exit(0)
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), ROBOTLIB_PREBUILD="1")
    out = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True,
        timeout=120, check=True,
    )  # fmt: skip
    pid = int(out.stdout.split()[0])
    end = time.monotonic() + 30
    while _alive(pid) and time.monotonic() < end:
        time.sleep(0.1)
    assert not _alive(pid)


def test_the_fake_table_fills_every_entry_in_range():
    table = np.zeros((3, 4, 72), dtype=np.uint16)
    _prebuild_run._fake_table(None, 0.0, table)
    assert table.min() >= 100 and table.max() < 5000
    assert len(np.unique(table)) > 100  # varied: the helper's filter resamples


# -- start-up without the helper: what a cold or a warm process skips ---------------


TAIL = textwrap.dedent("""
    import json
    import numpy as np
    from robotlib.localization import MCL, _prebuild
    from robotlib.world import load_world
    from numba.core import event

    compiled = []

    class Count(event.Listener):
        def on_start(self, ev):
            pass

        def on_end(self, ev):
            f = getattr(ev.data.get("dispatcher"), "py_func", None)
            compiled.append(getattr(f, "__name__", ""))

    class Busy:  # a helper that never gets there
        def poll(self):
            return False

    world = load_world("corridor")
    a, b = MCL.best(world, rng=0), MCL.best(world, rng=0)
    before = (a.particles.copy(), a.weights.copy(), a.rng.bit_generator.state)
    done = _prebuild.compile_tail(a, Busy())
    same = (np.array_equal(before[0], a.particles) and np.array_equal(before[1],
            a.weights) and before[2] == a.rng.bit_generator.state)
    event.register("numba:compile", Count())
    odo = np.array(world.start)
    z = np.linspace(0.4, 3.0, len(a.sensor.sonar.sensors))
    ea = a.step(odo, odo + [0.5, 0.0, 0.05], z).tolist()
    eb = b.step(odo, odo + [0.5, 0.0, 0.05], z).tolist()
    print(json.dumps({"done": done, "same": same, "compiled": compiled,
                      "resampled": a.info.resampled, "ests": [ea, eb],
                      "sets": [a.particles.tolist(), b.particles.tolist()]}))
""")


def test_the_tail_compiled_here_is_what_the_first_step_needs(tmp_path):
    """`compile_tail`: the last kernels for the step's own types, no state touched."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), ROBOTLIB_PREBUILD="0")
    out = subprocess.run(
        [sys.executable, "-c", TAIL], env=env, capture_output=True, text=True,
        timeout=600, check=True,
    )  # fmt: skip
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["done"] == 3 and got["same"] and got["resampled"]
    assert got["compiled"]  # the step's first kernels were compiled in the step
    for name in ("gather", "kld_resample", "cumulative", "outside"):
        assert name not in got["compiled"], name  # compiled before, same types
    assert got["ests"][0] == got["ests"][1]  # and the filter's numbers unchanged
    assert got["sets"][0] == got["sets"][1]
