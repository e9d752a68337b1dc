"""A MAVLink link on the asyncio loop: bytes <-> pymavlink messages, no threads, no polling.

Transports: UDP to a vehicle (``udpout``), UDP listening for a vehicle (``udpin``: we answer the
last peer heard), TCP client, serial (pyserial, read through ``loop.add_reader``). Messages are
MAVLink 2, ``ardupilotmega`` dialect (a superset of ``common``), encoded and decoded by pymavlink.
Every decoded message goes to ``on_message`` on the event loop thread, as it arrives.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from vehicle_agent.backends.mavlink.health import SequenceLoss, seq_of
from vehicle_agent.backends.mavlink.url import LinkAddress, MavlinkUrlError

log = logging.getLogger(__name__)

MessageHandler = Callable[[Any], None]
GCS_SYSTEM_ID = 255
"""Our MAVLink system id (a ground station / companion by convention)."""
COMPANION_COMPONENT_ID = 191
"""MAV_COMP_ID_ONBOARD_COMPUTER."""


class MavlinkLink:
    """One open link; :meth:`send` is synchronous (datagram/stream writes never block the loop)."""

    def __init__(
        self,
        address: LinkAddress,
        on_message: MessageHandler,
        *,
        system_id: int = GCS_SYSTEM_ID,
        component_id: int = COMPANION_COMPONENT_ID,
    ) -> None:
        self.address = address
        self.on_message = on_message
        self.mav = mavlink.MAVLink(None, srcSystem=system_id, srcComponent=component_id)
        """Encoder: build messages with ``link.mav.<name>_encode(...)``."""
        self._parser = mavlink.MAVLink(None)
        self._parser.robust_parsing = True
        self._transport: asyncio.BaseTransport | None = None
        self._serial: Any = None
        self._peer: tuple[str, int] | None = None
        self.bytes_in = 0
        self.bytes_out = 0
        self.messages_in = 0
        self.messages_out = 0
        self.bad_data = 0
        self.losses = SequenceLoss()
        """Messages lost on the link, from the senders' sequence numbers."""

    async def open(self) -> None:
        """Open the transport; raises :class:`MavlinkUrlError` (a BackendError) on failure."""
        loop = asyncio.get_running_loop()
        a = self.address
        try:
            if a.kind == "udpout":
                self._peer = (a.host, a.port)
                self._transport, _ = await loop.create_datagram_endpoint(
                    lambda: _Datagrams(self), remote_addr=(a.host, a.port)
                )
            elif a.kind == "udpin":
                self._transport, _ = await loop.create_datagram_endpoint(
                    lambda: _Datagrams(self), local_addr=(a.host, a.port)
                )
            elif a.kind == "tcp":
                self._transport, _ = await loop.create_connection(
                    lambda: _Stream(self), a.host, a.port
                )
            else:
                self._open_serial(loop)
        except OSError as exc:
            raise MavlinkUrlError(f"cannot open MAVLink link {a}: {exc}") from exc

    def _open_serial(self, loop: asyncio.AbstractEventLoop) -> None:
        try:
            import serial
        except ImportError:
            raise MavlinkUrlError(
                f"serial link {self.address} needs the pyserial package"
            ) from None
        port = serial.Serial(self.address.device, self.address.baud, timeout=0, write_timeout=0)
        self._serial = port
        loop.add_reader(port.fileno(), self._read_serial)

    def _read_serial(self) -> None:
        data = self._serial.read(4096)
        if data:
            self.feed(data)

    def feed(self, data: bytes, peer: tuple[str, int] | None = None) -> None:
        """Bytes from the transport: decode and hand every message to ``on_message``."""
        self.bytes_in += len(data)
        if peer is not None and self.address.kind == "udpin":
            self._peer = peer
        for message in self._parser.parse_buffer(data) or ():
            if message.get_type() == "BAD_DATA":
                self.bad_data += 1
                continue
            self.messages_in += 1
            self.losses.saw(*seq_of(message))
            try:
                self.on_message(message)
            except Exception:  # a bad message must not kill the link
                log.exception("MAVLink handler failed on %s", message.get_type())

    def send(self, message: Any) -> bool:
        """Encode and send one message; False when there is nowhere to send it yet."""
        data = message.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        transport: Any = self._transport
        if self._serial is not None:
            self._serial.write(data)
        elif transport is None or transport.is_closing():
            return False
        elif self.address.kind == "udpout":
            transport.sendto(data)
        elif self.address.kind == "udpin":
            if self._peer is None:
                return False
            transport.sendto(data, self._peer)
        else:
            transport.write(data)
        self.bytes_out += len(data)
        self.messages_out += 1
        return True

    def close(self) -> None:
        """Close the transport; safe to call twice."""
        if self._transport is not None:
            self._transport.close()
            self._transport = None
        if self._serial is not None:
            with contextlib.suppress(Exception):
                asyncio.get_running_loop().remove_reader(self._serial.fileno())
            self._serial.close()
            self._serial = None


class _Datagrams(asyncio.DatagramProtocol):
    def __init__(self, link: MavlinkLink) -> None:
        self.link = link

    def datagram_received(self, data: bytes, addr: tuple[str, int]) -> None:
        self.link.feed(data, addr)

    def error_received(self, exc: Exception) -> None:
        # ICMP port unreachable while the vehicle is not up yet: heartbeats will tell.
        log.debug("MAVLink UDP error on %s: %s", self.link.address, exc)


class _Stream(asyncio.Protocol):
    def __init__(self, link: MavlinkLink) -> None:
        self.link = link

    def data_received(self, data: bytes) -> None:
        self.link.feed(data)

    def connection_lost(self, exc: Exception | None) -> None:
        log.warning("MAVLink TCP link %s closed: %s", self.link.address, exc)
