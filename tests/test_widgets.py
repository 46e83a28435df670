"""The notebook panels: thin wrappers over tested functions, driven programmatically."""

from __future__ import annotations

import numpy as np
import pytest

import robotlib
from robotlib import widgets
from robotlib.experiment import drive_route
from robotlib.world import load_world


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
    assert len(panel.figure.axes) == 3
    assert "localized" in panel.status.value


def test_teleop_moves_the_robot():
    r = robotlib.robot("sim:corridor", seed=0)
    start = r.pose()
    pose, sonar = widgets.teleop(r, "forward", 0.5)
    assert abs(np.hypot(*(pose[:2] - start[:2])) - 0.5) < 0.05
    assert sonar.shape == (8,)
    pose, _ = widgets.teleop(r, "left", angle=np.pi / 2)
    assert abs(pose[2] - np.pi / 2) < np.radians(4)
    with pytest.raises(ValueError):
        widgets.teleop(r, "jump")
    r.disconnect()


def test_teleop_panel_buttons():
    r = robotlib.robot("sim:corridor", seed=0)
    panel = widgets.TeleopPanel(r, distance=1.0)
    x0 = panel.pose[0]
    panel.buttons["forward"].click()
    assert panel.log == ["forward"]
    assert abs(panel.pose[0] - x0 - 1.0) < 0.06
    panel.distance.value = 0.5
    panel.buttons["back"].click()
    assert abs(panel.pose[0] - x0 - 0.5) < 0.08
    r.disconnect()
