"""`Session`: the Pioneer protocol of one link to one simulated robot, with no I/O.

Bytes in, bytes out: the SYNC handshake, OPEN (which a server may refuse
through ``claim``), commands in SI units applied to a `robotlib.sim.SimBody`,
and the SIP after each simulator step. Garbage, bad checksums and malformed
packets are skipped. `robotlib.pioneer.server` moves these bytes between
sessions and sockets. Imports the protocol's own modules only (the body and
simulator come in as arguments).
"""

from __future__ import annotations

import logging
import time

from .commands import SYNC0, SYNC1, SYNC2, decode_si
from .packets import Packet, PacketDecoder, PacketError, frame
from .sip import (
    ConvFactors,
    default_config,
    encode_config,
    encode_sip,
    encode_sync2_reply,
    factors_for,
    sip_from_si,
)

__all__ = ["Session"]

log = logging.getLogger("robotlib.pioneer.server")

_MOTION = {"MOVE", "HEAD", "DHEAD", "VEL", "RVEL", "VEL2", "SETV", "SETRV", "STOP"}


class Session:
    """The Pioneer protocol of one link to one simulated robot (no I/O).

    Parameters
    ----------
    sim : robotlib.sim.Simulator
        The simulator (for SIM_RESET).
    body : robotlib.sim.SimBody
        The robot this link drives.
    name, robot_class, subclass : str
        What the SYNC2 reply reports.
    config : dict, optional
        The config packet's fields (default: `default_config`).
    watchdog : float
        Stop the robot after this long without a packet from the client, s.
    clock : callable
        Wall-clock time, s (for the watchdog).
    claim : callable, optional
        ``claim(session) -> bool``, asked when the client sends OPEN: whether
        this session may take the robot (the server refuses a second client
        while another one drives it). Default: always.
    """

    def __init__(
        self,
        sim,
        body,
        *,
        name: str = "robotlib",
        robot_class: str = "Pioneer",
        subclass: str = "p3dx",
        config: dict | None = None,
        watchdog: float = 2.0,
        clock=time.monotonic,
        claim=None,
    ):
        self.sim = sim
        self.body = body
        self.ident = (name, robot_class, subclass)
        self.factors: ConvFactors = factors_for(subclass)
        wd = int(watchdog * 1000)
        self.config = default_config(
            **{"name": name, "subtype": subclass, "watchdog": wd, **(config or {})}
        )
        self.watchdog = watchdog
        self.clock = clock
        self.decoder = PacketDecoder()
        self.expect = SYNC0  # next sync id; 3 = synced, waiting for OPEN
        self.open = False
        self.ignored = 0
        self.last_packet = clock()
        self.refused = False
        self.was_open = False
        self._claim = claim
        self._watchdog_fired = False
        self.step_asked = False  # SIM_STEP received since the last SIP
        self.fresh = False  # opened, no SIP sent yet

    def receive(self, data: bytes) -> bytes:
        """Take bytes from the client; return the bytes to send back."""
        out = []
        for pkt in self.decoder.feed(data):
            self.last_packet = self.clock()
            self._watchdog_fired = False
            try:
                out.append(self.handle(pkt.id, pkt.data))
            except (PacketError, ValueError, TypeError) as exc:
                self.ignored += 1
                log.debug("ignored packet 0x%02x: %s", pkt.id, exc)
        return b"".join(out)

    def handle(self, packet_id: int, data: bytes) -> bytes:
        """Act on one packet; return the reply bytes (often none)."""
        if not self.open:
            return self._handle_sync(packet_id, data)
        cmd = decode_si(Packet(packet_id, data), self.factors.vel2_divisor)
        name, value = cmd.name, cmd.value
        if name in _MOTION:
            self.body.command(name, value)
        elif name == "ROTATE":
            self.body.command("RVEL", value)
        elif name in ("SETA", "SETRA"):
            if value != 0:  # an acceleration of 0 would freeze the robot
                self.body.command(name, value)
        elif name == "ESTOP":
            self.body.command("STOP")
        elif name == "ENABLE":
            self.body.enable_motors(bool(value))
        elif name == "SONAR":
            self.body.enable_sonar(bool(value))
        elif name == "SETO":
            self.body.reset_odometry()
        elif name == "CONFIG":
            return encode_config(self.config)
        elif name == "SIM_SET_POSE":
            self.body.set_true_pose(value)
        elif name == "SIM_RESET":
            self.sim.reset()
            for body in self.sim.bodies:  # every client's odometry restarts too
                body.reset_odometry()
        elif name == "CLOSE":
            self.close()
        elif name == "SIM_STEP":
            self.step_asked = True  # a lock-step server steps when all have asked
        # PULSE, OPEN again, HOSTBAUD and unknown commands: nothing to do
        return b""

    def _handle_sync(self, packet_id: int, data: bytes) -> bytes:
        if packet_id == SYNC0 and not data:
            self.expect = SYNC1
            return frame(SYNC0)
        if packet_id == SYNC1 and self.expect == SYNC1 and not data:
            self.expect = SYNC2
            return frame(SYNC1)
        if packet_id == SYNC2 and self.expect == SYNC2 and not data:
            self.expect = 3
            return encode_sync2_reply(*self.ident)
        if packet_id == 1 and self.expect == 3:  # OPEN
            if self._claim is not None and not self._claim(self):
                self.refused = True
                return b""
            self.open = self.was_open = self.fresh = True
            self.body.begin_session()
            return b""
        if packet_id in (SYNC0, SYNC1, SYNC2):
            self.expect = SYNC0  # out of order: start again
        return b""

    @property
    def silent_for(self) -> float:
        """Seconds since the client's last valid packet."""
        return self.clock() - self.last_packet

    def close(self) -> None:
        """End the connection's open state: stop the robot, wait for a new SYNC."""
        if self.open:
            self.body.command("STOP")
        self.open = False
        self.expect = SYNC0

    def tick(self) -> bytes:
        """After a simulator step: the SIP to send (b"" unless open)."""
        self.step_asked = self.fresh = False
        if not self.open:
            return b""
        if not self._watchdog_fired and self.clock() - self.last_packet > self.watchdog:
            self.body.command("STOP")
            self._watchdog_fired = True
        st = self.body.state
        enabled = bool(getattr(self.body, "_sonar_on", True))
        sonar = list(enumerate(st.sonar[:16])) if enabled else []
        sip = sip_from_si(
            st.pose,
            st.velocity[0],
            st.velocity[1],
            sonar,
            stalled=st.stalled,
            motors_enabled=st.motors_enabled,
            sonar_enabled=enabled,
            moving=bool(self.body.moving),
            factors=self.factors,
        )
        return encode_sip(sip)
