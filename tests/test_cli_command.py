"""``skyquill command``: the CLI's action names map onto the bus's operator commands."""

from __future__ import annotations

import argparse
import io
from contextlib import redirect_stdout
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


def test_reject_and_cancel_take_a_client_or_a_selection(monkeypatch: pytest.MonkeyPatch) -> None:
    command, fields = _sent(monkeypatch, "reject", "--client", "flood", "--reason", "junk")
    assert (command, fields["client_id"], fields["reason"]) == ("reject", "flood", "junk")
    command, fields = _sent(monkeypatch, "cancel", "--job", "j1", "--job", "j2")
    assert (command, fields["job_ids"]) == ("cancel", ["j1", "j2"])
    assert OperatorCommand(command=command, **fields).job_ids == ["j1", "j2"]  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["approve", "--client", "flood"], "--job and --client go with reject or cancel"),
        (["reject", "j1", "--client", "flood"], "reject takes one of a job id, --job or --client"),
        (["cancel", "--job", "j1", "--client", "flood"], "one of a job id, --job or --client"),
    ],
)
def test_a_bulk_command_named_badly_is_one_line_and_sends_nothing(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], argv: list[str], said: str
) -> None:
    parser = argparse.ArgumentParser()
    cmd_command.add_arguments(parser)
    monkeypatch.setattr(cmd_command, "send", lambda *a, **k: pytest.fail("sent"))
    assert cmd_command.run(parser.parse_args(["show.yaml", *argv])) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1


def test_one_cli_command_rejects_a_clients_flood_and_prints_one_line(tmp_path: Path) -> None:
    from test_orchestrator_service import RunningOrchestrator, eventually, make_show

    from bus.keys import ShowKeys
    from bus.messages import ShowSnapshot, SubmitReply, SubmitRequest
    from bus.rpc import query, query_one
    from bus.session import BusSettings, free_tcp_endpoint, open_session
    from cli.main import main as skyquill

    ep = free_tcp_endpoint()
    with open_session(BusSettings(router_listen=[ep], connect=[ep]), role="router"):
        path, show = make_show(tmp_path, "flood", ep, policy={"moderation": True})
        keys = ShowKeys(show.show_id)
        bus = BusSettings(router_listen=[], connect=[ep])
        with RunningOrchestrator(show), open_session(bus, role="client") as client:
            eventually(lambda: query(client, keys.snapshot, None, ShowSnapshot, timeout_s=0.5))
            for who in ("flood", "flood", "flood", "kiosk"):
                request = SubmitRequest(text="L", client_id=who)
                assert query_one(client, keys.submit, request, SubmitReply).ok
            out = io.StringIO()
            with redirect_stdout(out):
                assert skyquill(["command", str(path), "reject", "--client", "flood"]) == 0
            assert out.getvalue() == "rejected 3 job(s) of client 'flood'\n"
            snap = query_one(client, keys.snapshot, None, ShowSnapshot)
            states = sorted((j.client_id, j.state) for j in snap.jobs)
            assert states == [("flood", "rejected")] * 3 + [("kiosk", "awaiting_approval")]
