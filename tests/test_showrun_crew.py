"""The test and benchmark crew (``cli.showrun.Stagehand``): what it confirms, without a show (the
bus replaced at the two calls it makes)."""

from __future__ import annotations

import time

import pytest

import cli.showrun as showrun
from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    OperatorCommand,
    ShowSnapshot,
    VehicleStateName,
    VehicleSummary,
)


def vehicle(vehicle_id: str, state: VehicleStateName) -> VehicleSummary:
    return VehicleSummary(vehicle_id=vehicle_id, kind="quadrotor-brush", state=state, alive=True)


def test_the_crew_changes_sheets_and_the_batteries_of_vehicles_waiting_for_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A soak at time scale 4 stood still after 10 minutes: all four vehicles waited for a
    battery swap that no one confirmed."""
    shown = ShowSnapshot(
        show_id="s", time_s=0.0, queue_paused=False, jobs=[],
        vehicles=[vehicle("uav1", "battery_swap"), vehicle("uav2", "idle"),
                  vehicle("uav3", "battery_swap")],
        dirty_boards=["b2"],
    )  # fmt: skip
    sent: list[OperatorCommand] = []

    def reply(_session: object, _key: str, command: OperatorCommand, _type: type) -> CommandReply:
        sent.append(command)
        return CommandReply(ok=True)

    monkeypatch.setattr(showrun, "snapshot", lambda *_a, **_k: shown)
    monkeypatch.setattr(showrun, "query_one", reply)
    with showrun.Stagehand(object(), ShowKeys("s"), period_s=0.01) as crew:  # type: ignore[arg-type]
        deadline = time.monotonic() + 5.0
        while len(crew.swapped) < 2 and time.monotonic() < deadline:
            time.sleep(0.01)
    assert crew.replaced[:1] == ["b2"]
    assert crew.swapped[:2] == ["uav1", "uav3"]
    assert {c.command for c in sent} == {"fresh_sheet", "battery_swapped"}
    assert all(c.operator == "stagehand" for c in sent)
    assert not [c for c in sent if c.vehicle_id == "uav2"]
