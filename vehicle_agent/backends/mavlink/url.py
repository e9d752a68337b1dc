"""Where an autopilot is: the show file's ``mavlink_url`` parsed once (pure).

=============================  =================================================================
``udp:HOST:PORT``              the vehicle listens at HOST:PORT; we send first and it answers us
``udpout:HOST:PORT``           the same (``skyquill sim-mavlink`` prints its vehicles this way,
                               as does a MAVLink router's UDP server endpoint)
``udpin:HOST:PORT``            we listen at HOST:PORT and the vehicle sends to us (PX4 SITL's
                               offboard port 14540, ArduPilot ``--out udp:...``)
``tcp:HOST:PORT``              TCP client (ArduPilot SITL serves MAVLink on tcp 5760)
``serial:DEVICE[:BAUD]``       a serial port, e.g. ``serial:/dev/ttyACM0:921600`` (needs pyserial);
``/dev/...[:BAUD]``            the same without the scheme
=============================  =================================================================

Note for pymavlink users: pymavlink reads a bare ``udp:`` as "listen"; here ``udp:`` means "the
vehicle is there", which is what a show file names. Use ``udpin:`` to listen.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from vehicle_agent.backends.base import BackendError

LinkKind = Literal["udpout", "udpin", "tcp", "serial"]
DEFAULT_BAUD = 57600


class MavlinkUrlError(BackendError):
    """A ``mavlink_url`` that cannot be understood; the message says what is accepted."""


@dataclass(frozen=True)
class LinkAddress:
    """A parsed ``mavlink_url``."""

    kind: LinkKind
    """How to open the link."""
    host: str = ""
    """Host name or address (network kinds)."""
    port: int = 0
    """UDP/TCP port (network kinds)."""
    device: str = ""
    """Serial device path (serial)."""
    baud: int = DEFAULT_BAUD
    """Serial baud rate (serial)."""

    def __str__(self) -> str:
        if self.kind == "serial":
            return f"serial:{self.device}:{self.baud}"
        return f"{self.kind}:{self.host}:{self.port}"


_SCHEMES: dict[str, LinkKind] = {
    "udp": "udpout",
    "udpout": "udpout",
    "udpin": "udpin",
    "tcp": "tcp",
    "serial": "serial",
}


def parse_mavlink_url(url: str) -> LinkAddress:
    """Parse ``url``; raises :class:`MavlinkUrlError` naming the accepted forms."""
    text = url.strip()
    if text.startswith("/dev/") or text.upper().startswith("COM"):
        text = f"serial:{text}"
    scheme, sep, rest = text.partition(":")
    rest = rest.removeprefix("//")
    kind = _SCHEMES.get(scheme.lower()) if sep else None
    if kind is None:
        raise MavlinkUrlError(
            f"mavlink_url {url!r}: expected udp:HOST:PORT, udpin:HOST:PORT, tcp:HOST:PORT or "
            "serial:DEVICE[:BAUD]"
        )
    if kind == "serial":
        device, _, baud = rest.rpartition(":") if rest.count(":") >= 1 else (rest, "", "")
        if not device:
            device, baud = rest, ""
        return LinkAddress(kind, device=device, baud=_number(url, baud or str(DEFAULT_BAUD)))
    host, _, port = rest.rpartition(":")
    if kind == "udpin" and not host:
        host = "0.0.0.0"
    if not host:
        raise MavlinkUrlError(f"mavlink_url {url!r}: missing host, expected {scheme}:HOST:PORT")
    number = _number(url, port)
    if not 0 < number < 65536:
        raise MavlinkUrlError(f"mavlink_url {url!r}: port {number} not in 1..65535")
    return LinkAddress(kind, host=host, port=number)


def _number(url: str, text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise MavlinkUrlError(f"mavlink_url {url!r}: {text!r} is not a number") from None
