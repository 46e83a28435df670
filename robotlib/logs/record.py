"""Record any `robotlib.robot.Robot` to an MCAP file with ROS 2 message types.

`record(robot, path)` returns a `Recorder`: a `Robot` that drives the robot
it wraps and writes every poll (odometry, velocity, sonar, stall and motor
flags, the robot's clock, the true pose where the backend has one, a laser
scan where the state carries one) and every motion command to ``path``. The
topics and their types are listed in `robotlib.logs._messages`; a run opens
in Foxglove and in ROS 2 tools (``ros2 bag info``), and `robotlib.logs.replay`
reads it back bit for bit. The file is written with the ``mcap`` library,
the messages encoded by `robotlib.logs._cdr` (the same bytes as
``mcap-ros2-support``'s encoder, a few times faster); ``mcap-ros2-support``
decodes them on reading.

Message times are the robot's own clock (`RobotState.time`, s), so the same
seeded simulator run gives the same file. Chunks are kept small
(`CHUNK_SIZE`): a file cut short loses at most its last chunk.

Imports the robot interface and the robot's constants; never a backend.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
from mcap.writer import Writer

from ..p3dx import SONAR_POSES
from ..robot import Robot, RobotState
from . import _cdr
from . import _messages as m

__all__ = ["Recorder", "record", "CHUNK_SIZE"]

CHUNK_SIZE = 16 * 1024
"""Bytes of messages per MCAP chunk (about two seconds of a Pioneer's polls)."""


class Recorder(Robot):
    """A robot that records itself: wraps ``inner`` and writes ``path``.

    Use it in place of the robot it wraps (`record` makes one). Attributes
    it does not have (``true_pose``, ``body``, ``vel2``, ...) come from the
    wrapped robot. `close` finishes the file; `disconnect` (or leaving a
    ``with`` block) disconnects the robot and finishes the file.

    Parameters
    ----------
    inner : Robot
        The robot to drive and record.
    path : str or pathlib.Path
        The ``.mcap`` file to write (replaced if it exists).
    metadata : dict, optional
        Strings stored as the file's ``robotlib`` metadata record (e.g. the
        world's name, the address, the seed).
    """

    def __init__(self, inner: Robot, path, metadata: dict | None = None):
        super().__init__()
        self.inner = inner
        self.path = Path(path)
        self._file = open(self.path, "wb")  # noqa: SIM115 - closed by close()
        self._writer = Writer(self._file, chunk_size=CHUNK_SIZE)
        self._writer.start(profile="ros2", library="robotlib")
        self._channels = {}
        for topic, kind in m.TOPICS.items():
            sid = self._writer.register_schema(kind, "ros2msg", m.msgdef(kind).encode())
            self._channels[topic] = self._writer.register_channel(topic, "cdr", sid)
        self._label = None
        meta = {"format": "robotlib-run-1", "robot": type(inner).__name__}
        meta.update({str(k): str(v) for k, v in (metadata or {}).items()})
        self._writer.add_metadata("robotlib", meta)
        self._truth = getattr(inner, "true_pose", None)
        self._seq = 0
        self._t = 0.0
        self._cmd_vel = [0.0, 0.0]
        self.polls = 0
        self.finished = False

    def __getattr__(self, name):
        if name == "inner":  # during __init__, before it is set
            raise AttributeError(name)
        return getattr(self.inner, name)

    # -- writing ----------------------------------------------------------
    def _write(self, topic: str, data: bytes, t: float) -> None:
        ns = int(round(t * 1e9))
        self._writer.add_message(
            self._channels[topic], log_time=ns, data=data, publish_time=ns,
            sequence=self._seq,
        )  # fmt: skip
        self._seq += 1

    def write_state(self, st: RobotState, truth=None) -> None:
        """Write one poll's state (and the true pose, if given)."""
        sonar = np.asarray(st.sonar, dtype=float)
        tp = np.full(3, np.nan) if truth is None else np.asarray(truth, float)
        row = np.concatenate(
            [
                [st.time, *np.asarray(st.pose, float)],
                [float(st.velocity[0]), float(st.velocity[1])],
                [float(bool(st.stalled)), float(bool(st.motors_enabled))],
                tp,
                sonar,
            ]
        )
        t = float(st.time)
        self._t = t
        if self._label is None or len(row) != self._label[0]:
            label = m.state_msg(row)["layout"]["dim"][0]["label"]
            self._label = (len(row), label)
        self._write("/robotlib/state", _cdr.encode_state(row, self._label[1]), t)
        self._write("/odom", _cdr.encode_odometry(t, st.pose, st.velocity), t)
        if len(sonar) == len(SONAR_POSES):
            cloud = m.sonar_cloud_msg(t, sonar, SONAR_POSES)
            data = _cdr.encode_cloud(t, cloud["fields"], cloud["data"], len(sonar), 32)
            self._write("/sonar", data, t)
        laser = st.extra.get("laser") if st.extra else None
        if laser is not None:
            lo, hi = st.extra.get("laser_angles", (-math.pi / 2, math.pi / 2))
            rmax = float(st.extra.get("laser_max_range", 80.0))
            self._write("/scan", _cdr.encode_laser(t, laser, lo, hi, rmax), t)
        if truth is not None:
            self._write("/ground_truth", _cdr.encode_pose_stamped(t, "map", tp), t)
        self.polls += 1

    def write_command(self, command: str, value=None) -> None:
        """Write one motion command (SI units), at the last poll's time."""
        text = command if value is None else f"{command} {json.dumps(value)}"
        self._write("/robotlib/command", _cdr.encode_string(text), self._t)
        if command in ("VEL", "RVEL", "STOP"):
            if command == "VEL":
                self._cmd_vel[0] = float(value)
            elif command == "RVEL":
                self._cmd_vel[1] = float(value)
            else:
                self._cmd_vel = [0.0, 0.0]
            self._write("/cmd_vel", _cdr.encode_twist(*self._cmd_vel), self._t)

    # -- the Robot interface ---------------------------------------------
    def _send(self, command: str, value=None) -> None:
        self.inner._send(command, value)
        if not self.finished:
            self.write_command(command, value)

    def _update(self) -> RobotState:
        st = self.inner._poll()
        if not self.finished:
            self.write_state(st, None if self._truth is None else self._truth())
        return st

    def _close(self) -> None:
        try:
            self.inner.disconnect()
        finally:
            self.close()

    def close(self) -> None:
        """Finish the file (summary, index); the robot stays connected."""
        if not self.finished:
            self.finished = True
            try:
                self._writer.finish()
            finally:
                self._file.close()

    @property
    def size(self) -> int:
        """Bytes written so far."""
        return os.path.getsize(self.path)


def record(r: Robot, path, **metadata) -> Recorder:
    """Start recording robot ``r`` to ``path`` (an ``.mcap`` file).

    Parameters
    ----------
    r : Robot
        Any robot: ``robot("sim:...")``, ``robot("tcp://...")``, a serial one.
    path : str or pathlib.Path
        Output file.
    **metadata
        Stored as strings in the file (``world="corridor"``, ``seed=1``...);
        a `robotlib.sim.SimRobot`'s world name is stored by default.

    Returns
    -------
    Recorder
        Drive it as the robot itself.
    """
    sim = getattr(r, "simulator", None)
    if sim is not None and "world" not in metadata:
        name = getattr(sim.world, "name", "")
        source = getattr(sim.world, "source", None)
        metadata["world"] = name or (str(source) if source else "")
    return Recorder(r, path, metadata)
