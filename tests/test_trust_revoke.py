"""Revocation without re-keying (issue 30): ``skyquill keys SHOW --revoke NAME``.

A show runs as real processes (its router is ``skyquill router``, which watches the keys folder's
list of clients), with two outside clients issued by ``skyquill keys --client``: an operator's
laptop and a watcher. The operator is revoked while connected; within 5 s it can do nothing (no
command, no submission, no snapshot, no data on its subscriptions, nothing after reconnecting)
while the watcher and the vehicle go on and the show still writes.
"""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from show_probe import all_alive, snapshot_when
from test_orchestrator_service import make_show

from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    OperatorCommand,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
    VehicleCommand,
)
from bus.rpc import query, query_one
from bus.session import Session, SessionOpenError, free_tcp_endpoint, open_session
from cli.main import main as skyquill
from cli.showrun import ShowRun, Stagehand, derived_show, snapshot, wait_for_jobs
from showfile import SecuritySettings, Show, load_show
from trust.files import IdentityFiles, KeysError
from trust.pki import issue
from trust.settings import client_session_settings, ensure_show_keys, session_settings

AIRSHOW = Path(__file__).resolve().parent.parent / "shows" / "airshow-2014.yaml"
SHUT_OUT_WITHIN_S = 5.0


def _keys_show(tmp_path: Path) -> tuple[Path, Show]:
    return make_show(
        tmp_path,
        "revoke",
        free_tcp_endpoint(),
        security=SecuritySettings(mode="mtls", keys_dir=tmp_path / "keys"),
    )


def test_revoking_is_for_issued_names_and_a_name_issued_again_is_a_new_certificate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, show = _keys_show(tmp_path)
    assert skyquill(["keys", str(path), "--client", "alice", "--role", "operator"]) == 0
    first = (show.keys_dir / "clients" / "alice" / "issuer.pem").read_bytes()
    assert skyquill(["keys", str(path), "--revoke", "bob"]) == 1
    assert "no client 'bob'; the show's clients: alice" in capsys.readouterr().err
    assert skyquill(["keys", str(path), "--revoke", "alice"]) == 0
    assert "revoked client alice (operator)" in capsys.readouterr().out
    assert skyquill(["keys", str(path), "--revoke", "alice"]) == 1
    assert "(revoked already)" in capsys.readouterr().err
    assert skyquill(["keys", str(path), "--client", "alice", "--role", "watcher"]) == 0
    assert (show.keys_dir / "clients" / "alice" / "issuer.pem").read_bytes() != first
    assert skyquill(["keys", str(path), "--revoke", "../x"]) == 2
    folder = sorted(p.name for p in (show.keys_dir / "clients" / "alice").iterdir())
    assert folder == ["ca.pem", "cert.pem", "issuer.pem", "key.pem", "zenoh-client.json5"]
    keys = sorted(str(p.relative_to(show.keys_dir)) for p in show.keys_dir.rglob("*.key"))
    assert keys == ["ca.key"]  # the issuer's key is never written


def _old_client(show: Show, name: str, role: str) -> Path:
    """A client folder as skyquill issued it before clients had names (common name = role)."""
    folder = show.keys_dir / "clients" / name
    files = IdentityFiles(role, folder / "cert.pem", folder / "key.pem", folder / "ca.pem")
    issue(show.keys_dir, files, show_id=show.show_id)
    return folder


def test_client_folders_issued_before_names_are_refused_with_what_to_do(tmp_path: Path) -> None:
    _, show = _keys_show(tmp_path)
    ensure_show_keys(show)
    folder = _old_client(show, "press", "watcher")
    with pytest.raises(KeysError, match=r"issued before clients had names.*--client NAME"):
        client_session_settings(show, folder)


def _router(show: Show) -> Session:
    """The show's router as ``skyquill router`` opens it (again after each change of clients)."""
    return open_session(session_settings(show, "router"), role="router")


def _connects(show: Show, folder: Path, timeout_s: float = 10.0) -> bool:
    try:
        settings = client_session_settings(show, folder)
        with open_session(settings, role="client", open_timeout_s=timeout_s):
            return True
    except SessionOpenError:
        return False


@pytest.mark.timeout(120)
def test_a_revoked_or_replaced_certificate_cannot_even_connect(tmp_path: Path) -> None:
    """Revocation is at connection, not only in the access control: the router no longer
    trusts the client's issuer. The certificate of a name issued again is refused too."""
    path, show = _keys_show(tmp_path)
    assert skyquill(["keys", str(path), "--client", "alice", "--role", "operator"]) == 0
    assert skyquill(["keys", str(path), "--client", "press", "--role", "watcher"]) == 0
    clients = show.keys_dir / "clients"
    shutil.copytree(clients / "alice", tmp_path / "stolen")
    with _router(show):
        assert _connects(show, tmp_path / "stolen")
    assert skyquill(["keys", str(path), "--revoke", "alice"]) == 0
    with _router(show):
        assert not _connects(show, tmp_path / "stolen", timeout_s=2.0)
        assert _connects(show, clients / "press")
    assert skyquill(["keys", str(path), "--client", "alice", "--role", "operator"]) == 0
    with _router(show):
        assert _connects(show, clients / "alice")
        assert not _connects(show, tmp_path / "stolen", timeout_s=2.0)


@pytest.fixture(scope="module")
def show_run(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[ShowRun, Path]]:
    out = tmp_path_factory.mktemp("revoke")
    base = load_show(AIRSHOW)
    path, show = derived_show(AIRSHOW, out, time_scale=6.0, vehicles=base.vehicles[:1])
    for name, role in (("alice", "operator"), ("press", "watcher")):
        assert skyquill(["keys", str(path), "--client", name, "--role", role]) == 0
    with ShowRun(path, show, log_dir=out / "logs") as run, run.client() as operator:
        snapshot_when(operator, run.keys, "the show to become ready", all_alive)
        with Stagehand(operator, run.keys):  # one board, a fresh sheet per character
            yield run, path


def _client(show: Show, name: str) -> Session:
    settings = client_session_settings(show, show.keys_dir / "clients" / name)
    return open_session(settings, role="client", open_timeout_s=10.0)


class Received:
    """Times [s, monotonic] at which a session's subscription got a ``fleet`` sample."""

    def __init__(self, session: Session, keys: ShowKeys) -> None:
        self.times_s: list[float] = []
        self._lock = threading.Lock()
        self.subscriber = session.declare_subscriber(keys.fleet, self._on_sample)

    def _on_sample(self, _: object) -> None:
        with self._lock:
            self.times_s.append(time.monotonic())

    def since(self, start_s: float) -> int:
        with self._lock:
            return sum(1 for t in self.times_s if t > start_s)


def _answers(session: Session, keys: ShowKeys) -> bool:
    return bool(query(session, keys.snapshot, None, ShowSnapshot, timeout_s=0.5))


@pytest.mark.multiprocess
@pytest.mark.slow
@pytest.mark.timeout(240)
def test_a_revoked_operator_is_shut_out_and_the_show_goes_on(
    show_run: tuple[ShowRun, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    run, path = show_run
    keys, show = run.keys, run.show
    alice_key, alice_commands = keys.submit_as("operator@alice"), keys.command_as("operator@alice")
    with _client(show, "alice") as alice, _client(show, "press") as press:
        alice_sees, press_sees = Received(alice, keys), Received(press, keys)
        assert _answers(alice, keys)
        job = query_one(alice, alice_key, SubmitRequest(text="A"), SubmitReply, timeout_s=5.0)
        assert job.ok and job.job_id
        resume = OperatorCommand(command="resume", operator="bob")  # she may say she is bob...
        assert query_one(alice, alice_commands, resume, CommandReply, timeout_s=5.0).ok
        said = [e.message for e in snapshot(alice, keys).events if e.kind == "operator"]
        assert said[-1] == "operator@alice (bob): resume"  # ...the log says whose key it was
        assert query(alice, keys.command, resume, CommandReply, timeout_s=1.0) == []  # console's
        revoked_s = time.monotonic()
        assert skyquill(["keys", str(path), "--revoke", "alice"]) == 0
        while _answers(alice, keys) or not _answers(press, keys):  # not a router gap: press is
            assert time.monotonic() - revoked_s < SHUT_OUT_WITHIN_S, "alice was not shut out"
        shut_out_s = time.monotonic() - revoked_s
        quiet_from_s = time.monotonic() + 0.5
        for command in ("pause", "land_all"):
            refused = OperatorCommand(command=command)
            assert query(alice, alice_commands, refused, CommandReply, timeout_s=1.0) == []
        estop = VehicleCommand(command="estop")
        assert query(alice, keys.vehicle_command("uav1"), estop, CommandReply, timeout_s=1.0) == []
        assert query(alice, alice_key, SubmitRequest(text="B"), SubmitReply, timeout_s=1.0) == []
        time.sleep(2.5)  # the fleet is published every second
        assert alice_sees.since(quiet_from_s) == 0
        assert press_sees.since(quiet_from_s) >= 2
        assert not _connects(show, show.keys_dir / "clients" / "alice", timeout_s=2.0)
    with run.client() as operator:
        snap = snapshot(operator, keys)
        assert not snap.queue_paused and all(v.alive for v in snap.vehicles), snap.vehicles
        reply = query_one(operator, keys.submit, SubmitRequest(text="L"), SubmitReply)
        assert reply.ok and reply.job_id
        done = wait_for_jobs(operator, keys, [job.job_id, reply.job_id], timeout_s=180.0)
    assert [j.state for j in done] == ["done", "done"], done
    with capsys.disabled():
        print(f"\nrevoked operator shut out {shut_out_s:.2f} s after `skyquill keys --revoke`")
