"""``skyquill command``: the CLI's action names map onto the bus's operator commands."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import get_args, get_type_hints

import pytest

from bus.messages import OperatorCommand
from cli import cmd_command


def _sent(monkeypatch: pytest.MonkeyPatch, *argv: str) -> tuple[str, dict[str, object]]:
    parser = argparse.ArgumentParser()
    cmd_command.add_arguments(parser)
    got: list[tuple[str, dict[str, object]]] = []

    def fake_send(show_path: Path, command: str, **fields: object) -> int:
        got.append((command, fields))
        return 0

    monkeypatch.setattr(cmd_command, "send", fake_send)
    assert cmd_command.run(parser.parse_args(["show.yaml", *argv])) == 0
    (sent,) = got
    return sent


@pytest.mark.parametrize("spelling", ["land-all", "land_all"])
def test_land_all_is_accepted_in_both_spellings(
    monkeypatch: pytest.MonkeyPatch, spelling: str
) -> None:
    command, fields = _sent(monkeypatch, spelling, "--reason", "wind")
    assert command == "land_all" and fields["reason"] == "wind"
    assert OperatorCommand(command=command, **fields).command == "land_all"  # type: ignore[arg-type]


def test_every_cli_action_is_a_bus_command(monkeypatch: pytest.MonkeyPatch) -> None:
    bus_commands = set(get_args(get_type_hints(OperatorCommand)["command"]))
    for action in cmd_command.ACTIONS:
        assert action.replace("-", "_") in bus_commands, action
    command, fields = _sent(monkeypatch, "prioritize", "j1", "--priority", "3")
    assert (command, fields["job_id"], fields["priority"]) == ("prioritize", "j1", 3)
