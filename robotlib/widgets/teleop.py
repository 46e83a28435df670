"""Notebook panel for driving a robot by hand (Lab 0).

`teleop` moves a robot one step and reads its sonar; `TeleopPanel` adds
buttons and a map, which shows where the next step and turns would go (it
redraws when a slider moves), and a status line: what the robot is doing
(the buttons are disabled meanwhile), then its odometry and nearest echo.
The panel runs headless (its callbacks are plain methods), so tests press
its buttons programmatically. Imports the robot API and plotting; never an
estimator.
"""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np

from ..plotting import plot_robot, plot_sonar, plot_world
from ..plotting.style import COLORS, WIDTH, legend_outside

__all__ = ["teleop", "TeleopPanel"]


def teleop(r, command: str, distance: float = 0.5, angle: float = math.pi / 4):
    """Move a robot one step and read its sonar.

    Parameters
    ----------
    r : robotlib.Robot
        The robot.
    command : str
        ``"forward"``, ``"back"``, ``"left"``, ``"right"`` or ``"stop"``.
    distance : float
        Length of a forward or backward step, m.
    angle : float
        Angle of a turn, rad.

    Returns
    -------
    pose : numpy.ndarray, shape (3,)
        Odometry pose after the step, m and rad.
    sonar : numpy.ndarray, shape (8,)
        Sonar ranges after the step, m.
    """
    if command == "forward":
        r.move(distance)
        r.wait_move_done()
    elif command == "back":
        r.move(-distance)
        r.wait_move_done()
    elif command in ("left", "right"):
        r.setdeltaheading(angle if command == "left" else -angle)
        r.wait_heading_done()
    elif command == "stop":
        r.stop()
    else:
        raise ValueError(f"unknown command {command!r}")
    return r.pose(), r.readsonar()


class TeleopPanel:
    """Buttons that drive a robot step by step, with a map of its surroundings.

    Parameters
    ----------
    r : robotlib.Robot
        The robot; a simulated one (``robot("sim:...")``) also shows its
        world and true pose.

    Attributes
    ----------
    pose, sonar : numpy.ndarray
        After the last command.
    log : list of str
        The commands sent.
    """

    COMMANDS = ("forward", "back", "left", "right", "stop")

    def __init__(self, r, distance: float = 0.5, angle_deg: float = 45.0):
        import ipywidgets as w

        self.robot = r
        self.log: list[str] = []
        self.distance = w.FloatSlider(
            value=distance, min=0.1, max=2.0, step=0.1, description="step [m]",
            continuous_update=False,
        )  # fmt: skip
        self.angle = w.FloatSlider(
            value=angle_deg, min=5.0, max=180.0, step=5.0, description="turn [deg]",
            continuous_update=False,
        )  # fmt: skip
        self.distance.observe(lambda _c: self._preview(), names="value")
        self.angle.observe(lambda _c: self._preview(), names="value")
        self.buttons = {c: w.Button(description=c) for c in self.COMMANDS}
        for c, b in self.buttons.items():
            b.on_click(lambda _b, c=c: self.send(c))
        self.output = w.Output()
        self.status = w.Label()
        self.widget = w.VBox(
            [
                w.HBox(list(self.buttons.values())),
                w.HBox([self.distance, self.angle]),
                self.status,
                self.output,
            ]
        )
        self.figure = plt.figure(figsize=(WIDTH, 4.0))
        plt.close(self.figure)
        self.pose, self.sonar = r.pose(), r.readsonar()
        self.status.value = self._report("ready")
        self.draw()

    def send(self, command: str):
        """Run one command (what a button does); return ``(pose, sonar)``.

        The buttons are disabled and the status line says what runs until
        the robot has done it.
        """
        step, turn = self.distance.value, self.angle.value
        doing = {
            "forward": f"moving {step:.1f} m forward",
            "back": f"moving {step:.1f} m back",
            "left": f"turning {turn:.0f} deg left",
            "right": f"turning {turn:.0f} deg right",
            "stop": "stopping",
        }.get(command, command)
        for b in self.buttons.values():
            b.disabled = True
        self.status.value = f"{doing} ..."
        try:
            self.pose, self.sonar = teleop(
                self.robot, command, step, math.radians(turn)
            )
        except BaseException:
            self.status.value = f"{doing}: failed"
            raise
        finally:
            for b in self.buttons.values():
                b.disabled = False
        self.log.append(command)
        self.status.value = self._report(f"done ({doing})")
        self.draw()
        return self.pose, self.sonar

    def _preview(self) -> None:
        """Say at once that a slider moved, then redraw where a step would go."""
        said = self.status.value
        self.status.value = "drawing the next step and turns ..."
        self.draw()
        self.status.value = said

    def _report(self, head: str) -> str:
        x, y, th = (float(v) + 0.0 for v in self.pose)
        k = int(np.argmin(self.sonar))
        return (
            f"{head}: odometry x {x:.2f} m, y {y:.2f} m, heading {math.degrees(th):.0f}"
            f" deg; nearest echo {float(self.sonar[k]):.2f} m (sonar {k})"
        )

    def draw(self) -> None:
        """Redraw the map, the robot and its sonar."""
        from IPython.display import display

        self.figure.clear()
        ax = self.figure.add_subplot()
        true_pose = getattr(self.robot, "true_pose", None)
        shown = np.asarray(true_pose() if true_pose else self.pose)
        sim = getattr(self.robot, "simulator", None)
        if sim is not None:
            plot_world(ax, sim.world)
        plot_sonar(ax, shown, self.sonar)
        plot_robot(ax, shown, label="robot (true pose)")
        x, y, th = (float(v) for v in shown)
        d, turn = float(self.distance.value), math.radians(self.angle.value)
        ax.annotate(
            "", (x + d * math.cos(th), y + d * math.sin(th)), (x, y),
            arrowprops={"arrowstyle": "->", "color": COLORS["path"], "ls": "--"},
        )  # fmt: skip
        ax.plot([], [], "--", color=COLORS["path"], label=f"forward: {d:.1f} m")
        for sign in (1, -1):
            a = th + sign * turn
            ax.plot(
                [x, x + 0.6 * math.cos(a)], [y, y + 0.6 * math.sin(a)], ":",
                color=COLORS["reference"],
            )  # fmt: skip
        ax.plot([], [], ":", color=COLORS["reference"], label=f"turns: {turn:.2f} rad")
        ax.set_xlim(shown[0] - 6, shown[0] + 6)
        ax.set_ylim(shown[1] - 3, shown[1] + 3)
        legend_outside(ax, "right")
        ax.set_title(f"odometry ({self.pose[0]:.2f}, {self.pose[1]:.2f}) m")
        self.output.clear_output(wait=True)
        with self.output:
            display(self.figure)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)
