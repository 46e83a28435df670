"""The notebook panels: thin wrappers over tested functions, driven programmatically."""

from __future__ import annotations

import re

import numpy as np
import pytest

import robotlib
from robotlib.experiments import drive_route
from robotlib.localization import MCL
from robotlib.widgets import mcl as widgets
from robotlib.widgets import teleop as teleop_widgets
from robotlib.world import load_world, world_names


@pytest.fixture(scope="module")
def route():
    return drive_route(load_world("corridor"), seed=0, n_steps=12)


def test_mcl_filter_choices():
    world = load_world("corridor")
    for sensor in widgets.SENSORS:
        for resampler in widgets.RESAMPLERS:
            mcl = widgets.mcl_filter(
                world, n=60, sensor=sensor, resampler=resampler, rng=0
            )
            assert mcl.n == 60
    with pytest.raises(ValueError, match="sensor"):
        widgets.mcl_filter(world, sensor="laser")
    with pytest.raises(ValueError, match="resampler"):
        widgets.mcl_filter(world, resampler="magic")
    with pytest.raises(ValueError, match="preset"):
        widgets.mcl_filter(world, preset="oracle")


def test_best_preset_is_mcl_best(route):
    """The panel's "best" choices build the very filter `MCL.best` builds."""
    world = route.world
    ours = widgets.mcl_filter(world, preset="best (beam + KLD)", rng=3)
    best = MCL.best(world, rng=3)
    assert ours.n == best.n == widgets.PRESETS["best (beam + KLD)"]["n"]
    for k in range(8):
        args = (route.odometry[max(k - 1, 0)], route.odometry[k], route.sonar[k])
        np.testing.assert_array_equal(ours.step(*args), best.step(*args))
        assert ours.n == best.n
    assert best.n < 50_000  # KLD has shrunk the set: the comparison meant something
    # explicit choices override the preset's
    assert widgets.mcl_filter(world, preset="best (beam + KLD)", n=500, rng=0).n == 500
    paper = widgets.mcl_filter(world, preset="paper", rng=0)
    assert paper.n == 300 and paper.resampling.lam == 0.5


def test_run_mcl_is_deterministic_and_tracks(route):
    a = widgets.run_mcl(route, tracking=True, n=100, seed=1)
    b = widgets.run_mcl(route, tracking=True, n=100, seed=1)
    assert len(a) == len(route)
    np.testing.assert_array_equal(a.estimate, b.estimate)
    assert a.error.mean() < 0.3  # tracking from the true start pose holds


def test_paper_resize_shrinks_with_lambda(route):
    slow = widgets.run_mcl(route, n=300, lam=0.0, seed=0, n_steps=5)
    fast = widgets.run_mcl(route, n=300, lam=5.0, seed=0, n_steps=5)
    assert slow.n_particles == [300] * 5
    assert fast.n_particles[-1] < fast.n_particles[0]


def test_mcl_panel_callbacks(route):
    panel = widgets.MCLPanel(route, n_steps=6, n=100, lam=0.5)
    assert not panel.lam.continuous_update and not panel.n.continuous_update
    assert panel.history.n_particles[0] == 100
    panel.n.value = 150  # as if the slider were released at 150
    assert panel.history.n_particles[0] == 150
    panel.lam.value = 0.0
    assert panel.history.n_particles == [150] * 6
    panel.sensor.value = "beam"
    panel.resampler.value = "low variance"
    assert panel.settings()["sensor"] == "beam"
    assert len(panel.figure.axes) == 4  # map (+ its colour bar: the step), error, count
    assert "localized" in panel.status.value


@pytest.mark.slow
def test_mcl_panel_presets_and_worlds(route):
    panel = widgets.MCLPanel(route, n_steps=6, n=300, lam=0.5)
    assert panel.preset.value == "paper"  # the choices make the paper's filter
    assert "corridor_periodic" in panel.world.options
    assert set(world_names()) <= set(panel.world.options)
    runs = []
    run = panel.refresh
    panel.refresh = lambda: runs.append(1) or run()
    panel.preset.value = "best (beam + KLD)"
    assert len(runs) == 1  # one run for the preset, not one per control it set
    best = widgets.PRESETS["best (beam + KLD)"]
    assert {k: panel.settings()[k] for k in best} == best
    assert panel.history.n_particles[0] == best["n"]
    panel.n.value = 2000  # a hand-made change leaves the preset
    assert panel.preset.value == panel.CUSTOM
    assert panel.history.n_particles[0] == 2000
    panel.world.value = "corridor_periodic"
    assert panel.route.world.name == "corridor_periodic"
    assert len(panel.route) == len(route) and panel.route.seed == route.seed
    assert len(panel.history) == 6
    assert panel.status.value.startswith("corridor_periodic")
    np.testing.assert_allclose(
        panel.history.true_pose[0], load_world("corridor_periodic").start, atol=1e-6
    )
    panel.preset.value = "paper"
    assert panel.settings()["sensor"] == "paper" and panel.settings()["n"] == 300
    assert panel.history.n_particles[0] == 300
    assert len(runs) == 4
    with pytest.raises(ValueError, match="preset"):
        widgets.MCLPanel(route, n_steps=2, preset="oracle")


def test_teleop_moves_the_robot():
    r = robotlib.robot("sim:corridor", seed=0)
    start = r.pose()
    pose, sonar = teleop_widgets.teleop(r, "forward", 0.5)
    assert abs(np.hypot(*(pose[:2] - start[:2])) - 0.5) < 0.05
    assert sonar.shape == (8,)
    pose, _ = teleop_widgets.teleop(r, "left", angle=np.pi / 2)
    assert abs(pose[2] - np.pi / 2) < np.radians(4)
    with pytest.raises(ValueError):
        teleop_widgets.teleop(r, "jump")
    r.disconnect()


def test_teleop_panel_buttons():
    r = robotlib.robot("sim:corridor", seed=0)
    panel = teleop_widgets.TeleopPanel(r, distance=1.0)
    x0 = panel.pose[0]
    panel.buttons["forward"].click()
    assert panel.log == ["forward"]
    assert abs(panel.pose[0] - x0 - 1.0) < 0.06
    panel.distance.value = 0.5
    panel.buttons["back"].click()
    assert abs(panel.pose[0] - x0 - 0.5) < 0.08
    r.disconnect()


def test_teleop_panel_is_busy_while_the_robot_moves(monkeypatch):
    r = robotlib.robot("sim:corridor", seed=0)
    panel = teleop_widgets.TeleopPanel(r, distance=1.0)
    assert panel.status.value.startswith("ready: odometry x")
    seen = []

    def watched(*args):
        seen.append((panel.status.value, [b.disabled for b in panel.buttons.values()]))
        return teleop(*args)

    teleop = teleop_widgets.teleop
    monkeypatch.setattr(teleop_widgets, "teleop", watched)
    panel.buttons["left"].click()
    assert seen == [("turning 45 deg left ...", [True] * 5)]
    assert not any(b.disabled for b in panel.buttons.values())
    assert panel.status.value.startswith("done (turning 45 deg left): odometry x")
    said, shown = panel.status.value, []
    panel.status.observe(lambda c: shown.append(c["new"]), names="value")
    panel.angle.value = 90.0  # a slider: "drawing" at once, then the same report
    assert shown == ["drawing the next step and turns ...", said]
    heading = re.search(r"heading (-?\d+) deg; nearest echo", panel.status.value)
    assert heading and abs(int(heading.group(1)) - 45) <= 4
    r.disconnect()
