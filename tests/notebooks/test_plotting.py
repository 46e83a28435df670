import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest

from robotlib import load_world
from robotlib import plotting as rp
from robotlib.sensing import expected_ranges


@pytest.fixture
def ax():
    fig, ax = plt.subplots()
    yield ax
    plt.close(fig)


def test_world_is_drawn_in_metres_with_equal_axes(ax):
    world = load_world("office")
    walls = rp.plot_world(ax, world)
    assert len(walls.get_segments()) == len(world.segments)
    assert ax.get_xlim() == (world.bounds[0], world.bounds[2])
    assert ax.get_aspect() == 1.0
    assert ax.get_xlabel() == "x [m]"


def test_robot_footprint_is_placed_and_turned(ax):
    patch = rp.plot_robot(ax, (2.0, 1.0, np.pi / 2))
    xy = patch.get_xy()
    # Turned 90 degrees: the 0.425 m width lies along x, the length along y.
    assert np.ptp(xy[:, 0]) == pytest.approx(0.425)
    assert np.ptp(xy[:, 1]) == pytest.approx(0.511)
    assert xy[:, 1].max() == pytest.approx(1.0 + 0.210)


def test_sonar_cones_reach_their_readings_and_no_echo_is_faint(ax):
    world = load_world("corridor")
    z = expected_ranges(world, world.start)[0]
    z[3] = 5.0
    cones = rp.plot_sonar(ax, world.start, z)
    # Each cone's outline reaches out to its reading from its sonar.
    x, y, _ = world.start
    for path, r in zip(cones.get_paths(), z, strict=True):
        far = np.hypot(path.vertices[:, 0] - x, path.vertices[:, 1] - y).max()
        assert far == pytest.approx(r, abs=0.2)
    alphas = cones.get_facecolor()[:, 3]
    assert len(alphas) == 8
    assert alphas[3] < alphas[0]


def test_trajectories_and_particles(ax):
    line = rp.plot_trajectory(
        ax, np.array([[0, 0, 0], [1, 1, 0], [2, 1, 0]]), label="true"
    )
    assert line.get_label() == "true"
    np.testing.assert_array_equal(line.get_xdata(), [0, 1, 2])
    particles = load_world("arena").sample_free_poses(50, rng=0)
    dots = rp.plot_particles(ax, particles, weights=np.linspace(0, 1, 50))
    assert dots.get_offsets().shape == (50, 2)
    sizes = dots.get_sizes()
    assert sizes[-1] > sizes[0]


def test_grid_shows_in_world_coordinates(ax):
    grid = load_world("maze").occupancy_grid(0.1)
    image = rp.plot_grid(ax, grid)
    assert image.get_extent() == list(grid.extent)


def test_animation_is_html_with_a_bounded_frame_count():
    fig, ax = plt.subplots()
    drawn = []
    page = rp.animate(fig, drawn.append, 1000, max_frames=12)
    assert "<script" in page.data
    # Thinned to at most 12 frames, first and last kept (each drawn once more
    # at most by matplotlib's initial draw).
    assert set(drawn) <= set(range(1000))
    assert 0 in drawn and 999 in drawn
    assert len(set(drawn)) <= 12
    assert not plt.fignum_exists(fig.number)


def test_animation_counts_its_frames_on_a_progress_bar():
    made = []

    class Bar:
        def __init__(self, total, desc):
            self.n, self.total, self.desc, self.closed = 0, total, desc, False
            made.append(self)

        def update(self, k=1):
            assert not self.closed
            self.n += k
            assert self.n <= self.total

        def close(self):
            self.closed = True

    fig, ax = plt.subplots()
    rp.animate(fig, lambda i: ax.set_title(str(i)), 7, progress=Bar)
    (bar,) = made
    assert (bar.total, bar.n, bar.closed) == (7, 7, True)


def test_animation_shows_its_first_frame_offline():
    """No stylesheet from the web; the image holds frame 0 before any script runs."""
    import base64
    import re

    fig, ax = plt.subplots()
    page = rp.animate(fig, lambda i: ax.plot([0, i], [0, i]), 3).data
    assert "http://" not in page and "https://" not in page
    assert 'class="fa' not in page
    # the buttons' characters: Latin and Geometric Shapes, which DejaVu and
    # Liberation have (the Miscellaneous Technical media symbols showed as boxes)
    buttons = re.findall(r"<button[^>]*>(.*?)</button>", page, re.S)
    assert len(buttons) == 9
    for label in buttons:
        for code in re.findall(r"&#x([0-9A-Fa-f]+);", label):
            assert 0x25A0 <= int(code, 16) <= 0x25FF, label
    src = re.search(r'<img id="_anim_img\w+" src="data:image/png;base64,([^"]+)"', page)
    assert src is not None
    assert base64.b64decode(src.group(1), validate=True)[:4] == b"\x89PNG"
    assert "document.getElementById(img_id)" in page  # waits for the page


def test_an_mcl_run_breaks_the_true_path_at_a_kidnapping():
    """The true path must not draw a straight line from the old place to the new."""
    from matplotlib.figure import Figure

    from robotlib.localization import History
    from robotlib.plotting.mcl import plot_mcl_run
    from robotlib.plotting.style import COLORS

    h = History()
    for k in range(12):  # 0.5 m a step along y = 1, carried to y = 8 before step 6
        h.true_pose.append(np.array([0.5 * k, 1.0 if k < 6 else 8.0, 0.0]))
        h.estimate.append(h.true_pose[-1] + 0.1)
        h.n_particles.append(100)
    world = load_world("corridor")
    for kidnap, longest in ((0, np.hypot(0.5, 7.0)), (6, 0.5)):
        fig = plot_mcl_run(h, world, Figure(), kidnap=kidnap)
        ax_map, ax_err = fig.axes[:2]
        true = [ln for ln in ax_map.get_lines() if ln.get_color() == COLORS["true"]]
        steps = [np.hypot(*np.diff(ln.get_xydata(), axis=0).T) for ln in true]
        assert max(s.max() for s in steps) == pytest.approx(longest, abs=0.01)
        assert sum(map(len, steps)) == 11 - (kidnap > 0)  # every step but the carry
        lines = ax_err.get_lines()
        upright = [ln.get_xdata() for ln in lines if list(ln.get_ydata()) == [0, 1]]
        marks = [x[0] for x in upright if x[0] == x[1]]
        assert marks == ([6.5] if kidnap else [])  # between steps 6 and 7 (1-based)
