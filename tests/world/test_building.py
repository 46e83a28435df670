"""The shipped office building ``worlds/building.map`` (issue 17).

The generator reproduces the shipped file bit for bit, the file reads as a
17 m x 31 m building of about 250 walls, and every room of it is reachable
from the robot's home: the only free regions the robot cannot reach are the
insides of furniture.
"""

from __future__ import annotations

import importlib.util
from collections import deque

import numpy as np
import pytest

from robotlib.world import WORLDS_DIR, load_world, read_world, world_names
from robotlib.world.model import ROBOT_RADIUS


def _make_worlds():
    spec = importlib.util.spec_from_file_location(
        "make_worlds", WORLDS_DIR / "make_worlds.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def building():
    return load_world("building")


def test_generator_reproduces_the_shipped_file():
    text = _make_worlds().building_map()
    assert text.encode("ascii") == (WORLDS_DIR / "building.map").read_bytes()


def test_generator_is_seeded():
    mw = _make_worlds()
    assert mw.building(seed=17) == mw.building(seed=17)
    assert mw.building(seed=18) != mw.building(seed=17)


def test_building_is_listed_and_office_sized(building):
    assert "building" in world_names()
    assert building.name == "building"
    walls = np.asarray(building.segments)
    assert 200 <= len(walls) <= 300
    lo = walls.reshape(-1, 2).min(axis=0)
    hi = walls.reshape(-1, 2).max(axis=0)
    # 17 m x 31 m, plus the 0.6 m entrance recess to the west
    assert hi - lo == pytest.approx([17.6, 31.0])
    assert 10 <= len(building.points) <= 100
    assert building.is_free(building.start[:2])


def test_another_seed_reads_back(tmp_path):
    """A different seed's building is a valid map too (the generator is not tuned)."""
    path = tmp_path / "b3.map"
    path.write_text(_make_worlds().building_map(seed=3), encoding="ascii")
    w = read_world(path)
    assert 200 <= len(w.segments) <= 300
    _assert_every_room_reachable(w)


def _components(free: np.ndarray) -> np.ndarray:
    """Label 4-connected components of ``free`` (0: not free)."""
    label = np.zeros(free.shape, dtype=int)
    ny, nx = free.shape
    n = 0
    for i, j in zip(*np.nonzero(free), strict=True):
        if label[i, j]:
            continue
        n += 1
        label[i, j] = n
        todo = deque([(i, j)])
        while todo:
            a, b = todo.popleft()
            for c, d in ((a + 1, b), (a - 1, b), (a, b + 1), (a, b - 1)):
                if 0 <= c < ny and 0 <= d < nx and free[c, d] and not label[c, d]:
                    label[c, d] = n
                    todo.append((c, d))
    return label


def _assert_every_room_reachable(world, res: float = 0.1) -> None:
    dist = world.distance_field(res)
    xy = dist.centres()
    x0, y0, x1, y1 = 0.0, 0.0, 17.0, 31.0  # inside the outline (not the recess)
    r = ROBOT_RADIUS
    free = (
        (dist.data > r)
        & (xy[..., 0] - r >= x0)
        & (xy[..., 0] + r <= x1)
        & (xy[..., 1] - r >= y0)
        & (xy[..., 1] + r <= y1)
    )
    label = _components(free)
    i, j = dist.cell_of(np.array(world.start[:2]))
    home = label[i, j]
    assert home
    areas = np.bincount(label.ravel()) * res**2
    areas[0] = 0
    assert areas[home] > 300.0, f"only {areas[home]:.0f} m2 reachable"
    others = [a for k, a in enumerate(areas) if k not in (0, home) and a > 0]
    # the insides of desks, crates and racks; a room cut off is several m2
    assert max(others, default=0.0) < 0.5, f"a free region of {max(others):.1f} m2"


def test_every_room_is_reachable(building):
    _assert_every_room_reachable(building)
    # and the world's own admissible area agrees
    reach = building.free_space(0.1).data.sum() * 0.1**2
    assert reach > 300.0


@pytest.mark.slow
def test_lab3_panel_kidnaps_in_the_building(building):
    """Lab 3's last panel: `MCL.best` on a building tour, kidnapped by the button."""
    from robotlib.experiments import drive_tour
    from robotlib.experiments.reproduce import recovery_steps
    from robotlib.widgets.mcl import MCLPanel

    tour = drive_tour(building, 0, 24)
    panel = MCLPanel(tour, n_steps=24, preset="best (beam + KLD)")
    assert panel.world.value == "building" and panel.history.localized_step()
    panel.kidnap_button.click()
    assert panel.kidnap.value == 12
    taken = panel._route_of("building", 12)
    assert taken.kidnapped_at == 12 and taken.world is building
    np.testing.assert_array_equal(taken.truth[:12], tour.truth[:12])
    assert np.hypot(*(taken.truth[12, :2] - tour.truth[12, :2])) > 1.0
    assert "kidnapped before step 12" in panel.status.value
    assert panel.recovered_after == recovery_steps(panel.history.error, 12)


def test_mcl_figure_puts_a_tall_building_beside_the_plots(building):
    from matplotlib.figure import Figure

    from robotlib.experiments import drive_tour
    from robotlib.widgets.mcl import plot_mcl_run, run_mcl

    history = run_mcl(drive_tour(building, 1, 6), seed=0)
    fig = plot_mcl_run(history, building, Figure(figsize=(9, 5.4)))
    ax_map, ax_err, ax_n = fig.axes[:3]
    fig.canvas.draw()
    m, e, n = (a.get_position() for a in (ax_map, ax_err, ax_n))
    assert m.x1 < e.x0 and m.x1 < n.x0  # the map on the left
    assert n.y1 < e.y0  # error above particles
    assert m.height > 1.5 * e.height
