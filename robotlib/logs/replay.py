"""Read a recorded run back, and replay it as a `robotlib.robot.Robot`.

`read_log(path)` reads an MCAP file written by `robotlib.logs.record` (or a
CARMEN log, by its suffix: see `robotlib.logs.carmen`) into a `RecordedRun`:
the polls' states in order, the true poses where recorded, the commands and
the file's metadata. A file cut short or damaged keeps every state before
the bad record, and the run remembers the error (`RecordedRun.error`).

`LogRobot` (``robot("log:run.mcap")``) answers each poll with the next
recorded state, so code that only reads (MCL, mapping) runs on it unchanged;
motion commands raise `ReplayError`; after the last state a poll raises
`EndOfLog`, or the file's `LogError` if it was damaged there.

Imports the robot interface, the CARMEN reader and the errors; never a
backend.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..robot import Robot, RobotState
from . import _cdr
from . import _messages as m
from .carmen import read_carmen_into
from .errors import EndOfLog, LogError, ReplayError

__all__ = [
    "LogError",
    "EndOfLog",
    "ReplayError",
    "RecordedRun",
    "read_log",
    "LogRobot",
]


@dataclass
class RecordedRun:
    """A recorded run, in memory.

    Attributes
    ----------
    path : pathlib.Path
        The file.
    states : list of RobotState
        One per poll, in order.
    truth : list of numpy.ndarray or None
        The true pose ``(x, y, theta)`` at each poll, or None where the
        backend had none.
    commands : list of tuple
        ``(poll, text)``: each motion command and the number of polls
        recorded before it.
    metadata : dict
        The file's ``robotlib`` metadata (strings).
    error : LogError or None
        What stopped the reading early, if anything.
    """

    path: Path
    states: list = field(default_factory=list)
    truth: list = field(default_factory=list)
    commands: list = field(default_factory=list)
    metadata: dict = field(default_factory=dict)
    error: LogError | None = None

    def __len__(self) -> int:
        return len(self.states)

    @property
    def odometry(self) -> np.ndarray:
        """Odometry poses, shape (T, 3), m and rad."""
        return np.array([s.pose for s in self.states]).reshape(-1, 3)

    @property
    def sonar(self) -> np.ndarray:
        """Sonar ranges, shape (T, S), m."""
        return np.array([s.sonar for s in self.states])

    @property
    def times(self) -> np.ndarray:
        """The robot's clock at each poll, shape (T,), s."""
        return np.array([s.time for s in self.states])

    @property
    def true_poses(self) -> np.ndarray:
        """True poses, shape (T, 3) (NaN where none was recorded)."""
        rows = [np.full(3, np.nan) if t is None else t for t in self.truth]
        return np.array(rows).reshape(-1, 3)


def _state_from_row(data, extra: dict) -> tuple[RobotState, np.ndarray | None]:
    n = len(m.STATE_FIELDS)
    row = np.asarray(data, dtype=float)
    if row.shape[0] < n:
        raise ValueError(f"a state row needs {n}+ values, got {row.shape[0]}")
    truth = row[8:11].copy()
    st = RobotState(
        pose=row[1:4].copy(),
        velocity=(float(row[4]), float(row[5])),
        sonar=row[n:].copy(),
        stalled=bool(row[6]),
        time=float(row[0]),
        motors_enabled=bool(row[7]),
        extra=extra,
    )
    return st, (None if np.isnan(truth).all() else truth)


def _read_mcap(run: RecordedRun) -> None:
    from mcap.records import Channel, Message, Metadata, Schema
    from mcap.stream_reader import StreamReader
    from mcap_ros2.decoder import DecoderFactory

    factory = DecoderFactory()
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    decoders: dict[int, object] = {}
    k = 0
    with open(run.path, "rb") as f:
        try:
            for k, rec in enumerate(  # noqa: B007 - k names the bad record
                StreamReader(f, validate_crcs=True).records, 1
            ):
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, Metadata) and rec.name == "robotlib":
                    run.metadata.update(rec.metadata)
                elif isinstance(rec, Message):
                    ch = channels[rec.channel_id]
                    if ch.id not in decoders:
                        decoders[ch.id] = factory.decoder_for(
                            ch.message_encoding, schemas.get(ch.schema_id)
                        )
                    topic = ch.topic
                    if topic == "/robotlib/state":
                        st, truth = _state_from_row(_cdr.decode_state(rec.data), {})
                        run.states.append(st)
                        run.truth.append(truth)
                    elif topic == "/scan" and run.states:
                        msg = decoders[ch.id](rec.data)
                        run.states[-1].extra.update(
                            laser=np.asarray(msg.ranges, dtype=float),
                            laser_angles=(msg.angle_min, msg.angle_max),
                            laser_max_range=msg.range_max,
                        )
                    elif topic == "/robotlib/command":
                        msg = decoders[ch.id](rec.data)
                        run.commands.append((len(run.states), msg.data))
        except Exception as exc:  # noqa: BLE001 - any damage becomes a LogError
            why = str(exc) or "the file ends inside it"
            run.error = LogError(
                f"{run.path}: damaged or truncated at record {k + 1} "
                f"(after {len(run.states)} polls): {type(exc).__name__}: {why}"
            )
    if not run.states and run.error is None and not channels:
        run.error = LogError(f"{run.path}: no recorded run in this file")


def read_log(path) -> RecordedRun:
    """Read a recorded run (``.mcap``, or a CARMEN ``.log``/``.clf``/``.txt``).

    Parameters
    ----------
    path : str or pathlib.Path
        The file.

    Returns
    -------
    RecordedRun
        Everything readable; `RecordedRun.error` says where reading stopped
        if the file is damaged.

    Raises
    ------
    FileNotFoundError
        If there is no such file.
    LogError
        If not a single state could be read.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no recorded run at {path}")
    run = RecordedRun(path)
    if path.suffix.lower() == ".mcap":
        _read_mcap(run)
    else:
        read_carmen_into(run)
    if not run.states:
        raise run.error or LogError(f"{path}: no polls recorded")
    return run


_REFUSED = "{} is a recorded run: it cannot {} (motion commands are refused)"


class LogRobot(Robot):
    """A recorded run behind the `robotlib.robot.Robot` interface.

    Each poll returns the next recorded state; `true_pose` the recorded
    truth at the last poll. Motion commands raise `ReplayError`.

    Parameters
    ----------
    run : RecordedRun or str or pathlib.Path
        The run, or its file.
    """

    def __init__(self, run):
        super().__init__()
        self.run = run if isinstance(run, RecordedRun) else read_log(run)
        self.address = f"log:{self.run.path}"
        self.index = -1

    @classmethod
    def from_address(cls, address: str, **options) -> LogRobot:
        """Open ``"log:PATH"`` (an ``.mcap`` run or a CARMEN log)."""
        if options:
            raise TypeError(f"log: takes no options, got {sorted(options)}")
        return cls(address.split(":", 1)[1])

    @property
    def metadata(self) -> dict:
        """The file's metadata (world, seed, ...)."""
        return self.run.metadata

    @property
    def remaining(self) -> int:
        """Polls left in the run."""
        return len(self.run.states) - 1 - self.index

    def __len__(self) -> int:
        return len(self.run.states)

    def true_pose(self) -> np.ndarray:
        """Return the recorded true pose at the last poll (for evaluation only).

        Raises
        ------
        LookupError
            If this poll has no recorded truth.
        """
        self._latest()
        truth = self.run.truth[self.index]
        if truth is None:
            raise LookupError(f"{self.address}: no true pose at poll {self.index}")
        return truth.copy()

    def _send(self, command: str, value=None) -> None:
        raise ReplayError(_REFUSED.format(self.address, f"execute {command}"))

    def _refuse(self, what: str):
        raise ReplayError(_REFUSED.format(self.address, what))

    def move(self, distance: float) -> None:  # noqa: D102 - refused
        self._refuse(f"move {distance} m")

    def setheading(self, theta: float) -> None:  # noqa: D102 - refused
        self._refuse(f"turn to {theta} rad")

    def setdeltaheading(self, dtheta: float) -> None:  # noqa: D102 - refused
        self._refuse(f"turn by {dtheta} rad")

    def setvel(self, v: float) -> None:  # noqa: D102 - refused
        self._refuse(f"drive at {v} m/s")

    def setrotvel(self, w: float) -> None:  # noqa: D102 - refused
        self._refuse(f"turn at {w} rad/s")

    def stop(self) -> None:  # noqa: D102 - refused
        self._refuse("stop")

    def _update(self) -> RobotState:
        if self.index + 1 >= len(self.run.states):
            if self.run.error is not None:
                raise self.run.error
            raise EndOfLog(
                f"{self.address}: end of the recorded run after "
                f"{len(self.run.states)} polls"
            )
        self.index += 1
        return self.run.states[self.index]

    def _close(self) -> None:
        pass

    def __repr__(self) -> str:
        return f"LogRobot({self.address!r}, {len(self)} polls)"


def command_value(text: str):
    """Split a recorded command ``"MOVE 0.5"`` into ``("MOVE", 0.5)``."""
    name, _, rest = text.partition(" ")
    return name, (json.loads(rest) if rest else None)
