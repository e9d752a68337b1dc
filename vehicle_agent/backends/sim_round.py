"""One step of a simulated fleet per turn of the event loop, for every vehicle that asked in it.

A fleet host wakes its awake vehicles together (one :class:`vehicle_agent.pacer.SharedTicker`):
their control loops run one after the other in the same turn of the event loop. Each hands its
reference to its live vehicle and awaits :meth:`StepRound.stepped`; the first to ask schedules
the fleet's step, so one call steps them all, then each reads its vehicle back. A vehicle whose
tick comes later is stepped in a later round: every tick is stepped once, whoever shares it.

The step waits two turns, not one: vehicles behind the wall clock run their ticks back to back
(a ``sleep(0)`` between them, :class:`vehicle_agent.pacer.SharedTicker`), three turns a tick
(tick, step, read back). Stepped one turn after the first asks, vehicles whose cycles are a turn
apart never met (a 20-vehicle host stepped about 8 at a time, and paid for splitting its fleet
at every step); waiting a turn more gathers them, and, resumed together after a shared step, they
keep ticking in the same turns from then on.
"""

from __future__ import annotations

import asyncio
from typing import Any

from vehicles.kind import SimulatedFleet, VehicleKind


class StepRound:
    """Steps ``fleet`` once for all the vehicles that await :meth:`stepped` in one turn."""

    def __init__(self, fleet: SimulatedFleet) -> None:
        self.fleet = fleet
        self._waiters: list[asyncio.Future[None]] = []
        self.steps = 0
        """How many times the fleet was stepped (one call each, whatever the vehicles)."""

    async def stepped(self) -> None:
        """Return once the fleet has stepped (with every vehicle given a reference by then)."""
        loop = asyncio.get_running_loop()
        if not self._waiters:
            loop.call_soon(loop.call_soon, self._step)  # two turns (see the module docstring)
        waiter: asyncio.Future[None] = loop.create_future()
        self._waiters.append(waiter)
        await waiter

    def _step(self) -> None:
        waiters, self._waiters = self._waiters, []
        try:
            self.fleet.step()
        except Exception as exc:  # every vehicle of the round hears it (a backend fault)
            for waiter in waiters:
                if not waiter.done():
                    waiter.set_exception(exc)
            return
        self.steps += 1
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(None)


class StepRounds:
    """A fleet host's rounds: one per kind and settings (vehicles of equal settings share one
    world and controller, so one fleet); none for a kind without a fleet."""

    def __init__(self) -> None:
        self._rounds: list[tuple[str, Any, StepRound]] = []

    @property
    def steps(self) -> int:
        """Fleet steps of every round so far: one per control tick when the host's vehicles in
        flight all tick in the same turns (more when their ticks fall apart)."""
        return sum(step_round.steps for _, _, step_round in self._rounds)

    def round_for(self, kind: VehicleKind, settings: Any) -> StepRound | None:
        """The round of vehicles of ``kind`` with ``settings`` (made on first use)."""
        for name, known, step_round in self._rounds:
            if name == kind.name and known == settings:
                return step_round
        fleet = kind.simulated_fleet(settings)
        if fleet is None:
            return None
        step_round = StepRound(fleet)
        self._rounds.append((kind.name, settings, step_round))
        return step_round
