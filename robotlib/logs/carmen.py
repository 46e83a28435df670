"""Read the classic CARMEN robot log format into a `robotlib.logs.RecordedRun`.

CARMEN logs (the Radish data sets and many public runs) are text, one
message per line, in metres, radians and seconds; ``#`` starts a comment.
Lines read here:

- ``ODOM x y theta tv rv accel timestamp host logger_timestamp``
- ``FLASER n r1 .. rn x y theta odom_x odom_y odom_theta timestamp host lts``
  (a front laser over 180 degrees; ``RLASER`` the rear one, skipped)
- ``RAWLASER1`` .. ``RAWLASER4``: ``type start_angle fov resolution
  max_range accuracy remission_mode n r1 .. rn m e1 .. em timestamp host lts``
- ``SONAR cone_angle n r1 .. rn ox1 oy1 oth1 .. oxn oyn othn timestamp host lts``
- ``TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta timestamp host lts``

Every laser or sonar line is one poll: the odometry pose (the laser line's
own, else the last ``ODOM``), the last ``ODOM``'s velocities, the last sonar
ranges (none: an empty array) and laser ranges (``state.extra["laser"]``,
with ``"laser_angles"`` and ``"laser_max_range"``), and the last
``TRUEPOS``. A log without sensor lines gives one poll per ``ODOM``. Other
message types are skipped. A malformed line stops the reading there, with a
`LogError` naming the file and line; what came before stays readable. A
``.bz2`` or ``.gz`` log is read as it is compressed (the public logs ship so);
a damaged archive stops the reading the same way.

Imports the robot's state record and the log errors only.
"""

from __future__ import annotations

import bz2
import gzip
import math
from pathlib import Path

import numpy as np

from ..robot import RobotState
from .errors import LogError

__all__ = ["read_carmen_into", "parse_carmen_line"]

_SENSORS = ("FLASER", "RAWLASER1", "RAWLASER2", "RAWLASER3", "RAWLASER4", "SONAR")


def _floats(tokens, what: str) -> list[float]:
    try:
        return [float(t) for t in tokens]
    except ValueError as exc:
        raise ValueError(f"{what}: {exc}") from None


def _count(tokens, i: int, what: str) -> int:
    if i >= len(tokens):
        raise ValueError(f"{what}: missing count")
    n = int(tokens[i])
    if n < 0 or i + 1 + n > len(tokens):
        raise ValueError(f"{what}: {n} values announced, fewer given")
    return n


def parse_carmen_line(line: str) -> tuple[str, dict] | None:
    """Parse one CARMEN line into ``(kind, fields)``; None for other lines.

    Raises
    ------
    ValueError
        If a known message is malformed (too few numbers, bad numbers).
    """
    tokens = line.split()
    if not tokens or tokens[0].startswith("#"):
        return None
    kind = tokens[0]
    if kind == "ODOM":
        v = _floats(tokens[1:8], "ODOM")
        if len(v) < 7:
            raise ValueError("ODOM: needs x y theta tv rv accel timestamp")
        return kind, {"pose": v[0:3], "velocity": (v[3], v[4]), "time": v[6]}
    if kind == "TRUEPOS":
        v = _floats(tokens[1:8], "TRUEPOS")
        if len(v) < 7:
            raise ValueError("TRUEPOS: needs 6 poses' numbers and a timestamp")
        return kind, {"truth": v[0:3], "pose": v[3:6], "time": v[6]}
    if kind == "FLASER":
        n = _count(tokens, 1, kind)
        v = _floats(tokens[2 : 2 + n + 7], kind)
        if len(v) < n + 7:
            raise ValueError("FLASER: needs the ranges, two poses and a timestamp")
        return kind, {
            "laser": v[:n],
            "pose": v[n + 3 : n + 6],
            "time": v[n + 6],
            "angles": (-math.pi / 2, math.pi / 2),
            "max_range": 81.9,
        }
    if kind.startswith("RAWLASER") and kind in _SENSORS:
        head = _floats(tokens[1:7], kind)
        if len(head) < 6:
            raise ValueError(f"{kind}: needs its 7 parameters")
        n = _count(tokens, 8, kind)
        ranges = _floats(tokens[9 : 9 + n], kind)
        k = _count(tokens, 9 + n, kind)
        rest = _floats(tokens[10 + n + k : 11 + n + k], kind)
        if not rest:
            raise ValueError(f"{kind}: missing timestamp")
        start, fov = head[1], head[2]
        return kind, {
            "laser": ranges,
            "time": rest[0],
            "angles": (start, start + fov),
            "max_range": head[4],
        }
    if kind == "SONAR":
        n = _count(tokens, 2, kind)
        v = _floats(tokens[3 : 3 + 4 * n + 1], kind)
        if len(v) < 4 * n + 1:
            raise ValueError("SONAR: needs n ranges, n offsets and a timestamp")
        return kind, {"sonar": v[:n], "time": v[4 * n]}
    return None


def _open_text(path):
    """Open a log as text, through bz2 or gzip by its suffix."""
    path = Path(path)
    opener = {".bz2": bz2.open, ".gz": gzip.open}.get(path.suffix.lower(), open)
    return opener(path, "rt", encoding="utf-8", errors="replace")


def read_carmen_into(run) -> None:
    """Fill a `RecordedRun` (its ``path`` set) from a CARMEN log."""
    odom = {"pose": [0.0, 0.0, 0.0], "velocity": (0.0, 0.0), "time": 0.0}
    sonar = np.zeros(0)
    truth = None
    odoms = []
    has_sensor = False
    run.metadata.setdefault("format", "carmen")
    with _open_text(run.path) as f:
        lines = enumerate(f, 1)
        while True:
            try:
                lineno, line = next(lines, (None, None))
            except (OSError, EOFError) as exc:  # a damaged archive
                run.error = LogError(f"{run.path}: cannot read on ({exc})")
                break
            if line is None:
                break
            try:
                parsed = parse_carmen_line(line)
            except (ValueError, IndexError) as exc:
                run.error = LogError(f"{run.path}, line {lineno}: {exc}")
                break
            if parsed is None:
                continue
            kind, v = parsed
            if kind == "ODOM":
                odom = v
                odoms.append(_state(v["pose"], v["velocity"], sonar, v["time"], {}))
                continue
            if kind == "TRUEPOS":
                truth = np.array(v["truth"], dtype=float)
                continue
            has_sensor = True
            extra = {}
            if "sonar" in v:
                sonar = np.array(v["sonar"], dtype=float)
            if "laser" in v:
                extra = {
                    "laser": np.array(v["laser"], dtype=float),
                    "laser_angles": v["angles"],
                    "laser_max_range": v["max_range"],
                }
            pose = v.get("pose", odom["pose"])
            run.states.append(_state(pose, odom["velocity"], sonar, v["time"], extra))
            run.truth.append(None if truth is None else truth.copy())
    if not has_sensor:
        run.states = odoms
        run.truth = [None] * len(odoms)


def _state(pose, velocity, sonar, t, extra) -> RobotState:
    return RobotState(
        pose=np.array(pose, dtype=float),
        velocity=(float(velocity[0]), float(velocity[1])),
        sonar=np.array(sonar, dtype=float),
        time=float(t),
        extra=extra,
    )
