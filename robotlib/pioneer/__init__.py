"""The Pioneer client/server protocol (ARCOS / P2OS / MobileSim).

- `robotlib.pioneer.packets`: framing, checksum, command arguments.
- `robotlib.pioneer.commands`: command numbers, SI <-> wire for commands.
- `robotlib.pioneer.sip`: the SIP, config packet and SYNC2 reply; conversion
  factors and odometry unwrapping.
- `robotlib.pioneer.transport`: TCP, serial, file descriptor and in-memory
  links, with every timeout in `Timeouts`.
- `robotlib.pioneer.client`: `PioneerRobot`, the paper's API over the link.
- `robotlib.pioneer.session`: `Session`, one link's protocol with no I/O.
- `robotlib.pioneer.server`: `SimServer` and ``robotlib sim-server``.

Submodules are imported on use; this package imports nothing heavy.
"""
