"""Who is asking, by network address: the peer, or what a trusted proxy says it saw. Pure.

Rate limits hold per client address, since cookies are the client's to drop. Behind a reverse
proxy every request comes from the proxy's address, so the kiosk then reads ``X-Forwarded-For``,
but only when the direct peer is one of the show's ``trusted_proxies``: anyone else could write
that header. Each proxy appends the address it saw, so the header is read from the right, and the
right-most address that is not itself a trusted proxy is the client (everything left of it was
written by the client and may be forged).
"""

from __future__ import annotations

import ipaddress
from collections.abc import Iterable, Sequence

from kiosk.errors import KioskError

IPNetwork = ipaddress.IPv4Network | ipaddress.IPv6Network
IPAddress = ipaddress.IPv4Address | ipaddress.IPv6Address

IPV6_CLIENT_PREFIX = 64
"""An IPv6 client owns a whole /64 (SLAAC, privacy addresses): limited as one address."""


class BadProxySettingError(KioskError, ValueError):
    """A ``trusted_proxies`` entry that is not an address or network."""


def proxy_networks(entries: Iterable[str]) -> tuple[IPNetwork, ...]:
    """Parse ``trusted_proxies`` (``"10.0.0.5"``, ``"10.0.0.0/8"``, ``"::1"``)."""
    networks = []
    for entry in entries:
        try:
            networks.append(ipaddress.ip_network(entry.strip(), strict=False))
        except ValueError:
            raise BadProxySettingError(
                f"kiosk.trusted_proxies: {entry!r} is not an IP address or network"
            ) from None
    return tuple(networks)


def parse_address(text: str) -> IPAddress | None:
    """An address from a header entry (``1.2.3.4``, ``1.2.3.4:5678``, ``[::1]:5678``), or None."""
    text = text.strip()
    if text.startswith("[") and "]" in text:
        text = text[1 : text.index("]")]
    elif text.count(":") == 1:  # IPv4 with a port; a bare IPv6 address has several colons
        text = text.split(":", 1)[0]
    try:
        address = ipaddress.ip_address(text)
    except ValueError:
        return None
    if isinstance(address, ipaddress.IPv6Address) and address.ipv4_mapped is not None:
        return address.ipv4_mapped
    return address


def _trusted(address: IPAddress, proxies: Sequence[IPNetwork]) -> bool:
    return any(address.version == net.version and address in net for net in proxies)


def client_address(peer: str, forwarded_for: Sequence[str], proxies: Sequence[IPNetwork]) -> str:
    """The client's address: ``peer`` itself unless it is a trusted proxy, else the right-most
    untrusted address of the ``X-Forwarded-For`` header lines (``forwarded_for``, in order).

    A malformed entry where the client's address should be ends the search at the last proxy:
    trusted proxies write well-formed addresses, so that entry came from elsewhere.
    """
    peer_address = parse_address(peer)
    if peer_address is None or not proxies or not _trusted(peer_address, proxies):
        return str(peer_address) if peer_address is not None else peer
    client = peer_address
    entries = [part for line in forwarded_for for part in line.split(",") if part.strip()]
    for entry in reversed(entries):
        address = parse_address(entry)
        if address is None:
            break
        client = address
        if not _trusted(address, proxies):
            break
    return str(client)


def rate_key(address: str) -> str:
    """The key an address is rate-limited under: itself, or its /64 for IPv6."""
    parsed = parse_address(address)
    if isinstance(parsed, ipaddress.IPv6Address):
        return str(ipaddress.ip_network(f"{parsed}/{IPV6_CLIENT_PREFIX}", strict=False))
    return str(parsed) if parsed is not None else address
