"""Recorded runs: record any robot to MCAP, replay a run as a robot, read CARMEN.

- `record`, `Recorder`: drive a robot and write every poll and command to an
  MCAP file with ROS 2 message types (`record`; topics in `_messages`)
- `read_log`, `RecordedRun`, `LogRobot` (``robot("log:run.mcap")``),
  `LogError`, `EndOfLog`, `ReplayError`: read a run back and replay it
  (`replay`)
- `parse_carmen_line`: the CARMEN text format, read by `read_log` for
  ``.log``, ``.clf`` and ``.txt`` files (`carmen`)

MCAP through the maintained ``mcap`` and ``mcap-ros2-support`` libraries
(pure Python, no ROS installation). Imports the robot interface and the
robot's constants; never a backend, an estimator or plotting.
"""

from .carmen import parse_carmen_line
from .record import CHUNK_SIZE, Recorder, record
from .replay import (
    EndOfLog,
    LogError,
    LogRobot,
    RecordedRun,
    ReplayError,
    command_value,
    read_log,
)

__all__ = [
    "CHUNK_SIZE",
    "EndOfLog",
    "LogError",
    "LogRobot",
    "RecordedRun",
    "Recorder",
    "ReplayError",
    "command_value",
    "parse_carmen_line",
    "read_log",
    "record",
]
