"""The show CA, its certificates, the generated access control and ``skyquill keys``."""

from __future__ import annotations

import json
import logging
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest
import zenoh
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID
from hypothesis import given, settings
from hypothesis import strategies as st

from bus.keys import ShowKeys
from bus.rpc import JSON
from bus.session import SessionOpenError, free_tcp_endpoint, open_session
from cli.main import main
from showfile import Show, ShowError, dump_show, load_show
from showfile.roles import RESERVED_IDS
from trust.acl import access_control
from trust.pki import KeysError, identity_files, is_valid, issue_client
from trust.settings import ensure_show_keys, identities, secured, session_settings

SOLO = Path(__file__).resolve().parents[1] / "shows" / "solo.yaml"
AIRSHOW = Path(__file__).resolve().parents[1] / "shows" / "airshow-2014.yaml"


def _show(tmp_path: Path, source: Path = AIRSHOW, host: str = "127.0.0.1") -> tuple[Path, Show]:
    base = load_show(source)
    endpoint = free_tcp_endpoint().replace("127.0.0.1", host)
    show = base.model_copy(
        update={
            "zenoh": base.zenoh.model_copy(
                update={"router_listen": (endpoint,), "connect": (endpoint,)}
            ),
            "security": base.security.model_copy(update={"keys_dir": tmp_path / "keys"}),
        }
    )
    path = tmp_path / "show.yaml"
    dump_show(show, path)
    return path, load_show(path)


def _common_name(path: Path) -> str:
    cert = x509.load_pem_x509_certificate(path.read_bytes())
    return str(cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value)


def test_keys_are_made_once_private_and_named_after_their_identity(tmp_path: Path) -> None:
    _, show = _show(tmp_path)
    assert ensure_show_keys(show) == ["router", "orchestrator", "kiosk", "operator",
                                      "crew", "uav1", "uav2", "uav3", "uav4"]  # fmt: skip
    assert ensure_show_keys(show) == []  # idempotent: nothing stale
    for identity in identities(show):
        files = identity_files(show.keys_dir, identity)
        assert _common_name(files.cert) == identity
        assert stat.S_IMODE(files.key.stat().st_mode) == 0o600
        assert is_valid(files, ["127.0.0.1"])
    assert stat.S_IMODE((show.keys_dir / "ca.key").stat().st_mode) == 0o600
    other = identity_files(show.keys_dir, "uav1")
    other.key.write_bytes(identity_files(show.keys_dir, "uav2").key.read_bytes())
    assert not is_valid(other)  # a key that is not the certificate's
    assert ensure_show_keys(show) == ["uav1"]


def test_a_new_router_host_reissues_the_certificates(tmp_path: Path) -> None:
    _, show = _show(tmp_path)
    ensure_show_keys(show)
    _, moved = _show(tmp_path, host="127.0.0.2")
    assert "router" in ensure_show_keys(moved)
    assert is_valid(identity_files(moved.keys_dir, "router"), ["127.0.0.2"])


def _rules_of(acl: dict[str, object], common_name: str) -> list[dict[str, object]]:
    policies = {p["subjects"][0]: p["rules"] for p in acl["policies"]}  # type: ignore[attr-defined]
    rules = {r["id"]: r for r in acl["rules"]}  # type: ignore[attr-defined]
    return [rules[r] for r in policies[f"cn {common_name}"]]


def _may(acl: dict[str, object], common_name: str, message: str, key: str) -> bool:
    """Whether an ingress ``message`` on exactly ``key`` is allowed (keys here are literal or
    end in ``/**`` / ``/*``: enough to read the generated rules)."""
    for rule in _rules_of(acl, common_name):
        if "ingress" not in rule["flows"] or message not in rule["messages"]:  # type: ignore[operator]
            continue
        for expr in rule["key_exprs"]:  # type: ignore[attr-defined]
            if expr == key or (expr.endswith("/**") and key.startswith(expr[:-2])):
                return True
            head, _, tail = expr.partition("/*/")
            if tail and key.startswith(head + "/") and key.endswith("/" + tail):
                return True
    return False


def test_access_control_gives_each_identity_only_its_part() -> None:
    clients = {
        "submitter@booth": "submitter",
        "watcher@press": "watcher",
        "operator@al": "operator",
    }
    acl = access_control("s", ["uav1", "uav2"], clients=clients)
    k = ShowKeys("s")
    assert acl["default_permission"] == "deny" and acl["enabled"] is True
    assert _may(acl, "uav1", "put", k.telemetry("uav1"))
    assert not _may(acl, "uav1", "put", k.telemetry("uav2"))
    assert not _may(acl, "uav1", "put", k.job("j1"))
    assert _may(acl, "uav1", "liveliness_token", k.vehicle_alive("uav1"))
    assert not _may(acl, "uav1", "liveliness_token", k.vehicle_alive("uav2"))
    assert _may(acl, "uav1", "query", k.report("uav1"))
    assert not _may(acl, "uav1", "query", k.report("uav2"))
    assert not _may(acl, "uav1", "query", k.command)
    assert _may(acl, "uav1", "query", k.clock) and _may(acl, "uav2", "query", k.clock)
    for identity in ("kiosk", "submitter@booth", "watcher@press", "operator", "crew"):
        assert not _may(acl, identity, "query", k.clock)  # only vehicles measure their clocks
    for identity in ("kiosk", "submitter@booth"):
        assert _may(acl, identity, "query", k.submit_as(identity))  # its own submit key only
        assert not _may(acl, identity, "query", k.submit)
        assert not _may(acl, identity, "query", k.submit_as("operator@al"))
        assert not _may(acl, identity, "query", k.command)
        assert not _may(acl, identity, "query", k.vehicle_command("uav1"))
        assert not _may(acl, identity, "declare_subscriber", k.telemetry("uav1"))
    assert _may(acl, "operator", "query", k.submit) and _may(acl, "operator", "query", k.command)
    for key in (k.submit_as("operator@al"), k.command_as("operator@al")):  # its own keys only:
        assert _may(acl, "operator@al", "query", key)
        assert not _may(acl, "operator", "query", key)
    for key in (k.submit, k.command, k.command_as("operator@bo")):  # the log names who sent it
        assert not _may(acl, "operator@al", "query", key)
    for identity in ("operator", "operator@al"):
        assert _may(acl, identity, "query", k.vehicle_command("uav2"))
        assert not _may(acl, identity, "query", k.vehicle_assign("uav2"))
        assert not _may(acl, identity, "put", k.job("j1"))
    assert _may(acl, "watcher@press", "declare_subscriber", k.telemetry("uav1"))
    assert not _may(acl, "watcher@press", "query", k.command)
    subjects = {name for s in acl["subjects"] for name in s["cert_common_names"]}
    assert not subjects & {"submitter", "watcher"}  # no rule for a role's bare name any more
    assert _may(acl, "orchestrator", "query", k.vehicle_assign("uav2"))
    assert _may(acl, "orchestrator", "put", k.fleet)


vehicle_ids = st.lists(
    st.from_regex(r"[a-z][a-z0-9_-]{0,8}", fullmatch=True).filter(lambda v: v not in RESERVED_IDS),
    min_size=1,
    max_size=6,
    unique=True,
)


@settings(max_examples=50, deadline=None)
@given(vehicle_ids)
def test_a_vehicle_never_sends_under_another_vehicles_keys(ids: list[str]) -> None:
    acl = access_control("show", ids)
    k = ShowKeys("show")
    for vehicle in ids:
        for rule in _rules_of(acl, vehicle):
            if "ingress" not in rule["flows"]:
                continue
            for expr in rule["key_exprs"]:  # type: ignore[attr-defined]
                assert "*" not in expr, expr  # only literal keys
                assert (
                    expr.startswith(f"{k.prefix}/vehicles/{vehicle}/")
                    or expr == k.report(vehicle)
                    or expr == k.orchestrator_alive
                    or expr == k.clock  # a query only: the orchestrator answers it
                ), (vehicle, expr)
    assert len({s["id"] for s in acl["subjects"]}) == len(acl["subjects"])  # type: ignore[union-attr]


def test_a_vehicle_cannot_take_a_role_name(tmp_path: Path) -> None:
    text = SOLO.read_text(encoding="utf-8").replace("{id: uav1,", "{id: kiosk,")
    path = tmp_path / "bad.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ShowError, match=r"bad\.yaml:\d+: vehicles\[0\]\.id: .*reserved"):
        load_show(path)


def test_security_none_warns_and_uses_plain_settings(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    _, show = _show(tmp_path)
    plain = show.model_copy(update={"security": show.security.model_copy(update={"mode": "none"})})
    with caplog.at_level(logging.WARNING):
        settings_ = session_settings(plain, "orchestrator")
    assert settings_ is plain.zenoh
    assert "security: none" in caplog.text
    assert ensure_show_keys(plain) == []


def test_missing_keys_give_a_one_line_hint(tmp_path: Path) -> None:
    _, show = _show(tmp_path)
    with pytest.raises(Exception, match="skyquill keys"):
        session_settings(show, "orchestrator")


@pytest.mark.parametrize("command", [("status",), ("submit", "--text", "L")])
def test_status_and_submit_find_the_keys_from_another_directory(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    command: tuple[str, ...],
) -> None:
    """Issue 31: keys made from the checkout's root (as the README runs ``skyquill keys``) are
    found by a command run elsewhere with the show file's absolute path. Nobody listens (the
    discard port): the command fails to reach the bus, not for want of its keys."""
    root = tmp_path.resolve()
    (root / "shows").mkdir()
    (root / "elsewhere").mkdir()
    text = SOLO.read_text(encoding="utf-8").replace("tcp/127.0.0.1:7448", "tcp/127.0.0.1:9")
    text = text.replace(
        "multicast_scouting: false", "multicast_scouting: false\n  open_timeout_s: 0"
    )
    show = root / "shows" / "solo.yaml"
    show.write_text(text, encoding="utf-8")
    monkeypatch.chdir(root)
    assert main(["keys", "shows/solo.yaml"]) == 0
    assert (root / "out" / "solo" / "keys" / "operator" / "cert.pem").is_file()
    monkeypatch.chdir(root / "elsewhere")
    capsys.readouterr()
    assert main([command[0], str(show), *command[1:], "--timeout", "0.1"]) == 2
    err = capsys.readouterr().err
    assert f"skyquill {command[0]}:" in err and "is missing" not in err, err


def test_cli_issues_a_client_whose_config_file_joins_the_show(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, show = _show(tmp_path)
    assert main(["keys", str(path)]) == 0
    assert main(["keys", str(path), "--client", "press", "--role", "watcher"]) == 0
    out = capsys.readouterr().out
    config_path = show.keys_dir / "clients" / "press" / "zenoh-client.json5"
    assert str(config_path) in out
    assert json.loads(config_path.read_text())["mode"] == "client"
    assert main(["keys", str(path), "--client", "../x"]) == 2
    keys = ShowKeys(show.show_id)
    got: list[bytes] = []
    with (
        open_session(session_settings(show, "router"), role="router"),
        open_session(session_settings(show, "orchestrator"), role="client") as orchestrator,
    ):
        orchestrator.declare_queryable(
            keys.snapshot, lambda q: q.reply(keys.snapshot, b"{}", encoding=JSON)
        )
        orchestrator.declare_queryable(keys.command, lambda q: q.reply(keys.command, b"{}"))
        with zenoh.open(zenoh.Config.from_file(str(config_path))) as outsider:
            deadline = time.monotonic() + 5.0
            while not got and time.monotonic() < deadline:
                got = [r.ok.payload.to_bytes() for r in outsider.get(keys.snapshot) if r.ok]
            refused = list(outsider.get(keys.command, payload=b"{}", timeout=1.0))
        cli = [sys.executable, "-m", "zenoh_cli", "--config", str(config_path), "--mode", "client"]
        answered = subprocess.run(
            [*cli, "get", "--decoder", "json", "-s", keys.snapshot],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert got == [b"{}"]
    assert refused == []
    assert answered.stdout.strip() == "{}", answered.stderr[-500:]


def _usages(path: Path) -> set[x509.ObjectIdentifier]:
    cert = x509.load_pem_x509_certificate(path.read_bytes())
    return set(cert.extensions.get_extension_for_class(x509.ExtendedKeyUsage).value)


CLIENT_AUTH, SERVER_AUTH = ExtendedKeyUsageOID.CLIENT_AUTH, ExtendedKeyUsageOID.SERVER_AUTH


@pytest.mark.timeout(60)
def test_only_the_routers_certificate_can_serve(tmp_path: Path) -> None:
    """A router started with any other certificate of the show (a submitter's) is refused by a
    vehicle's session, name checking on; the real router's certificate is accepted."""
    _, show = _show(tmp_path)
    ensure_show_keys(show)
    submitter = issue_client(show.keys_dir, "booth", "submitter", show_id=show.show_id)
    assert _usages(submitter.cert) == {CLIENT_AUTH}
    assert _usages(identity_files(show.keys_dir, "uav1").cert) == {CLIENT_AUTH}
    assert _usages(identity_files(show.keys_dir, "router").cert) == {SERVER_AUTH, CLIENT_AUTH}
    rogue = secured(show, submitter, router=True)
    with open_session(rogue, role="router"), pytest.raises(SessionOpenError):
        open_session(session_settings(show, "uav1"), role="client", open_timeout_s=2.0)
    with (
        open_session(session_settings(show, "router"), role="router"),
        open_session(session_settings(show, "uav1"), role="client", open_timeout_s=5.0),
    ):
        pass


@pytest.mark.parametrize("old_mark", [None, "certificates by role"])
def test_a_keys_folder_of_an_older_version_is_refused_with_what_to_do(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], old_mark: str | None
) -> None:
    """A CA without today's mark issued certificates that all could serve (no mark), or signed
    outside clients itself, which no router could then refuse at connection: copies of them are
    out of reach, so the folder is refused (never silently kept nor patched)."""
    path, show = _show(tmp_path)
    ensure_show_keys(show)
    ca_path = show.keys_dir / "ca.pem"
    ca = x509.load_pem_x509_certificate(ca_path.read_bytes())
    key = serialization.load_pem_private_key((show.keys_dir / "ca.key").read_bytes(), None)
    assert isinstance(key, ec.EllipticCurvePrivateKey)
    old_name = x509.Name(
        [
            a
            if a.oid != NameOID.ORGANIZATIONAL_UNIT_NAME or old_mark is None
            else x509.NameAttribute(NameOID.ORGANIZATIONAL_UNIT_NAME, old_mark)
            for a in ca.subject
            if a.oid != NameOID.ORGANIZATIONAL_UNIT_NAME or old_mark is not None
        ]
    )
    builder = (
        x509.CertificateBuilder()
        .subject_name(old_name)
        .issuer_name(old_name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(ca.not_valid_before_utc)
        .not_valid_after(ca.not_valid_after_utc)
    )
    for extension in ca.extensions:
        builder = builder.add_extension(extension.value, extension.critical)
    old = builder.sign(key, hashes.SHA256())
    ca_path.write_bytes(old.public_bytes(serialization.Encoding.PEM))
    with pytest.raises(KeysError, match=r"older skyquill.*move the folder away.*skyquill keys"):
        ensure_show_keys(show)
    assert main(["keys", str(path)]) == 1
    said = capsys.readouterr().err
    assert (
        said.count("\n") == 1
        and "could pose as the router or its outside clients could not be shut out" in said
    )
