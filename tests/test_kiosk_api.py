"""The kiosk's JSON API over HTTP against a fake orchestrator on real loopback Zenoh.

One router, one fake orchestrator session and one kiosk (uvicorn in a thread) for the module.
"""

from __future__ import annotations

import http.client
import json
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
from test_kiosk_support import (
    L_DRAWING,
    WAIT_S,
    Browser,
    FakeOrchestrator,
    done_metrics,
    drawing,
    fresh_address,
    sse_events,
)

from bus.keys import ShowKeys
from bus.session import BusSettings, loopback_settings, open_session
from kiosk.limits import SubmissionLimits
from kiosk.qr import qr_svg
from kiosk.service import serving
from kiosk.settings import KioskSettings, settings_from_show
from showfile import load_show

pytestmark = pytest.mark.timeout(120)

KEYS = ShowKeys("kiosk-api-test")
BLOCKLIST = ("bad", "坏蛋")


@pytest.fixture(scope="module")
def bus() -> Iterator[tuple[BusSettings, FakeOrchestrator]]:
    settings = loopback_settings()
    with (
        open_session(settings, role="router"),
        open_session(settings, role="client") as orchestrator_session,
    ):
        fake = FakeOrchestrator(orchestrator_session, KEYS).start()
        yield settings, fake
        fake.stop()


@pytest.fixture(scope="module")
def kiosk(bus: tuple[BusSettings, FakeOrchestrator]) -> Iterator[str]:
    zenoh_settings, _ = bus
    settings = KioskSettings(
        show_id=KEYS.show_id,
        port=0,
        limits=SubmissionLimits(
            max_payload_bytes=250_000, max_strokes=60, max_points=5_000, max_text_chars=4,
            blocklist=BLOCKLIST,
        ),
        rate_limit_per_minute=6,
        submit_timeout_s=1.0,
        places={"uav3": 3, "uav4": 4},
    )  # fmt: skip
    with serving(settings, zenoh_settings, role="client") as server:
        yield server.url


@pytest.fixture
def fake(bus: tuple[BusSettings, FakeOrchestrator]) -> Iterator[FakeOrchestrator]:
    orchestrator = bus[1]
    orchestrator.mode = "accept"
    yield orchestrator
    orchestrator.mode = "accept"


@pytest.fixture
def visitor(kiosk: str) -> Browser:
    return Browser(kiosk)


def wait_for(check: Callable[[], Any], what: str) -> Any:
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        if value := check():
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def assert_refused(reply: Any, status: int, code: str) -> str:
    assert reply.status == status, reply.body
    assert reply.body["ok"] is False
    assert reply.body["error"]["code"] == code
    message = reply.body["error"]["message"]
    assert message and "Traceback" not in message and "{" not in message
    return str(message)


# --- the page and its configuration ---------------------------------------------------------------


def test_page_is_served_with_a_session_cookie_and_a_strict_policy(visitor: Browser) -> None:
    with visitor._opener.open(visitor.base_url + "/", timeout=WAIT_S) as resp:
        html = resp.read().decode()
        assert resp.status == 200
        assert "default-src 'self'" in resp.headers["content-security-policy"]
    assert '<canvas id="pad"' in html and "/static/kiosk.js" in html
    assert any(c.name == "skyquill_kiosk" for c in visitor.cookies)
    reply = visitor.get("/api/config")
    assert reply.status == 200
    assert reply.body["config"]["max_text_chars"] == 4
    assert reply.body["config"]["writing_area_m"] == [1.2, 1.2]
    with visitor._opener.open(visitor.base_url + "/static/kiosk.js", timeout=WAIT_S) as resp:
        script = resp.read().decode()
    assert "setPointerCapture" in script
    # what the server says (labels, messages) goes into the page as text, never as HTML
    assert "textContent" in script
    assert not any(sink in script for sink in ("innerHTML", "outerHTML", "insertAdjacentHTML"))


# --- preview --------------------------------------------------------------------------------------


def test_preview_of_typed_text_has_turning_points_and_a_pen_down_path(visitor: Browser) -> None:
    reply = visitor.post("/api/preview", {"text": "L"})
    assert reply.status == 200, reply.body
    preview = reply.body["preview"]
    assert preview["turning_point_count"] >= 3  # an L has a corner between its two ends
    path = preview["path"]
    half = 0.6 + 1e-6
    assert all(abs(x) <= half + 0.1 and abs(y) <= half + 0.1 for x, y, _ in path)
    down = [p for p in path if p[2]]
    assert down and len(down) < len(path)  # starts and ends in the air, writes in between
    # the corner of the L (bottom left) is visited with the pen down
    xs, ys = [p[0] for p in down], [p[1] for p in down]
    corner = min(down, key=lambda p: (p[0] - min(xs)) ** 2 + (p[1] - min(ys)) ** 2)
    assert any(abs(tp[0] - corner[0]) < 0.05 and abs(tp[1] - corner[1]) < 0.05
               for tp in preview["turning_points"][0])  # fmt: skip
    assert preview["duration_s"] > 1.0


def test_preview_of_a_drawing_keeps_its_shape(visitor: Browser) -> None:
    reply = visitor.post("/api/preview", L_DRAWING)
    assert reply.status == 200, reply.body
    preview = reply.body["preview"]
    (tps,) = preview["turning_points"]
    # drawn top-down then right, y down on screen: in the preview (y up) it starts high
    assert tps[0][1] > tps[-1][1]
    assert tps[-1][0] > tps[0][0]


def test_a_small_drawing_in_a_corner_keeps_its_size_and_place(visitor: Browser) -> None:
    # a T about 1/6 of the 300 px canvas, in its top-left corner (y down on screen)
    small_t = drawing([
        [[20.0, 20.0, 0.0], [70.0, 20.0, 0.2]],
        [[45.0, 20.0, 0.4], [45.0, 70.0, 0.6]],
    ])  # fmt: skip
    reply = visitor.post("/api/preview", small_t)
    assert reply.status == 200, reply.body
    points = [p for stroke in reply.body["preview"]["turning_points"] for p in stroke]
    xs, ys = [x for x, _ in points], [y for _, y in points]
    area = 1.2 - 2 * 0.05  # the writing area less its margins, [m]
    assert max(xs) - min(xs) == pytest.approx(area * 50 / 300, rel=0.1)  # not blown up
    corner = (-area / 2 + area * 20 / 300, area / 2 - area * 20 / 300)
    assert (min(xs), max(ys)) == pytest.approx(corner, abs=0.01)  # still top left (y up)


def test_a_single_tap_is_refused_not_blown_up(visitor: Browser) -> None:
    tap = drawing([[[150.0, 150.0, 0.0], [152.0, 152.0, 0.0]]])  # what the page makes of a tap
    message = assert_refused(visitor.post("/api/preview", tap), 422, "too_small")
    assert "tap" in message


def test_preview_of_a_drawing_with_a_zero_length_stroke_is_refused(visitor: Browser) -> None:
    dot = drawing([[[10.0, 10.0, 0.0], [10.0, 10.0, 0.1]]])
    message = assert_refused(visitor.post("/api/preview", dot), 422, "bad_drawing")
    assert "draw" in message


# --- rejections -----------------------------------------------------------------------------------


def test_too_large_payload_is_refused_before_reading(
    visitor: Browser, fake: FakeOrchestrator
) -> None:
    n_before = len(fake.requests)
    huge = b'{"text": "' + b"a" * 300_000 + b'"}'
    message = assert_refused(visitor.post("/api/submit", huge), 413, "too_large")
    assert "too big" in message
    assert len(fake.requests) == n_before


def test_too_large_chunked_payload_is_refused(kiosk: str) -> None:
    conn = http.client.HTTPConnection(kiosk.split("//")[1].rstrip("/"), timeout=WAIT_S)
    chunks = (b"[" + b"1," * 50_000 + b"1]" for _ in range(3))
    conn.request("POST", "/api/preview", body=chunks, encode_chunked=True,
                 headers={"Content-Type": "application/json"})  # fmt: skip
    resp = conn.getresponse()
    assert resp.status == 413
    assert json.loads(resp.read())["error"]["code"] == "too_large"
    conn.close()


def test_too_many_points_is_refused(visitor: Browser, fake: FakeOrchestrator) -> None:
    n_before = len(fake.requests)
    stroke = [[float(i % 300), float(i // 300), 0.001 * i] for i in range(5_001)]
    assert_refused(visitor.post("/api/submit", drawing([stroke])), 400, "too_many_points")
    assert len(fake.requests) == n_before


def test_the_biggest_drawing_the_pad_may_send_fits_the_body_and_the_bus(
    visitor: Browser, fake: FakeOrchestrator
) -> None:
    """5,000 points with widths at their longest digits (``showfile/services.py``: the show's
    limits must hold them; 200 kB did not)."""
    strokes = [
        [
            {
                "x": 1000.5 + 2 * i,
                "y": 1000.5 + 5 * k,
                "t": round(100.123 + 0.011 * (100 * k + i), 3),
                "w": 0.01234,
            }
            for i in range(100)
        ]
        for k in range(50)
    ]
    body = drawing(strokes)  # type: ignore[arg-type]
    body["strokes"]["canvas"] = {"width": 1920, "height": 1400}
    sent = json.dumps(body, separators=(",", ":")).encode()  # as JSON.stringify sends it
    assert len(sent) > 220_000
    reply = visitor.post("/api/submit", sent)
    assert reply.status == 200, reply.body
    assert len(fake.requests[-1].strokes["strokes"]) == 50


def test_too_many_strokes_is_refused(visitor: Browser) -> None:
    strokes = [[[float(i), 0.0], [float(i), 10.0]] for i in range(61)]
    message = assert_refused(
        visitor.post("/api/preview", drawing(strokes)), 400, "too_many_strokes"
    )
    assert "60" in message


def test_malformed_json_is_refused(visitor: Browser) -> None:
    for body in (b"{not json", b"[1, 2]", b"\xff\xfe", b'{"text": "A", "priority": 9}'):
        assert visitor.post("/api/submit", body).body["error"]["code"] in (
            "bad_json",
            "bad_request",
        )
        reply = visitor.post("/api/preview", body)
        assert reply.status == 400
    assert_refused(visitor.post("/api/preview", {"text": 5}), 400, "bad_request")
    assert_refused(visitor.post("/api/preview", {"text": "A", **L_DRAWING}), 400, "bad_request")
    assert_refused(visitor.post("/api/preview", {}), 400, "empty")


@pytest.mark.parametrize("text", ["bad", "BAD", "b ad", "ＢＡＤ", "坏蛋"])
def test_blocked_text_is_refused_without_echoing_it(
    visitor: Browser, fake: FakeOrchestrator, text: str
) -> None:
    n_before = len(fake.requests)
    for path in ("/api/preview", "/api/submit"):
        message = assert_refused(visitor.post(path, {"text": text}), 400, "blocked_text")
        assert text.lower() not in message.lower() and "坏" not in message
    assert len(fake.requests) == n_before


def test_text_too_long_or_without_glyph_is_refused(visitor: Browser) -> None:
    assert "4" in assert_refused(
        visitor.post("/api/preview", {"text": "ABCDE"}), 400, "text_too_long"
    )
    message = assert_refused(visitor.post("/api/preview", {"text": "\U0001f600"}), 422, "no_glyph")
    assert "\U0001f600" in message


@pytest.mark.parametrize(
    "body",
    [
        b'{"text": "\\ud800"}',  # a lone surrogate: no UTF-8 text holds it
        b'{"text": "A\\udc00"}',
        b'{"strokes": {"\\ud800": 1, "strokes": [[[0, 0], [9, 9]]]}}',
        b'{"text": ' + b"9" * 5_000 + b"}",  # beyond Python's integer conversion limit
    ],
)
def test_bodies_no_text_can_hold_are_bad_json_not_a_crash(
    visitor: Browser, fake: FakeOrchestrator, body: bytes
) -> None:
    n_before = len(fake.requests)
    for path in ("/api/preview", "/api/submit"):
        assert_refused(visitor.post(path, body), 400, "bad_json")
    assert len(fake.requests) == n_before


def post_raw(kiosk: str, path: str, headers: dict[str, str]) -> tuple[int, str]:
    """POST ``{"text": "A"}`` with exactly ``headers``: the status and the error code."""
    host = kiosk.split("//")[1].rstrip("/")
    conn = http.client.HTTPConnection(host, timeout=WAIT_S, source_address=(fresh_address(), 0))
    try:
        conn.request("POST", path, body=b'{"text": "A"}', headers=headers)
        resp = conn.getresponse()
        reply = json.loads(resp.read())
    finally:
        conn.close()
    return resp.status, reply["error"]["code"] if not reply["ok"] else ""


def test_only_json_from_the_kiosks_own_page_is_taken(kiosk: str, fake: FakeOrchestrator) -> None:
    """Another web page can make a visitor's browser post a form or text/plain to the kiosk
    without asking: refused, as is any page of another origin."""
    own = "http://" + kiosk.split("//")[1].rstrip("/")
    n_before = len(fake.requests)
    for content_type in ("text/plain", "application/x-www-form-urlencoded", "text/json", None):
        headers = {"Content-Type": content_type} if content_type else {}
        for path in ("/api/preview", "/api/submit"):
            assert post_raw(kiosk, path, headers) == (415, "unsupported_media_type")
    for origin in ("https://evil.example", "null", own + ".evil.example", "http://127.0.0.1:1"):
        headers = {"Content-Type": "application/json", "Origin": origin}
        for path in ("/api/preview", "/api/submit"):
            assert post_raw(kiosk, path, headers) == (403, "cross_origin")
    assert len(fake.requests) == n_before
    same = {"Content-Type": "application/json; charset=utf-8", "Origin": own}
    assert post_raw(kiosk, "/api/submit", same) == (200, "")
    assert post_raw(kiosk, "/api/preview", {"Content-Type": "application/json"}) == (200, "")


def test_request_headers_are_capped(kiosk: str) -> None:
    json_type = {"Content-Type": "application/json"}
    for padding_bytes in (17_000, 100_000):
        headers = {**json_type, "X-Padding": "a" * padding_bytes}
        assert post_raw(kiosk, "/api/preview", headers) == (431, "headers_too_large")
    many = {**json_type, **{f"X-Pad-{i}": "a" * 1_000 for i in range(20)}}
    assert post_raw(kiosk, "/api/preview", many) == (431, "headers_too_large")
    assert post_raw(kiosk, "/api/preview", {**json_type, "X-Padding": "a" * 8_000}) == (200, "")


def test_rate_limit_per_client(kiosk: str, fake: FakeOrchestrator) -> None:
    walker = Browser(kiosk)
    for _ in range(6):  # attempts count even when refused for another reason
        assert walker.post("/api/submit", {}).status == 400
    reply = walker.post("/api/submit", {"text": "A"})
    message = assert_refused(reply, 429, "rate_limited")
    assert "wait" in message
    assert 1 <= int(reply.headers["retry-after"]) <= 60
    # a fresh cookie from the same address does not help; another address is not affected
    assert Browser(kiosk, source=walker.source).post("/api/submit", {}).status == 429
    assert Browser(kiosk).post("/api/submit", {}).status == 400


def test_orchestrator_refusal_and_absence_get_plain_messages(
    visitor: Browser, fake: FakeOrchestrator
) -> None:
    fake.mode = "queue_full"
    assert "queue is full" in assert_refused(
        visitor.post("/api/submit", {"text": "A"}), 503, "queue_full"
    )
    fake.mode = "accept"
    # the service kept running and accepts again
    assert visitor.post("/api/submit", {"text": "A"}).status == 200


def _follow(visitor: Browser, reply: Any) -> Callable[[], dict[str, Any]]:
    path = f"/api/jobs/{reply.body['ticket']}?token={reply.body['token']}"
    return lambda: visitor.get(path).body


def test_absent_orchestrator_keeps_the_ticket_pending_until_it_answers(
    visitor: Browser, fake: FakeOrchestrator
) -> None:
    fake.stop()
    try:
        reply = visitor.post("/api/submit", {"text": "Z"})
        assert reply.status == 202, reply.body
        job = reply.body["job"]
        assert job["state"] == "sending" and not job["final"] and reply.body["job_id"] is None
        assert "not confirmed" in job["status_text"] and "could not be accepted" not in str(job)
        status = _follow(visitor, reply)
        assert status()["job"]["state"] == "sending"
    finally:
        fake.start()
    body = wait_for(lambda: (b := status())["job"]["state"] == "queued" and b, "the late answer")
    tries = [r for r in fake.requests if r.text == "Z"]
    assert tries and len({r.idempotency_key for r in tries}) == 1
    assert [j.job_id for j in fake.jobs.values() if j.label == "Z"] == [body["job"]["job_id"]]


def test_hung_orchestrator_answers_late_once_and_the_status_says_it_is_stale(
    visitor: Browser, fake: FakeOrchestrator
) -> None:
    sent = len(fake.requests)
    wait_for(lambda: not visitor.get("/healthz").body["stale"], "fresh fleet news")
    fake.thawed.clear()
    try:
        started = time.monotonic()
        reply = visitor.post("/api/submit", {"text": "B"})
        assert reply.status == 202 and reply.body["job"]["state"] == "sending", reply.body
        status = _follow(visitor, reply)
        wait_for(lambda: status()["stale"], "the stale flag")
        assert time.monotonic() - started < 3.0 + 1.0  # submit timeout 1 s, stale within 3 s
    finally:
        fake.thawed.set()
    body = wait_for(lambda: (b := status())["job"]["state"] == "queued" and b, "the late answer")
    wait_for(lambda: not status()["stale"], "fresh news again")
    mine = [r for r in fake.requests[sent:] if r.text == "B"]
    assert len({r.idempotency_key for r in mine}) == 1  # every try carried the same key
    assert len([j for j in fake.jobs.values() if j.label == "B"]) == 1
    assert body["job"]["job_id"] in fake.jobs


def test_late_refusal_is_shown_on_the_ticket(visitor: Browser, fake: FakeOrchestrator) -> None:
    fake.stop()
    try:
        reply = visitor.post("/api/submit", {"text": "C"})
        assert reply.status == 202
        fake.mode = "invalid_text"
    finally:
        fake.start()
    status = _follow(visitor, reply)
    job = wait_for(lambda: (j := status()["job"])["final"] and j, "the late refusal")
    assert job["state"] == "refused" and "could not be accepted" in job["status_text"]


def test_unknown_job_and_other_clients_job(kiosk: str, fake: FakeOrchestrator) -> None:
    owner, other = Browser(kiosk), Browser(kiosk)
    submitted = owner.post("/api/submit", {"text": "永"})
    assert submitted.status == 200, submitted.body
    job_id, token = submitted.body["job_id"], submitted.body["token"]
    assert_refused(other.get("/api/jobs/no-such-job?token=x"), 404, "unknown_job")
    # a job on the bus that this kiosk did not submit (e.g. from the operator's CLI)
    fake.set_state("cli-job", "queued")
    assert_refused(other.get("/api/jobs/cli-job?token=x"), 404, "unknown_job")
    assert_refused(other.get(f"/api/jobs/{job_id}"), 403, "not_your_job")
    assert_refused(other.get(f"/api/jobs/{job_id}?token={token[:-1]}x"), 403, "not_your_job")
    assert_refused(other.get(f"/api/jobs/{job_id}/events?token=wrong"), 403, "not_your_job")
    mine = owner.get(f"/api/jobs/{job_id}?token={token}")
    assert mine.status == 200 and mine.body["job"]["job_id"] == job_id
    code = submitted.body["code"]
    assert len(code) == 8 and code.isalnum() and code.isupper()
    typed = f"{code[:4].lower()}-{code[4:]}"  # as a visitor might type it
    opened = other.get(f"/api/t/{typed}")
    assert opened.status == 200 and opened.body["token"] == token
    assert opened.body["job"]["job_id"] == job_id
    assert_refused(other.get("/api/t/AAAA2222"), 404, "unknown_job")
    assert other.request_raw(f"/t/{code}")[:2] == (200, "text/html; charset=utf-8")  # the page
    qr = owner.request_raw(f"/api/jobs/{job_id}/qr.svg?token={token}")
    assert qr[0] == 200 and qr[1].startswith("image/svg+xml")
    assert qr[2] == qr_svg(f"{kiosk.rstrip('/')}/t/{code}")
    assert other.request_raw(f"/api/jobs/{job_id}/qr.svg?token=x")[0] == 403
    by_ticket = owner.get(f"/api/jobs/{submitted.body['ticket']}?token={token}")
    assert by_ticket.status == 200 and by_ticket.body["job"]["job_id"] == job_id
    assert_refused(other.get(f"/api/jobs/{submitted.body['ticket']}?token=x"), 403, "not_your_job")


# --- submitting and following a job ---------------------------------------------------------------


def test_submit_reaches_the_orchestrator_and_status_follows_the_bus(
    kiosk: str, visitor: Browser, fake: FakeOrchestrator
) -> None:
    reply = visitor.post("/api/submit", L_DRAWING)
    assert reply.status == 200, reply.body
    body = reply.body
    job_id, token = body["job_id"], body["token"]
    request = fake.requests[-1]
    assert request.strokes is not None and request.text is None
    assert request.strokes["strokes"] == L_DRAWING["strokes"]["strokes"]
    cookie = next(str(c.value) for c in visitor.cookies if c.name == "skyquill_kiosk")
    assert request.client_id.startswith("kiosk-") and cookie not in request.client_id
    assert body["job"]["state"] == "queued" and body["job"]["queue_position"] >= 1
    assert body["preview"]["path"]

    path = f"/api/jobs/{job_id}?token={token}"
    fake.set_state(job_id, "queued", queue_position=2, eta_s=95.0)
    job = wait_for(
        lambda: (j := visitor.get(path).body["job"])["queue_position"] == 2 and j, "queue update"
    )
    assert "number 2" in job["status_text"] and "about 2 minutes" in job["status_text"]

    frames = sse_events(kiosk, f"/api/jobs/{job_id}/events?token={token}")
    events = ((n, d) for n, d in frames if n == "job")
    name, first = next(events)
    assert name == "job" and first["state"] == "queued" and not first["final"]
    assert next(frames)[0] == "live"  # between changes, the stream says whether it is current
    fake.set_state(job_id, "writing", vehicle_id="uav3", progress=0.4, queue_position=None)
    _, writing = next(events)
    assert writing["state"] == "writing" and "by drone 3 at board 3" in writing["status_text"]
    assert "40%" in writing["status_text"]
    fake.set_state(job_id, "queued", vehicle_id="uav3", attempts=1, queue_position=1)
    _, requeued = next(events)
    assert "had to land" in requeued["status_text"] and "next in line" in requeued["status_text"]
    fake.set_state(job_id, "writing", vehicle_id="uav4", attempts=2, progress=0.1)
    _, again = next(events)
    assert "now drone 4 is writing it" in again["status_text"]
    assert not [t for t in (writing, again) if "uav" in t["status_text"]]  # no internal ids
    fake.set_state(job_id, "done", vehicle_id="uav4", progress=1.0, metrics=done_metrics())
    _, done = next(events)
    assert done["final"] and done["metrics"]["rmse_pen_down_m"] == pytest.approx(0.012)
    assert "Done" in done["status_text"]
    assert list(events) == []  # the stream ends after the final state
    # a late reader gets the final state at once
    assert next(sse_events(kiosk, f"/api/jobs/{job_id}/events?token={token}"))[1]["state"] == "done"


def test_the_show_files_kiosk_section_sets_the_limits() -> None:
    show = load_show(Path(__file__).resolve().parents[1] / "shows" / "solo.yaml")
    assert settings_from_show(show).limits.max_text_chars == 1
    assert settings_from_show(show).trusted_proxies == ()  # X-Forwarded-For ignored by default
    kiosk = type(show.kiosk).model_validate(
        {**show.kiosk.model_dump(), "max_text_chars": 4, "max_strokes": 7,
         "trusted_proxies": ["127.0.0.1", "10.0.0.0/8"]}
    )  # fmt: skip
    settings = settings_from_show(show.model_copy(update={"kiosk": kiosk}), port=0)
    assert (settings.limits.max_text_chars, settings.limits.max_strokes, settings.port) == (4, 7, 0)
    assert settings.trusted_proxies == ("127.0.0.1/32", "10.0.0.0/8")


def test_a_flight_longer_than_the_shows_limit_is_refused_with_the_reason() -> None:
    from kiosk.errors import RejectedError
    from kiosk.limits import Submission
    from kiosk.preview import plan_preview

    text = Submission(text="L", strokes=None, label="L")
    settings = KioskSettings(show_id="t")
    allowed = plan_preview(text, settings)["duration_s"]
    assert 1.0 < allowed <= settings.max_flight_s == 90.0
    with pytest.raises(RejectedError) as err:
        plan_preview(text, replace(settings, max_flight_s=allowed / 2))
    assert err.value.code == "too_long" and f"{round(allowed)} seconds" in err.value.message
    show = load_show(Path(__file__).resolve().parents[1] / "shows" / "solo.yaml")
    assert settings_from_show(show).max_flight_s == show.kiosk.max_flight_s == 90.0
