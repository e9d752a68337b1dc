"""The crew's rights, without processes: pairing codes, what the page lists, what the crew's
identity may send (access control and the orchestrator), and the crew's routes over HTTP with a
stand-in for its bus link."""

from __future__ import annotations

import contextlib
import http.cookiejar
import json
import re
import stat
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from bus.bridge import RingChannel
from bus.keys import ShowKeys
from bus.messages import CommandReply, OperatorCommand, ShowSnapshot, VehicleSummary
from kiosk.app import create_app
from kiosk.crew.pairing import (
    CODE_TTL_S,
    PHONE_TTL_S,
    PairingBook,
    PairingError,
    PairingFile,
    new_code,
    shown_code,
)
from kiosk.crew.routes import CrewDesk
from kiosk.crew.tasks import crew_tasks
from kiosk.service import KioskServer
from kiosk.settings import KioskSettings
from orchestrator.operator import refused
from trust.acl import access_control

KEYS = ShowKeys("crew-test")


def test_a_code_pairs_one_phone_once_and_only_in_time() -> None:
    code = new_code()
    book = PairingBook().offered("deck-1", code, now_s=100.0)
    late, name = book.paired(code, "t-late", now_s=100.0 + CODE_TTL_S + 1)
    assert name is None and late == book
    assert book.paired("WRONG-CODE", "t", now_s=101.0)[1] is None
    book, name = book.paired(shown_code(code).lower(), "token-1", now_s=101.0)  # as typed
    assert name == "deck-1"
    assert book.paired(code, "token-2", now_s=102.0)[1] is None  # used up
    assert book.holder("token-1", 200.0) == "deck-1"
    assert book.holder("token-2", 200.0) is None
    assert book.holder("token-1", 101.0 + PHONE_TTL_S + 1) is None  # a show day, then a new code
    book, gone = book.unpaired("deck-1")
    assert gone == 1 and book.holder("token-1", 200.0) is None


def test_a_new_code_withdraws_the_old_one_and_names_are_plain() -> None:
    book = PairingBook().offered("deck-1", "AAAA2222", 0.0).offered("deck-1", "BBBB3333", 1.0)
    assert book.paired("AAAA2222", "t", 2.0)[1] is None
    assert book.paired("BBBB3333", "t", 2.0)[1] == "deck-1"
    with pytest.raises(PairingError):
        PairingBook().offered("<b>deck</b>", "CCCC4444", 0.0)


def test_the_file_keeps_hashes_only_and_is_private(tmp_path: Path) -> None:
    phones = PairingFile(tmp_path / "crew-phones.json")
    phones.change(lambda book: (book.offered("deck-1", "ABCD2345", 0.0), None))
    assert phones.change(lambda book: book.paired("ABCD-2345", "secret-token", 1.0)) == "deck-1"
    text = phones.path.read_text()
    assert "ABCD2345" not in text and "secret-token" not in text
    assert stat.S_IMODE(phones.path.stat().st_mode) == 0o600
    assert phones.read().holder("secret-token", 2.0) == "deck-1"
    phones.path.write_text("{not json")
    with pytest.raises(PairingError):
        phones.read()


def test_the_page_lists_boards_waiting_for_a_sheet_and_vehicles_waiting_for_a_battery() -> None:
    vehicles = [
        VehicleSummary("uav1", "quadrotor-brush", "idle", True, board_id="b1"),
        VehicleSummary("uav2", "quadrotor-brush", "battery_swap", True, board_id="b2",
                       battery_fraction=0.123),
        VehicleSummary("uav3", "quadrotor-brush", "writing", True, board_id="b3"),
    ]  # fmt: skip
    snap = ShowSnapshot("s", 0.0, False, [], vehicles, dirty_boards=["b3", "b1"])
    tasks = crew_tasks(snap, {"uav1": 1, "uav2": 2, "uav3": 3})
    assert [(t.command, t.target, t.place) for t in tasks] == [
        ("fresh_sheet", "b1", 1),
        ("fresh_sheet", "b3", 3),
        ("battery_swapped", "uav2", 2),
    ]
    assert tasks[2].battery_percent == 12


@pytest.mark.parametrize(
    "command", ["approve", "reject", "cancel", "estop", "land_all", "release", "pause"]
)
def test_the_orchestrator_refuses_the_crew_anything_but_sheets_and_batteries(command: Any) -> None:
    reply = refused("crew", OperatorCommand(command=command, job_id="j1", vehicle_id="uav1"))
    assert reply is not None and not reply.ok and reply.error is not None
    assert reply.error.code == "forbidden"
    assert refused("operator", OperatorCommand(command=command)) is None
    assert refused("operator@alice", OperatorCommand(command=command)) is None


def test_the_crew_may_confirm_sheets_and_batteries() -> None:
    assert refused("crew", OperatorCommand(command="fresh_sheet", board_id="b1")) is None
    assert refused("crew", OperatorCommand(command="battery_swapped", vehicle_id="u")) is None


def _may(acl: dict[str, Any], common_name: str, message: str, key: str) -> bool:
    """Whether ``common_name`` may send ``message`` on the literal ``key`` (ingress rules)."""
    policy = next(p for p in acl["policies"] if p["subjects"] == [f"cn {common_name}"])
    rules = {r["id"]: r for r in acl["rules"]}
    for rule in (rules[i] for i in policy["rules"]):
        if "ingress" in rule["flows"] and message in rule["messages"]:
            for expr in rule["key_exprs"]:
                if expr == key or (expr.endswith("/*") and key.rsplit("/", 1)[0] == expr[:-2]):
                    return True
    return False


def test_access_control_gives_the_crew_its_own_command_key_and_nothing_else() -> None:
    acl = access_control(KEYS.show_id, ["uav1"])
    crew_key = KEYS.command_as("crew")
    assert _may(acl, "crew", "query", crew_key)
    assert _may(acl, "crew", "declare_subscriber", KEYS.fleet)
    others = [KEYS.command, KEYS.vehicle_command("uav1"), KEYS.vehicle_assign("uav1")]
    others += [KEYS.submit, KEYS.submit_as("crew"), KEYS.command_as("operator@alice")]
    for key in others:
        assert not _may(acl, "crew", "query", key), key
    assert not _may(acl, "crew", "put", KEYS.fleet)
    for other in ("kiosk", "uav1"):  # the public's session, a vehicle: not the crew's key
        assert not _may(acl, other, "query", crew_key)


class FakeCrewLink:
    """The crew link's surface, recording what it was asked to send."""

    def __init__(self) -> None:
        self.sent: list[tuple[str, str, str]] = []

    async def start(self) -> None: ...

    async def close(self) -> None: ...

    def end_streams(self) -> None: ...

    def view(self) -> list[dict[str, object]]:
        return []

    def stale(self, _max_age_s: float) -> bool:
        return False

    @contextlib.contextmanager
    def watch(self) -> Iterator[RingChannel[bool]]:
        yield RingChannel(1)

    async def confirm(self, command: str, target: str, phone: str) -> CommandReply:
        self.sent.append((command, target, phone))
        return CommandReply(ok=True, message=f"{target}: done")


class FakePublicLink:
    async def start(self) -> None: ...

    async def close(self) -> None: ...

    def end_streams(self) -> None: ...


@dataclass
class Reply:
    status_code: int
    body: bytes
    headers: dict[str, str]

    def json(self) -> Any:
        return json.loads(self.body)


class Client:
    """One phone's browser: its own cookies; JSON bodies unless told otherwise."""

    def __init__(self, base_url: str) -> None:
        self.base_url = base_url.rstrip("/")
        self._opener = urllib.request.build_opener(
            urllib.request.HTTPCookieProcessor(http.cookiejar.CookieJar())
        )

    def request(
        self, method: str, path: str, body: object = None, headers: dict[str, str] | None = None
    ) -> Reply:
        data = body if isinstance(body, bytes) or body is None else json.dumps(body).encode()
        sent = {"Content-Type": "application/json", **(headers or {})}
        req = urllib.request.Request(self.base_url + path, data=data, method=method, headers=sent)
        try:
            with self._opener.open(req, timeout=5) as resp:
                return Reply(resp.status, resp.read(), dict(resp.headers))
        except urllib.error.HTTPError as err:
            with err:
                return Reply(err.code, err.read(), dict(err.headers))

    def post(self, path: str, body: object, headers: dict[str, str] | None = None) -> Reply:
        return self.request("POST", path, body, headers)

    def get(self, path: str) -> Reply:
        return self.request("GET", path)


@contextlib.contextmanager
def _serving(crew: CrewDesk | None) -> Iterator[Client]:
    public: Any = FakePublicLink()
    app = create_app(KioskSettings(show_id=KEYS.show_id), public, lambda s: {},
                     has_glyph=lambda c: True, crew=crew)  # fmt: skip
    server = KioskServer(app, "127.0.0.1", 0)
    server.start_in_thread()
    try:
        yield Client(server.url)
    finally:
        server.stop()


@pytest.fixture
def crew(tmp_path: Path) -> Iterator[tuple[Client, FakeCrewLink, PairingFile]]:
    phones = PairingFile(tmp_path / "crew-phones.json")
    link = FakeCrewLink()
    with _serving(CrewDesk(link, phones)) as client:  # type: ignore[arg-type]
        yield client, link, phones


def _pair(client: Client, phones: PairingFile, name: str = "deck-1") -> None:
    phones.change(lambda book: (book.offered(name, "ABCD2345", time.time()), None))
    reply = client.post("/crew/api/pair", {"code": "abcd 2345"})
    assert reply.status_code == 200 and reply.json()["name"] == name
    cookie = reply.headers["set-cookie"]
    assert "HttpOnly" in cookie and "Path=/crew" in cookie and "SameSite=strict" in cookie


def test_an_unpaired_browser_can_send_nothing(crew: Any) -> None:
    client, link, _ = crew
    body = {"command": "fresh_sheet", "target": "b1"}
    assert client.post("/crew/api/confirm", body).status_code == 401
    assert client.get("/crew/api/events").status_code == 401
    assert client.post("/crew/api/pair", {"code": "ABCD-2345"}).status_code == 403
    # the public's page and API have no way to a crew command
    for path in ("/api/confirm", "/api/command", "/api/fresh_sheet"):
        assert client.post(path, body).status_code in (404, 405)
    assert link.sent == []


def test_a_paired_phone_confirms_sheets_and_batteries_only(crew: Any) -> None:
    client, link, phones = crew
    _pair(client, phones)
    for body in ({"command": "approve", "target": "j1"}, {"command": "estop", "target": "uav1"},
                 {"command": "fresh_sheet", "target": "<b>b1</b>"}):  # fmt: skip
        assert client.post("/crew/api/confirm", body).status_code in (400, 403), body
    assert link.sent == []
    reply = client.post("/crew/api/confirm", {"command": "fresh_sheet", "target": "b1"})
    assert reply.status_code == 200 and reply.json()["ok"]
    reply = client.post("/crew/api/confirm", {"command": "battery_swapped", "target": "uav2"})
    assert reply.status_code == 200
    assert link.sent == [("fresh_sheet", "b1", "deck-1"), ("battery_swapped", "uav2", "deck-1")]
    assert client.get("/crew/api/me").json()["name"] == "deck-1"


def test_another_site_cannot_confirm_for_a_paired_phone(crew: Any) -> None:
    client, link, phones = crew
    _pair(client, phones)
    body = {"command": "fresh_sheet", "target": "b1"}
    forged = client.post("/crew/api/confirm", body, headers={"Origin": "http://evil.test"})
    assert forged.status_code == 403
    form = {"Content-Type": "application/x-www-form-urlencoded"}
    as_form = client.post("/crew/api/confirm", b"command=fresh_sheet", form)
    assert as_form.status_code == 415
    assert link.sent == []


def test_an_unpaired_phone_is_shut_out_at_its_next_request(crew: Any) -> None:
    client, link, phones = crew
    _pair(client, phones)
    assert phones.change(lambda book: book.unpaired("deck-1")) == 1
    reply = client.post("/crew/api/confirm", {"command": "fresh_sheet", "target": "b1"})
    assert reply.status_code == 401 and reply.json()["error"]["code"] == "not_paired"
    assert link.sent == []


def test_guessing_codes_is_rate_limited(crew: Any) -> None:
    client, _, _ = crew
    codes = [client.post("/crew/api/pair", {"code": f"AAAA{i:04d}"}).status_code
             for i in range(7)]  # fmt: skip
    assert codes[:5] == [403] * 5 and codes[5:] == [429, 429]


def test_without_the_crews_session_there_is_no_crew_page() -> None:
    with _serving(None) as client:
        assert client.get("/crew").status_code == 404
        assert client.post("/crew/api/pair", {"code": "x"}).status_code == 404


CREW_WORDS = Path(__file__).resolve().parents[1] / "kiosk" / "static" / "i18n" / "crew"


def test_the_crew_page_says_every_word_in_both_languages() -> None:
    """The same keys in each catalogue; every key the page and its script name is there, and
    every word there is used (the script builds no key from pieces)."""
    en, zh = (json.loads((CREW_WORDS / f"{lang}.json").read_text()) for lang in ("en", "zh-Hans"))
    assert set(en) == set(zh)
    static = CREW_WORDS.parents[1]
    html = (static / "crew.html").read_text()
    script = (static / "crew.js").read_text()
    named = set(re.findall(r'data-i18n(?:-[a-z-]+)?="(\w+)"', html))
    named |= {k for k in re.findall(r'"(\w+)"', script) if k in en or k.startswith(("err_",))}
    assert named <= set(en), named - set(en)
    assert set(en) - {"lang_name"} <= named, set(en) - named
    for key in en:
        assert set(re.findall(r"\{(\w+)\}", en[key])) == set(re.findall(r"\{(\w+)\}", zh[key]))
