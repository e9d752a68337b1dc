"""The console's battery: percent and minutes left in the fleet table, a vehicle in
``battery_swap`` shown as such with its reason (and an alert), and ``b`` confirming the swap."""

from __future__ import annotations

from bus.messages import OperatorCommand, ShowSnapshot, VehicleStatus, VehicleSummary
from tui import commands as cmd
from tui.model import ConsoleModel
from tui.settings import ConsoleSettings
from tui.widgets.fleet_table import COLUMNS, row_cells

REASON = "battery swap: 21% left, the next job would leave 19% (reserve 20%)"


def _model(swap: bool) -> ConsoleModel:
    model = ConsoleModel(ConsoleSettings(show_id="t"))
    model.apply(VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle",
                              battery_fraction=0.21, battery_minutes_left=5.4), 1.0)  # fmt: skip
    summary = VehicleSummary(
        vehicle_id="uav1",
        kind="quadrotor-brush",
        state="battery_swap" if swap else "idle",
        alive=True,
        message=REASON if swap else "",
        battery_fraction=0.21,
    )
    model.apply(ShowSnapshot(show_id="t", time_s=1.0, queue_paused=False, jobs=[],
                             vehicles=[summary]), 1.5)  # fmt: skip
    return model


def test_the_battery_column_shows_percent_and_minutes_left() -> None:
    row = _model(swap=False).vehicle_row("uav1", 2.0)
    assert row is not None
    cells = dict(zip((key for key, _ in COLUMNS), row_cells(row), strict=True))
    assert cells["battery"] == ("21% 5m", "yellow")
    assert cells["state"][0] == "idle"


def test_a_vehicle_waiting_for_its_swap_shows_it_with_its_reason_and_b_confirms_it() -> None:
    model = _model(swap=True)
    row = model.vehicle_row("uav1", 2.0)
    assert row is not None and row.state == "battery_swap" and row.message == REASON
    assert row_cells(row)[2][0] == "battery swap"
    (alert,) = model.alerts()
    assert alert.kind == "battery_swap" and alert.message == f"uav1 {REASON}; swap it, then b"
    request = cmd.vehicle_request("battery_swapped", row)
    assert isinstance(request, cmd.Ask)
    assert request.commands == (OperatorCommand(command="battery_swapped", vehicle_id="uav1"),)
    idle = _model(swap=False).vehicle_row("uav1", 2.0)
    refused = cmd.vehicle_request("battery_swapped", idle)
    assert isinstance(refused, cmd.Refusal) and "not waiting for a battery swap" in refused.message
