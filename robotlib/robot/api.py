"""The paper's robot API: one `Robot` interface, several backends.

``robot(address)`` opens a robot; the same functions (``move``,
``setheading``, ``setdeltaheading``, ``ismovedone``, ``isheadingdone``,
``readsonar``, ``disconnect``, plus ``setvel``, ``setrotvel``, ``stop`` and
``pose``) drive the in-process simulator (``"sim:corridor"``) or a Pioneer
over its protocol (``"tcp://127.0.0.1:8101"``, ``"serial:///dev/ttyUSB0"``).

Backends are registered in `BACKENDS` by address scheme and imported on
first use, so this module imports no backend: the interface is in
`robotlib.robot.base`.
"""

from __future__ import annotations

import importlib

import numpy as np

from .base import Robot

__all__ = [
    "BACKENDS",
    "robot",
    "move",
    "setheading",
    "setdeltaheading",
    "setvel",
    "setrotvel",
    "stop",
    "ismovedone",
    "isheadingdone",
    "readsonar",
    "pose",
    "disconnect",
]


BACKENDS = {
    "sim": "robotlib.sim:SimRobot",
    "tcp": "robotlib.pioneer.client:PioneerRobot",
    "serial": "robotlib.pioneer.client:PioneerRobot",
    "log": "robotlib.logs:LogRobot",
}
"""Address scheme to backend class (``module:Class``), imported on first use."""


def robot(address: str = "sim:corridor", **options) -> Robot:
    """Open a robot by address.

    Parameters
    ----------
    address : str
        ``"sim:NAME_OR_PATH"`` for the in-process simulator in a shipped world
        or a world file; ``"tcp://HOST:PORT"`` for MobileSim or
        ``robotlib sim-server``; ``"serial:///dev/ttyUSB0"`` for a real
        Pioneer over RS-232; ``"log:run.mcap"`` to replay a recorded run
        (`robotlib.logs`).
    **options
        Passed to the backend's ``from_address`` (e.g. ``seed=1`` for the
        simulator, ``timeout=5.0`` for a Pioneer).

    Returns
    -------
    Robot
    """
    scheme = address.split(":", 1)[0]
    if scheme not in BACKENDS:
        raise ValueError(
            f"unknown robot address {address!r}: expected one of "
            + ", ".join(f"{s}:..." for s in BACKENDS)
        )
    module, cls = BACKENDS[scheme].split(":")
    backend = getattr(importlib.import_module(module), cls)
    return backend.from_address(address, **options)


def move(r: Robot, distance: float) -> None:
    """Drive ``distance`` metres straight ahead; see `Robot.move`."""
    r.move(distance)


def setheading(r: Robot, theta: float) -> None:
    """Turn to absolute heading ``theta`` rad; see `Robot.setheading`."""
    r.setheading(theta)


def setdeltaheading(r: Robot, dtheta: float) -> None:
    """Turn by ``dtheta`` rad; see `Robot.setdeltaheading`."""
    r.setdeltaheading(dtheta)


def setvel(r: Robot, v: float) -> None:
    """Drive at ``v`` m/s; see `Robot.setvel`."""
    r.setvel(v)


def setrotvel(r: Robot, w: float) -> None:
    """Turn at ``w`` rad/s; see `Robot.setrotvel`."""
    r.setrotvel(w)


def stop(r: Robot) -> None:
    """Stop; see `Robot.stop`."""
    r.stop()


def ismovedone(r: Robot) -> bool:
    """Poll once; see `Robot.ismovedone`."""
    return r.ismovedone()


def isheadingdone(r: Robot) -> bool:
    """Poll once; see `Robot.isheadingdone`."""
    return r.isheadingdone()


def readsonar(r: Robot) -> np.ndarray:
    """Poll once; eight ranges in m; see `Robot.readsonar`."""
    return r.readsonar()


def pose(r: Robot) -> np.ndarray:
    """Poll once; odometry pose; see `Robot.pose`."""
    return r.pose()


def disconnect(r: Robot) -> None:
    """Stop and close; see `Robot.disconnect`."""
    r.disconnect()
