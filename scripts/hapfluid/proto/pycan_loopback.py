"""python-can interface for hapfluid's loopback bus (firmware_bridge/protocol.md, section 4.6).

The bus end (haptic-fake-device) listens on a Unix SOCK_SEQPACKET socket and relays every peer's
frames to the other peers; each packet is a kernel `struct can_frame` (16 bytes) or `struct
canfd_frame` (72 bytes). This adapter connects as a peer, so python-can tools (hapfluid.can_monitor,
cantools, your own scripts) see the very bytes a SocketCAN bus would carry:

    bus = can.Bus(interface="hapfluid_loopback", channel="/tmp/hapfluid-left.sock")

python-can finds the interface through the `can.interface` entry point the hapfluid package
declares (scripts/pyproject.toml), so nothing needs registering once the package is installed.
"""
from __future__ import annotations

import select
import socket
import struct
import time

import can

CAN_EFF_FLAG = 0x80000000
CAN_RTR_FLAG = 0x40000000
CAN_ERR_FLAG = 0x20000000
CAN_EFF_MASK = 0x1FFFFFFF
CAN_SFF_MASK = 0x000007FF
CANFD_BRS = 0x01
CANFD_ESI = 0x02
CAN_FRAME = struct.Struct("=IB3x8s")     # struct can_frame
CANFD_FRAME = struct.Struct("=IBB2x64s")  # struct canfd_frame
RECONNECT_PERIOD_S = 0.1  # after the bus went away (the fake device restarted)


def pack(msg: can.Message) -> bytes:
    can_id = msg.arbitration_id & (CAN_EFF_MASK if msg.is_extended_id else CAN_SFF_MASK)
    if msg.is_extended_id:
        can_id |= CAN_EFF_FLAG
    if msg.is_remote_frame:
        can_id |= CAN_RTR_FLAG
    if msg.is_error_frame:
        can_id |= CAN_ERR_FLAG
    data = bytes(msg.data)
    if msg.is_fd:
        flags = (CANFD_BRS if msg.bitrate_switch else 0) | (CANFD_ESI if msg.error_state_indicator else 0)
        return CANFD_FRAME.pack(can_id, len(data), flags, data)
    return CAN_FRAME.pack(can_id, len(data), data)


def unpack(raw: bytes, channel: str) -> can.Message | None:
    if len(raw) == CAN_FRAME.size:
        can_id, length, data = CAN_FRAME.unpack(raw)
        fd, flags = False, 0
    elif len(raw) == CANFD_FRAME.size:
        can_id, length, flags, data = CANFD_FRAME.unpack(raw)
        fd = True
    else:
        return None  # not a CAN frame (an HID/bulk loopback bus): nothing a CAN tool can show
    extended = bool(can_id & CAN_EFF_FLAG)
    return can.Message(timestamp=time.time(), arbitration_id=can_id & (CAN_EFF_MASK if extended else CAN_SFF_MASK),
                       is_extended_id=extended, is_remote_frame=bool(can_id & CAN_RTR_FLAG),
                       is_error_frame=bool(can_id & CAN_ERR_FLAG), is_fd=fd, bitrate_switch=bool(flags & CANFD_BRS),
                       error_state_indicator=bool(flags & CANFD_ESI), dlc=min(length, 64), data=data[:length],
                       channel=channel, check=False)


class LoopbackBus(can.BusABC):
    """A peer on a hapfluid loopback bus. `channel` is the bus socket path."""

    def __init__(self, channel: str, fd: bool = True, **kwargs):
        self.channel_info = f"hapfluid loopback {channel}"
        self._path = str(channel)
        self._sock = None
        try:
            self._connect()
        except OSError as err:
            raise can.CanInterfaceNotImplementedError(
                f"no hapfluid loopback bus at {self._path} ({err}): start haptic-fake-device --address {self._path}"
            ) from err
        self._next_reconnect = 0.0
        super().__init__(channel=channel, **kwargs)

    def _connect(self):
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        try:
            sock.connect(self._path)
        except OSError:
            sock.close()
            raise
        if self._sock is not None:
            self._sock.close()
        self._sock = sock

    def _reconnect(self) -> bool:
        if time.monotonic() < self._next_reconnect:
            return False
        self._next_reconnect = time.monotonic() + RECONNECT_PERIOD_S
        try:
            self._connect()
            return True
        except OSError:
            return False

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        try:
            self._sock.send(pack(msg))
        except OSError as err:
            if not self._reconnect():
                raise can.CanOperationError(f"loopback bus {self._path}: {err}") from err
            self._sock.send(pack(msg))

    def _recv_internal(self, timeout):
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            wait = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([self._sock], [], [], wait)
            if ready:
                try:
                    raw = self._sock.recv(128)
                except OSError:
                    raw = b""
                if not raw:  # the bus closed: it restarts under us; keep trying to rejoin
                    time.sleep(RECONNECT_PERIOD_S)
                    self._reconnect()
                    if deadline is not None and time.monotonic() >= deadline:
                        return None, False
                    continue
                msg = unpack(raw, self._path)
                if msg is not None:
                    return msg, False
                continue
            if deadline is not None and time.monotonic() >= deadline:
                return None, False

    def fileno(self) -> int:
        return self._sock.fileno()

    def shutdown(self) -> None:
        super().shutdown()
        self._sock.close()
