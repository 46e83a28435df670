"""The errors of reading and replaying recorded runs.

`LogError` (a damaged file, or not a run), `EndOfLog` (polled past the last
state) and `ReplayError` (a motion command to a recorded robot). Their own
module so that every reader (MCAP, CARMEN) and the replay can raise them
without importing one another. Imports nothing.
"""

from __future__ import annotations

__all__ = ["LogError", "EndOfLog", "ReplayError"]


class LogError(ValueError):
    """A recorded run's file is damaged or not a run; names the file and record."""


class EndOfLog(EOFError):
    """A replayed robot was polled past its last recorded state."""


class ReplayError(RuntimeError):
    """A motion command was sent to a replayed (recorded) robot."""
