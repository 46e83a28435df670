"""`PioneerRobot`: the paper's robot API over the Pioneer protocol (TCP or serial).

Connecting runs the SYNC handshake, opens the robot, asks for its config
packet, enables the motors and the sonar. A background reader thread decodes
every SIP into the latest `RobotState` (SI units) and sends PULSE when the
client is otherwise quiet. Polls wait for the next SIP, bounded in time; a
dead or silent link raises `LinkTimeout` (or the link's `ConnectionError`)
instead of hanging.
"""

from __future__ import annotations

import threading
import time

import numpy as np

from ..p3dx import CYCLE, SONAR_MAX_RANGE
from ..robot import Robot, RobotState, RobotTimeout
from ..world.geometry import wrap_angle
from .commands import SYNC0, SYNC1, SYNC2, Command, command, encode_si
from .packets import Packet, PacketDecoder, PacketError
from .sip import (
    CONFIG_ID,
    SIP_ID,
    SIP_MOVING_ID,
    Odometry,
    decode_config,
    decode_sip,
    decode_sync2_reply,
    factors_for,
    sip_to_si,
)
from .transport import DEFAULT_TIMEOUTS, Timeouts, Transport, open_transport

__all__ = ["PioneerRobot", "LinkTimeout", "SyncError"]

N_FRONT_SONAR = 8


class LinkTimeout(RobotTimeout, ConnectionError):
    """The robot sent nothing valid for longer than the link timeout."""


class SyncError(ConnectionError):
    """The SYNC handshake did not complete."""


class PioneerRobot(Robot):
    """A Pioneer 3-DX (or MobileSim, or ``robotlib sim-server``) over its protocol.

    Parameters
    ----------
    transport : Transport
        An open byte link (see `robotlib.pioneer.transport`).
    timeouts : Timeouts
        Every time limit of the link.
    request_config : bool
        Ask for the config packet (CONFIG 1) and wait briefly for it.
    enable_motors, sonar : bool
        Send ENABLE 1 and SONAR 1 after opening.
    reset_odometry : bool
        Send SETO after opening, so odometry starts at (0, 0, 0).
    lockstep : bool
        For a lock-step ``robotlib sim-server``: every poll asks for the next
        cycle (``SIM_STEP``) before waiting for its SIP. The server is silent
        between polls, so only a poll's wait counts against the link timeout.

    Attributes
    ----------
    name, robot_class, subclass : str
        From the SYNC2 reply.
    factors : ConvFactors
        The conversion factors chosen from ``subclass``.
    config : dict or None
        The decoded config packet, if one arrived.
    """

    def __init__(
        self,
        transport: Transport,
        *,
        timeouts: Timeouts = DEFAULT_TIMEOUTS,
        request_config: bool = True,
        enable_motors: bool = True,
        sonar: bool = True,
        reset_odometry: bool = False,
        lockstep: bool = False,
    ):
        super().__init__()
        self.transport = transport
        self.timeouts = timeouts
        self.lockstep = bool(lockstep)
        self.config: dict | None = None
        self._decoder = PacketDecoder()
        self._cond = threading.Condition()
        self._error: BaseException | None = None
        self._sips = 0
        self._robot_state: RobotState | None = None
        self._sonar = np.full(16, SONAR_MAX_RANGE)
        self._last_write = time.monotonic()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        try:
            self.name, self.robot_class, self.subclass = self._sync()
            self.factors = factors_for(self.subclass)
            self._odometry = Odometry(self.factors)
            self._write(command(Command.OPEN, 1))
            self._thread = threading.Thread(
                target=self._reader, name=f"pioneer {transport.name}", daemon=True
            )
            self._thread.start()
            if request_config:
                self._write(command(Command.CONFIG, 1))
            if enable_motors:
                self._write(encode_si("ENABLE", True))
            if sonar:
                self._write(encode_si("SONAR", True))
            if reset_odometry:
                self._write(encode_si("SETO"))
            self._state = self._update()
            if request_config:
                self._wait_config()
        except BaseException:
            self._shutdown()
            raise

    @classmethod
    def from_address(
        cls,
        address: str,
        *,
        timeout: float | None = None,
        timeouts: Timeouts | None = None,
        baudrate: int = 9600,
        **options,
    ) -> PioneerRobot:
        """Connect to ``tcp://HOST:PORT``, ``serial:///dev/DEVICE`` or ``serial:URL``.

        Parameters
        ----------
        address : str
        timeout : float, optional
            The link timeout, s: how long a silent robot may stay silent
            before polls raise `LinkTimeout`.
        timeouts : Timeouts, optional
            All time limits (``timeout`` overrides its ``link``).
        baudrate : int
            Serial speed.
        **options
            Passed to `PioneerRobot`.
        """
        t = timeouts or DEFAULT_TIMEOUTS
        if timeout is not None:
            t = Timeouts(**{**t.__dict__, "link": float(timeout)})
        transport = open_transport(address, t, baudrate=baudrate)
        try:
            return cls(transport, timeouts=t, **options)
        except BaseException:
            transport.close()
            raise

    # -- the link ---------------------------------------------------------
    def _write(self, data: bytes) -> None:
        self.transport.write(data)
        self._last_write = time.monotonic()

    def _sync(self) -> tuple[str, str, str]:
        """Run the SYNC0/1/2 handshake; return (name, class, subclass)."""
        t = self.timeouts
        self.transport.reset_input()
        deadline = time.monotonic() + t.sync_total
        step = 0
        while time.monotonic() < deadline:
            self._write(command((SYNC0, SYNC1, SYNC2)[step]))
            reply = self._wait_packet(min(t.sync_reply, deadline - time.monotonic()))
            if reply is None:
                step = 0
            elif reply.id in (SIP_ID, SIP_MOVING_ID):
                # still open from an earlier client: close it and start over
                self._write(command(Command.CLOSE, 1))
                left = max(0.0, deadline - time.monotonic())
                self._drain(min(2 * t.sync_reply, left))
                step = 0
            elif reply.id == step:
                if step == 2:
                    return decode_sync2_reply(reply.data)
                step += 1
            else:
                step = 0
        raise SyncError(
            f"{self.transport.name}: no SYNC handshake within {t.sync_total} s "
            "(is a Pioneer, MobileSim or robotlib sim-server there?)"
        )

    def _wait_packet(self, timeout: float) -> Packet | None:
        deadline = time.monotonic() + max(0.0, timeout)
        while True:
            pending = getattr(self, "_pending", [])
            if pending:
                return pending.pop(0)
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self._pending = self._decoder.feed(self.transport.read(left))

    def _drain(self, duration: float) -> None:
        end = time.monotonic() + duration
        while time.monotonic() < end:
            self.transport.read(max(0.0, min(0.05, end - time.monotonic())))
        self._pending = []
        self._decoder.reset()

    def _reader(self) -> None:
        """Background loop: read, decode, keep the latest state, send PULSE."""
        t = self.timeouts
        last_packet = time.monotonic()
        try:
            for pkt in getattr(self, "_pending", []):
                self._handle(pkt)
            self._pending = []
            while not self._stop.is_set():
                data = self.transport.read(t.poll)
                now = time.monotonic()
                if data:
                    packets = self._decoder.feed(data)
                    for pkt in packets:
                        self._handle(pkt)
                    if packets:
                        last_packet = now
                if not self.lockstep and now - last_packet > t.link:
                    raise LinkTimeout(
                        f"{self.transport.name}: nothing valid from the robot for "
                        f"{now - last_packet:.1f} s (link timeout {t.link} s): "
                        "the robot or the link is dead"
                    )
                if now - self._last_write >= t.pulse:
                    self._write(command(Command.PULSE))
        except BaseException as exc:  # stored, raised on the next poll
            if not self._stop.is_set():
                with self._cond:
                    self._error = exc
                    self._cond.notify_all()

    def _handle(self, pkt: Packet) -> None:
        if pkt.id in (SIP_ID, SIP_MOVING_ID):
            try:
                raw = decode_sip(pkt.data, moving=pkt.id == SIP_MOVING_ID)
            except PacketError:
                return
            si = sip_to_si(raw, self.factors)
            pose = self._odometry.update(si.x_raw, si.y_raw, si.theta)
            if not si.sonar_enabled:
                self._sonar[:] = SONAR_MAX_RANGE  # sonar off: no echo anywhere
            for i, rng in si.sonar.items():
                if 0 <= i < len(self._sonar):
                    self._sonar[i] = min(rng, SONAR_MAX_RANGE)
            with self._cond:
                self._sips += 1
                cycle = (self.config or {}).get("sip_cycle") or CYCLE * 1000
                self._robot_state = RobotState(
                    pose=pose,
                    velocity=(si.v, si.w),
                    sonar=self._sonar[:N_FRONT_SONAR].copy(),
                    stalled=si.stalled,
                    time=self._sips * cycle / 1000.0,
                    motors_enabled=si.motors_enabled,
                    extra={
                        "wheels": (si.left, si.right),
                        "battery": si.battery,
                        "bumpers": si.bumpers,
                        "flags": si.flags,
                        "sonar_enabled": si.sonar_enabled,
                        "sonar_all": self._sonar.copy(),
                        "moving": raw.moving,
                    },
                )
                self._cond.notify_all()
        elif pkt.id == CONFIG_ID:
            try:
                cfg = decode_config(pkt.data)
            except PacketError:
                return
            with self._cond:
                self.config = cfg
                self._cond.notify_all()

    def _wait_config(self) -> None:
        deadline = time.monotonic() + self.timeouts.config
        with self._cond:
            while self.config is None and self._error is None:
                left = deadline - time.monotonic()
                if left <= 0:
                    return
                self._cond.wait(left)

    def _check(self) -> None:
        if self._error is not None:
            raise self._error

    # -- the Robot backend ------------------------------------------------
    def _send(self, command_name: str, value=None) -> None:
        self._check()
        self._write(encode_si(command_name, value, self.factors.vel2_divisor))

    def _update(self) -> RobotState:
        """Wait for the next SIP (at most the link timeout) and return its state."""
        deadline = time.monotonic() + self.timeouts.link
        with self._cond:
            target = self._sips + 1
            if self.lockstep:
                self._write(encode_si("SIM_STEP"))
            while self._sips < target:
                self._check()
                left = deadline - time.monotonic()
                if left <= 0:
                    raise LinkTimeout(
                        f"{self.transport.name}: no SIP from the robot for "
                        f"{self.timeouts.link} s (link timeout): the robot or the "
                        "link is dead"
                    )
                self._cond.wait(left)
            return self._robot_state

    def _close(self) -> None:
        try:
            if self._error is None:
                self._write(encode_si("ENABLE", False))
                self._write(command(Command.CLOSE, 1))
        except ConnectionError:
            pass
        finally:
            self._shutdown()

    def _shutdown(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(self.timeouts.close + self.timeouts.poll)
        self.transport.close()

    # -- more of the protocol ----------------------------------------------
    @property
    def latest(self) -> RobotState | None:
        """The state from the most recent SIP, without waiting (None before one)."""
        with self._cond:
            self._check()
            return self._robot_state

    def vel2(self, left: float, right: float) -> None:
        """Drive the wheels at ``left`` and ``right`` m/s (cancels move and heading)."""
        self._move_start = None
        self._heading_target = None
        self._send("VEL2", (left, right))

    def dhead(self, dtheta: float) -> None:
        """Turn by ``dtheta`` rad from the current heading, with the DHEAD command."""
        self._heading_target = wrap_angle(self._latest().pose[2] + float(dtheta))
        self._send("DHEAD", float(dtheta))

    def enable_motors(self, on: bool = True) -> None:
        """Switch the motors on or off (ENABLE)."""
        self._send("ENABLE", bool(on))

    def sonar_on(self, on: bool = True) -> None:
        """Switch the sonar on or off (SONAR)."""
        self._send("SONAR", bool(on))

    def reset_odometry(self) -> None:
        """Set the robot's odometry to (0, 0, 0) here (SETO)."""
        self._send("SETO")

    def estop(self) -> None:
        """Emergency stop (ESTOP)."""
        self._move_start = None
        self._heading_target = None
        self._send("ESTOP")

    def sim_set_pose(self, x: float, y: float, theta: float) -> None:
        """MobileSim only: move the simulated robot's true pose (m, m, rad)."""
        self._send("SIM_SET_POSE", (x, y, theta))

    def sim_reset(self) -> None:
        """MobileSim only: put the simulated robot back at its start."""
        self._send("SIM_RESET")

    def __repr__(self) -> str:
        return (
            f"PioneerRobot({self.transport.name!r}, name={self.name!r}, "
            f"subclass={self.subclass!r})"
        )
