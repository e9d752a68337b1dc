"""The orchestrator's snapshot asked by a test while the orchestrator may not answer yet.

A starting or restarting orchestrator, or one whose queryable has not yet reached the test's
session, gives no reply (``NoReplyError``): the multi-process tests ask again until the show is
as they need it, here in one place."""

from __future__ import annotations

import time
from collections.abc import Callable

from bus.keys import ShowKeys
from bus.messages import ShowSnapshot
from bus.rpc import NoReplyError
from bus.session import Session
from cli.showrun import snapshot

POLL_S = 0.2


def answering_snapshot(
    session: Session, keys: ShowKeys, *, timeout_s: float = 2.0
) -> ShowSnapshot | None:
    """The orchestrator's view, or None while it does not answer."""
    try:
        return snapshot(session, keys, timeout_s=timeout_s)
    except NoReplyError:
        return None


def snapshot_when(
    session: Session,
    keys: ShowKeys,
    what: str,
    ready: Callable[[ShowSnapshot], bool] | None = None,
    *,
    timeout_s: float = 60.0,
) -> ShowSnapshot:
    """The first snapshot for which ``ready`` holds (None: the first answer), asked until
    ``timeout_s`` has passed; fails naming ``what`` it waited for."""
    deadline = time.monotonic() + timeout_s
    while True:
        shown = answering_snapshot(session, keys)
        if shown is not None and (ready is None or ready(shown)):
            return shown
        assert time.monotonic() < deadline, f"timed out after {timeout_s:.0f} s waiting for {what}"
        time.sleep(POLL_S)


def all_alive(shown: ShowSnapshot) -> bool:
    """Whether the orchestrator knows vehicles and sees every one of them alive."""
    return bool(shown.vehicles) and all(v.alive for v in shown.vehicles)
