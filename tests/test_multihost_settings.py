"""A show across hosts: the show file's ``zenoh.hosts``, which endpoints each identity uses,
and the companion routers' identity and rights on real Zenoh routers over mutual TLS (loopback).
"""

from __future__ import annotations

import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import zenoh

from bus.keys import ShowKeys
from bus.session import Session, free_tcp_endpoint, open_session
from cli.supervisor import child_env, show_children, skyquill_argv
from showfile import Show, ShowError, dump_show, load_show
from trust.acl import access_control
from trust.hosts import HostError, check_hosts, endpoints, host_named
from trust.pki import KeysError
from trust.settings import check_keys, ensure_show_keys, identities, session_settings

VENUE = Path(__file__).resolve().parent.parent / "shows" / "venue-multihost.yaml"


def _venue(tmp_path: Path, **zenoh_updates: Any) -> tuple[Path, Show]:
    show = load_show(VENUE)
    storage = show.storage.model_copy(update={"database": tmp_path / "show.sqlite3"})
    security = show.security.model_copy(update={"keys_dir": tmp_path / "keys"})
    z = show.zenoh.model_copy(update=zenoh_updates)
    path = tmp_path / "venue.yaml"
    dump_show(show.model_copy(update={"zenoh": z, "storage": storage, "security": security}), path)
    return path, load_show(path)


def test_each_identity_joins_its_own_hosts_router() -> None:
    show = load_show(VENUE)
    check_hosts(show)
    assert endpoints(show, "uav1").connect == ("tcp/127.0.0.1:7447",)
    assert endpoints(show, "uav1").router_connect == ("tcp/10.77.1.1:7447",)
    assert endpoints(show, "router@rack2").router_connect == ("tcp/10.77.2.1:7447",)
    ground = endpoints(show, "orchestrator")
    assert ground.router_connect == () and "tcp/10.77.2.1:7447" in ground.router_listen
    assert endpoints(show, "watcher") == ground  # outside clients join the ground station
    assert {"router@rack1", "router@rack2"} <= set(identities(show))
    assert [s.name for s in show_children(VENUE, ["uav3"], services=False, host="rack2")] == [
        "router",
        "agent uav3",
    ]


def test_hosts_that_do_not_fit_the_fleet_are_refused_naming_the_field(tmp_path: Path) -> None:
    show = load_show(VENUE)
    rack2 = show.zenoh.hosts["rack2"]
    hosts = {**show.zenoh.hosts, "rack2": rack2.model_copy(update={"vehicles": ("uav9",)})}
    _, wrong = _venue(tmp_path, hosts=hosts)
    with pytest.raises(HostError, match=r"zenoh\.hosts\.rack2\.vehicles: uav9 is not a vehicle"):
        check_hosts(wrong)
    hosts["rack2"] = rack2.model_copy(update={"vehicles": ()})
    _, missing = _venue(tmp_path, hosts=hosts)
    with pytest.raises(HostError, match="no host runs uav3"):
        check_hosts(missing)
    with pytest.raises(HostError, match=r"no host 'rack9' in zenoh.hosts \(ground, rack1, rack2\)"):
        host_named(show, "rack9")
    text = VENUE.read_text(encoding="utf-8").replace("services: true", "services: false")
    (tmp_path / "headless.yaml").write_text(text, encoding="utf-8")
    with pytest.raises(ShowError, match="exactly one host must have services: true"):
        load_show(tmp_path / "headless.yaml")


def test_a_companion_router_may_send_only_what_its_own_vehicles_may() -> None:
    acl = access_control("venue", ["uav1", "uav2", "uav3"], {"router@rack1": ["uav1", "uav2"]})
    rules = {rule["id"]: rule for rule in acl["rules"]}
    (policy,) = [p for p in acl["policies"] if p["subjects"] == ["cn router@rack1"]]
    ingress = [rules[rid] for rid in policy["rules"] if rules[rid]["flows"] == ["ingress"]]
    granted = {(m, key) for rule in ingress for m in rule["messages"] for key in rule["key_exprs"]}
    keys = {key for _, key in granted}
    assert ("put", "skyquill/venue/vehicles/uav2/telemetry") in granted
    assert not [key for key in keys if "uav3" in key or "*" in key]
    assert not [key for m, key in granted if m == "query" and key.endswith("command")]
    assert not [key for key in keys if key.endswith("assign") and ("query", key) in granted]
    assert ("query", "skyquill/venue/orchestrator/report/uav1") in granted  # its vehicles' only


def test_a_companion_host_never_makes_keys_it_names_the_folders_to_copy(tmp_path: Path) -> None:
    _, show = _venue(tmp_path)
    with pytest.raises(
        KeysError, match=r"no valid certificate for router@rack2, uav3: copy ca.pem"
    ):
        check_keys(show, ["router@rack2", "uav3"])
    assert not (tmp_path / "keys").exists()
    ensure_show_keys(show)  # the ground station's `up`
    check_keys(show, ["router@rack2", "uav3"])


@pytest.mark.multiprocess
def test_up_without_host_or_with_an_unknown_one_says_so_in_one_line(tmp_path: Path) -> None:
    path, _ = _venue(tmp_path)
    for extra, expected in (
        ((), "spans hosts ground, rack1, rack2: give --host NAME on each"),
        (("--host", "rack9"), "no host 'rack9' in zenoh.hosts"),
    ):
        done = subprocess.run(
            skyquill_argv("up", str(path), "--headless", *extra),
            env=child_env(),
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert done.returncode == 2 and expected in done.stderr, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1, done.stderr


# --- two real routers over mutual TLS ------------------------------------------------------------


@pytest.fixture
def two_routers(tmp_path: Path) -> Iterator[Show]:
    """The venue on loopback: the ground router and rack1's, linked, each with the same ACL."""
    ground, rack1 = free_tcp_endpoint(), free_tcp_endpoint()
    show = load_show(VENUE)
    hosts = {
        "ground": show.zenoh.hosts["ground"].model_copy(update={"router_listen": (ground,)}),
        "rack1": show.zenoh.hosts["rack1"].model_copy(
            update={"router_listen": (rack1,), "router_connect": (ground,)}
        ),
        "rack2": show.zenoh.hosts["rack2"].model_copy(
            update={"router_listen": (free_tcp_endpoint(),), "router_connect": (ground,)}
        ),
    }
    _, show = _venue(tmp_path, hosts=hosts)
    ensure_show_keys(show)
    check_keys(show, ["router@rack1", "uav1"])
    with (
        open_session(session_settings(show, "router"), role="router"),
        open_session(session_settings(show, "router@rack1"), role="router"),
    ):
        yield show


def _heard(listener: Session, key: str, speaker: Session, said_key: str) -> bool:
    """Whether a put by ``speaker`` on ``said_key`` reaches ``listener``'s subscriber."""
    got = threading.Event()
    subscriber = listener.declare_subscriber(key, lambda _sample: got.set())
    try:
        time.sleep(0.5)  # let the declaration cross both routers
        deadline = time.monotonic() + 2.0
        while not got.is_set() and time.monotonic() < deadline:
            speaker.put(said_key, b"{}")
            got.wait(0.2)
        return got.is_set()
    finally:
        subscriber.undeclare()  # type: ignore[no-untyped-call]


@pytest.mark.multiprocess
def test_vehicles_behind_a_companion_router_reach_the_ground_and_only_as_themselves(
    two_routers: Show,
) -> None:
    show = two_routers
    keys = ShowKeys(show.show_id)
    everything = f"{keys.prefix}/**"
    impostor = session_settings(show, "router@rack1")  # its certificate, straight to the ground
    ground = endpoints(show, "router").router_listen[0].replace("tcp/", "tls/")
    with (
        open_session(session_settings(show, "orchestrator"), role="client") as orchestrator,
        open_session(session_settings(show, "uav1"), role="client") as uav1,
        open_session(impostor, role="client", connect=[ground]) as rack1,
    ):
        assert _heard(orchestrator, everything, uav1, keys.telemetry("uav1"))  # two hops
        assert not _heard(orchestrator, everything, uav1, keys.telemetry("uav3"))
        assert _heard(orchestrator, everything, rack1, keys.telemetry("uav2"))
        assert not _heard(orchestrator, everything, rack1, keys.telemetry("uav3"))
        assert not _heard(orchestrator, everything, rack1, keys.command)
        assert _asked(orchestrator, keys.reports_all, rack1, keys.report("uav1"))
        assert not _asked(orchestrator, keys.reports_all, rack1, keys.report("uav3"))
        assert not _asked(orchestrator, keys.command, rack1, keys.command)


def _asked(server: Session, key: str, asker: Session, asked_key: str) -> bool:
    """Whether a query by ``asker`` on ``asked_key`` reaches ``server``'s queryable."""
    got = threading.Event()

    def answer(query: zenoh.Query) -> None:
        got.set()
        query.reply(query.key_expr, b"{}")

    queryable = server.declare_queryable(key, answer)
    try:
        time.sleep(0.5)
        for _ in range(3):
            list(asker.get(asked_key, timeout=0.5))
            if got.is_set():
                break
        return got.is_set()
    finally:
        queryable.undeclare()  # type: ignore[no-untyped-call]
