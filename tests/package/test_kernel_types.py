"""Kernels compile once per argument type: public functions hand them one type."""

from __future__ import annotations

import copy

import numpy as np

from robotlib._config import readonly
from robotlib.avoidance import VFH, choose_direction, polar_histogram, run_episode
from robotlib.avoidance import _kernels as avoidance_kernels
from robotlib.planning import CSpace, astar
from robotlib.planning import _kernels as planning_kernels
from robotlib.world import World

BOX = World(segments=[[0, 0, 4, 0], [4, 0, 4, 3], [4, 3, 0, 3], [0, 3, 0, 0]])


def test_readonly_is_a_view_of_the_same_data():
    a = np.arange(6.0).reshape(2, 3)
    r = readonly(a)
    assert not r.flags.writeable and a.flags.writeable
    assert np.shares_memory(a, r)
    assert readonly(r) is r


def test_a_copied_controller_reuses_the_compiled_kernel():
    """A deep copy (as a worker gets) has writable arrays; no new signature."""
    vfh = VFH(histogram=polar_histogram, direction=choose_direction)
    kw = {"goal": (3.0, 1.5), "start": (1.0, 1.5, 0.0), "seed": 0, "max_time": 0.3}
    run_episode(BOX, vfh, **kw)
    before = len(avoidance_kernels.certainty_update.signatures)
    twin = copy.deepcopy(vfh)
    assert twin.sensors.flags.writeable
    run_episode(BOX, twin, **kw)
    assert len(avoidance_kernels.certainty_update.signatures) == before


def test_planning_with_and_without_the_cost_map_shares_one_kernel():
    cs = CSpace.from_array(np.zeros((4, 4), dtype=bool))
    astar(cs, (0.5, 0.5), (3.5, 3.5))
    before = len(planning_kernels.astar.signatures)
    plan = astar(cs, (0.5, 0.5), (3.5, 3.5), use_cost=False)
    assert plan.found
    assert len(planning_kernels.astar.signatures) == before
