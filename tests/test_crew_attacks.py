"""The crew's identity on a running, secured show: what it may send and what it may not.

The show runs as real processes (router with mutual TLS and the generated access control,
orchestrator, two agents), with boards b1 and b2 waiting for a fresh sheet (as stored by an
orchestrator that stopped while they waited); the kiosk serves with both its sessions, the
public's (certificate ``kiosk``) and the crew's (``crew``). The crew's certificate can confirm a
sheet, in its own name, and nothing else; the public's cannot confirm anything.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from test_trust_attacks import _no_answer, _submit, _wait_ready, as_identity

from bus.messages import CommandReply, OperatorCommand, SubmitReply, SubmitRequest, VehicleCommand
from bus.rpc import query_one
from cli.showrun import ShowRun, derived_show, snapshot
from kiosk.service import serving
from kiosk.settings import settings_from_show
from orchestrator.store import JobStore
from showfile import load_show
from trust.settings import session_settings

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
WAITING = ("b1", "b2")
"""Boards waiting for a fresh sheet when the show starts."""


@dataclass
class CrewShow:
    run: ShowRun
    path: Path
    """The show file."""
    url: str
    """The kiosk's public page (the crew's is ``crew`` under it)."""


@pytest.fixture(scope="module")
def crew_show(tmp_path_factory: pytest.TempPathFactory) -> Iterator[CrewShow]:
    out = tmp_path_factory.mktemp("crew")
    base = load_show(AIRSHOW)
    path, show = derived_show(
        AIRSHOW,
        out,
        time_scale=6.0,
        vehicles=base.vehicles[:2],
        policy=base.policy.model_copy(update={"moderation": True}),
    )
    assert show.security.mode == "mtls"
    with JobStore(show.database_path) as store:
        store.save(dirty_boards=WAITING)
    with ShowRun(path, show, log_dir=out / "logs") as run:
        with run.client() as operator:
            _wait_ready(operator, run.keys)
        settings = dataclasses.replace(settings_from_show(show, port=0), host="127.0.0.1")
        with serving(
            settings,
            session_settings(show, "kiosk"),
            role="client",
            crew_zenoh=session_settings(show, "crew"),
        ) as server:
            yield CrewShow(run, path, server.url)


def _as_crew(keys_command: str, session: object, **fields: object) -> CommandReply:
    request = OperatorCommand(**fields)  # type: ignore[arg-type]
    return query_one(session, keys_command, request, CommandReply, timeout_s=5.0)  # type: ignore[arg-type]


def test_the_crew_cannot_moderate_stop_or_submit(crew_show: CrewShow) -> None:
    run = crew_show.run
    keys = run.keys
    with run.client() as operator:
        job_id = _submit(operator, keys.submit, "A")
    with as_identity(run.show, "crew") as crew:
        for fields in (
            {"command": "approve", "job_id": job_id},
            {"command": "cancel", "job_id": job_id},
            {"command": "estop"},
            {"command": "land", "vehicle_id": "uav1"},
            {"command": "land_all"},
            {"command": "pause"},
        ):
            reply = _as_crew(keys.command_as("crew"), crew, **fields)
            assert not reply.ok and reply.error is not None, fields
            assert reply.error.code == "forbidden", reply
        # the operators' key, a vehicle's own key, a submission: the router drops them
        _no_answer(crew, keys.command, OperatorCommand(command="estop"), CommandReply)
        _no_answer(crew, keys.vehicle_command("uav1"), VehicleCommand(command="estop"),
                   CommandReply)  # fmt: skip
        _no_answer(crew, keys.submit_as("crew"), SubmitRequest(text="A"), SubmitReply)
    with run.client() as operator:
        snap = snapshot(operator, keys)
    job = next(j for j in snap.jobs if j.job_id == job_id)
    assert job.state == "awaiting_approval"
    assert not snap.queue_paused
    assert not any(v.held or v.paused for v in snap.vehicles), snap.vehicles
    assert not any(e.message.startswith("crew") for e in snap.events)


def test_the_publics_session_cannot_confirm_for_the_crew(crew_show: CrewShow) -> None:
    keys = crew_show.run.keys
    with as_identity(crew_show.run.show, "kiosk") as public:
        for key in (keys.command_as("crew"), keys.command_as("kiosk"), keys.command):
            _no_answer(public, key, OperatorCommand(command="fresh_sheet", board_id="b2"),
                       CommandReply)  # fmt: skip
    with crew_show.run.client() as operator:
        assert "b2" in snapshot(operator, keys).dirty_boards


def test_the_crew_confirms_a_sheet_in_its_own_name(crew_show: CrewShow) -> None:
    """The identity is the certificate's; a name the sender claims is only written beside it."""
    keys = crew_show.run.keys
    with as_identity(crew_show.run.show, "crew") as crew:
        claimed = {"command": "fresh_sheet", "board_id": "b2", "operator": "operator@alice"}
        reply = _as_crew(keys.command_as("crew"), crew, **claimed)
        assert reply.ok, reply
    with crew_show.run.client() as operator:
        snap = snapshot(operator, keys)
    assert "b2" not in snap.dirty_boards and "b1" in snap.dirty_boards
    said = [e.message for e in snap.events if e.kind == "operator"]
    assert said[-1] == "crew (operator@alice): fresh_sheet b2", said
