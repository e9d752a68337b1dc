"""Attacks of an outsider on a running, secured show (issue: trust on the bus).

One show runs for the module as real processes (router in this process, orchestrator and two
agents supervised, mutual TLS and the generated access control on). Each attack is made with a
real Zenoh session holding one role's certificate, another show's certificate, or none, and
must be refused with the show unaffected; the last test checks that the show still writes.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bus.keys import ShowKeys
from bus.messages import (
    AgentReport,
    CommandReply,
    JobAssignment,
    JobMetrics,
    OperatorCommand,
    SubmitReply,
    SubmitRequest,
    VehicleCommand,
    VehicleStatus,
)
from bus.pubsub import publish
from bus.rpc import NoReplyError, RemoteError, query, query_one
from bus.session import BusSettings, Session, SessionOpenError, open_session
from cli.main import main as skyquill
from cli.showrun import ShowRun, derived_show, snapshot, wait_for_jobs
from showfile import Show, load_show
from trust.pki import identity_files, issue
from trust.settings import client_session_settings, secured, session_settings

pytestmark = [pytest.mark.multiprocess, pytest.mark.slow, pytest.mark.timeout(240)]

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
TIME_SCALE = 6.0


@pytest.fixture(scope="module")
def show_run(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ShowRun]:
    out = tmp_path_factory.mktemp("secured")
    base = load_show(AIRSHOW)
    path, show = derived_show(
        AIRSHOW,
        out,
        time_scale=TIME_SCALE,
        vehicles=base.vehicles[:2],
        policy=base.policy.model_copy(update={"moderation": True}),
    )
    assert show.security.mode == "mtls"
    for name, role in OUTSIDE_CLIENTS.items():  # before the router starts: it admits them
        assert skyquill(["keys", str(path), "--client", name, "--role", role]) == 0
    with ShowRun(path, show, log_dir=out / "logs") as run:
        with run.client() as operator:
            _wait_ready(operator, run.keys)
        yield run


def _wait_ready(session: Session, keys: ShowKeys) -> None:
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:
        try:
            snap = snapshot(session, keys, timeout_s=2.0)
        except (NoReplyError, RemoteError):
            time.sleep(0.2)
            continue
        if all(v.alive and v.state in ("idle", "landed") for v in snap.vehicles):
            return
        time.sleep(0.2)
    raise AssertionError("the show did not become ready")


def as_identity(show: Show, identity: str) -> Session:
    return open_session(session_settings(show, identity), role="client", open_timeout_s=10.0)


OUTSIDE_CLIENTS = {
    "outsider-submitter": "submitter",
    "outsider-watcher": "watcher",
    "press": "watcher",
    "booth": "submitter",
}
"""Issued with ``skyquill keys --client`` before the show starts (name -> role)."""


def as_client(show: Show, name: str) -> Session:
    settings = client_session_settings(show, show.keys_dir / "clients" / name)
    return open_session(settings, role="client", open_timeout_s=10.0)


def _submit(session: Session, key: str, text: str) -> str:
    reply = query_one(session, key, SubmitRequest(text=text), SubmitReply, timeout_s=5)
    assert reply.ok and reply.job_id
    return reply.job_id


def _no_answer(session: Session, key: str, request: object, reply_type: type) -> None:
    """The router dropped the query: no queryable answered it (and nothing happened)."""
    replies = query(session, key, request, reply_type, timeout_s=1.5)  # type: ignore[arg-type]
    assert replies == [], f"{key} answered {replies}"


ROLES_WITHOUT_COMMAND = ("kiosk", "submitter", "watcher", "uav2")


def _session_for(show_run: ShowRun, who: str) -> Session:
    if who in ("kiosk", "uav2", "operator"):
        return as_identity(show_run.show, who)
    return as_client(show_run.show, f"outsider-{who}")


@pytest.mark.parametrize("who", ROLES_WITHOUT_COMMAND)
def test_only_operators_command_vehicles(show_run: ShowRun, who: str) -> None:
    keys = show_run.keys
    with _session_for(show_run, who) as attacker:
        for command in ("estop", "land"):
            _no_answer(
                attacker,
                keys.vehicle_command("uav1"),
                VehicleCommand(command=command),
                CommandReply,
            )
        for command in ("land_all", "pause", "estop"):
            _no_answer(attacker, keys.command, OperatorCommand(command=command), CommandReply)
    with show_run.client() as operator:
        snap = snapshot(operator, keys)
    assert not snap.queue_paused
    assert all(v.state in ("idle", "landed") for v in snap.vehicles), snap.vehicles


@pytest.mark.parametrize("who", ROLES_WITHOUT_COMMAND)
def test_nobody_but_the_operator_moderates(show_run: ShowRun, who: str) -> None:
    keys = show_run.keys
    with show_run.client() as operator:
        job_id = _submit(operator, keys.submit, "A")
        with _session_for(show_run, who) as attacker:
            for command in ("approve", "cancel", "reject"):
                _no_answer(
                    attacker,
                    keys.command,
                    OperatorCommand(command=command, job_id=job_id),
                    CommandReply,
                )
        job = {j.job_id: j for j in snapshot(operator, keys).jobs}[job_id]
        assert job.state == "awaiting_approval"
        reply = query_one(
            operator, keys.command, OperatorCommand(command="reject", job_id=job_id), CommandReply
        )
        assert reply.ok


def test_nobody_assigns_but_the_orchestrator(show_run: ShowRun) -> None:
    """The paused-queue attack: a made-up job sent straight to an agent is never flown."""
    keys = show_run.keys
    made_up = VehicleCommand(command="assign", job=JobAssignment(job_id="jfake", text="X"))
    with show_run.client() as operator:
        _no_answer(operator, keys.vehicle_assign("uav1"), made_up, CommandReply)
        refused = query_one(operator, keys.vehicle_command("uav1"), made_up, CommandReply)
        assert not refused.ok and refused.error is not None
        assert refused.error.code == "forbidden"
        with as_identity(show_run.show, "uav2") as other_vehicle:
            _no_answer(other_vehicle, keys.vehicle_assign("uav1"), made_up, CommandReply)
        time.sleep(0.5)
        uav1 = {v.vehicle_id: v for v in snapshot(operator, keys).vehicles}["uav1"]
    assert uav1.job_id is None and uav1.state in ("idle", "landed")


def test_a_vehicle_reports_only_its_own_jobs(show_run: ShowRun) -> None:
    keys = show_run.keys
    forged = AgentReport(
        vehicle_id="uav1",
        job_id="j-anything",
        event="done",
        metrics=JobMetrics(
            rmse_pen_down_m=0.0, rmse_m=0.0, max_error_m=0.0, iou=1.0, duration_s=1.0
        ),
    )
    with as_identity(show_run.show, "uav2") as uav2:
        _no_answer(uav2, keys.report("uav1"), forged, CommandReply)  # another vehicle's key
        reply = query_one(uav2, keys.report("uav2"), forged, CommandReply)  # names another
        assert not reply.ok and reply.error is not None and reply.error.code == "forbidden"
    with as_identity(show_run.show, "kiosk") as kiosk:
        _no_answer(kiosk, keys.report("uav1"), forged, CommandReply)


def test_no_one_speaks_or_lives_for_a_vehicle(show_run: ShowRun) -> None:
    """Fake status ("idle, claim me"), fake telemetry, fake liveliness tokens: none arrive."""
    keys = show_run.keys
    seen: list[str] = []
    alive: list[str] = []
    with show_run.client() as operator:
        operator.declare_subscriber(
            f"{keys.prefix}/vehicles/**", lambda s: seen.append(str(s.key_expr))
        )
        operator.liveliness().declare_subscriber(
            keys.vehicles_alive_all, lambda s: alive.append(str(s.key_expr)), history=False
        )
        with (
            as_identity(show_run.show, "kiosk") as kiosk,
            as_identity(show_run.show, "uav2") as uav2,
        ):
            for attacker in (kiosk, uav2):
                publish(
                    attacker,
                    keys.vehicle_status("uav1"),
                    VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle"),
                )
                publish(
                    attacker,
                    keys.vehicle_status("ghost"),
                    VehicleStatus(vehicle_id="ghost", kind="quadrotor-brush", state="idle"),
                )
            tokens = [
                kiosk.liveliness().declare_token(keys.vehicle_alive("uav1")),
                uav2.liveliness().declare_token(keys.vehicle_alive("ghost")),
            ]
            time.sleep(1.0)
            for token in tokens:
                token.undeclare()
        assert not any("ghost" in k for k in seen), seen
        snap = snapshot(operator, keys)
    assert "ghost" not in {v.vehicle_id for v in snap.vehicles}
    assert not any("ghost" in k for k in alive)


def test_no_certificate_or_another_shows_certificate_cannot_join(
    show_run: ShowRun, tmp_path: Path
) -> None:
    show = show_run.show
    own = identity_files(show.keys_dir, "operator")
    no_cert = BusSettings(
        router_listen=(),
        connect=secured(show, own, router=False).connect,
        tls={"root_ca_certificate": str(own.ca), "verify_name_on_connect": False},
    )
    with pytest.raises(SessionOpenError):
        open_session(no_cert, role="client", open_timeout_s=1.0).close()
    plain = BusSettings(router_listen=(), connect=show.zenoh.connect)
    with pytest.raises(SessionOpenError):
        open_session(plain, role="client", open_timeout_s=1.0).close()
    foreign = tmp_path / "foreign"
    files = issue(
        foreign, identity_files(foreign, "operator"), show_id="other", hosts=["127.0.0.1"]
    )
    stolen_ca = BusSettings(
        router_listen=(),
        connect=no_cert.connect,
        tls={
            "root_ca_certificate": str(own.ca),  # trusts the right router...
            "connect_certificate": str(files.cert),  # ...but is signed by another CA
            "connect_private_key": str(files.key),
            "enable_mtls": True,
            "verify_name_on_connect": False,
        },
    )
    with pytest.raises(SessionOpenError):
        open_session(stolen_ca, role="client", open_timeout_s=1.0).close()


def test_watcher_sees_the_show_and_the_show_still_writes(show_run: ShowRun) -> None:
    keys = show_run.keys
    with as_client(show_run.show, "press") as watcher:
        assert snapshot(watcher, keys).show_id == show_run.show.show_id
    with as_client(show_run.show, "booth") as submitter:
        job_id = _submit(submitter, keys.submit_as("submitter@booth"), "T")
    with show_run.client() as operator:
        reply = query_one(
            operator, keys.command, OperatorCommand(command="approve", job_id=job_id), CommandReply
        )
        assert reply.ok, reply
        (job,) = wait_for_jobs(operator, keys, [job_id], timeout_s=120.0)
    assert job.state == "done", job
