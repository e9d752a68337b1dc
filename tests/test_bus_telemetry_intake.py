"""The orchestrator's telemetry intake over real loopback Zenoh: ``bus.pubsub.subscribe`` decoding
on Zenoh's thread into ``bus.bridge.LatestByKey``, read by a task that takes as fast as it can
(what ``benchmarks/bench_bus.py`` times)."""

from __future__ import annotations

import asyncio
import time

from bus.bridge import LatestByKey
from bus.keys import ShowKeys
from bus.messages import Telemetry
from bus.pubsub import MessagePublisher
from bus.session import Session, loopback_settings, open_session
from orchestrator.service import subscribe_telemetry

KEYS = ShowKeys("intake-test")
VEHICLES = ("v0", "v1", "v2")
SENT_N = 300
WAIT_S = 10.0  # upper bound for delivery on loopback; never a timing assertion
SEND_PERIOD_S = 0.002
"""Between rounds of samples: 500 Hz per vehicle, ten times a show's telemetry rate. Sent in one
burst instead, Zenoh dropped two thirds of them beside a busy test worker (304 of 900 pushed, a
fresh clone's CI run): a loss under congestion that is Zenoh's, not the intake's."""


def _telemetry(vehicle_id: str, n: float) -> Telemetry:
    """Telemetry numbered ``n`` (in ``t_s``)."""
    return Telemetry(
        vehicle_id=vehicle_id,
        t_s=n,
        state="writing",
        position_m_enu=(0.0, 0.0, 1.0),
        velocity_mps_enu=(0.0, 0.0, 0.0),
    )


class _Counted(LatestByKey[str, Telemetry]):
    """The intake's store, counting what the subscription handed it (Zenoh itself may drop a
    sample under congestion: that loss is not the intake's)."""

    def __init__(self) -> None:
        super().__init__()
        self.pushed = 0
        self.last_pushed: dict[str, float] = {}
        self.stamps: set[float] = set()

    def push(self, key: str, item: Telemetry) -> None:
        self.pushed += 1  # Zenoh calls one subscriber's callbacks one at a time
        self.last_pushed[key] = item.t_s
        self.stamps.add(item.t_s)
        super().push(key, item)


async def _receive(receiver: Session, sender: Session) -> tuple[dict[str, list[float]], _Counted]:
    latest = _Counted()
    sub = subscribe_telemetry(receiver, KEYS, latest)
    pubs = {v: MessagePublisher(sender, KEYS.telemetry(v)) for v in (*VEHICLES, "probe")}
    taken: dict[str, list[float]] = {}

    def keep(changed: dict[str, Telemetry]) -> None:
        for vehicle_id, message in changed.items():
            taken.setdefault(vehicle_id, []).append(message.t_s)

    deadline = time.monotonic() + WAIT_S
    while "probe" not in taken:  # the subscription reaches the router
        assert time.monotonic() < deadline, "the subscription never saw the probe"
        pubs["probe"].put(_telemetry("probe", time.monotonic()))
        await asyncio.sleep(0.05)
        keep(latest.take_nowait())

    async def read() -> None:
        while True:
            keep(await latest.take())

    reader = asyncio.create_task(read())
    for n in range(SENT_N):
        for v in VEHICLES:
            pubs[v].put(_telemetry(v, n))
        if n == SENT_N // 2:  # on v1's key but claiming v0; not JSON; a delete: none is kept
            pubs["v1"].put(_telemetry("v0", 10_000.0))
            sender.put(KEYS.telemetry("v2"), b"{not json")
            sender.delete(KEYS.telemetry("v0"))
        await asyncio.sleep(SEND_PERIOD_S)
    n = SENT_N
    while not all(v in taken and taken[v][-1] >= SENT_N - 1 for v in VEHICLES):
        assert time.monotonic() < deadline + WAIT_S, f"the last samples never came: {taken}"
        await asyncio.sleep(0.1)
        for v in VEHICLES:  # one more round, in case Zenoh dropped a last one
            pubs[v].put(_telemetry(v, n))
        n += 1
    await asyncio.sleep(0.1)  # what is still on its way
    reader.cancel()
    sub.undeclare()  # type: ignore[no-untyped-call]
    keep(latest.take_nowait())
    return taken, latest


def test_intake_keeps_order_per_vehicle_and_accounts_for_every_sample() -> None:
    settings = loopback_settings()
    with (
        open_session(settings, role="router"),
        open_session(settings, role="client") as receiver,
        open_session(settings, role="client") as sender,
    ):
        taken, latest = asyncio.run(_receive(receiver, sender))
    assert set(taken) == {*VEHICLES, "probe"}
    assert 10_000.0 not in latest.stamps  # the sample claiming another vehicle was refused
    for vehicle_id in VEHICLES:
        stamps = taken[vehicle_id]
        assert stamps == sorted(set(stamps)), vehicle_id  # only forward, none twice
        assert stamps[-1] == latest.last_pushed[vehicle_id] >= SENT_N - 1  # the newest kept
    assert sum(map(len, taken.values())) + latest.replaced == latest.pushed  # none lost inside
    assert latest.pushed >= 0.8 * SENT_N * len(VEHICLES)  # and the stream did go through it
