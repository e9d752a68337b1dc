"""The kiosk's rate limit holds per client address over real HTTP, whatever the cookies.

Visitors connect from distinct loopback addresses (Linux routes all of 127/8 to loopback); one of
them, 127.0.0.2, is the show's trusted reverse proxy and forwards other clients' addresses in
``X-Forwarded-For``. Refused submissions (an empty body) count like accepted ones, so no
orchestrator is needed: the limit is checked before anything reaches the bus.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from test_kiosk_support import Browser, fresh_address

from bus.session import loopback_settings, open_session
from kiosk.service import serving
from kiosk.settings import KioskSettings

pytestmark = pytest.mark.timeout(60)

RATE = 6
PROXY = "127.0.0.2"


@pytest.fixture(scope="module")
def kiosk() -> Iterator[str]:
    zenoh = loopback_settings()
    settings = KioskSettings(
        show_id="kiosk-rate-test",
        port=0,
        rate_limit_per_minute=RATE,
        trusted_proxies=(PROXY, "10.0.0.0/8"),
        submit_timeout_s=1.0,
    )
    with open_session(zenoh, role="router"), serving(settings, zenoh, role="client") as server:
        yield server.url


def statuses(browsers: list[Browser]) -> list[int]:
    return [b.post("/api/submit", {}).status for b in browsers]


def allowed_then_limited(count: int) -> list[int]:
    """What ``count`` attempts within a minute get: 400 (empty body) up to the limit, then 429."""
    return [400] * min(count, RATE) + [429] * max(0, count - RATE)


def test_fresh_cookies_from_one_address_are_limited(kiosk: str) -> None:
    address = fresh_address()
    visitors = [Browser(kiosk, source=address) for _ in range(20)]
    assert statuses(visitors) == allowed_then_limited(20)
    cookies = {c.value for b in visitors for c in b.cookies if c.name == "skyquill_kiosk"}
    assert len(cookies) == 20  # every request came with (and was given) a cookie of its own
    assert statuses([Browser(kiosk)]) == [400]  # another address is not affected


def test_addresses_forwarded_by_a_trusted_proxy_are_limited_separately(kiosk: str) -> None:
    first = [Browser(kiosk, source=PROXY, forwarded_for="203.0.113.5") for _ in range(8)]
    second = [Browser(kiosk, source=PROXY, forwarded_for="203.0.113.6") for _ in range(3)]
    assert statuses(first) == allowed_then_limited(8)
    assert statuses(second) == allowed_then_limited(3)
    # the client writes the left part of the header: only the right-most untrusted entry counts
    forged = [
        Browser(kiosk, source=PROXY, forwarded_for=f"198.51.100.{n}, 203.0.113.7") for n in range(8)
    ]
    assert statuses(forged) == allowed_then_limited(8)
    # through two trusted proxies (an inner one on 10/8), the client is still found
    chained = [
        Browser(kiosk, source=PROXY, forwarded_for="203.0.113.8, 10.1.2.3") for _ in range(7)
    ]
    assert statuses(chained) == allowed_then_limited(7)


def test_forwarded_for_from_an_untrusted_peer_is_ignored(kiosk: str) -> None:
    address = fresh_address()
    forged = [Browser(kiosk, source=address, forwarded_for=f"192.0.2.{n}") for n in range(1, 11)]
    assert statuses(forged) == allowed_then_limited(10)
    # the forged addresses were never charged: the proxy may still forward one of them
    assert statuses([Browser(kiosk, source=PROXY, forwarded_for="192.0.2.9")]) == [400]
