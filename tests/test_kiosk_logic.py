"""Pure parts of the kiosk: limits, blocklist, rate limiter, job book, the words people read."""

from __future__ import annotations

from typing import Any

import msgspec
import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.messages import JobMetrics, JobState, JobStateName, WrittenInk
from bus.ratelimit import SlidingWindowLimiter
from kiosk import wording
from kiosk.addresses import (
    BadProxySettingError,
    client_address,
    parse_address,
    proxy_networks,
    rate_key,
)
from kiosk.errors import RejectedError
from kiosk.jobs import JobBook, job_view
from kiosk.limits import SubmissionLimits, check_submission, decode_json_body, is_blocked


def state(job_id: str, name: JobStateName, updated_at_s: float, **kw: object) -> JobState:
    return JobState(
        job_id=job_id, state=name, label="A", kind="text", client_id="c", created_at_s=0.0,
        updated_at_s=updated_at_s, **kw,  # type: ignore[arg-type]
    )  # fmt: skip


# --- rate limiter ---------------------------------------------------------------------------------


def test_limiter_allows_limit_per_window_then_says_how_long_to_wait() -> None:
    limiter = SlidingWindowLimiter(3, window_s=60.0)
    assert [limiter.hit("a", t) for t in (0.0, 10.0, 20.0)] == [None, None, None]
    assert limiter.hit("a", 30.0) == pytest.approx(30.0)  # the event at t=0 leaves at t=60
    assert limiter.hit("b", 30.0) is None  # keys are independent
    assert limiter.hit("a", 60.0) is None  # the first event has left the window
    assert limiter.hit("a", 61.0) == pytest.approx(9.0)


@given(st.lists(st.floats(0.0, 600.0), max_size=60), st.integers(1, 5))
def test_limiter_never_lets_more_than_limit_into_any_window(times: list[float], limit: int) -> None:
    limiter = SlidingWindowLimiter(limit, window_s=60.0)
    allowed = [t for t in sorted(times) if limiter.hit("k", t) is None]
    for t in allowed:
        assert sum(1 for u in allowed if t - 60.0 < u <= t) <= limit


def test_limiter_forgets_idle_clients_when_many() -> None:
    limiter = SlidingWindowLimiter(1, window_s=10.0, max_keys=100)
    for i in range(100):
        limiter.hit(f"old{i}", 0.0)
    assert limiter.hit("new", 100.0) is None
    assert len(limiter._events) == 1


# --- client addresses ---------------------------------------------------------------------------

PROXIES = proxy_networks(["127.0.0.1", "10.0.0.0/8", "::1"])


@pytest.mark.parametrize(
    ("peer", "forwarded", "client"),
    [
        ("192.0.2.1", ["198.51.100.1"], "192.0.2.1"),  # not a proxy: the header is ignored
        ("127.0.0.1", [], "127.0.0.1"),  # a proxy's own request
        ("127.0.0.1", ["198.51.100.1"], "198.51.100.1"),
        ("127.0.0.1", ["6.6.6.6, 198.51.100.1"], "198.51.100.1"),  # left part is the client's
        ("127.0.0.1", ["6.6.6.6", "198.51.100.1, 10.0.0.7"], "198.51.100.1"),  # two lines
        ("127.0.0.1", ["198.51.100.1:4711"], "198.51.100.1"),
        ("::1", ["[2001:db8::5]:443"], "2001:db8::5"),
        ("::ffff:127.0.0.1", ["198.51.100.1"], "198.51.100.1"),
        ("127.0.0.1", ["198.51.100.1, not-an-address"], "127.0.0.1"),
        ("127.0.0.1", ["10.0.0.8, 10.0.0.7"], "10.0.0.8"),  # all trusted: the left-most
    ],
)
def test_client_address_believes_only_trusted_proxies(
    peer: str, forwarded: list[str], client: str
) -> None:
    assert client_address(peer, forwarded, PROXIES) == client
    assert client_address(peer, forwarded, ()) == str(parse_address(peer))  # no proxies: the peer


def test_rate_key_groups_an_ipv6_clients_network() -> None:
    assert rate_key("2001:db8:1:2::1") == rate_key("2001:db8:1:2:ffff::9") == "2001:db8:1:2::/64"
    assert rate_key("2001:db8:1:3::1") != rate_key("2001:db8:1:2::1")
    assert rate_key("203.0.113.9") == "203.0.113.9"
    with pytest.raises(BadProxySettingError, match=r"trusted_proxies: 'proxy\.local'"):
        proxy_networks(["proxy.local"])


# --- blocklist and submission checks --------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "blocked"),
    [("bad", True), ("Bad", True), ("ＢＡＤ", True), ("b-a d", True), ("abadx", True),
     ("bed", False), ("坏蛋", True), ("坏", False), ("", False)],
)  # fmt: skip
def test_blocklist_matches_after_normalisation(text: str, blocked: bool) -> None:
    assert is_blocked(text, ["BAD", "坏蛋"]) is blocked


def test_check_submission_text_and_strokes() -> None:
    limits = SubmissionLimits(max_text_chars=3, max_strokes=2, max_points=6)
    sub = check_submission({"text": "  永 "}, limits, lambda c: True)
    assert sub.text == "永" and sub.strokes is None and sub.label == "永"
    doc: dict[str, Any] = {
        "units": "px",
        "y_axis": "down",
        "strokes": [[[0, 0], [1, 1]], [[2, 2], [3, 3]]],
    }
    sub = check_submission({"strokes": doc}, limits, lambda c: True)
    assert sub.text is None and sub.label == "drawing (2 strokes)"
    # a label or device the page never sends is not passed on (free text past the blocklist)
    sub = check_submission(
        {"strokes": {**doc, "label": "[/x]", "device": "\x1b[31m"}}, limits, bool
    )
    assert sub.strokes == doc and sub.label == "drawing (2 strokes)"
    with pytest.raises(RejectedError) as err:
        check_submission({"strokes": {**doc, "strokes": doc["strokes"] * 2}}, limits, bool)
    assert err.value.code == "too_many_strokes"
    with pytest.raises(RejectedError) as err:
        check_submission({"strokes": {**doc, "strokes": [[[0, 0]] * 7]}}, limits, bool)
    assert err.value.code == "too_many_points" and err.value.stroke_index == 0
    with pytest.raises(RejectedError) as err:
        check_submission(
            {"strokes": {**doc, "strokes": [[[0, 0], [1, 1]], [[5, 5]]]}}, limits, bool
        )
    assert err.value.code == "short_stroke" and err.value.stroke_index == 1
    with pytest.raises(RejectedError) as err:
        check_submission({"text": "A"}, limits, lambda c: c != "A")
    assert err.value.code == "no_glyph" and err.value.status == 422


@pytest.mark.parametrize("raw", [b"", b"nul", b"[]", b'"A"', b"\xc3\x28", b"[" * 100_000])
def test_decode_json_body_refuses_anything_but_an_object(raw: bytes) -> None:
    with pytest.raises(RejectedError) as err:
        decode_json_body(raw)
    assert err.value.code == "bad_json" and err.value.message == wording.BAD_JSON


# --- job book -------------------------------------------------------------------------------------


def test_job_book_tokens_and_state_order() -> None:
    book = JobBook(max_jobs=2)
    job = book.add(session_id="s", label="A", preview=None)
    assert job.pending and book.view(job)["state"] == "sending" and book.pending_count() == 1
    assert book.authorised(job.ticket, job.token) is job
    book.bind(job.ticket, "j1")
    assert not job.pending and book.pending_count() == 0
    assert book.view(job)["state"] == "checking"  # accepted: never "sending" again
    assert book.authorised("j1", job.token) is job
    assert book.authorised("j1", job.token + "x") is None
    assert book.authorised("j1", None) is None
    assert book.authorised("j2", job.token) is None
    other = book.add(session_id="s", label="B", preview=None)
    assert other.key != job.key and other.ticket != job.ticket and len(other.key) <= 64
    book.refuse(other.ticket, "no")
    assert book.view(other)["final"] and book.view(other)["status_text"] == "no"
    assert book.update(state("j1", "queued", 0.0))
    assert book.update(state("j1", "writing", 5.0))
    assert not book.update(state("j1", "queued", 4.0))  # older news is ignored
    assert not book.update(state("j1", "writing", 5.0))  # same news is not a change
    assert book.update(state("j1", "done", 6.0))
    assert not book.update(state("j1", "writing", 7.0))  # nothing comes after a final state
    assert getattr(book.state("j1"), "state", None) == "done"
    assert book.view(job)["state"] == "done"
    newest = book.add(session_id="s", label="C", preview=None)
    assert book.get("j1") is None and book.get(newest.ticket) is newest  # bounded, oldest dropped


# --- words ----------------------------------------------------------------------------------------


def test_status_text_says_what_happens_in_plain_words() -> None:
    assert "approve" in wording.status_text("awaiting_approval")
    assert "next in line" in wording.status_text("queued", queue_position=1, eta_s=20.0)
    assert "less than a minute" in wording.status_text("queued", queue_position=1, eta_s=20.0)
    assert "number 4" in wording.status_text("queued", queue_position=4, eta_s=200.0)
    assert "about 3 minutes" in wording.status_text("queued", queue_position=4, eta_s=200.0)
    assert "by drone 2" in wording.status_text("writing", board=2, progress=0.5)  # its board
    assert "50%" in wording.status_text("writing", board=2, progress=0.5)
    assert wording.status_text("done", board=2).startswith("Done!")
    paused = wording.status_text("queued", queue_position=4, eta_s=200.0, paused=True)
    assert "paused" in paused and "number 4" in paused and "minute" not in paused  # no promise
    assert job_view(state("j", "queued", 1.0), show_paused=True)["show_paused"]
    requeued = wording.status_text("queued", attempts=1, queue_position=2, eta_s=10.0)
    assert "had to land" in requeued and "number 2" in requeued
    again = wording.status_text(
        "writing", attempts=2, board=2, progress=0.3, place="board 2 from the left"
    )
    assert "now drone 2" in again and "board 2 from the left" in again and "30%" in again
    assert wording.board_numbers({"u1": "b1", "u2": "b2", "u3": "gone"}, ["b2", "b1"]) == {
        "u1": 2, "u2": 1
    }  # fmt: skip
    placed = job_view(state("j", "writing", 1.0, vehicle_id="u1"), {"u1": 2})
    assert placed["board"] == 2 and placed["place"] == "board 2 from the left"
    view = job_view(state("j", "rejected", 1.0))
    assert view["final"] and "not approve" in view["status_text"]


def test_the_ink_picture_is_kept_when_a_later_state_of_the_job_has_none() -> None:
    ink = WrittenInk(
        width_px=8, height_px=2, extent_m_board=(-0.6, -0.15, 0.6, 0.15), bits=b"\x81\x18"
    )
    metrics = JobMetrics(rmse_pen_down_m=0.01, rmse_m=0.01, max_error_m=0.02, iou=0.8, duration_s=9)
    book = JobBook()
    job = book.add(session_id="s", label="A", preview=None)
    book.bind(job.ticket, "j")
    with_ink = msgspec.structs.replace(metrics, written=ink)
    assert book.update(state("j", "done", 5.0, metrics=with_ink))
    assert not book.update(state("j", "done", 5.0, metrics=metrics))  # a snapshot without it
    written = book.view(job)["metrics"]["written"]
    assert written == {
        "format": "bitmap1", "width_px": 8, "height_px": 2,
        "extent_m_board": [-0.6, -0.15, 0.6, 0.15], "bits": "gRg=",
    }  # fmt: skip
